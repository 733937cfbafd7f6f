"""Curvature coefficients: each vertex's detail as a combination of its neighbours' details."""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .checks import as_count, as_float, check_bool
from .errors import CurvdetailError
from .geometry import centroid_diameter, ignoring_underflow
from .cotan_laplacian import checked_cotan_laplacian, laplacian_product
from .mixed_voronoi_area import _mixed_voronoi_area_unchecked

#: Default relative singular-value threshold (below ~1e-7 it selects the Gram matrices' roundoff).
DEFAULT_RCOND = 1e-6

#: Default widest ring: a ring that cannot represent its vertex's detail is widened up to this.
DEFAULT_MAX_RING = 3

#: Gram matrices with ``det(G) > WELL_CONDITIONED * trace(G)^3`` (hence ``cond(G) < 1e6``) are
#: inverted in closed form; the others go through the eigendecomposition.
WELL_CONDITIONED = 1e-6

#: A ring goes through the SVD of its ring matrix where one of its singular value ratios
#: ``sigma_k / sigma_1`` (from ``G_i``'s eigenvalues) lies in this band (see `_coefficients`).
SVD_BAND = (1e-7, 1e-3)


@dataclass(frozen=True)
class CoefficientInfo:
    """What `curvature_coefficients` found about each one-ring.

    Attributes
    ----------
    rank : (n,) int array
        Numerical rank (0-3) of the detail matrix of the ring the coefficients span.
    rank_deficient : int
        Number of vertices with ``rank < 3`` (flat or cylindrical rings).
    rank_deficient_vertices : (r,) int array
        Those vertices, increasing.
    residual : (n,) float array
        ``|D_i - sum_j C_ij D_j|``.
    scale : (n,) float array
        The reference ``s_i`` of the relative threshold.
    rcond : float
        The threshold used.
    ring : (n,) int array
        The ring each vertex's coefficients span: 1 (the one-ring) but where widened.
    widened_vertices : (w,) int array
        The vertices with ``ring > 1``, increasing.
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

    Row ``i`` is the minimum-norm solution ``c_i = D_N^T (D_N D_N^T)^+ D_i`` of ``D_N c_i = D_i``,
    where ``D_N`` (3 x |N(i)|) holds the one-ring's curvature details ``D_j = (L V)_j`` (the
    paper's ``K_j A_j``). It depends only on angles and length ratios of the details, so ``C``
    does not change when the mesh is rotated, uniformly scaled or moved.

    A singular value ``sigma_k`` of ``D_N`` is kept only if ``sigma_k > rcond * s_i``, with
    ``s_i = max(sigma_1(D_N), sqrt(sum_j A_j^2) / size)`` (``A_j`` mixed Voronoi areas, ``size``
    twice the largest distance of a vertex from the vertices' centroid): a ring flatter than
    curvature ``rcond / size`` gets zero coefficients. Where the kept span does not hold ``D_i``
    (a grid's valence-2 corner), the row is fitted over the two-ring instead (without the vertex),
    then the three-ring, up to ``max_ring``. See docs/guide/editing.md, "Curvature coefficients".

    Parameters
    ----------
    V : (n, 3) float array
        Vertex positions.
    F : (m, 3) int array
        Triangles.
    rcond : float
        Relative singular-value threshold, in (0, 1).
    max_ring : int
        Widest ring for a vertex whose one-ring cannot represent its detail (1: one-ring only).
    return_info : bool
        Also return a `CoefficientInfo`.

    Returns
    -------
    C : (n, n) scipy.sparse.csr_matrix
        Every mesh edge stored in both directions (possibly as an explicit 0; a widened row stores
        its whole ring), zero diagonal; rows are not normalized.
    info : CoefficientInfo
        Only with ``return_info=True``.

    Raises
    ------
    MeshError
        If the mesh is malformed (as for `cotan_laplacian`).
    ValueError
        If ``rcond`` is outside (0, 1), ``max_ring`` is not a count >= 1 or ``return_info`` is not
        a bool.

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
    # the one-ring pairs from L's pattern (every edge both ways, every diagonal entry, sorted)
    diag_rows = np.repeat(np.arange(n), np.diff(L.indptr))
    off = L.indices != diag_rows
    C, rank, scale, ring = _coefficients(D, A, diag_rows[off], L.indices[off].astype(np.int64), n, rcond,
                                         centroid_diameter(V), want_scale=return_info, max_ring=max_ring)
    if not return_info:
        return C
    residual = np.linalg.norm(D - C @ D, axis=1)
    deficient = np.flatnonzero(rank < 3)
    info = CoefficientInfo(rank=rank, rank_deficient=int(deficient.size),
                           rank_deficient_vertices=deficient, residual=residual, scale=scale,
                           rcond=rcond, ring=ring, widened_vertices=np.flatnonzero(ring > 1))
    return C, info


def check_max_ring(max_ring):
    """``max_ring`` as an int >= 1, or a ValueError (``parameter="max_ring"``)."""
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


def check_rcond(rcond):
    """``rcond`` as a float in (0, 1), or a ValueError (``parameter="rcond"``)."""
    number = as_float(rcond)
    if number is None:
        raise CurvdetailError(f"rcond={rcond!r} is not a number; pass a threshold in (0, 1), e.g. 1e-6.",
                              parameter="rcond", value=rcond)
    if not 0.0 < number < 1.0:
        raise CurvdetailError(f"rcond={rcond!r} is outside (0, 1); pass a relative threshold such as 1e-6.",
                              parameter="rcond", value=rcond)
    return number


@ignoring_underflow
def _coefficients(D, A, rows, cols, n, rcond, size, *, want_scale=False, max_ring=1, adjacency=None):
    """Batched truncated pseudo-inverse solve over the pattern (rows, cols), sorted by row.

    Rows whose fit leaves a residual above the threshold are widened by one ring of ``adjacency``
    (the one-ring pairs, sorted by row; default (rows, cols)) at a time, ``max_ring - 1`` times
    at most, and no further once a widening adds no vertex. Returns (C, rank, scale or None, ring): ``C`` on the (widened) pattern, explicit zeros kept;
    ``ring`` (n,) the number of rings each row's coefficients span (1 = the given pattern)."""
    indptr = _row_pointers(rows, n)
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
        # on every row; the others are overwritten below
        d0, d1, d2 = D[:, 0], D[:, 1], D[:, 2]
        w = np.stack([(c00 * d0 + c01 * d1 + c02 * d2) / det,
                      (c01 * d0 + c11 * d1 + c12 * d2) / det,
                      (c02 * d0 + c12 * d1 + c22 * d2) / det], axis=1)
    rank = np.full(n, 3, dtype=np.int64)
    scale = None
    if want_scale:
        # sigma_1 of the well-conditioned rows from G's largest eigenvalue (the others: their fit)
        scale = area_scale.copy()
        scale[good] = np.maximum(np.sqrt(np.maximum(np.linalg.eigvalsh(_gram(g, good))[:, 2], 0.0)),
                                 area_scale[good])
    ring = np.ones(n, dtype=np.int64)
    hard = np.flatnonzero(~good)
    if hard.size:
        s_hard, residual = np.empty(hard.size), np.empty(hard.size)
        # G's eigenvalues carry ~1e-16 of the largest, so a singular value in SVD_BAND is known
        # only to 1e-10 ... 1e-2 of itself: those rows go through the SVD of the ring matrix
        # itself; rows certain to go there skip the eigendecomposition
        sure = _surely_in_svd_band(c00[hard], c11[hard], c22[hard], tr[hard])
        redo = sure.copy()
        # G = 0 (a flat grid's inside): w = 0 and rank 0, as the eigendecomposition would give
        zero = tr[hard] == 0.0
        w[hard[zero]], rank[hard[zero]], s_hard[zero] = 0.0, 0, area_scale[hard[zero]]
        residual[zero] = np.linalg.norm(D[hard[zero]], axis=1)
        probe = np.flatnonzero(~sure & ~zero)
        if probe.size:
            lam, U = np.linalg.eigh(_gram(g, hard[probe]))          # ascending eigenvalues
            sigma = np.sqrt(np.maximum(lam, 0.0))
            w[hard[probe]], rank[hard[probe]], s_hard[probe], residual[probe] = _fit(
                D[hard[probe]], U, sigma, area_scale[hard[probe]], rcond)
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = sigma[:, :2] / sigma[:, 2:]
            redo[probe] = ((ratio > SVD_BAND[0]) & (ratio < SVD_BAND[1])).any(axis=1)
        redo = np.flatnonzero(redo)
        if redo.size:
            rows_redo = hard[redo]
            cols_redo = cols[_rows_of(indptr, rows_redo)]
            w[rows_redo], rank[rows_redo], s_hard[redo], residual[redo] = _truncated_fit(
                D, A, rows_redo, indptr[rows_redo + 1] - indptr[rows_redo], cols_redo, rcond, size,
                area_scale=area_scale[rows_redo])
        if want_scale:
            scale[hard] = s_hard
        # widen the rings that cannot represent their own detail (a valence-2 corner)
        grow = residual > rcond * s_hard
        if max_ring > 1 and grow.any():
            wide = _widen(D, A, w, rank, scale, ring, hard[grow], rows, cols, indptr, n, rcond, size,
                          max_ring, adjacency)
            if wide is not None:           # widened rows take their wide ring's pattern
                wide_rows, wide_cols = wide
                kept = ring[rows] == 1
                rows, cols = np.concatenate([rows[kept], wide_rows]), np.concatenate([cols[kept], wide_cols])
                vals = np.einsum("ea,ea->e", D[cols], w[rows])
                return sp.csr_matrix((vals, (rows, cols)), shape=(n, n)), rank, scale, ring
    # C_ij = D_j . w_i  (w_i = G_i^+ D_i)
    vals = np.einsum("ea,ea->e", Dj, w[rows])
    return sp.csr_matrix((vals, cols, indptr), shape=(n, n)), rank, scale, ring


