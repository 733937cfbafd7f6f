"""Curvature coefficients: D_i = sum_j C_ij D_j, minimum norm, invariant, batched and robust."""

import warnings

import numpy as np
import pytest

from curvdetail import curvature_coefficients, curvature_detail
from curvdetail.curvature.errors import CurvdetailError, MeshError
from curvdetail.curvature.testing import grid


def _rotation(rng):
    Q, R = np.linalg.qr(rng.normal(size=(3, 3)))
    Q = Q * np.sign(np.diag(R))
    return Q if np.linalg.det(Q) > 0 else -Q


@pytest.mark.parametrize("name", ["mannequin_nose.obj", "mannequin_ear.obj", "spot.obj", "terrainA_1k.obj"])
def test_full_rank_rings_reproduce_detail_on_real_meshes(load_mesh, name):
    V, F = load_mesh(name)
    C, info = curvature_coefficients(V, F, return_info=True)
    D = curvature_detail(V, F)
    full = info.rank == 3
    # A rank-3 ring spans R^3, so the fit is exact up to the 3x3 pseudo-inverse's roundoff
    # (cond(G) up to ~1e10 on these meshes, i.e. ~1e-6 relative in the worst ring).
    rel = np.linalg.norm(D - C @ D, axis=1)[full] / info.scale[full]
    assert full.mean() > 0.99
    assert rel.max() < 1e-6
    assert np.allclose(info.residual, np.linalg.norm(D - C @ D, axis=1))
    assert info.rank_deficient == np.count_nonzero(~full)


