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
    # coordinate-major (3, m) arrays: every operation below runs on contiguous rows; np.take
    # gathers ~3x faster than fancy indexing, and the in-place arithmetic halves the time at 2M
    # triangles (0.54 -> 0.28 s), bit for bit the same values
    Vt = np.ascontiguousarray(V.T)
    Ft = np.ascontiguousarray(F.T)
    P0, P1, P2 = (np.take(Vt, Ft[k], axis=1) for k in range(3))
    # edge opposite corner k, as a vector
    e0 = P2 - P1
    e1 = P0 - P2
    e2 = np.subtract(P1, P0, out=P0)
    cx = e1[1] * e2[2]
    cx -= e1[2] * e2[1]
    cy = e1[2] * e2[0]
    cy -= e1[0] * e2[2]
    cz = e1[0] * e2[1]
    cz -= e1[1] * e2[0]
    cx *= cx
    cy *= cy
    cz *= cz
    cx += cy
    cx += cz
    dbl = np.sqrt(cx, out=cx)
    sq = np.stack([_dot(e0, e0), _dot(e1, e1), _dot(e2, e2)], axis=1) if lengths else None
    # cot at corner k = (a . b) / |a x b| with a, b the two edges leaving it (= minus the two
    # edges that end there, hence the sign)
    cot = np.empty((3, dbl.shape[0]))
    _dot(e1, e2, out=cot[0])
    _dot(e2, e0, out=cot[1])
    _dot(e0, e1, out=cot[2])
    cot *= np.divide(-1.0, dbl)
    return cot.T, sq, dbl


def _dot(a, b, out=None):
    out = np.multiply(a[0], b[0], out=out)
    out += a[1] * b[1]
    out += a[2] * b[2]
    return out
