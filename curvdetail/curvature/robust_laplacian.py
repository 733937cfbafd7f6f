"""A cotangent Laplacian that tolerates degenerate triangles (Sharp & Crane 2020, mollification).

The plain `cotan_laplacian` refuses triangles of zero area: their cotangents
are infinite. Scans have them (a vertex on the opposite edge: a "cap"; two vertices at one point:
a "needle"). The mollified Laplacian takes its cotangents from the edge lengths alone (an
intrinsic metric), each lengthened by the smallest ``delta`` that leaves every triangle's
triangle inequality a slack of ``eps`` x the mean edge length; ``delta`` is 0 on a mesh without
such slivers, where the result is the plain cotan Laplacian to rounding.
"""

import numpy as np
import scipy.sparse as sp

from .checks import ZERO_AREA_RELATIVE, as_faces, as_vertices
from .geometry import bbox_diagonal, face_double_areas

#: Sharp & Crane's mollification factor: the least triangle-inequality slack, x the mean edge length.
MOLLIFY = 1e-6


def robust_laplacian(V, F, eps=MOLLIFY):
    """The mollified intrinsic cotangent Laplacian ``L`` and its lumped mass ``M``.

    Same convention as `cotan_laplacian`: symmetric positive semi-definite,
    ``(L X)_i = 1/2 sum_j (cot a_ij + cot b_ij)(x_i - x_j)``, rows summing to zero, the cotangents
    those of the triangles with edge lengths ``l + delta`` (``delta`` as in the module's text).
    A sum of one positive semi-definite energy per triangle, so PSD whatever the mesh.

    Parameters
    ----------
    V : (n, 3) float array
        Vertex positions
    F : (m, 3) int array
        Triangles (zero-area ones allowed)
    eps : float
        Least triangle-inequality slack, x the mean edge length

    Returns
    -------
    L : (n, n) scipy.sparse.csr_matrix
        The Laplacian
    M : (n, n) scipy.sparse.dia_matrix
        Lumped (barycentric) mass: a third of each intrinsic triangle area to each of its corners
    delta : float
        The length added to every edge (0 on a clean mesh)

    Raises
    ------
    MeshError
        Malformed ``V`` or ``F`` (shapes, dtypes, NaN, indices)

    Examples
    --------
    >>> V = np.array([[0, 0, 0], [2, 0, 0], [1, 0, 0], [1, 1, 0]], float)   # vertex 2 on edge 0-1
    >>> L, M, delta = robust_laplacian(V, [[0, 1, 2], [1, 0, 3]])
    >>> bool(np.isfinite(L.data).all() and delta > 0 and abs(L.sum(axis=1)).max() < 1e-6)
    True
    """
    V = as_vertices(V)
    F = as_faces(F, V.shape[0])
    n = V.shape[0]
    # l[:, k]: the length of the edge opposite corner k
    lengths = np.linalg.norm(V[F[:, [2, 0, 1]]] - V[F[:, [1, 2, 0]]], axis=2)
    slack = lengths.sum(axis=1, keepdims=True) - 2.0 * lengths          # l_j + l_k - l_i, per corner i
    delta = float(max(0.0, eps * lengths.mean() - slack.min()))
    a = lengths + delta
    s = a.sum(axis=1, keepdims=True)
    area = 0.25 * np.sqrt(s[:, 0] * np.prod(s - 2.0 * a, axis=1))      # Heron
    sq = a ** 2
    cot = (sq.sum(axis=1, keepdims=True) - 2.0 * sq) / (4.0 * area[:, None])   # (b^2 + c^2 - a^2) / 4A
    i, j = F[:, [1, 2, 0]].ravel(), F[:, [2, 0, 1]].ravel()           # the edge opposite each corner
    w = 0.5 * cot.ravel()
    off = sp.coo_matrix((-w, (i, j)), shape=(n, n))
    off = (off + off.T).tocsr()
    L = (off - sp.diags(np.asarray(off.sum(axis=1)).ravel())).tocsr()
    L.sum_duplicates()
    mass = np.bincount(F.ravel(), weights=np.repeat(area / 3.0, 3), minlength=n)
    return L, sp.diags(mass), delta


def degenerate_triangles(V, F):
    """Indices of the triangles of ``(V, F)`` the plain checks call zero-area (twice the area at
    most ``2 ZERO_AREA_RELATIVE`` x the bbox diagonal squared), as an int64 array."""
    V, F = as_vertices(V), as_faces(F, np.shape(V)[0])
    return np.flatnonzero(face_double_areas(V, F) <= 2.0 * ZERO_AREA_RELATIVE * bbox_diagonal(V) ** 2)


def flip_caps(V, F, rounds=8):
    """``F`` with the longest edge of each zero-area triangle flipped, where it has a second
    triangle and the flipped edge is not an edge already.

    A zero-area "cap" has its third vertex on its longest edge: flipping that edge splits the
    neighbouring triangle at that vertex, the same surface (point for point) without the cap (the
    intrinsic Delaunay flip of an edge facing a 180 degree angle). A "needle" (two vertices at one
    point) stays. Repeated up to ``rounds`` times, for caps next to caps.

    Parameters
    ----------
    V : (n, 3) float array, F : (m, 3) int array
        A consistently oriented manifold mesh

    Returns
    -------
    F : (m, 3) int64 array
        A new array, same triangle count and vertices

    Examples
    --------
    >>> V = np.array([[0, 0, 0], [2, 0, 0], [1, 0, 0], [1, 1, 0]], float)
    >>> flip_caps(V, [[0, 1, 2], [1, 0, 3]]).tolist()
    [[0, 3, 2], [3, 1, 2]]
    """
    V = as_vertices(V)
    F = as_faces(F, V.shape[0]).copy()
    n = V.shape[0]
    for _ in range(rounds):
        bad = degenerate_triangles(V, F)
        keys = (F * n + F[:, [1, 2, 0]]).ravel()        # half-edge F[f, c] -> F[f, c+1]
        order = np.argsort(keys)
        flipped, touched = 0, set()
        for f in bad:
            if f in touched:
                continue
            tri = F[f]
            edge_len = np.linalg.norm(V[tri[[1, 2, 0]]] - V[tri], axis=1)
            c = int(np.argmax(edge_len))                # edge tri[c] -> tri[c+1], opposite tri[c+2]
            p, q, k = tri[c], tri[(c + 1) % 3], tri[(c + 2) % 3]
            at = np.searchsorted(keys, q * n + p, sorter=order)
            if at == keys.size or keys[order[at]] != q * n + p:
                continue                                # a boundary edge: nothing to flip with
            g = order[at] // 3
            if g in touched:
                continue
            l = F[g][(order[at] % 3 + 2) % 3]            # the apex of the other triangle
            there = np.searchsorted(keys, [k * n + l, l * n + k], sorter=order).clip(max=keys.size - 1)
            if (keys[order[there]] == [k * n + l, l * n + k]).any():
                continue                                # edge k-l exists: the flip would double it
            F[f], F[g] = (p, l, k), (l, q, k)
            touched.update((f, g))
            flipped += 1
        if not flipped:
            break
    return F