def test_pattern_is_the_one_ring_with_zero_diagonal(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    edges = {tuple(e) for f in F for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}
    edges |= {(j, i) for i, j in edges}
    C = curvature_coefficients(V, F, max_ring=1)
    coo = C.tocoo()
    assert set(zip(coo.row.tolist(), coo.col.tolist())) == edges
    assert np.all(C.diagonal() == 0)
    # by default the one corner whose one-ring cannot hold its detail (vertex 95, valence 2)
    # stores its two-ring instead; every other row keeps the one-ring
    C, info = curvature_coefficients(V, F, return_info=True)
    assert info.widened_vertices.tolist() == [95]
    ring1 = {j for i, j in edges if i == 95}
    ring2 = ring1 | {k for i, k in edges if i in ring1} - {95}
    coo = C.tocoo()
    pairs = set(zip(coo.row.tolist(), coo.col.tolist()))
    assert {p for p in pairs if p[0] != 95} == {e for e in edges if e[0] != 95}
    assert {j for i, j in pairs if i == 95} == ring2
    assert np.all(C.diagonal() == 0)


def _corner_strip():
    # a bent strip: vertex 0 is a corner of one triangle (valence 2), its Gram matrix is singular
    V = np.array([[0, 0, 0], [1, 0, 0.3], [0, 1, 0.2], [1, 1, 0.9], [2, 0.5, 0.1]], float)
    F = np.array([[0, 1, 2], [1, 3, 2], [1, 4, 3]])
    return V, F


def test_a_corner_whose_one_ring_misses_its_detail_takes_its_two_ring():
    # the corner's two neighbours span a plane its detail leaves: the one-ring relation cannot
    # hold (residual 10 % of the ring's scale); over the two-ring (vertices 1-4) it holds exactly,
    # and the row is the minimum-norm solution there, as np.linalg.pinv gives it
    V, F = _corner_strip()
    D = curvature_detail(V, F)
    _, narrow = curvature_coefficients(V, F, max_ring=1, return_info=True)
    assert narrow.residual[0] > 1e-2 * narrow.scale[0]
    C, info = curvature_coefficients(V, F, return_info=True)
    assert info.ring[0] == 2 and 0 in info.widened_vertices        # (vertex 4 is such a corner too)
    expected = np.linalg.pinv(D[[1, 2, 3, 4]].T) @ D[0]
    assert np.allclose(C[0, [1, 2, 3, 4]].toarray().ravel(), expected, rtol=1e-9)
    assert info.residual[0] < 1e-12 * info.scale[0]


def test_widened_rows_keep_the_coefficients_invariant(load_mesh, rng):
    # terrainA_1k's two valence-2 grid corners are widened; the decision and the rows are the
    # same for a rotated, scaled, translated copy
    V, F = load_mesh("terrainA_1k.obj")
    C, info = curvature_coefficients(V, F, return_info=True)
    assert info.widened_vertices.size == 2
    C2, info2 = curvature_coefficients(2.5 * V @ _rotation(rng).T + 7.0, F, return_info=True)
    assert np.array_equal(info.widened_vertices, info2.widened_vertices)
    assert abs(C2 - C).max() < 1e-8


def test_coefficients_are_invariant_under_rotation_and_uniform_scale(load_mesh, rng):
    V, F = load_mesh("spot.obj")
    C = curvature_coefficients(V, F)
    C2 = curvature_coefficients(2.5 * V @ _rotation(rng).T + [3.0, -1.0, 7.0], F)
    # D -> 2.5 R D leaves the minimum-norm solution unchanged; the difference is roundoff
    # amplified by the ring's conditioning (coefficients are O(1), max |c| ~ 6 here).
    assert abs(C2 - C).max() < 1e-8


@pytest.mark.parametrize("scale", [1e-58, 1e70])
def test_coefficients_at_extreme_scales_are_the_same_and_quiet(load_mesh, scale):
    # the closed-form cofactors overflow at 1e70 (G ~ 1e140 per entry): those rings take the SVD
    # path, without numpy's overflow warnings reaching the user
    V, F = load_mesh("mannequin_nose.obj")
    C = curvature_coefficients(V, F)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        C2 = curvature_coefficients(scale * V, F)
    assert abs(C2 - C).max() < 1e-8


def test_coefficients_of_a_mesh_too_small_for_its_areas_are_refused_by_name(load_mesh):
    # 0.9e-60 across: the triangle areas (~1e-122 per face) are on their way to underflow
    V, F = load_mesh("mannequin_nose.obj")
    with pytest.raises(MeshError, match=r"\b1e-60\b") as e:               # the limit
        curvature_coefficients(1e-60 * V, F)
    assert e.value.parameter == "V" and e.value.value < 1e-60


def test_coefficients_are_the_minimum_norm_solution(load_mesh, rng):
    V, F = load_mesh("mannequin_ear.obj")
    C = curvature_coefficients(V, F).tocsr()
    D = curvature_detail(V, F)
    for i in rng.choice(V.shape[0], size=25, replace=False):
        nbrs = C.indices[C.indptr[i]:C.indptr[i + 1]]
        expected = np.linalg.pinv(D[nbrs].T, rcond=1e-6) @ D[i]
        got = C.data[C.indptr[i]:C.indptr[i + 1]]
        # pinv works on D_N itself, we on its Gram matrix: they agree to ~cond * 1e-16
        assert np.allclose(got, expected, rtol=1e-6, atol=1e-7 * np.abs(expected).max())


def test_flat_plane_rings_are_rank_deficient_with_zero_coefficients(plane_grid):
    V, F = plane_grid
    C, info = curvature_coefficients(V, F, return_info=True)
    xy = V[:, :2]
    deep = ((xy > 0.1 - 1e-9) & (xy < 0.9 + 1e-9)).all(axis=1)   # rings away from the boundary
    assert np.all(np.isfinite(C.data))
    assert np.all(info.rank[deep] == 0)
    assert abs(C[np.flatnonzero(deep)]).max() == 0.0       # flat: D_i = 0 is kept exactly
    assert info.rank_deficient == np.count_nonzero(info.rank < 3) >= deep.sum()
    assert np.array_equal(info.rank_deficient_vertices, np.flatnonzero(info.rank < 3))


def test_cylinder_rings_are_rank_two_and_still_reproduce_detail(open_cylinder):
    V, F = open_cylinder
    C, info = curvature_coefficients(V, F, return_info=True)
    D = curvature_detail(V, F)
    z = V[:, 2]
    inner = (z > z.min() + 0.25) & (z < z.max() - 0.25)   # two rings away from the rims
    assert np.all(info.rank[inner] == 2)                   # all details are radial: coplanar
    assert info.rank_deficient >= inner.sum()
    assert np.all(np.isfinite(C.data))
    # the radial detail lies in the span of the radial neighbours: still represented exactly
    rel = np.linalg.norm(D - C @ D, axis=1)[inner] / np.linalg.norm(D[inner], axis=1)
    assert rel.max() < 1e-9


def test_valence_two_corner_gets_the_pseudo_inverse_not_garbage():
    # with the one-ring only, the corner's singular Gram matrix takes the pseudo-inverse
    V, F = _corner_strip()
    C, info = curvature_coefficients(V, F, max_ring=1, return_info=True)
    D = curvature_detail(V, F)
    expected = np.linalg.pinv(D[[1, 2]].T) @ D[0]
    assert info.rank[0] == 2
    assert np.allclose(C[0, [1, 2]].toarray().ravel(), expected, rtol=1e-9)


@pytest.mark.parametrize("max_ring", [0, -1, 1.5, "2", True])
def test_bad_max_ring_is_refused(plane_grid, max_ring):
    V, F = plane_grid
    with pytest.raises(ValueError, match="max_ring"):
        curvature_coefficients(V, F, max_ring=max_ring)


@pytest.mark.parametrize("value", ["no", np.array([True, False])])
def test_return_info_must_be_a_bool(plane_grid, value):
    V, F = plane_grid
    with pytest.raises(ValueError, match="return_info"):
        curvature_coefficients(V, F, return_info=value)


@pytest.mark.parametrize("rcond", [0.0, 1.0, -1e-3, "abc"])
def test_bad_rcond_is_refused(plane_grid, rcond):
    with pytest.raises(ValueError, match="rcond"):
        curvature_coefficients(*plane_grid, rcond=rcond)


@pytest.mark.parametrize("rcond", ["1e-6", True, np.True_, None])
def test_rcond_that_is_not_a_number_is_refused_even_if_float_takes_it(plane_grid, rcond):
    # "1e-6" and True went through float() (the other numeric parameters refuse them)
    with pytest.raises(CurvdetailError) as e:
        curvature_coefficients(*plane_grid, rcond=rcond)
    assert (e.value.parameter, e.value.value) == ("rcond", rcond)



def test_rcond_takes_numpy_scalars(plane_grid):
    from curvdetail.curvature.curvature_coefficients import check_rcond

    assert check_rcond(np.float32(1e-3)) == pytest.approx(1e-3) and check_rcond(np.array(1e-6)) == 1e-6


def test_malformed_mesh_is_refused_before_any_algebra(plane_grid):
    V, F = plane_grid
    bad = F.copy()
    bad[3, 1] = V.shape[0] + 5
    with pytest.raises(MeshError, match="outside"):
        curvature_coefficients(V, bad)


def test_a_rotation_does_not_move_the_flatness_threshold():
    # the threshold's length was the bounding-box diagonal, which a 45-degree turn of a square
    # lengthens from 1.41 to 2: rings of curvature 5.9e-7 counted as flat before the turn and
    # not after, and 64 rows of C changed by 0.17
    V, F = grid(12, 12)
    V[:, :2] -= 0.5
    V[:, 2] = 0.5 * 5.9e-7 * V[:, 0] ** 2
    c = np.cos(np.pi / 4)
    turn = np.array([[c, -c, 0.0], [c, c, 0.0], [0.0, 0.0, 1.0]])
    C, info = curvature_coefficients(V, F, return_info=True)
    C_turned, info_turned = curvature_coefficients(V @ turn.T, F, return_info=True)
    assert np.array_equal(info.rank, info_turned.rank)
    assert abs(C_turned - C).max() < 1e-12


def test_nearly_planar_rings_keep_their_coefficients_under_rotation():
    # rings whose details nearly lie in a plane (third singular value ~1e-5 of the first, kept):
    # G's eigenvalues carry ~1e-16 of the largest, so that singular value came out to ~1e-6 of
    # itself and the coefficients changed by 1.4e-5 of their size under a rotation and scale
    # (fandisk: 46 rows by more than 1e-6); through the SVD of the ring matrix, ~1e-10
    from curvdetail.curvature.curvature_coefficients import _coefficients

    worst = 0.0
    for seed in range(20):
        rng = np.random.default_rng(seed)
        k = 6
        D = np.zeros((k + 1, 3))
        D[1:] = rng.normal(size=(k, 3)) * [1.0, 0.3, 1e-5] @ _rotation(rng).T
        D[0] = rng.normal(size=3)
        rows, cols = np.zeros(k, dtype=np.int64), np.arange(1, k + 1)
        C, C2 = (_coefficients(X, np.ones(k + 1), rows, cols, k + 1, 1e-6, 1.0)[0][0, 1:].toarray().ravel()
                 for X in (D, 2.5 * D @ _rotation(rng).T))
        worst = max(worst, np.abs(C - C2).max() / np.abs(C).max())
    assert worst < 1e-8


def test_rings_are_padded_by_their_own_size_not_the_largest(monkeypatch):
    # a gently curved disc meshed as a polar grid: one pole of valence 128 among ~6,500 rings of
    # valence 6 whose singular values need the SVD (the pole's too). Padding every ring to the
    # pole's size made the SVD input rows x 128 x 3 (a 1M-vertex mesh with a pole of valence
    # 2048: ~100 GB); each batch is now at most twice as wide as its widest ring, and the
    # coefficients are those of pinv
    S, R = 128, 60
    r = np.linspace(0, 1, R + 1)[1:]
    a = np.linspace(0, 2 * np.pi, S, endpoint=False)
    x, y = (r[:, None] * np.cos(a)).ravel(), (r[:, None] * np.sin(a)).ravel()
    V = np.r_[[[0.0, 0.0, 0.02 * np.sin(1.0)]], np.c_[x, y, 0.02 * np.sin(2 * x + 1) * np.cos(3 * y)]]
    idx = 1 + np.arange(R * S).reshape(R, S)
    nxt = np.roll(idx, -1, axis=1)
    F = np.concatenate([np.c_[np.zeros(S, dtype=int), idx[0], nxt[0]],
                        np.c_[idx[:-1].ravel(), idx[1:].ravel(), nxt[1:].ravel()],
                        np.c_[idx[:-1].ravel(), nxt[1:].ravel(), nxt[:-1].ravel()]])
    widths = []
    svd = np.linalg.svd

    def spy(M, *args, **kwargs):
        widths.append(M.shape)
        return svd(M, *args, **kwargs)

    monkeypatch.setattr(np.linalg, "svd", spy)
    C = curvature_coefficients(V, F)
    monkeypatch.undo()
    assert sum(batch for batch, _, _ in widths) > 1000                  # the SVD path really ran
    assert sum(batch for batch, width, _ in widths if width > 16) == 1          # the pole alone
    assert max(width for _, width, _ in widths if width <= 16) <= 16
    D = curvature_detail(V, F)
    for i in (0, 1, S + 1):                                             # the pole and two rings
        ring = C[i].indices
        expected = np.linalg.pinv(D[ring].T, rcond=1e-6) @ D[i]
        assert np.abs(C[i, ring].toarray().ravel() - expected).max() < 1e-9 * np.abs(expected).max()


def test_rings_still_unresolved_at_max_ring_keep_their_widest_fit():
    # a 3 x 3 grid with two lifted corners: vertices 2 and 6 cannot represent their detail even
    # from their two-rings; with max_ring=2 their rows are the minimum-norm fit over the two-ring
    # (dropping those rows' entries left them empty and passed every other test)
    V, F = grid(3, 3)
    V[2, 2], V[6, 2] = 0.04, 0.08
    D = curvature_detail(V, F)
    C, info = curvature_coefficients(V, F, max_ring=2, return_info=True)
    edges = {tuple(e) for f in F for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}
    edges |= {(j, i) for i, j in edges}
    for i in (2, 6):
        assert info.ring[i] == 2 and info.residual[i] > info.rcond * info.scale[i]
        ring1 = {j for a, j in edges if a == i}
        ring2 = sorted(ring1 | {k for a, k in edges if a in ring1} - {i})
        assert C[i].indices.tolist() == ring2
        expected = np.linalg.pinv(D[ring2].T, rcond=1e-6) @ D[i]
        assert np.allclose(C[i, ring2].toarray().ravel(), expected, rtol=1e-9, atol=1e-12)


def _tetrahedron():
    # vertex 3's three neighbours' details have sigma_3 / sigma_1 = 0.277: truncated at rcond=0.3
    V = np.array([[0, 0, 0], [1, 0, 0], [0.2, 1, 0], [0.3, 0.3, 0.15]], float)
    F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]])
    return V, F


