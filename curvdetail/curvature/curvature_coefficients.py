"""Curvature coefficients: each vertex's detail as a combination of its neighbours' details."""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ._validate import as_count, as_float, centroid_diameter, check_bool
from .cotan_laplacian import checked_cotan_laplacian, laplacian_product
from .mixed_voronoi_area import _mixed_voronoi_area_unchecked

#: Default relative threshold on the singular values of a one-ring's detail matrix (see
#: :func:`curvature_coefficients`). The 3x3 Gram matrices carry ~1e-16 relative error in their
#: eigenvalues, i.e. ~1.5e-8 in the singular values, so thresholds below ~1e-7 select noise.
DEFAULT_RCOND = 1e-6

#: Default widest ring (see :func:`curvature_coefficients`): a ring that cannot represent its
#: vertex's detail is widened to the two-ring, then the three-ring.
DEFAULT_MAX_RING = 3


@dataclass(frozen=True)
class CoefficientInfo:
    """What :func:`curvature_coefficients` found about each one-ring.

    Attributes
    ----------
    rank : (n,) int array            numerical rank (0-3) of the detail matrix ``D_N(i)`` of the
                                     ring the coefficients span (the one-ring but where widened)
    rank_deficient : int             number of vertices with ``rank < 3`` (flat or cylindrical
                                     rings); their coefficients are the truncated (regularized)
                                     minimum-norm solution
    rank_deficient_vertices : (r,) int array   those vertices, increasing
    residual : (n,) float array      ``|D_i - sum_j C_ij D_j|`` (absolute; zero where ``D_i`` lies
                                     in the span of the kept singular directions)
    scale : (n,) float array         the reference ``s_i`` of the relative threshold
    rcond : float                    the threshold used
    ring : (n,) int array            the ring each vertex's coefficients span: 1 (the one-ring)
                                     but where the one-ring could not represent the detail
    widened_vertices : (w,) int array   the vertices with ``ring > 1``, increasing
    """

    rank: np.ndarray
    rank_deficient: int
    rank_deficient_vertices: np.ndarray
    residual: np.ndarray
    scale: np.ndarray
    rcond: float
    ring: np.ndarray
    widened_vertices: np.ndarray


