"""Curvature detail ``D = L V`` (the paper's ``K_i A_i``)."""

from .cotan_laplacian import checked_cotan_laplacian, laplacian_product


def curvature_detail(V, F):
    """Curvature detail ``D_i = K_i A_i = (L V)_i``, the gradient of the surface area at ``V``.

    Extensive: it scales with the vertex's area, so it must never be interpolated across meshes
    of different density (transfer ``K`` and multiply by the new area instead).

    Parameters
    ----------
    V : (n, 3) float array
        Vertex positions.
    F : (m, 3) int array
        Triangles.

    Returns
    -------
    D : (n, 3) float array
        Equal to ``cotan_laplacian(V, F) @ V``.

    Raises
    ------
    MeshError
        If the mesh is malformed (as for `cotan_laplacian`).

    Examples
    --------
    >>> import numpy as np
    >>> from curvdetail.curvature.testing import grid
    >>> V, F = grid(5, 5)                        # a flat square
    >>> D = curvature_detail(V, F)
    >>> inner = (V[:, :2] > 0).all(1) & (V[:, :2] < 1).all(1)
    >>> bool(np.abs(D[inner]).max() < 1e-12)     # a plane has no interior detail
    True
    """
    V, F, L = checked_cotan_laplacian(V, F)
    return laplacian_product(L, V)      # L @ V, without cancellation far from the origin
