"""anchor_vertices and the reconstruction of closed surfaces, several pieces and several loops."""

import numpy as np
import pytest

from curvdetail import ConstraintError, Reconstructor, anchor_vertices, boundary_vertices, curvature_detail, reconstruct
from curvdetail.curvature.cotan_laplacian import cotan_laplacian
from curvdetail.curvature.geometry import bbox_diagonal
from curvdetail.curvature.testing import cylinder, icosphere


def torus(R=1.0, r=0.35, n_major=48, n_minor=20):
    """A closed genus-1 torus around the z axis."""
    u = 2 * np.pi * np.arange(n_major) / n_major
    v = 2 * np.pi * np.arange(n_minor) / n_minor
    U, W = np.meshgrid(u, v, indexing="ij")
    V = np.column_stack([((R + r * np.cos(W)) * np.cos(U)).ravel(), ((R + r * np.cos(W)) * np.sin(U)).ravel(),
                         (r * np.sin(W)).ravel()])
    i, j = np.meshgrid(np.arange(n_major), np.arange(n_minor), indexing="ij")
    a = (i * n_minor + j).ravel()
    b = (((i + 1) % n_major) * n_minor + j).ravel()
    c = (i * n_minor + (j + 1) % n_minor).ravel()
    d = (((i + 1) % n_major) * n_minor + (j + 1) % n_minor).ravel()
    return V, np.concatenate([np.column_stack([a, b, d]), np.column_stack([a, d, c])])


def two_spheres():
    V, F = icosphere(subdivisions=3)
    return np.vstack([V, V + [3.0, 0.5, 0.0]]), np.vstack([F, F + V.shape[0]])


@pytest.mark.parametrize("rows", ["free", "all"])
def test_closed_sphere_rebuilt_from_its_detail_with_one_anchor(rows):
    V, F = icosphere(radius=2.0, subdivisions=4)
    a = anchor_vertices(V, F)
    assert a.size == 1
    X = reconstruct(V, F, curvature_detail(V, F), a, V[a], rows=rows)
    assert abs(X - V).max() < 1e-10 * bbox_diagonal(V)


def test_torus_rebuilt_from_its_detail_with_one_anchor():
    V, F = torus()
    a = anchor_vertices(V, F)
    X = reconstruct(V, F, curvature_detail(V, F), a, V[a], rows="free")
    assert a.size == 1 and abs(X - V).max() < 1e-10 * bbox_diagonal(V)


def test_free_rows_system_of_a_closed_piece_with_one_anchor_is_nonsingular():
    # L is singular on a closed piece (L 1 = 0); L_ff with one vertex removed is positive definite
    V, F = icosphere(subdivisions=2)
    L = cotan_laplacian(V, F).toarray()
    free = np.setdiff1d(np.arange(V.shape[0]), anchor_vertices(V, F))
    assert np.linalg.eigvalsh(L)[0] == pytest.approx(0.0, abs=1e-10)
    assert np.linalg.eigvalsh(L[np.ix_(free, free)])[0] > 1e-3


def test_flattest_vertex_is_the_anchor():
    V, F = icosphere(subdivisions=3)
    V[:, 2] *= 0.5                           # an ellipsoid: flattest at the poles (0, 0, +-0.5)
    a = anchor_vertices(V, F)
    assert abs(V[a[0], 2]) == pytest.approx(0.5)


def test_k_anchors_by_farthest_point_sampling():
    V, F = icosphere(subdivisions=3)
    a = anchor_vertices(V, F, k=2)
    assert a.size == 2 and np.linalg.norm(V[a[0]] - V[a[1]]) == pytest.approx(2.0)   # antipodes


def test_two_pieces_each_get_an_anchor_and_are_rebuilt():
    V, F = two_spheres()
    a = anchor_vertices(V, F)
    n = V.shape[0] // 2
    assert a.size == 2 and (a < n).sum() == 1
    X = reconstruct(V, F, curvature_detail(V, F), a, V[a], rows="all")
    assert abs(X - V).max() < 1e-10 * bbox_diagonal(V)


def test_boundary_loops_are_fixed_and_a_piece_with_boundary_gets_no_anchor():
    Vc, Fc = cylinder(n_around=24, n_along=9)              # two boundary loops
    Vs, Fs = icosphere(subdivisions=2)
    V, F = np.vstack([Vc, Vs + 5.0]), np.vstack([Fc, Fs + Vc.shape[0]])
    a = anchor_vertices(V, F)
    b = boundary_vertices(F)
    assert np.isin(b, a).all() and a.size == b.size + 1 and a[-1] >= Vc.shape[0]


def test_a_given_fixed_vertex_settles_its_piece():
    V, F = two_spheres()
    a = anchor_vertices(V, F, fixed=[5])
    assert a.size == 2 and a[0] == 5


def test_no_fixed_vertex_names_the_parameter():
    V, F = icosphere(subdivisions=1)
    with pytest.raises(ConstraintError) as e:
        Reconstructor(V, F, [])
    assert e.value.parameter == "fixed" and e.value.count == 0


def test_bad_k_is_refused():
    with pytest.raises(ValueError):
        anchor_vertices(*icosphere(subdivisions=1), k=0)
