"""Curvature detail carried to a retriangulation (curvdetail.remesh.transfer)."""

import numpy as np
import pytest

from curvdetail.curvature import curvature_detail, mixed_voronoi_area
from curvdetail.curvature.errors import MeshError
from curvdetail.curvature.testing import grid, icosphere
from curvdetail.remesh import edge_curvature_measure, retriangulate, transfer_curvature
from curvdetail.curvature import boundary_loop


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


def _bad_mesh(kind):
    V, F = grid(5, 5)
    if kind == "nan vertex":
        V[3, 0] = np.nan
    elif kind == "zero area":
        V[F[7, 0]] = V[F[7, 1]]
    return {"nan vertex": (V, F), "zero area": (V, F), "(m, 4) F": (V, np.c_[F, F[:, :1]]),
            "negative index": (V, F - 1), "empty F": (V, F[:0]), "bool V": (V.astype(bool), F),
            "None V": (None, F), "index out of range": (V, F + 100), "float F": (V, F + 0.5)}[kind]


@pytest.mark.parametrize("kind, words", [
    ("nan vertex", r"V: 1 vertices have NaN or infinite coordinates \(first: 3\)"),
    ("zero area", r"triangles have zero area \(first: .*7"),
    ("(m, 4) F", r"F has shape \(32, 4\)"),
    ("negative index", "vertex indices outside"),
    ("empty F", "F is empty"),
    ("bool V", "V has dtype bool"),
    ("None V", "V has dtype object"),
    ("index out of range", "vertex indices outside"),
    ("float F", "F has non-integer entries"),
])
def test_edge_measure_refuses_malformed_meshes_by_name(kind, words):
    # it had no checks: NaN came out silently for a NaN vertex or a zero-area triangle, (m, 4)
    # and negative indices were taken, other cases raised numpy errors
    with pytest.raises(MeshError, match=words):
        edge_curvature_measure(*_bad_mesh(kind))


@pytest.mark.parametrize("value, words", [
    (0, "at least 1"), (-1, "at least 1"), (2.5, "whole number"), ("5", "whole number"),
    (True, "whole number"), (np.inf, "whole number"),
    (10 ** 30, r"asks for 5.6e\+31 edge samples, more than 20,000,000"),
])
def test_samples_per_edge_must_be_a_sane_whole_number(value, words):
    # 0 and -1 were clamped to 1, 2.5 truncated, "5" and True accepted, 10**30 an OverflowError
    V, F = grid(5, 5)
    with pytest.raises(ValueError, match=words):
        transfer_curvature(V, F, V, F, samples_per_edge=value)


def test_options_that_would_be_ignored_are_refused():
    V, F = grid(5, 5)
    uv = (V[:, :2], V[:, :2])
    with pytest.raises(ValueError, match="uv is only used with location='uv'"):
        transfer_curvature(V, F, V, F, location="closest", uv=uv)
    with pytest.raises(ValueError, match="samples_per_edge is used by method='conservative' only"):
        transfer_curvature(V, F, V, F, method="pointwise", samples_per_edge=3)


def test_malformed_uv_is_named_as_uv():
    # uv=5 raised a TypeError; a NaN in uv was reported as "points: ... rows are NaN"
    V, F = grid(5, 5)
    with pytest.raises(ValueError, match=r"needs uv=\(UVs, UVt\), a pair of arrays.*got int"):
        transfer_curvature(V, F, V, F, location="uv", uv=5)
    UV = V[:, :2].copy()
    UV[4, 1] = np.nan
    with pytest.raises(MeshError, match=r"uv\[0\] \(UVs\): 1 vertices have NaN .*\(first: 4\)"):
        transfer_curvature(V, F, V, F, location="uv", uv=(UV, V[:, :2]))
    with pytest.raises(MeshError, match=r"uv\[1\] \(UVt\) has dtype <U"):
        transfer_curvature(V, F, V, F, location="uv", uv=(V[:, :2], V[:, :2].astype(str)))


@pytest.mark.parametrize("method", ["conservative", "pointwise"])
def test_a_target_that_is_not_the_same_surface_is_refused(load_mesh, method):
    # the closest point of a far target would silently give it the wrong detail
    V, F = load_mesh("mannequin_nose.obj")
    with pytest.raises(MeshError, match=r"source and target lie up to .* % of the source's bbox diagonal apart"):
        transfer_curvature(V, F, V + [0.0, 0.0, 1000.0], F, method=method)
    D = transfer_curvature(V, F, V + [0.0, 0.0, 1e-3], F, method=method)       # a slight offset is fine
    assert np.all(np.isfinite(D))