def _surely_in_svd_band(c00, c11, c22, tr):
    """Rows whose Gram matrix ``G`` certainly has ``sigma_2 / sigma_1`` inside `SVD_BAND`,
    told from its invariants alone (no eigendecomposition); (k,) bool. ``c00, c11, c22`` (k,):
    the diagonal cofactors, ``tr`` the trace.

    ``q = (c00 + c11 + c22) / tr^2 = (lambda_1 (lambda_2 + lambda_3) + lambda_2 lambda_3) / tr^2``
    puts ``lambda_2 / lambda_1`` in ``[q / 2, q]`` up to ``O(q^2)`` and roundoff; the band kept
    leaves a margin of 1e-4 at the top and a factor 100 at the bottom."""
    low, high = SVD_BAND
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        q = (c00 + c11 + c22) / tr ** 2
        return (q > 200.0 * low ** 2) & (q < (1.0 - 1e-4) * high ** 2)


def _widen(D, A, w, rank, scale, ring, target, rows, cols, indptr, n, rcond, size, max_ring, adjacency):
    """Refit the rows ``target`` over wider rings until their detail is represented, the ring
    stops growing or ``max_ring`` is reached. Updates ``w``, ``rank``, ``scale`` (where not None)
    and ``ring`` in place; returns the widened rows' pattern ``(rows, cols)``, or None."""
    if adjacency is None:
        P = sp.csr_matrix((np.ones(cols.size, dtype=bool), cols, indptr), shape=(n, n))
    else:
        ar, ac = adjacency
        P = sp.csr_matrix((np.ones(ac.size, dtype=bool), ac, _row_pointers(ar, n)), shape=(n, n))
    counts = indptr[target + 1] - indptr[target]          # the rows' rings, without the vertex
    ring_cols = cols[_rows_of(indptr, target)]
    pieces = []                                           # (rows, cols, ring) of every refit
    for extra in range(1, max_ring):
        R = sp.csr_matrix((np.ones(ring_cols.size, dtype=bool), ring_cols, _cumulative(counts)),
                          shape=(target.size, n))
        R = R + R @ P
        R.sort_indices()
        at = np.repeat(np.arange(target.size), np.diff(R.indptr))
        keep = R.indices != target[at]
        new_counts = np.bincount(at[keep], minlength=target.size)
        # a ring that adds no vertex (the row's whole component already) keeps its narrower fit
        moved = np.flatnonzero(new_counts > counts)
        if not moved.size:
            break
        ring_cols = R.indices[keep].astype(np.int64)[_rows_of(_cumulative(new_counts), moved)]
        target, counts = target[moved], new_counts[moved]
        w_t, rank_t, s_t, residual_t = _truncated_fit(D, A, target, counts, ring_cols, rcond, size)
        # a wider ring never fits worse: take it
        w[target], rank[target], ring[target] = w_t, rank_t, extra + 1
        if scale is not None:
            scale[target] = s_t
        pieces.append((np.repeat(target, counts), ring_cols, extra + 1))
        still = np.flatnonzero(residual_t > rcond * s_t)
        ring_cols = ring_cols[_rows_of(_cumulative(counts), still)]
        target, counts = target[still], counts[still]
        if not target.size:
            break
    if not pieces:
        return None
    wide_rows, wide_cols = (np.concatenate([p[k] for p in pieces]) for k in (0, 1))
    last = ring[wide_rows] == np.concatenate([np.full(p[0].size, p[2]) for p in pieces])
    return wide_rows[last], wide_cols[last]


