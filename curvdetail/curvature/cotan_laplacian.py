"""Cotangent Laplacian (positive semi-definite sign convention)."""

import numpy as np
import scipy.sparse as sp

from ._geometry import corner_cotangents
from ._validate import check_mesh_cotangents


def cotan_laplacian(V, F):
    """Cotangent Laplacian ``L`` with ``(L X)_i = 1/2 sum_j (cot a_ij + cot b_ij) (x_i - x_j)``.

    ``L`` is symmetric and positive semi-definite; its rows sum to zero and ``L @ V`` is the
    gradient of the Dirichlet energy (= of the surface area) at ``V``, i.e. ``(L V)_i = K_i A_i``
    (the paper's curvature detail). A boundary edge has a single cotangent.

    Sign convention: libigl's ``igl.cotmatrix`` returns ``-L`` (negative semi-definite); this
    function returns ``L`` itself.

    Parameters
    ----------
    V : (n, 3) float array   vertex positions
    F : (m, 3) int array     triangles (orientation does not matter here)

    Returns
    -------
    L : (n, n) scipy.sparse.csr_matrix, float64

    Raises
    ------
    MeshError   if V or F is malformed, a triangle has zero area, an edge is non-manifold or a
                vertex is unreferenced (names the first ones)

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
    V, F, cot = check_mesh_cotangents(V, F)
    return _cotan_laplacian_unchecked(V, F, cot)


def _cotan_laplacian_unchecked(V, F, cot=None):
    """``L`` without input checks; ``cot``: corner cotangents already computed for (V, F)."""
    n = V.shape[0]
    if cot is None:
        cot, _, _ = corner_cotangents(V, F, lengths=False)
    # the edge opposite corner k joins corners k+1 and k+2
    i = F[:, [1, 2, 0]].ravel()
    j = F[:, [2, 0, 1]].ravel()
    w = 0.5 * cot.ravel()
    diagonal = np.bincount(i, w, minlength=n) + np.bincount(j, w, minlength=n)
    every = np.arange(n)
    rows = np.concatenate([i, j, every])
    cols = np.concatenate([j, i, every])
    vals = np.concatenate([-w, -w, diagonal])
    L = sp.csr_matrix((vals, (rows, cols)), shape=(n, n))    # sums the two sides of each edge
    L.sum_duplicates()
    return L
