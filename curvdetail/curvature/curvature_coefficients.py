"""Curvature coefficients: each vertex's detail as a combination of its neighbours' details."""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ._validate import as_float, centroid_diameter
from .cotan_laplacian import checked_cotan_laplacian, laplacian_product
from .mixed_voronoi_area import _mixed_voronoi_area_unchecked

#: Default relative threshold on the singular values of a one-ring's detail matrix (see
#: :func:`curvature_coefficients`). The 3x3 Gram matrices carry ~1e-16 relative error in their
#: eigenvalues, i.e. ~1.5e-8 in the singular values, so thresholds below ~1e-7 select noise.
DEFAULT_RCOND = 1e-6


@dataclass(frozen=True)
class CoefficientInfo:
    """What :func:`curvature_coefficients` found about each one-ring.

    Attributes
    ----------
    rank : (n,) int array            numerical rank (0-3) of the one-ring detail matrix ``D_N(i)``
    rank_deficient : int             number of vertices with ``rank < 3`` (flat, cylindrical or
                                     valence-2 rings); their coefficients are the truncated
                                     (regularized) minimum-norm solution
    rank_deficient_vertices : (r,) int array   those vertices, increasing
    residual : (n,) float array      ``|D_i - sum_j C_ij D_j|`` (absolute; zero where ``D_i`` lies
                                     in the span of the kept singular directions)
    scale : (n,) float array         the reference ``s_i`` of the relative threshold
    rcond : float                    the threshold used
    """

    rank: np.ndarray
    rank_deficient: int
    rank_deficient_vertices: np.ndarray
    residual: np.ndarray
    scale: np.ndarray
    rcond: float


def curvature_coefficients(V, F, *, rcond=DEFAULT_RCOND, return_info=False):
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

    Parameters
    ----------
    V : (n, 3) float array   vertex positions
    F : (m, 3) int array     triangles
    rcond : float            relative singular-value threshold, in (0, 1); default 1e-6
    return_info : bool       also return a :class:`CoefficientInfo` (ranks, rank-deficient count,
                             residuals)

    Returns
    -------
    C : (n, n) scipy.sparse.csr_matrix   one-ring sparsity pattern (every mesh edge in both
                                         directions is stored, possibly as an explicit 0), zero
                                         diagonal; rows are not normalized and need not sum to 1
    info : CoefficientInfo               only with ``return_info=True``

    Raises
    ------
    MeshError    malformed mesh (shapes, NaN, bad indices, zero-area or non-manifold elements)
    ValueError   ``rcond`` outside (0, 1)

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
    V, F, L = checked_cotan_laplacian(V, F)
    rcond = check_rcond(rcond)
    n = V.shape[0]
    D = laplacian_product(L, V)
    A = _mixed_voronoi_area_unchecked(V, F)
    rows, cols = _one_ring_pairs(F, n)
    C, rank, scale = _coefficients(D, A, rows, cols, n, rcond, centroid_diameter(V), want_scale=return_info)
    if not return_info:
        return C
    residual = np.linalg.norm(D - C @ D, axis=1)
    deficient = np.flatnonzero(rank < 3)
    info = CoefficientInfo(rank=rank, rank_deficient=int(deficient.size),
                           rank_deficient_vertices=deficient, residual=residual, scale=scale,
                           rcond=rcond)
    return C, info


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


def _coefficients(D, A, rows, cols, n, rcond, size, *, want_scale=False):
    """Batched truncated pseudo-inverse solve; returns (C, rank, scale or None)."""
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
    hard = np.flatnonzero(~good) if not want_scale else np.arange(n)
    if hard.size:
        G = np.empty((hard.size, 3, 3))
        for a in range(3):
            for b in range(a, 3):
                G[:, a, b] = G[:, b, a] = g[a, b][hard]
        lam, U = np.linalg.eigh(G)                  # ascending eigenvalues
        lam = np.maximum(lam, 0.0)
        sigma = np.sqrt(lam)
        s_hard = np.maximum(sigma[:, 2], area_scale[hard])
        keep = sigma > rcond * s_hard[:, None]
        inv = np.zeros_like(lam)
        inv[keep] = 1.0 / lam[keep]
        proj = np.einsum("nab,na->nb", U, D[hard]) * inv
        bad = ~good[hard]
        w[hard[bad]] = np.einsum("nab,nb->na", U[bad], proj[bad])
        rank[hard] = keep.sum(axis=1)
        if want_scale:
            scale = s_hard
    # C_ij = D_j . w_i  (w_i = G_i^+ D_i)
    vals = np.einsum("ea,ea->e", Dj, w[rows])
    C = sp.csr_matrix((vals, (rows, cols)), shape=(n, n))
    return C, rank, scale
