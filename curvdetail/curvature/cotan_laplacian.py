"""Cotangent Laplacian (positive semi-definite sign convention)."""

import numpy as np
import scipy.sparse as sp

from .checks import _check_mesh, non_manifold_error
from .geometry import bbox_centre, corner_cotangents


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
    """Every `check_mesh` check and ``L`` in one pass: ``(V, F, L)``, V and F converted."""
    V, F, U, diagonal = checked_cotan_triangle(V, F)
    return V, F, _symmetric_from_upper(U, diagonal)


def checked_cotan_triangle(V, F):
    """Like `checked_cotan_laplacian`, with ``L`` as its strict upper triangle ``U`` (CSR,
    sorted, explicit zeros kept: the edge pattern) and its diagonal: ``(V, F, U, diagonal)``."""
    V, F, cot = _check_mesh(V, F, check_manifold=False, check_unreferenced=True, cotangents=True)
    U, diagonal = _assemble_upper(V, F, cot, check_manifold=True)
    return V, F, U, diagonal


def _cotan_laplacian_unchecked(V, F):
    """``L`` without input checks."""
    cot, _, _ = corner_cotangents(V, F, lengths=False)
    return _symmetric_from_upper(*_assemble_upper(V, F, cot, check_manifold=False))


def _assemble_upper(V, F, cot, check_manifold):
    """Strict upper triangle ``U`` and diagonal of ``L``; ``check_manifold`` refuses an edge of
    more than two triangles."""
    n = V.shape[0]
    # the edge opposite corner k joins corners k+1 and k+2, listed corner by corner (the layout
    # of cot.T); one entry per half-edge, summed per edge; L = U + U^T - diag(row sums)
    index = np.int32 if n < 2**31 - 1 else np.int64
    Ft = F.T.astype(index)
    i, j = Ft[[1, 2, 0]].ravel(), Ft[[2, 0, 1]].ravel()
    lo, hi = np.minimum(i, j), np.maximum(i, j, out=i)
    if check_manifold:
        counts = sp.csr_matrix((np.ones(lo.size, dtype=np.float32), (lo, hi)), shape=(n, n))
        counts.sum_duplicates()
        bad = np.flatnonzero(counts.data > 2.5)
        if bad.size:
            rows = np.searchsorted(counts.indptr, bad, side="right") - 1
            raise non_manifold_error(bad.size, zip(rows[:3], counts.indices[bad[:3]]))
    U = sp.csr_matrix((np.ascontiguousarray(cot.T).ravel() * -0.5, (lo, hi)), shape=(n, n))
    U.sum_duplicates()
    U.has_sorted_indices = True          # sum_duplicates sorted them
    diagonal = -(U @ np.ones(n) + np.bincount(U.indices, U.data, minlength=n))
    return U, diagonal


def _symmetric_from_upper(U, diagonal):
    """``L = U + U^T + diag(diagonal)`` as CSR with sorted indices."""
    n = U.shape[0]
    # lower triangle, diagonal, upper triangle in this order: the stable row sort of COO -> CSR
    # leaves every row's columns increasing, with no duplicates to sum
    ur = np.repeat(np.arange(n, dtype=U.indices.dtype), np.diff(U.indptr))
    uc, uv = U.indices, U.data
    every = np.arange(n, dtype=U.indices.dtype)
    return sp.csr_matrix((np.concatenate([uv, diagonal, uv]),
                          (np.concatenate([uc, every, ur]), np.concatenate([ur, every, uc]))),
                         shape=(n, n))


def laplacian_product(L, V, centre=None):
    """``L @ V`` for positions ``V`` (n, 3), computed as ``L @ (V - c)`` (``c``: ``centre`` or the
    bbox centre): equal in exact arithmetic (rows of ``L`` sum to zero), without the cancellation
    of large coordinates far from the origin (UTM, ECEF)."""
    V = np.asarray(V, dtype=np.float64)
    return L @ (V - (bbox_centre(V) if centre is None else centre))