def test_a_ring_that_stops_growing_reports_the_ring_its_coefficients_span():
    # a tetrahedron: every one-ring is the rest of the mesh, so the two-ring adds nothing. At
    # rcond=0.3 vertex 3's truncated fit leaves a residual above the threshold; the row kept its
    # one-ring coefficients but was reported as ring 3 (max_ring) and listed as widened
    V, F = _tetrahedron()
    D = curvature_detail(V, F)
    C, info = curvature_coefficients(V, F, rcond=0.3, return_info=True)
    assert info.residual[3] > info.rcond * info.scale[3]          # still unresolved
    assert info.ring.tolist() == [1, 1, 1, 1] and info.widened_vertices.size == 0
    narrow, narrow_info = curvature_coefficients(V, F, rcond=0.3, max_ring=1, return_info=True)
    assert (C != narrow).nnz == 0 and np.array_equal(info.rank, narrow_info.rank)
    expected = np.linalg.pinv(D[[0, 1, 2]].T, rcond=0.3) @ D[3]
    assert np.allclose(C[3, [0, 1, 2]].toarray().ravel(), expected, rtol=1e-12)


def test_a_ring_that_stops_growing_after_one_widening_reports_ring_two():
    # the bent strip at rcond=0.2: corner 4's two-ring is its whole piece (vertices 0-3) and
    # still leaves a residual above the threshold; the three-ring is the same set (reported 3)
    V, F = _corner_strip()
    C, info = curvature_coefficients(V, F, rcond=0.2, return_info=True)
    assert info.residual[4] > info.rcond * info.scale[4]
    assert info.ring[4] == 2 and info.widened_vertices.tolist() == [4]
    assert C[4].indices.tolist() == [0, 1, 2, 3]
    C2, info2 = curvature_coefficients(V, F, rcond=0.2, max_ring=2, return_info=True)
    assert (C != C2).nnz == 0 and np.array_equal(info.ring, info2.ring)


