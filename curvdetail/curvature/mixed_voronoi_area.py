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
    cot, sq, dbl = corner_cotangents(V, F)
    area = 0.5 * dbl
    # Voronoi part of corner k: edges (k,k+1) opposite k+2 and (k,k+2) opposite k+1
    voronoi = np.stack([
        sq[:, 2] * cot[:, 2] + sq[:, 1] * cot[:, 1],
        sq[:, 0] * cot[:, 0] + sq[:, 2] * cot[:, 2],
        sq[:, 1] * cot[:, 1] + sq[:, 0] * cot[:, 0],
    ], axis=1) / 8.0
    obtuse_corner = cot < 0.0
    obtuse_face = obtuse_corner.any(axis=1)
    share = np.where(obtuse_corner, 0.5, 0.25) * area[:, None]
    contrib = np.where(obtuse_face[:, None], share, voronoi)
    return np.bincount(F.ravel(), weights=contrib.ravel(), minlength=V.shape[0])