def curvature_coefficients(V, F, *, rcond=DEFAULT_RCOND, max_ring=DEFAULT_MAX_RING, return_info=False):
    """Rotation- and scale-invariant curvature coefficients ``C`` with ``D_i = sum_j C_ij D_j``.

    For each vertex ``i`` with one-ring ``N(i)`` the coefficients ``c_i`` are the minimum-norm
    solution of ``D_N c_i = D_i``, where ``D_N`` is the 3 x |N(i)| matrix of the neighbours'
    curvature details ``D_j = (L V)_j`` (the paper's ``K_j A_j``):
    ``c_i = D_N^T (D_N D_N^T)^+ D_i``. The coefficients depend only on angles and length ratios of
    the details, so they do not change when the detail is rotated or uniformly scaled.

    Computation, batched (no per-vertex loop): the 3x3 Gram matrices ``G_i = D_N D_N^T`` are
    summed over the mesh edges with ``bincount``; where ``det(G_i) > 1e-6 trace(G_i)^3`` (so
    ``cond(G_i) < 1e6`` and rank 3 is certain) they are inverted in closed form (adjugate over
    determinant), all others are pseudo-inverted at once through a batched symmetric
    eigendecomposition. Never ``np.linalg.solve``, which returns wrong values without an error
    where ``G_i`` is singular (valence-2 corners). Forming ``G_i`` squares the ring's condition
    number; the threshold below is chosen well above the resulting ~1.5e-8 noise floor.

    Regularization (rank-deficient rings): a singular value ``sigma_k`` of ``D_N`` is kept only if
    ``sigma_k > rcond * s_i`` with ``s_i = max(sigma_1(D_N), sqrt(sum_j A_j^2) / size)``; the
    others are truncated (a truncated pseudo-inverse). ``sigma_1`` makes the threshold relative
    to the ring itself (coplanar details on a cylinder: the third singular value is roundoff);
    the second term is the detail a curvature of ``1 / size`` would give on the ring (``A_j`` mixed
    Voronoi areas, ``size`` twice the largest distance from the vertices' centroid: the
    bounding-box diagonal's size, but unchanged by rotations, as the coefficients must be), so
    that a ring whose curvature is below ``rcond / size`` counts as flat: its details are
    roundoff and its coefficients are zero
    (``D_i = 0`` is kept there). Vertices with fewer than three kept singular values are
    counted as rank-deficient; their detail is represented only where it lies in the kept span.
    Where a singular value lies between ~1e-7 and 1e-3 of the largest (near the threshold, or
    kept with a large weight), ``G_i``'s eigenvalues do not give it accurately (they carry
    ~1e-16 of the largest): those rings are pseudo-inverted through a batched SVD of the ring
    matrix ``D_N`` itself (zero-padded to the largest ring).

    Widening: where the detail does not lie in that span (the residual
    ``|D_i - sum_j C_ij D_j|`` is above ``rcond * s_i``: a valence-2 corner of a grid, whose two
    neighbours' details span a plane that its own detail leaves), the relation cannot hold and
    nothing keeps the edited detail there consistent with a similarity of the constraints: the
    editor's result then moved by up to 16 diagonals under a uniform scale of all constraints
    (terrainA_10k, two such corners). Those rows take the minimum-norm coefficients over the
    vertex's two-ring instead (without the vertex), then its three-ring, up to ``max_ring``;
    ``max_ring=1`` keeps the one-ring everywhere (the paper's relations). The decision depends
    only on ratios, so it too is invariant.

    Parameters
    ----------
    V : (n, 3) float array   vertex positions
    F : (m, 3) int array     triangles
    rcond : float            relative singular-value threshold, in (0, 1); default 1e-6
    max_ring : int           widest ring for a vertex whose one-ring cannot represent its detail
                             (>= 1; default 3; 1 = one-ring only)
    return_info : bool       also return a :class:`CoefficientInfo` (ranks, rank-deficient count,
                             residuals, widened rings)

    Returns
    -------
    C : (n, n) scipy.sparse.csr_matrix   one-ring sparsity pattern (every mesh edge in both
                                         directions is stored, possibly as an explicit 0; a
                                         widened row stores its whole ring), zero diagonal; rows
                                         are not normalized and need not sum to 1
    info : CoefficientInfo               only with ``return_info=True``

    Raises
    ------
    MeshError    malformed mesh (shapes, NaN, bad indices, zero-area or non-manifold elements)
    ValueError   ``rcond`` outside (0, 1), ``max_ring`` not a count >= 1, ``return_info`` not a bool

    Examples
    --------
    >>> import numpy as np
    >>> from curvdetail.curvature.testing import icosphere
    >>> from curvdetail.curvature import curvature_detail
    >>> V, F = icosphere(radius=2.0, subdivisions=2)
    >>> C, info = curvature_coefficients(V, F, return_info=True)
    >>> D = curvature_detail(V, F)
    >>> bool(np.abs(C @ D - D).max() < 1e-10 * np.abs(D).max())
    True
    >>> R = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))[0]
    >>> C2 = curvature_coefficients(3.0 * V @ R.T, F)          # rotated and scaled copy
    >>> bool(abs(C2 - C).max() < 1e-8)
    True
    >>> info.rank_deficient
    0
    """
    rcond = check_rcond(rcond)
    max_ring = check_max_ring(max_ring)
    return_info = check_bool(return_info, "return_info")
    V, F, L = checked_cotan_laplacian(V, F)
    n = V.shape[0]
    D = laplacian_product(L, V)
    A = _mixed_voronoi_area_unchecked(V, F)
    rows, cols = _one_ring_pairs(F, n)
    C, rank, scale, ring = _coefficients(D, A, rows, cols, n, rcond, centroid_diameter(V),
                                         want_scale=return_info, max_ring=max_ring)
    if not return_info:
        return C
    residual = np.linalg.norm(D - C @ D, axis=1)
    deficient = np.flatnonzero(rank < 3)
    info = CoefficientInfo(rank=rank, rank_deficient=int(deficient.size),
                           rank_deficient_vertices=deficient, residual=residual, scale=scale,
                           rcond=rcond, ring=ring, widened_vertices=np.flatnonzero(ring > 1))
    return C, info


