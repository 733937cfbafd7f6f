"""Mean curvature normal per vertex (Meyer et al. 2002)."""

from .cotan_laplacian import checked_cotan_laplacian, laplacian_product
from .mixed_voronoi_area import _mixed_voronoi_area_unchecked


def mean_curvature_normal(V, F):
    """Mean curvature normal and mixed Voronoi area per vertex.

    Parameters
    ----------
    V : (n, 3) float array
        Vertex positions.
    F : (m, 3) int array
        Triangles.

    Returns
    -------
    K : (n, 3) float array
        ``K_i = (L V)_i / A_i = 2 H_i n_i``; on a sphere of radius R it points away from the
        centre with ``|K| = 2 / R``. Intensive: independent of the mesh density. On boundary
        vertices it carries the boundary's geodesic-curvature term as well.
    A : (n,) float array
        Mixed Voronoi areas (`mixed_voronoi_area`); ``A.sum()`` is the surface area.

    Raises
    ------
    MeshError
        If the mesh is malformed (as for `cotan_laplacian`).

    Examples
    --------
    >>> import numpy as np
    >>> from curvdetail.curvature.testing import icosphere
    >>> K, A = mean_curvature_normal(*icosphere(radius=2.0, subdivisions=4))
    >>> bool(np.allclose(np.linalg.norm(K, axis=1), 1.0, atol=2e-2))
    True
    """
    V, F, L = checked_cotan_laplacian(V, F)
    A = _mixed_voronoi_area_unchecked(V, F)
    return laplacian_product(L, V) / A[:, None], A
