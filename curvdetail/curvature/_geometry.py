"""Per-triangle quantities shared by the cotangent Laplacian and the mixed Voronoi area."""

import numpy as np


def corner_cotangents(V, F):
    """Cotangent of the angle at each corner and squared length of the opposite edge.

    Returns
    -------
    cot : (m, 3) float   cot of the angle at corner k of each triangle
    sq  : (m, 3) float   squared length of the edge opposite corner k (joining corners k+1, k+2)
    dbl : (m,) float     twice the triangle's area
    """
    P0, P1, P2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    # edge opposite corner k, as a vector
    e0, e1, e2 = P2 - P1, P0 - P2, P1 - P0
    dbl = np.linalg.norm(np.cross(e1, e2), axis=1)
    sq = np.stack([np.einsum("ij,ij->i", e, e) for e in (e0, e1, e2)], axis=1)
    # cot at corner k = (a . b) / |a x b| with a, b the two edges leaving it
    dots = np.stack([
        -np.einsum("ij,ij->i", e1, e2),
        -np.einsum("ij,ij->i", e2, e0),
        -np.einsum("ij,ij->i", e0, e1),
    ], axis=1)
    return dots / dbl[:, None], sq, dbl