def check_max_ring(max_ring):
    """``max_ring`` as an int >= 1, or ValueError naming the value and the fix."""
    return as_count(max_ring, "max_ring", minimum=1)


def _one_ring_pairs(F, n):
    """Directed one-ring pairs (i, j), i != j, sorted by i then j (each mesh edge twice)."""
    i = np.concatenate([F[:, 0], F[:, 1], F[:, 2], F[:, 1], F[:, 2], F[:, 0]])
    j = np.concatenate([F[:, 1], F[:, 2], F[:, 0], F[:, 0], F[:, 1], F[:, 2]])
    P = sp.csr_matrix((np.ones(i.size, dtype=np.int8), (i, j)), shape=(n, n))
    P.sum_duplicates()
    P.sort_indices()
    rows = np.repeat(np.arange(n), np.diff(P.indptr))
    return rows, P.indices.astype(np.int64)


#: Gram matrices with ``det(G) > WELL_CONDITIONED * trace(G)^3`` (hence ``cond(G) < 1e6``) are
#: inverted in closed form; the others go through the eigendecomposition.
WELL_CONDITIONED = 1e-6


def check_rcond(rcond):
    """``rcond`` as a float in (0, 1), or ValueError naming the value and the fix."""
    number = as_float(rcond)           # a real number only: float("1e-6") and float(True) would pass
    if number is None:
        raise ValueError(f"rcond={rcond!r} is not a number; pass a threshold in (0, 1), e.g. 1e-6.")
    if not 0.0 < number < 1.0:
        raise ValueError(f"rcond={rcond!r} is outside (0, 1); pass a relative threshold such as 1e-6.")
    return number


