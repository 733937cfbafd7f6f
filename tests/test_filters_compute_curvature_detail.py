"""compute_curvature_detail: stored attributes equal the core functions' output; H as quality."""

import os

import numpy as np
import pymeshlab
import pytest

from curvdetail import boundary_vertices, curvature_detail, mean_curvature_normal
from curvdetail.curvature.testing import icosphere
from curvdetail.filters import apply
from curvdetail.filters.meshset import set_vertex_positions, vertex_attribute, vertex_normals

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


def meshset(name):
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, name))
    return ms


@pytest.mark.parametrize("name", ["mannequin_nose.obj", "terrainA_1k.obj", "spot.obj"])
def test_stored_attributes_equal_core_functions(name):
    ms = meshset(name)
    apply(ms, "compute_curvature_detail")
    V, F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    K, A = mean_curvature_normal(V, F)
    assert np.array_equal(vertex_attribute(ms, 0, "curvature_normal", "point"), K)
    assert np.array_equal(vertex_attribute(ms, 0, "curvature_detail", "point"), curvature_detail(V, F))
    assert np.array_equal(vertex_attribute(ms, 0, "curvature_area", "scalar"), A)


def test_quality_is_half_k_dot_area_weighted_normal():
    ms = meshset("mannequin_nose.obj")
    apply(ms, "compute_curvature_detail")
    V, F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    K, _ = mean_curvature_normal(V, F)
    H = 0.5 * np.einsum("ij,ij->i", K, vertex_normals(V, F))
    assert np.allclose(ms.current_mesh().vertex_scalar_array(), H, rtol=0, atol=1e-12 * np.abs(H).max())


def test_figures_are_range_and_percentiles_of_interior_h():
    ms = meshset("terrainA_1k.obj")
    figures = apply(ms, "compute_curvature_detail")
    F = ms.current_mesh().face_matrix()
    interior = np.setdiff1d(np.arange(ms.current_mesh().vertex_number()), boundary_vertices(F))
    H = ms.current_mesh().vertex_scalar_array()[interior]
    assert figures["curv_range_min"] == H.min() and figures["curv_range_max"] == H.max()
    assert figures["10_percentile"] == pytest.approx(np.percentile(H, 10), rel=1e-12)
    assert figures["90_percentile"] == pytest.approx(np.percentile(H, 90), rel=1e-12)
    assert figures["interior_vertices"] == 1089 - 128 and figures["boundary_vertices"] == 128


def test_a_mesh_without_interior_vertices_has_no_h_figures():
    # a strip of four triangles, every vertex on the boundary: the figures were the boundary
    # vertices' H (geodesic curvature), which the description says are left out
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.3], [0, 2, 0], [1, 2, 0]], float)
    F = np.array([[0, 1, 3], [0, 3, 2], [2, 3, 5], [2, 5, 4]])
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F))
    figures = apply(ms, "compute_curvature_detail")
    assert [figures[k] for k in ("curv_range_min", "curv_range_max", "10_percentile", "90_percentile")] \
        == [None] * 4
    assert figures["interior_vertices"] == 0 and figures["boundary_vertices"] == 6
    # two triangles of area sqrt(1.09) / 2, one of sqrt(1.18) / 2, one of 1 / 2
    assert figures["surface_area"] == pytest.approx(np.sqrt(1.09) + np.sqrt(1.18) / 2 + 0.5, rel=1e-12)


def test_mean_curvature_is_positive_one_over_radius_on_a_sphere():
    # icosphere of radius 2 (2562 vertices): discrete H within 0.1 % of 1/R = 0.5
    V, F = icosphere(radius=2.0, subdivisions=4)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32)))
    figures = apply(ms, "compute_curvature_detail")
    assert 0.4995 < figures["curv_range_min"] <= figures["curv_range_max"] < 0.5005
    assert figures["surface_area"] == pytest.approx(4 * np.pi * 4.0, rel=2e-3)


def test_matches_pymeshlab_mean_curvature_on_spot():
    # pymeshlab's discrete mean curvature (same cotangent formula, its own vertex normals for the
    # sign) on the closed cow: same sign convention and, for 99 % of the vertices, the same value
    # to 0.5 % of the largest |H| (measured: 0.22 %; the rest differ where normals disagree).
    ms = meshset("spot.obj")
    apply(ms, "compute_curvature_detail")
    ours = ms.current_mesh().vertex_scalar_array().copy()
    ms.compute_scalar_by_discrete_curvature_per_vertex(curvaturetype="Mean Curvature")
    theirs = ms.current_mesh().vertex_scalar_array()
    gap = np.abs(ours - theirs) / np.abs(ours).max()
    assert np.percentile(gap, 99) < 5e-3


def test_running_again_after_moving_vertices_updates_the_attributes():
    ms = meshset("mannequin_nose.obj")
    apply(ms, "compute_curvature_detail")
    V, F = ms.current_mesh().vertex_matrix() * 3.0, ms.current_mesh().face_matrix()
    set_vertex_positions(ms, 0, V)
    apply(ms, "compute_curvature_detail")
    assert np.array_equal(vertex_attribute(ms, 0, "curvature_detail", "point"), curvature_detail(V, F))


def test_reversed_triangles_are_refused_not_given_random_signs():
    # half the sphere's triangles reversed: H came out +-1/R at random, without a word
    from curvdetail import MeshError

    V, F = icosphere(radius=2.0, subdivisions=3)
    F = F.copy()
    F[::2] = F[::2, ::-1]
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F))
    with pytest.raises(MeshError, match="meshing_re_orient_faces_coherently") as e:       # the repair filter
        apply(ms, "compute_curvature_detail")
    assert e.value.parameter == "F" and e.value.count > 0
