"""Closest point on a triangle mesh (libigl's AABB tree), with the input checks its callers share."""

import igl
import numpy as np

from ..curvature.checks import ZERO_AREA_ADVICE, ZERO_AREA_RELATIVE, as_faces, as_vertices
from ..curvature.geometry import face_double_areas
from ..curvature.errors import MeshError, first_indices

#: Largest coordinate taken: everything runs in a unit frame, so only the squares of the
#: input's own differences must not overflow.
MAX_COORDINATE_HERE = 1e150

#: Points further than this (bbox diagonals of the mesh) are refused: libigl's squared
#: distances overflow beyond ~1e154 diagonals (and its face index is garbage there).
MAX_RELATIVE_DISTANCE = 1e100


def closest_points(P, V, F):
    """Exact closest point of a triangle mesh to each query point.

    libigl's ``point_mesh_squared_distance`` (an AABB tree, in double precision), run in a frame
    where the mesh has unit size, so the scale and position of the input do not matter.

    Parameters
    ----------
    P : (k, d) float array
        Query points, d = 2 (a planar mesh) or 3; k = 0 allowed.
    V : (n, d) float array
        Mesh vertices.
    F : (m, 3) int array
        Triangles, none of zero area.

    Returns
    -------
    sqrD : (k,) float array
        Squared distance from each point to its closest point.
    face : (k,) int64 array
        Triangle holding the closest point (of several at the same distance, any one).
    C : (k, d) float array
        The closest points.
    bary : (k, 3) float array
        Barycentric coordinates of ``C`` in ``face`` (>= 0, rows summing to 1).

    Raises
    ------
    MeshError
        Malformed input (see `check_points_and_mesh`).

    Examples
    --------
    >>> V = np.array([[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]]); F = np.array([[0, 1, 2]])
    >>> sqrD, face, C, bary = closest_points(np.array([[0.25, 0.25, 2.0]]), V, F)
    >>> sqrD.round(12).tolist(), face.tolist(), bary.round(12).tolist()
    ([4.0], [0], [[0.5, 0.25, 0.25]])
    """
    P, V, F = check_points_and_mesh(P, V, F, names=("P", "V", "F"))
    centre = 0.5 * (V.max(axis=0) + V.min(axis=0))
    P, U, scale = unit_frame(P, V)
    sqrD, face, C, bary = closest_in_frame(P, U, F)
    return sqrD * scale ** 2, face, C * scale + centre, bary


def closest_in_frame(P, V, F, bary=True):
    """`closest_points` on arrays that passed `check_points_and_mesh`, in the frame
    given (no rescaling): ``(sqrD, face, C, bary)``; ``bary=False``: None for the barycentrics."""
    if P.shape[0] == 0:
        return np.empty(0), np.empty(0, dtype=np.int64), np.empty((0, V.shape[1])), np.empty((0, 3))
    sqrD, face, C = igl.point_mesh_squared_distance(P, V, F)
    return sqrD, face, C, _barycentric(C, V[F[face]]) if bary else None


class SurfaceTree:
    """libigl's AABB tree of a checked triangle mesh, built once for many distance queries.

    The tree holds the mesh in its unit frame (bounding box centred at the origin, diagonal 1),
    so queries do not depend on the mesh's scale or position; a planar mesh is held in z = 0
    (libigl's 2D tree corrupts memory).

    Parameters
    ----------
    V : (n, d) float array
        Vertex positions, d = 2 or 3, as `check_points_and_mesh` returns them.
    F : (m, 3) int64 array
        Triangles.

    Examples
    --------
    >>> V = np.array([[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]]); F = np.array([[0, 1, 2]])
    >>> SurfaceTree(V, F).distance(np.array([[0.25, 0.25, 2.0], [2.0, 0.0, 0.0]])).round(12).tolist()
    [2.0, 1.0]
    """

    def __init__(self, V, F):
        self.centre = 0.5 * (V.max(axis=0) + V.min(axis=0))
        self.scale = diagonal(V)
        self.U = _in_space((V - self.centre) / self.scale)
        self.F = F
        self._tree = igl.AABB()
        self._tree.init(self.U, F)

    def squared_distance_in_frame(self, P):
        """Squared distances of the points ``P`` (k, d), given in the tree's unit frame."""
        if P.shape[0] == 0:
            return np.empty(0)
        return self._tree.squared_distance(self.U, self.F, _in_space(P))[0]

    def distance(self, P):
        """Exact distance (k,) of each point of ``P`` (k, d), in the mesh's coordinates."""
        return self.scale * np.sqrt(self.squared_distance_in_frame((P - self.centre) / self.scale))


def _in_space(X):
    """``X`` as a C-contiguous (k, 3) float64 array (z = 0 appended to planar points)."""
    X = X if X.shape[1] == 3 else np.column_stack([X, np.zeros(X.shape[0])])
    return np.ascontiguousarray(X, dtype=np.float64)


def _barycentric(X, T):
    """Barycentric coordinates of points ``X`` (k, d) in triangles ``T`` (k, 3, d), clipped to
    [0, 1] and normalized (``X`` lies on its triangle, up to rounding)."""
    e0, e1, w = T[:, 1] - T[:, 0], T[:, 2] - T[:, 0], X - T[:, 0]
    d00, d01, d11 = (e0 * e0).sum(1), (e0 * e1).sum(1), (e1 * e1).sum(1)
    d20, d21 = (w * e0).sum(1), (w * e1).sum(1)
    det = d00 * d11 - d01 * d01
    v, t = (d11 * d20 - d01 * d21) / det, (d00 * d21 - d01 * d20) / det
    bary = np.clip(np.column_stack([1.0 - v - t, v, t]), 0.0, 1.0)
    return bary / bary.sum(1, keepdims=True)


