"""Cotangent Laplacian (positive semi-definite sign convention)."""

import numpy as np
import scipy.sparse as sp

from .geometry import corner_cotangents, thread_pool
from .checks import _check_mesh, non_manifold_error
from .geometry import bbox_centre


def cotan_laplacian(V, F):
    """Cotangent Laplacian ``L`` with ``(L X)_i = 1/2 sum_j (cot a_ij + cot b_ij) (x_i - x_j)``.

    ``L`` is symmetric and positive semi-definite; its rows sum to zero and ``L @ V`` is the
    gradient of the Dirichlet energy (= of the surface area) at ``V``, i.e. ``(L V)_i = K_i A_i``
    (the paper's curvature detail). A boundary edge has a single cotangent.

    Sign convention: libigl's ``igl.cotmatrix`` returns ``-L`` (negative semi-definite); this
    function returns ``L`` itself.

    Parameters
    ----------
    V : (n, 3) float array
        Vertex positions.
    F : (m, 3) int array
        Triangles (their orientation does not matter here).

    Returns
    -------
    L : (n, n) scipy.sparse.csr_matrix
        Float64.

    Raises
    ------
    MeshError
        If V or F is malformed, a triangle has zero area, an edge is non-manifold or a vertex is
        unreferenced (``e.count``, ``e.first``: the offending elements).

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0]]); F = np.array([[0, 1, 2]])
    >>> L = cotan_laplacian(V, F)
    >>> np.allclose(L.sum(axis=1), 0)
    True
    >>> float(L[1, 2])   # edge opposite the right angle: -cot(90 deg) / 2
    0.0
    """
    return checked_cotan_laplacian(V, F)[2]


def checked_cotan_laplacian(V, F):
    """Every :func:`check_mesh` check and ``L`` in one pass: ``(V, F, L)`` with V, F converted
    (the non-manifold edge check is folded into the assembly)."""
    V, F, U, diagonal = checked_cotan_triangle(V, F)
    return V, F, _symmetric_from_upper(U, diagonal)


def checked_cotan_triangle(V, F, *, edge_counts=None):
    """Like :func:`checked_cotan_laplacian`, with ``L`` as its strict upper triangle ``U`` (CSR,
    sorted, explicit zeros kept: it has the edge pattern) and its diagonal: ``(V, F, U, diagonal)``.
    A caller that needs only part of ``L`` is spared building all of it.
    ``edge_counts``: :func:`_edge_pattern` of these triangles where the caller has it already."""
    V, F, cot = _check_mesh(V, F, check_manifold=False, check_unreferenced=True, cotangents=True)
    U, diagonal = _assemble_upper(V, F, cot, check_manifold=True, edge_counts=edge_counts)
    return V, F, U, diagonal


def _cotan_laplacian_unchecked(V, F, cot=None):
    """``L`` without input checks; ``cot``: corner cotangents already computed for (V, F)."""
    if cot is None:
        cot, _, _ = corner_cotangents(V, F, lengths=False)
    return _symmetric_from_upper(*_assemble_upper(V, F, cot, check_manifold=False))


def _assemble_upper(V, F, cot, check_manifold, edge_counts=None):
    """Strict upper triangle ``U`` and diagonal of ``L``; ``check_manifold`` refuses an edge of
    more than two triangles (counted by :func:`_edge_pattern`, or taken from ``edge_counts``)."""
    n = V.shape[0]
    # the edge opposite corner k joins corners k+1 and k+2; assemble the strict upper triangle
    # (one entry per half-edge, summed per edge); L = U + U^T - diag(row sums). The half-edges
    # are listed corner by corner from the (3, m) transposes, which are contiguous (cot comes from
    # corner_cotangents that way): 0.33 -> 0.25 s at 2M triangles, the same L bit for bit
    lo, hi = _half_edges(F, n)
    counting = None
    if check_manifold and edge_counts is None:
        # SciPy's COO -> CSR releases the GIL: count the triangles on each edge alongside the
        # weights' assembly (1M vertices: 0.5 s for one complex-valued pass, 0.2 s for these two)
        counting = thread_pool().submit(_edge_pattern, F, n, (lo, hi))
    w = np.ascontiguousarray(cot.T).ravel() * -0.5
    U = sp.csr_matrix((w, (lo, hi)), shape=(n, n))
    U.sum_duplicates()
    U.has_sorted_indices = True          # sum_duplicates sorted them
    if check_manifold:
        _refuse_non_manifold(edge_counts if counting is None else counting.result())
    diagonal = -(U @ np.ones(n) + np.bincount(U.indices, U.data, minlength=n))
    return U, diagonal


def _half_edges(F, n):
    """(lo, hi) vertex pair of the edge opposite each corner, corner by corner (corner 0 of every
    triangle, then corner 1, then corner 2)."""
    index = np.int32 if n < 2**31 - 1 else np.int64
    Ft = F.T.astype(index)
    i = Ft[[1, 2, 0]].ravel()
    j = Ft[[2, 0, 1]].ravel()
    return np.minimum(i, j), np.maximum(i, j, out=i)


def _edge_pattern(F, n, half_edges=None):
    """The pattern of ``L``'s strict upper triangle from the triangles alone: a CSR matrix with
    the same ``indptr`` and ``indices`` as the ``U`` of :func:`checked_cotan_triangle` (values:
    triangles per edge). ``half_edges``: :func:`_half_edges` of ``F`` where already at hand."""
    lo, hi = _half_edges(F, n) if half_edges is None else half_edges
    P = sp.csr_matrix((np.ones(lo.size, dtype=np.float32), (lo, hi)), shape=(n, n))
    P.sum_duplicates()
    return P


def _symmetric_from_upper(U, diagonal):
    """``L = U + U^T + diag(diagonal)`` as CSR with sorted indices."""
    n = U.shape[0]
    # lower triangle, diagonal, upper triangle in this order: the stable row sort of the COO -> CSR
    # conversion then leaves every row's columns increasing, with no duplicates to sum
    ur = np.repeat(np.arange(n, dtype=U.indices.dtype), np.diff(U.indptr))
    uc, uv = U.indices, U.data
    every = np.arange(n, dtype=U.indices.dtype)
    return sp.csr_matrix((np.concatenate([uv, diagonal, uv]),
                          (np.concatenate([uc, every, ur]), np.concatenate([ur, every, uc]))),
                         shape=(n, n))


def _refuse_non_manifold(counts):
    """``counts``: :func:`_edge_pattern` (triangles per edge)."""
    bad = np.flatnonzero(counts.data > 2.5)
    if bad.size:
        rows = np.searchsorted(counts.indptr, bad, side="right") - 1
        raise non_manifold_error(bad.size, zip(rows[:3], counts.indices[bad[:3]]))


def laplacian_product(L, V, centre=None):
    """``L @ V`` for positions ``V`` (n, 3), computed as ``L @ (V - c)``: equal in exact
    arithmetic (the rows of ``L`` sum to zero), but without the cancellation of large
    coordinates. Far from the origin (UTM, ECEF) ``L @ V`` sums terms ``w x`` of the coordinates'
    size to a result of the detail's size: a 1 mm sphere 1e6 m out lost six digits of ``K``.
    ``c`` is ``centre`` or the bounding box's centre; ``V - c`` is exact for coordinates within a
    factor two of it."""
    V = np.asarray(V, dtype=np.float64)
    return L @ (V - (bbox_centre(V) if centre is None else centre))