def _coefficients(D, A, rows, cols, n, rcond, size, *, want_scale=False, max_ring=1, adjacency=None):
    """Batched truncated pseudo-inverse solve over the pattern (rows, cols), sorted by row.

    Rows whose fit leaves a residual above the threshold are widened by one ring of ``adjacency``
    (the one-ring pairs; default (rows, cols)) at a time, ``max_ring - 1`` times at most.
    Returns (C, rank, scale or None, ring): ``C`` on the (widened) pattern, explicit zeros kept;
    ``ring`` (n,) the number of rings each row spans (1 = the given pattern)."""
    Dj = D[cols]
    # the 6 distinct entries of G_i = sum_j D_j D_j^T
    g = {}
    for a in range(3):
        for b in range(a, 3):
            g[a, b] = np.bincount(rows, weights=Dj[:, a] * Dj[:, b], minlength=n)
    area_scale = (np.sqrt(np.bincount(rows, weights=A[cols] ** 2, minlength=n))
                  / max(size, np.finfo(float).tiny))
    # closed form where G is safely full rank: adjugate / det. On huge coordinates (~1e70) the
    # cofactors overflow to inf / nan: those rows fail the test below and take the SVD path
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        c00 = g[1, 1] * g[2, 2] - g[1, 2] ** 2
        c01 = g[0, 2] * g[1, 2] - g[0, 1] * g[2, 2]
        c02 = g[0, 1] * g[1, 2] - g[0, 2] * g[1, 1]
        c11 = g[0, 0] * g[2, 2] - g[0, 2] ** 2
        c12 = g[0, 1] * g[0, 2] - g[0, 0] * g[1, 2]
        c22 = g[0, 0] * g[1, 1] - g[0, 1] ** 2
        det = g[0, 0] * c00 + g[0, 1] * c01 + g[0, 2] * c02
        tr = g[0, 0] + g[1, 1] + g[2, 2]
        # sigma_3 >= sqrt(det) / tr and sigma_1 <= sqrt(tr): rank 3 is certain when the bound
        # clears the threshold; cond(G) <= tr^3 / det keeps the adjugate accurate
        good = (det > WELL_CONDITIONED * tr ** 3) & \
               (np.sqrt(np.maximum(det, 0.0)) / tr > rcond * np.maximum(np.sqrt(tr), area_scale))
    w = np.zeros((n, 3))
    dg = det[good]
    d0, d1, d2 = D[good, 0], D[good, 1], D[good, 2]
    w[good, 0] = (c00[good] * d0 + c01[good] * d1 + c02[good] * d2) / dg
    w[good, 1] = (c01[good] * d0 + c11[good] * d1 + c12[good] * d2) / dg
    w[good, 2] = (c02[good] * d0 + c12[good] * d1 + c22[good] * d2) / dg
    rank = np.full(n, 3, dtype=np.int64)
    scale = None
    if want_scale:
        # sigma_1 of the well-conditioned rows: the largest eigenvalue of G is accurate
        G = np.empty((n, 3, 3))
        for a in range(3):
            for b in range(a, 3):
                G[:, a, b] = G[:, b, a] = g[a, b]
        scale = np.maximum(np.sqrt(np.maximum(np.linalg.eigvalsh(G)[:, 2], 0.0)), area_scale)
    ring = np.ones(n, dtype=np.int64)
    hard = np.flatnonzero(~good)
    if hard.size:
        G = np.empty((hard.size, 3, 3))
        for a in range(3):
            for b in range(a, 3):
                G[:, a, b] = G[:, b, a] = g[a, b][hard]
        lam, U = np.linalg.eigh(G)                  # ascending eigenvalues
        sigma = np.sqrt(np.maximum(lam, 0.0))
        w[hard], rank[hard], s_hard, residual = _fit(D[hard], U, sigma, area_scale[hard], rcond)
        # G's eigenvalues carry ~1e-16 of the largest, so a singular value between ~1e-7 and
        # 1e-3 of the largest (near the threshold, or kept with a large weight 1 / sigma^2) is
        # known only to 1e-10 ... 1e-2 of itself: those rows (fandisk: 46 of them changed by up to
        # 5e-5 under a rotation) go through the SVD of the ring matrix itself
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = sigma[:, :2] / sigma[:, 2:]
        redo = np.flatnonzero(((ratio > 1e-7) & (ratio < 1e-3)).any(axis=1))
        if redo.size:
            indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=n))])
            pick = _rows_of(indptr, hard[redo])
            w[hard[redo]], rank[hard[redo]], s_hard[redo], residual[redo] = _truncated_fit(
                D, A, hard[redo], rows[pick], cols[pick], rcond, size)
        if want_scale:
            scale[hard] = s_hard
        # widen the rings that cannot represent their own detail (a valence-2 corner's two
        # neighbours span a plane its detail leaves): the residual would otherwise be a constant
        # that no similarity of the constraints moves (see CurvatureEditor)
        grow = residual > rcond * s_hard
        wide_rows, wide_cols = [], []
        if max_ring > 1 and grow.any():
            ar, ac = adjacency if adjacency is not None else (rows, cols)
            P = sp.csr_matrix((np.ones(ar.size, dtype=np.float32), (ar, ac)), shape=(n, n))
            target = hard[grow]
            R = sp.csr_matrix((np.ones(rows.size, dtype=np.float32), (rows, cols)), shape=(n, n))[target]
            for extra in range(1, max_ring):
                R = R + R @ P
                R = R.tocoo()
                r, c = target[R.row], R.col.astype(np.int64)
                keep = r != c
                R = sp.csr_matrix((np.ones(int(keep.sum()), dtype=np.float32), (R.row[keep], c[keep])),
                                  shape=(target.size, n))
                R.sort_indices()
                r = target[np.repeat(np.arange(target.size), np.diff(R.indptr))]
                c = R.indices.astype(np.int64)
                w_t, rank_t, s_t, residual_t = _truncated_fit(D, A, target, r, c, rcond, size)
                # a wider ring never fits worse: take it (its pattern replaces the narrower one)
                w[target], rank[target], ring[target] = w_t, rank_t, extra + 1
                if want_scale:
                    scale[target] = s_t
                still = residual_t > rcond * s_t
                if extra == max_ring - 1 or not still.any():   # every row's widest fit is final
                    wide_rows.append(r)
                    wide_cols.append(c)
                    break
                done = ~still[np.searchsorted(target, r)]
                wide_rows.append(r[done])
                wide_cols.append(c[done])
                target = target[still]
                R = R[still]
        if wide_rows:
            narrow = ring[rows] == 1
            rows = np.concatenate([rows[narrow]] + wide_rows)
            cols = np.concatenate([cols[narrow]] + wide_cols)
            Dj = D[cols]
    # C_ij = D_j . w_i  (w_i = G_i^+ D_i)
    vals = np.einsum("ea,ea->e", Dj, w[rows])
    C = sp.csr_matrix((vals, (rows, cols)), shape=(n, n))
    C.sort_indices()
    return C, rank, scale, ring