def test_rows_without_neighbours_stay_at_ring_one():
    # rows with an empty pattern (only vertex 0 has neighbours) cannot fit their non-zero
    # detail; widening adds nothing to them, and they were reported as ring max_ring
    from curvdetail.curvature.curvature_coefficients import _coefficients

    rng = np.random.default_rng(3)
    D = rng.normal(size=(5, 3))
    rows, cols = np.zeros(4, dtype=np.int64), np.arange(1, 5)
    C, rank, _, ring = _coefficients(D, np.ones(5), rows, cols, 5, 1e-6, 1.0, max_ring=3)
    assert ring.tolist() == [1, 1, 1, 1, 1]
    assert C.nnz == 4 and C[0].indices.tolist() == [1, 2, 3, 4] and rank[1:].tolist() == [0, 0, 0, 0]
    assert np.allclose(C @ D, np.r_[[D[0]], np.zeros((4, 3))])


def test_edges_of_zero_cotangent_weight_stay_in_the_pattern():
    # a flat grid's diagonals have cotangent weight 0 (two right angles), stored in L as explicit
    # zeros; C's pattern, read off L's, still holds every mesh edge in both directions
    from curvdetail.curvature.cotan_laplacian import cotan_laplacian

    V, F = grid(6, 5)
    L = cotan_laplacian(V, F).tocoo()
    assert np.count_nonzero((L.data == 0) & (L.row != L.col)) == 2 * 20     # the 20 diagonals
    edges = {tuple(e) for f in F for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}
    edges |= {(j, i) for i, j in edges}
    coo = curvature_coefficients(V, F).tocoo()
    assert set(zip(coo.row.tolist(), coo.col.tolist())) == edges and coo.nnz == len(edges)


