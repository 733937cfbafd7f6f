"""Mixed Voronoi area per vertex (Meyer, Desbrun, Schroeder, Barr 2002)."""

import numpy as np

from .geometry import corner_cotangents
from .checks import checked_arrays


def mixed_voronoi_area(V, F):
    """Mixed Voronoi area ``A_i`` of every vertex.

    For a non-obtuse triangle each corner receives its Voronoi region,
    ``(|e_ij|^2 cot a + |e_ik|^2 cot b) / 8``; for an obtuse triangle the obtuse corner receives
    half the triangle's area and the two others a quarter each. The areas tile the surface:
    ``A.sum()`` equals the total triangle area.

    Parameters
    ----------
    V : (n, 3) float array
        Vertex positions.
    F : (m, 3) int array
        Triangles.

    Returns
    -------
    A : (n,) float array
        Strictly positive areas.

    Raises
    ------
    MeshError
        If the mesh is malformed (as for `cotan_laplacian`).

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0]]); F = np.array([[0, 1, 2]])
    >>> mixed_voronoi_area(V, F)   # right triangle: circumcentre at the hypotenuse midpoint
    array([0.25 , 0.125, 0.125])
    """
    V, F = checked_arrays(V, F)                  # no copy: the result is computed from them
    return _mixed_voronoi_area_unchecked(V, F)


def _mixed_voronoi_area_unchecked(V, F):
    # corner k's Voronoi part, (|e_{k+1}|^2 cot_{k+1} + |e_{k+2}|^2 cot_{k+2}) / 8 with e_j opposite
    # corner j, is dbl (1 + cot_{k+1} cot_{k+2}) / 8: |e_j|^2 = dbl (cot_{j+1} + cot_{j+2}) and the
    # cotangents of a triangle satisfy cot_0 cot_1 + cot_1 cot_2 + cot_2 cot_0 = 1
    cot, _, dbl = corner_cotangents(V, F, lengths=False)
    c = cot.T                                       # (3, m), contiguous rows
    eighth = dbl / 8.0
    contrib = np.empty_like(c)
    for k in range(3):
        np.multiply(c[(k + 1) % 3], c[(k + 2) % 3], out=contrib[k])
        contrib[k] += 1.0
        contrib[k] *= eighth
    # an obtuse triangle: half its area to the obtuse corner, a quarter to each other one
    obtuse_corner = c < 0.0
    obtuse = np.flatnonzero(obtuse_corner.any(axis=0))
    contrib[:, obtuse] = np.where(obtuse_corner[:, obtuse], 2.0, 1.0) * eighth[obtuse]
    return np.bincount(np.ascontiguousarray(F.T).ravel(), weights=contrib.ravel(), minlength=V.shape[0])