def _rows_of(indptr, which):
    """Positions of the entries of rows ``which`` in a row-sorted pattern with ``indptr``."""
    counts = indptr[which + 1] - indptr[which]
    starts = np.repeat(indptr[which] - np.concatenate([[0], np.cumsum(counts)[:-1]]), counts)
    return starts + np.arange(int(counts.sum()))


def _truncated_fit(D, A, target, rows, cols, rcond, size):
    """Truncated minimum-norm fit of ``D_i`` by its ring's details for the rows ``target``
    (increasing; ``rows``/``cols`` their pattern, sorted by row), through batched SVDs of the
    zero-padded ring matrices. Returns (w (t, 3), rank (t,), s_i (t,), residual (t,)), where
    ``C_ij = D_j . w_i``.

    Rings are batched by size (up to 16, larger ones padded to the next power of two), not all
    padded to the largest: one pole of valence 1024 among 100k such rings made that 5 GB and
    13 s (now 0.3 GB and 0.8 s for the whole call)."""
    at = np.searchsorted(target, rows)
    counts = np.bincount(at, minlength=target.size)
    first = np.concatenate([[0], np.cumsum(counts)[:-1]])
    slot = np.arange(rows.size) - first[at]
    area_scale = np.sqrt(np.bincount(at, weights=A[cols] ** 2, minlength=target.size)) / max(size, np.finfo(float).tiny)
    width = np.where(counts <= 16, np.maximum(counts, 3), 1 << np.ceil(np.log2(np.maximum(counts, 1))).astype(np.int64))
    sigma, U = np.zeros((target.size, 3)), np.zeros((target.size, 3, 3))
    for w in np.unique(width):
        group = np.flatnonzero(width == w)
        at_group = np.full(target.size, -1, dtype=np.int64)
        at_group[group] = np.arange(group.size)
        entry = at_group[at] >= 0
        M = np.zeros((group.size, int(w), 3))
        M[at_group[at[entry]], slot[entry]] = D[cols[entry]]
        # M = D_N^T; D_N's left singular vectors are M's right ones
        with np.errstate(over="ignore", invalid="ignore"):
            _, sigma_g, Vt = np.linalg.svd(M, full_matrices=False)      # descending
        sigma[group], U[group] = np.nan_to_num(sigma_g), Vt.transpose(0, 2, 1)
    return _fit(D[target], U, sigma, area_scale, rcond)


def _fit(Di, U, sigma, area_scale, rcond):
    """The truncated pseudo-inverse fit from a ring's singular directions ``U`` (t, 3, 3),
    columns, and values ``sigma`` (t, 3): (w, rank, s_i, residual) as :func:`_truncated_fit`."""
    s_ref = np.maximum(sigma.max(axis=1), area_scale)
    keep = sigma > rcond * s_ref[:, None]
    proj = np.einsum("tab,ta->tb", U, Di)                            # U^T D_i
    inv = np.zeros_like(sigma)
    inv[keep] = 1.0 / sigma[keep] ** 2
    w = np.einsum("tab,tb->ta", U, proj * inv)
    fitted = np.einsum("tab,tb->ta", U, proj * keep)
    residual = np.linalg.norm(Di - fitted, axis=1)
    return w, keep.sum(axis=1), s_ref, residual
