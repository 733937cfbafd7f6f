"""apply_curvature_reconstruction: a mesh rebuilt from its own detail is itself; constraints."""

import os

import numpy as np
import pymeshlab
import pytest

from curvdetail import boundary_vertices
from curvdetail.curvature.geometry import bbox_diagonal
from curvdetail.filters import FilterError, apply
from curvdetail.filters.meshset import set_vertex_positions

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


def meshset(name):
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, name))
    return ms


@pytest.mark.parametrize("rows", ["all", "free"])
@pytest.mark.parametrize("name", ["mannequin_nose.obj", "terrainA_1k.obj"])
def test_rebuild_from_own_detail_reproduces_the_mesh(name, rows):
    # exact in exact arithmetic; 1e-9 of the bbox diagonal allows for the sparse solve
    ms = meshset(name)
    V = ms.current_mesh().vertex_matrix().copy()
    apply(ms, "compute_curvature_detail")
    figures = apply(ms, "apply_curvature_reconstruction", rows=rows)
    X = ms.current_mesh().vertex_matrix()
    assert np.abs(X - V).max() < 1e-9 * bbox_diagonal(V)
    assert figures["max_displacement_percent_of_diagonal"] < 1e-7
    assert ms.mesh_number() == 1 and ms.current_mesh_id() == 0


def test_quality_is_the_distance_moved():
    ms = meshset("terrainA_1k.obj")
    apply(ms, "compute_curvature_detail")
    V = ms.current_mesh().vertex_matrix().copy()
    rng = np.random.default_rng(3)
    F = ms.current_mesh().face_matrix()
    bumped = V + 1e-3 * rng.normal(size=V.shape) * bbox_diagonal(V)
    b = boundary_vertices(F)
    bumped[b] = V[b]
    set_vertex_positions(ms, 0, bumped)        # stored detail is still the original one
    figures = apply(ms, "apply_curvature_reconstruction")
    X = ms.current_mesh().vertex_matrix()
    moved = np.linalg.norm(X - bumped, axis=1)
    assert np.allclose(ms.current_mesh().vertex_scalar_array(), moved, rtol=0, atol=1e-15)
    assert figures["max_displacement_percent_of_diagonal"] == pytest.approx(100 * moved.max() / bbox_diagonal(bumped), rel=1e-12)


def test_selected_vertices_stay_fixed_on_a_closed_mesh():
    ms = meshset("spot.obj")
    apply(ms, "compute_curvature_detail")
    V = ms.current_mesh().vertex_matrix().copy()
    condition = " || ".join(f"(vi == {k})" for k in range(0, 2930, 500))   # 6 spread vertices
    ms.compute_selection_by_condition_per_vertex(condselect=condition)
    figures = apply(ms, "apply_curvature_reconstruction")
    assert figures["fixed_vertices"] == 6 and figures["free_vertices"] == 2930 - 6
    assert np.abs(ms.current_mesh().vertex_matrix() - V).max() < 1e-9 * bbox_diagonal(V)


def test_closed_mesh_without_selection_is_rebuilt_from_one_anchor():
    ms = meshset("spot.obj")
    apply(ms, "compute_curvature_detail")
    V = ms.current_mesh().vertex_matrix().copy()
    figures = apply(ms, "apply_curvature_reconstruction")
    assert figures["anchors"] == 1 and figures["fixed_vertices"] == 1
    assert np.abs(ms.current_mesh().vertex_matrix() - V).max() < 1e-9 * bbox_diagonal(V)


def test_missing_detail_attribute_says_what_to_run():
    with pytest.raises(FilterError, match=r"\bcompute_curvature_detail\b") as e:        # the filter to run
        apply(meshset("mannequin_nose.obj"), "apply_curvature_reconstruction")
    assert e.value.value == "curvature_detail"


@pytest.mark.parametrize("rows", ["all", "free"])
def test_bumped_flat_grid_is_rebuilt_flat_from_its_stored_detail(rows):
    # known answer: the detail of a flat grid has no z component (interior: 0; boundary: the
    # in-plane conormal), so with the boundary fixed at z = 0 the z rows of both systems are
    # homogeneous and the rebuilt surface is the plane again, whatever L of the bumped geometry
    from curvdetail.curvature.testing import grid

    V, F = grid(12, 12)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F))
    apply(ms, "compute_curvature_detail")
    b = boundary_vertices(F)
    interior = np.setdiff1d(np.arange(V.shape[0]), b)
    bumped = V.copy()
    bumped[interior, 2] = 0.05 * np.sin(3 * V[interior, 0])
    set_vertex_positions(ms, 0, bumped)        # the stored detail is still the flat one
    assert np.abs(ms.current_mesh().vertex_matrix()[interior, 2]).max() > 0.01
    figures = apply(ms, "apply_curvature_reconstruction", rows=rows)
    X = ms.current_mesh().vertex_matrix()
    assert np.abs(X[:, 2]).max() < 1e-12                   # measured 0.0 for both rows
    assert np.array_equal(X[b], V[b])
    assert figures["max_displacement_percent_of_diagonal"] > 1