def check_points_and_mesh(points, V, F, names=("points", "V", "F")):
    """``(P, V, F)`` as C-contiguous float64 / float64 / int64 arrays, or MeshError: dtypes and
    shapes as `check_mesh` takes them (``V`` and ``points`` both
    (k, 2) or both (k, 3)), NaN or infinite coordinates, triangle indices outside ``V``,
    zero-area triangles or a mesh of zero extent, coordinates beyond 1e150 and points further
    than ``MAX_RELATIVE_DISTANCE`` (1e100) bbox diagonals. ``names``: the three arguments as
    the caller calls them, for the messages and ``e.parameter``."""
    P = as_coordinates(points, names[0], allow_empty=True)
    V = as_coordinates(V, names[1])
    _check_dimension(P, V, names)
    F = np.ascontiguousarray(as_faces(F, V.shape[0], names[2]), dtype=np.int64)
    if np.ptp(V, axis=0).max() == 0:
        raise MeshError(f"{names[1]}: all {V.shape[0]} vertices are at one point (zero extent)",
                        parameter=names[1], count=V.shape[0], hint="pass a mesh with area.")
    _, U, _ = unit_frame(V[:0], V)             # areas relative to the unit bbox diagonal: any scale
    U = U if U.shape[1] == 3 else np.column_stack([U, np.zeros(U.shape[0])])
    zero = np.flatnonzero(face_double_areas(U, F) <= 2.0 * ZERO_AREA_RELATIVE)
    if zero.size:
        raise MeshError(f"{names[2]}: {zero.size} triangles have zero area (first: {first_indices(zero)}; "
                        f"areas up to {ZERO_AREA_RELATIVE:g} of the bbox diagonal squared count)",
                        parameter=names[2], count=zero.size, first=zero[:5].tolist(), hint=ZERO_AREA_ADVICE)
    _check_reach(P, V, names)
    return P, V, F


def check_points(points, V, names=("points", "V")):
    """The query ``points`` as `check_points_and_mesh` checks them, against a mesh vertex array
    ``V`` that passed it: a C-contiguous float64 (k, d) array, or MeshError."""
    P = as_coordinates(points, names[0], allow_empty=True)
    _check_dimension(P, V, names)
    _check_reach(P, V, names)
    return P


def _check_dimension(P, V, names):
    if P.shape[1] != V.shape[1]:
        raise MeshError(f"{names[0]} {P.shape} and {names[1]} {V.shape} must both be (k, 2) or both (k, 3).",
                        parameter=names[0], value=P.shape)


def _check_reach(P, V, names):
    """MeshError where a point of ``P`` lies further than ``MAX_RELATIVE_DISTANCE`` bbox diagonals
    of ``V`` from it."""
    far = box_gap(P, V) / diagonal(V)
    if far.size and far.max() > MAX_RELATIVE_DISTANCE:
        bad = np.flatnonzero(far > MAX_RELATIVE_DISTANCE)
        raise MeshError(f"{names[0]}: {bad.size} points lie more than {MAX_RELATIVE_DISTANCE:.0e} bbox "
                        f"diagonals of {names[1]} from it (first: {first_indices(bad)}; up to {far.max():.3g})",
                        parameter=names[0], count=bad.size, first=bad[:5].tolist(),
                        hint="the closest-point arithmetic overflows there: pass points near the mesh.")


def as_coordinates(X, name, allow_empty=False):
    """``X`` as a C-contiguous (k, 2) or (k, 3) float64 array, checked by ``as_vertices``."""
    try:
        arr = np.asarray(X)
    except Exception:
        return as_vertices(X, name)                  # raises its "could not be read" MeshError
    if arr.ndim != 2 or arr.shape[1] not in (2, 3):
        raise MeshError(f"{name} has shape {arr.shape}; pass a (k, 2) or (k, 3) coordinate array.",
                        parameter=name, value=arr.shape)
    if arr.shape[0] == 0 and allow_empty:
        as_vertices(np.zeros((1, arr.shape[1]), dtype=arr.dtype), name, dim=arr.shape[1])   # its dtype check
        return np.empty((0, arr.shape[1]))
    return np.ascontiguousarray(as_vertices(arr, name, dim=arr.shape[1], max_coordinate=MAX_COORDINATE_HERE),
                                dtype=np.float64)


def unit_frame(P, V):
    """``P`` and ``V`` moved and scaled so that ``V``'s bounding box is centred at the origin
    with unit diagonal, and that diagonal (distances in the frame times it are true distances)."""
    centre = 0.5 * (V.max(axis=0) + V.min(axis=0))
    scale = diagonal(V)
    return (P - centre) / scale, (V - centre) / scale, scale


def diagonal(V):
    """The bounding-box diagonal of a mesh of non-zero extent, without squaring its extents
    (which underflow below ~1e-154)."""
    extent = np.ptp(V, axis=0)
    largest = extent.max()
    return float(largest * np.linalg.norm(extent / largest))


def box_gap(P, V):
    """Distance of each point from the bounding box of ``V`` (0 inside), shape (k,)."""
    lo, hi = V.min(axis=0), V.max(axis=0)
    return np.linalg.norm(np.maximum(np.maximum(lo - P, P - hi), 0.0), axis=1)
