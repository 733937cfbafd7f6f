"""Curvature detail carried to a retriangulation (curvdetail.remesh.transfer)."""

import numpy as np
import pytest

from curvdetail.curvature import curvature_detail, mixed_voronoi_area
from curvdetail.curvature.testing import icosphere
from curvdetail.remesh import edge_curvature_measure, retriangulate, transfer_curvature
from curvdetail.remesh._disk import boundary_loop


def _cap(radius=2.0):
    V, F = icosphere(radius=radius, subdivisions=4)
    keep = V[:, 2] > 0.5 * radius
    faces = F[keep[F].all(axis=1)]
    used = np.unique(faces)
    remap = np.full(V.shape[0], -1)
    remap[used] = np.arange(used.size)
    return V[used], remap[faces]


def test_edge_measure_halves_give_the_vertex_detail(load_mesh):
    V, F = load_mesh("mannequin_ear.obj")
    E, c = edge_curvature_measure(V, F)
    D = np.zeros_like(V)
    np.add.at(D, E[:, 0], 0.5 * c)
    np.add.at(D, E[:, 1], 0.5 * c)
    assert np.abs(D - curvature_detail(V, F)).max() < 1e-14


def test_conservative_transfer_onto_the_same_mesh_is_exact(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    assert np.abs(transfer_curvature(V, F, V, F) - curvature_detail(V, F)).max() < 1e-14


def test_pointwise_transfer_onto_the_same_mesh_is_exact(load_mesh):
    # each target vertex is located on itself (one-hot barycentrics), so D_t = K(x_t) A_t = D
    V, F = load_mesh("mannequin_nose.obj")
    D = curvature_detail(V, F)
    assert np.abs(transfer_curvature(V, F, V, F, method="pointwise") - D).max() < 1e-12 * np.abs(D).max()


def test_conservative_transfer_keeps_the_total_detail(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    Vt, Ft = retriangulate(V, F, target_edge=0.03)
    Ds = curvature_detail(V, F)
    scale = np.abs(Ds).sum()
    Dt = transfer_curvature(V, F, Vt, Ft, method="conservative")
    assert np.abs(Dt.sum(0) - Ds.sum(0)).max() <= 1e-12 * scale
    # the pointwise transfer does not conserve it (K A_t sums differently near the boundary)
    Dp = transfer_curvature(V, F, Vt, Ft, method="pointwise")
    assert np.abs(Dp.sum(0) - Ds.sum(0)).max() > 1e-3 * scale


@pytest.mark.parametrize("method", ["conservative", "pointwise"])
@pytest.mark.parametrize("location", ["closest", "uv"])
def test_sphere_cap_detail_is_two_over_r_normal_on_the_target(method, location):
    R = 2.0
    V, F = _cap(R)
    Vt, Ft = retriangulate(V, F, target_edge=0.04)
    uv = None
    if location == "uv":
        from curvdetail.remesh import parameterize

        UVs, UVt, _ = parameterize(V, F, Vt, Ft)
        uv = (UVs, UVt)
    Dt = transfer_curvature(V, F, Vt, Ft, method=method, location=location, uv=uv)
    K = Dt / mixed_voronoi_area(Vt, Ft)[:, None]
    interior = np.setdiff1d(np.arange(Vt.shape[0]), boundary_loop(Ft))
    # away from the boundary ring (its star catches the boundary's geodesic-curvature term)
    far = interior[Vt[interior, 2] > 0.6 * R]
    normal = Vt[far] / R
    # |K| = 2/R = 1 on the sphere, along the outward normal; the discrete K of the 2562-vertex
    # source is within ~2 % of it, the local transfer adds a few % per vertex
    assert np.median(np.abs((K[far] * normal).sum(1) - 2.0 / R)) < 0.05
    assert np.median(np.linalg.norm(K[far] - (K[far] * normal).sum(1)[:, None] * normal, axis=1)) < 0.05


def test_bad_options_are_refused(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    with pytest.raises(ValueError, match="not a transfer"):
        transfer_curvature(V, F, V, F, method="nearest")
    with pytest.raises(ValueError, match="needs uv="):
        transfer_curvature(V, F, V, F, location="uv")
