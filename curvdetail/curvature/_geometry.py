"""Per-triangle quantities shared by the cotangent Laplacian and the mixed Voronoi area."""

import numpy as np


def corner_cotangents(V, F, *, lengths=True):
    """Cotangent of the angle at each corner and squared length of the opposite edge.

    ``lengths=False`` skips the squared lengths (``sq`` is then None).

    Returns
    -------
    cot : (m, 3) float   cot of the angle at corner k of each triangle
    sq  : (m, 3) float   squared length of the edge opposite corner k (joining corners k+1, k+2)
    dbl : (m,) float     twice the triangle's area
    """
    # coordinate-major (3, m) arrays: every operation below runs on contiguous rows
    Vt = np.ascontiguousarray(V.T)
    Ft = np.ascontiguousarray(F.T)
    P0, P1, P2 = Vt[:, Ft[0]], Vt[:, Ft[1]], Vt[:, Ft[2]]
    # edge opposite corner k, as a vector
    e0, e1, e2 = P2 - P1, P0 - P2, P1 - P0
    cx = e1[1] * e2[2] - e1[2] * e2[1]
    cy = e1[2] * e2[0] - e1[0] * e2[2]
    cz = e1[0] * e2[1] - e1[1] * e2[0]
    dbl = np.sqrt(cx * cx + cy * cy + cz * cz)
    sq = np.stack([_dot(e0, e0), _dot(e1, e1), _dot(e2, e2)], axis=1) if lengths else None
    # cot at corner k = (a . b) / |a x b| with a, b the two edges leaving it (= minus the two
    # edges that end there, hence the sign)
    inv = -1.0 / dbl
    cot = np.stack([_dot(e1, e2) * inv, _dot(e2, e0) * inv, _dot(e0, e1) * inv], axis=1)
    return cot, sq, dbl


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
