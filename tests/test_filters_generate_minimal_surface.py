"""generate_minimal_surface: a new current layer spanning the same boundary with less area."""

import os

import numpy as np
import pymeshlab
import pytest

from curvdetail import ConstraintError, boundary_vertices
from curvdetail.curvature.testing import grid
from curvdetail.filters import apply

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


def test_planar_boundary_spans_the_plane():
    # a bump with a flat rim: the minimal surface is the plane z = 0 (to the solver's precision)
    V, F = grid(9, 9)
    V[:, 2] = V[:, 0] * (1 - V[:, 0]) * V[:, 1] * (1 - V[:, 1])
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32)), "bump")
    figures = apply(ms, "generate_minimal_surface")
    X = ms.current_mesh().vertex_matrix()
    assert figures["converged"] and np.abs(X[:, 2]).max() < 1e-9
    assert figures["area_minimal"] == pytest.approx(1.0, abs=1e-12)


def test_terrain_gets_a_new_current_layer_with_the_same_boundary_and_less_area():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "terrainA_1k.obj"))
    V, F = ms.current_mesh().vertex_matrix().copy(), ms.current_mesh().face_matrix().copy()
    figures = apply(ms, "generate_minimal_surface", max_iterations=5, tol=1e-9)   # stops at the cap
    assert ms.mesh_number() == 2 and ms.current_mesh_id() == 1
    assert ms.current_mesh().label() == "terrainA_1k.obj minimal surface"
    X = ms.current_mesh().vertex_matrix()
    b = boundary_vertices(F)
    assert np.array_equal(X[b], V[b]) and np.array_equal(ms.current_mesh().face_matrix(), F)
    assert figures["iterations"] == 5 and figures["area_minimal"] < figures["area_source"]
    assert np.allclose(ms.current_mesh().vertex_scalar_array(), np.linalg.norm(X - V, axis=1))
    assert np.array_equal(ms.mesh(0).vertex_matrix(), V)          # the source is untouched


def test_closed_mesh_is_refused():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "spot.obj"))
    with pytest.raises(ConstraintError, match=r"layer 0 \('spot\.obj'\)") as e:
        apply(ms, "generate_minimal_surface")
    assert e.value.count == 0                                    # boundary vertices
    assert ms.mesh_number() == 1


def test_tol_defaults_to_the_core_tolerance_on_the_normal_step():
    # the core stops on the largest step normal to the surface (DEFAULT_TOL = 1e-4); the filter
    # must not keep its own, 100 times tighter default that described the full vertex step
    from curvdetail.curvature.minimal_surface import DEFAULT_TOL
    from curvdetail.filters import get_filter

    spec = get_filter("generate_minimal_surface")
    tol = spec.parameter("tol")
    assert tol.default == DEFAULT_TOL
    assert "normal to the surface" in tol.description and "normal to the surface" in spec.description


def test_default_tolerance_converges_on_the_terrain():
    # with the old 1e-6 default the terrain still slid tangentially after 200 steps and was
    # reported as not converged; on the normal step with 1e-4 it settles in a few steps
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "terrainA_1k.obj"))
    figures = apply(ms, "generate_minimal_surface")
    assert figures["converged"] and figures["iterations"] < 20 and figures["last_step"] < 1e-4