def _gram(g, which):
    """The Gram matrices ``G_i`` (k, 3, 3) of the rows ``which`` (an index or a mask) from their
    six distinct entries ``g``."""
    G = np.empty((g[0, 0][which].size, 3, 3))
    for a in range(3):
        for b in range(a, 3):
            G[:, a, b] = G[:, b, a] = g[a, b][which]
    return G


def _cumulative(counts):
    """Row pointers (k + 1,) from per-row counts (k,)."""
    indptr = np.zeros(counts.size + 1, dtype=np.int64)
    np.cumsum(counts, out=indptr[1:])
    return indptr


def _row_pointers(rows, n):
    """Row pointers (n + 1,) of a pattern sorted by row."""
    return _cumulative(np.bincount(rows, minlength=n))


def _rows_of(indptr, which):
    """Positions of the entries of rows ``which`` in a row-sorted pattern with ``indptr``."""
    counts = indptr[which + 1] - indptr[which]
    starts = np.repeat(indptr[which] - np.concatenate([[0], np.cumsum(counts)[:-1]]), counts)
    return starts + np.arange(int(counts.sum()))


def _truncated_fit(D, A, target, counts, cols, rcond, size, *, area_scale=None):
    """Truncated minimum-norm fit of ``D_i`` by its ring's details for the rows ``target``
    (``counts`` (t,) ring sizes; ``cols`` the rings' vertices, row after row), through batched
    SVDs of the ring matrices, zero-padded in batches by size (up to 16, larger ones to the next
    power of two). Returns (w (t, 3), rank (t,), s_i (t,), residual (t,)), where
    ``C_ij = D_j . w_i``. ``area_scale`` (t,): the rings' ``sqrt(sum_j A_j^2) / size`` if at hand."""
    if area_scale is None:
        at = np.repeat(np.arange(target.size), counts)
        area_scale = (np.sqrt(np.bincount(at, weights=A[cols] ** 2, minlength=target.size))
                      / max(size, np.finfo(float).tiny))
    width = np.where(counts <= 16, np.maximum(counts, 3), 1 << np.ceil(np.log2(np.maximum(counts, 1))).astype(np.int64))
    entry_width = np.repeat(width, counts)
    sigma, U = np.zeros((target.size, 3)), np.zeros((target.size, 3, 3))
    for w in np.unique(width):
        group = np.flatnonzero(width == w)
        cols_group, counts_group = cols[entry_width == w], counts[group]
        # entry e of the group's row r goes to slot e - first(r) of that row's padded block
        shift = np.arange(group.size) * w - _cumulative(counts_group)[:-1]
        M = np.zeros((group.size, w, 3))
        M.reshape(-1, 3)[np.arange(cols_group.size) + np.repeat(shift, counts_group)] = D[cols_group]
        # M = D_N^T; D_N's left singular vectors are M's right ones
        with np.errstate(over="ignore", invalid="ignore"):
            _, sigma_g, Vt = np.linalg.svd(M, full_matrices=False)      # descending
        sigma[group], U[group] = np.nan_to_num(sigma_g), Vt.transpose(0, 2, 1)
    return _fit(D[target], U, sigma, area_scale, rcond)


def _fit(Di, U, sigma, area_scale, rcond):
    """The truncated pseudo-inverse fit from a ring's singular directions ``U`` (t, 3, 3),
    columns, and values ``sigma`` (t, 3): (w, rank, s_i, residual) as `_truncated_fit`."""
    s_ref = np.maximum(sigma.max(axis=1), area_scale)
    keep = sigma > rcond * s_ref[:, None]
    proj = np.einsum("tab,ta->tb", U, Di)                            # U^T D_i
    with np.errstate(divide="ignore", over="ignore"):      # sigma's that are not kept may be ~0
        inv = np.where(keep, 1.0 / sigma ** 2, 0.0)
    w = np.einsum("tab,tb->ta", U, proj * inv)
    fitted = np.einsum("tab,tb->ta", U, proj * keep)
    residual = np.linalg.norm(Di - fitted, axis=1)
    return w, keep.sum(axis=1), s_ref, residual
