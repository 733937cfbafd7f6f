"""Per-triangle quantities shared by the cotangent Laplacian and the mixed Voronoi area."""

import functools

import numpy as np


def ignoring_underflow(function):
    """``function`` run with numpy's underflow ignored, the caller's other ``np.seterr`` kept:
    squares of a tiny component (a triangle almost in a coordinate plane) underflow harmlessly."""
    @functools.wraps(function)
    def quiet(*args, **kwargs):
        with np.errstate(under="ignore"):
            return function(*args, **kwargs)
    return quiet


@ignoring_underflow
def corner_cotangents(V, F, *, lengths=True):
    """Cotangent of the angle at each corner and squared length of the opposite edge.

    ``lengths=False`` skips the squared lengths (``sq`` is then None).

    Returns
    -------
    cot : (m, 3) float array
        Cot of the angle at corner k of each triangle (the transpose of a contiguous (3, m) array).
    sq : (m, 3) float array
        Squared length of the edge opposite corner k (joining corners k+1, k+2).
    dbl : (m,) float array
        Twice the triangle's area.
    """
    # coordinate-major (3, m) arrays, contiguous rows; np.take and in-place arithmetic: half the time
    Vt = np.ascontiguousarray(V.T)
    Ft = np.ascontiguousarray(F.T)
    P0, P1, P2 = (np.take(Vt, Ft[k], axis=1) for k in range(3))
    e0, e1 = P2 - P1, P0 - P2                       # edge opposite corner k, as a vector
    e2 = np.subtract(P1, P0, out=P0)
    dbl = np.zeros(Ft.shape[1])
    for a, b, c, d in ((1, 2, 2, 1), (2, 0, 0, 2), (0, 1, 1, 0)):      # |e1 x e2|^2, term by term
        cross = e1[a] * e2[b]
        cross -= e1[c] * e2[d]
        cross *= cross
        dbl += cross
    np.sqrt(dbl, out=dbl)
    sq = np.stack([_dot(e0, e0), _dot(e1, e1), _dot(e2, e2)]).T if lengths else None
    # cot at corner k = (a . b) / |a x b| with a, b the two edges leaving it (minus those ending there)
    cot = np.stack([_dot(e1, e2), _dot(e2, e0), _dot(e0, e1)])
    cot *= np.divide(-1.0, dbl)
    return cot.T, sq, dbl


def _dot(a, b):
    out = a[0] * b[0]
    out += a[1] * b[1]
    out += a[2] * b[2]
    return out


def folded_triangles(V, F, X, A):
    """Triangles of ``X`` (rest shape ``V``, same ``F``) folded over, increasing: their normal
    points against both their rest normal and the one the linear map ``A`` (3, 3) (an edit's
    turn) gives the rest shape, so a triangle turned by up to that turn does not count."""
    def normals(Y):
        return np.cross(Y[F[:, 1]] - Y[F[:, 0]], Y[F[:, 2]] - Y[F[:, 0]])

    after = normals(X)
    against_rest = np.einsum("ij,ij->i", normals(V), after) < 0
    against_turned = np.einsum("ij,ij->i", normals(V @ np.asarray(A).T), after) < 0
    return np.flatnonzero(against_rest & against_turned)


def face_double_areas(V, F):
    """|(v1 - v0) x (v2 - v0)| per triangle, shape (m,)."""
    # coordinate-major (3, m) rows, contiguous: 3x faster than columns of (m, 3) arrays
    Vt = np.ascontiguousarray(np.asarray(V, dtype=np.float64).T)
    Ft = np.ascontiguousarray(np.asarray(F).T)
    P0, a, b = (np.take(Vt, Ft[k], axis=1) for k in range(3))
    a -= P0
    b -= P0
    cx = a[1] * b[2] - a[2] * b[1]
    cy = a[2] * b[0] - a[0] * b[2]
    cz = a[0] * b[1] - a[1] * b[0]
    cx *= cx
    cy *= cy
    cz *= cz
    cx += cy
    cx += cz
    return np.sqrt(cx, out=cx)


def bbox_diagonal(V):
    """Length of the axis-aligned bounding box's diagonal."""
    Vt = np.ascontiguousarray(np.asarray(V, dtype=np.float64).T)
    extent = Vt.max(axis=1) - Vt.min(axis=1)
    largest = float(np.abs(extent).max()) if extent.size else 0.0
    if not 0.0 < largest < np.inf:
        return largest
    # scaled by the largest extent: no square over- or underflows
    with np.errstate(under="ignore"):
        return largest * float(np.sqrt(np.sum((extent / largest) ** 2)))


def centroid_diameter(V):
    """Twice the largest distance of a vertex from the centroid: a rotation-invariant length of
    the bbox diagonal's size, for thresholds."""
    V = np.asarray(V, dtype=np.float64)
    if not V.shape[0]:
        return 0.0
    offsets = V - V.mean(axis=0)
    return float(2.0 * np.sqrt(np.einsum("ij,ij->i", offsets, offsets).max()))


def bbox_centre(V):
    """The centre of the axis-aligned bounding box, shape (3,) (zeros for no vertices)."""
    Vt = np.ascontiguousarray(np.asarray(V, dtype=np.float64).T)
    if not Vt.shape[1]:
        return np.zeros(Vt.shape[0])
    return 0.5 * (Vt.max(axis=1) + Vt.min(axis=1))


def vertex_normals(X, F, face_cross=None, aligned=False):
    """Area-weighted unit vertex normals, shape (n, 3); ``face_cross`` (m, 3): the triangles'
    ``(x1 - x0) x (x2 - x0)`` where at hand. ``aligned=True`` (triangles not consistently
    oriented): each normal enters a vertex's sum turned to agree with the vertex's largest
    triangle, so reversed triangles do not cancel (the sign is then arbitrary)."""
    fn = np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]]) if face_cross is None else face_cross
    n = X.shape[0]
    if not aligned:
        N = np.column_stack([np.bincount(F.ravel(), weights=np.repeat(fn[:, k], 3), minlength=n)
                             for k in range(3)])
    else:
        corner_vertex = F.ravel()
        corner_face = np.repeat(np.arange(F.shape[0]), 3)
        size = np.repeat(np.einsum("ij,ij->i", fn, fn), 3)
        order = np.lexsort((size, corner_vertex))
        last = np.flatnonzero(np.r_[corner_vertex[order][1:] != corner_vertex[order][:-1], True])
        reference = np.zeros((n, 3))
        reference[corner_vertex[order][last]] = fn[corner_face[order][last]]
        N = np.zeros((n, 3))
        for corner in range(3):
            sign = np.where(np.einsum("ij,ij->i", fn, reference[F[:, corner]]) < 0, -1.0, 1.0)
            N += np.column_stack([np.bincount(F[:, corner], weights=sign * fn[:, k], minlength=n)
                                  for k in range(3)])
    length = np.linalg.norm(N, axis=1, keepdims=True)
    return N / np.where(length > 0, length, 1.0)