def test_rows_sent_to_the_svd_without_eigenvalues_are_those_the_eigenvalues_send(rng):
    # the shortcut tells from G's invariants which rows certainly go through the SVD; it must
    # never take a row that G's eigenvalues would not send there (sigma_2 / sigma_1 near the
    # band's ends: 1e-7 and 1e-3, over 35 orders of magnitude of scale)
    from curvdetail.curvature.curvature_coefficients import SVD_BAND, _surely_in_svd_band

    k = 200_000
    Q = np.stack([_rotation(np.random.default_rng(s)) for s in range(64)])[rng.integers(0, 64, k)]
    ratio_2 = np.exp(rng.uniform(np.log(1e-8), np.log(1e-2), k))
    ratio_2[:20_000] = 1e-3 * (1 + rng.uniform(-3e-4, 3e-4, 20_000))       # at the band's top
    ratio_2[20_000:40_000] = 1e-7 * np.exp(rng.uniform(-2, 2, 20_000))     # and its bottom
    ratio_3 = ratio_2 * np.exp(rng.uniform(np.log(1e-6), 0, k))
    sigma = np.c_[np.ones(k), ratio_2, ratio_3] * np.exp(rng.uniform(-20, 20, k))[:, None]
    G = np.einsum("kab,kb,kcb->kac", Q, sigma ** 2, Q)
    c00 = G[:, 1, 1] * G[:, 2, 2] - G[:, 1, 2] ** 2
    c11 = G[:, 0, 0] * G[:, 2, 2] - G[:, 0, 2] ** 2
    c22 = G[:, 0, 0] * G[:, 1, 1] - G[:, 0, 1] ** 2
    sure = _surely_in_svd_band(c00, c11, c22, G[:, 0, 0] + G[:, 1, 1] + G[:, 2, 2])
    s = np.sqrt(np.maximum(np.linalg.eigvalsh(G), 0.0))
    in_band = ((s[:, :2] / s[:, 2:] > SVD_BAND[0]) & (s[:, :2] / s[:, 2:] < SVD_BAND[1])).any(axis=1)
    assert not np.any(sure & ~in_band)
    # inside, sigma_2 / sigma_1 in (1.5e-6, 7e-4) (q in [r^2, 2 r^2] within (2e-12, 1e-6)): all taken
    inner = (ratio_2 > 1.5e-6) & (ratio_2 < 7e-4)
    assert sure[inner].all() and inner.sum() > 50_000
