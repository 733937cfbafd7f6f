"""Locate points in a triangle mesh: containing (or nearest) triangle and barycentric coordinates."""

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ..curvature._validate import (check_choice, ZERO_AREA_ADVICE, ZERO_AREA_RELATIVE, as_count, as_faces, as_vertices, bbox_diagonal,
                                   face_double_areas)
from ..curvature.errors import MeshError, first_indices

#: Points further than this (bbox diagonals of the mesh) from its bounding box skip the fast
#: engines for the bounding-box tree search: pymeshlab's grid search slows down with the
#: distance (0.2 s at 1e4 diagonals on a 40k-vertex grid, no answer after 60 s at 1e10).
FAR_POINTS = 1.0

#: Largest coordinate taken here: everything runs in a unit frame, so only the squares of the
#: input's own differences must not overflow (the core's limit, for areas, is lower).
MAX_COORDINATE_HERE = 1e150

#: Points further than this (bbox diagonals) are refused: the closest-point tests multiply
#: squared lengths, which overflow beyond ~1e77 diagonals.
MAX_RELATIVE_DISTANCE = 1e50

#: Barycentric coordinates taken by interpolate / spread: entries in [-tol, 1 + tol], rows summing
#: to 1 within tol. locate() clips and normalizes its coordinates, so they are off by rounding only.
BARY_TOLERANCE = 1e-6

#: Most vertices spread() returns rows for: its (n, c) result is dense (0.8 GB per column here).
MAX_SPREAD_VERTICES = 100_000_000


def locate(points, V, F, *, engine="auto", candidates=8, chunk=20_000):
    """Nearest triangle and barycentric coordinates of each point, vectorized.

    Works in the plane (a parameter domain, ``V`` of shape (n, 2)) and in space ((n, 3): the
    closest point on the surface). A planar point inside a triangle gets distance 0; one a hair
    outside the domain falls back to the nearest triangle (its closest point, ``distance > 0``).

    Engines: ``"numpy"``: candidate triangles from a ``cKDTree`` of centroids (plus the nearest
    vertex's triangles in a second round where the first is not certain), exact closest point on
    each (Ericson's region tests, all in numpy); the candidates are certain only where triangle
    sizes vary little (a large triangle beside small ones can be missed). ``"auto"``: in the
    plane matplotlib's trapezoid-map point location (C++); in space pymeshlab's
    ``transfer_attributes_per_vertex`` (a uniform grid, C++, searching one diagonal of the mesh
    around each point) for the nearest face; then the exact barycentric coordinates of the
    closest point in that face. Points more than ``FAR_POINTS`` bbox diagonals outside the
    mesh's bounding box skip both (pymeshlab's grid search slows down with the distance,
    without bound), and the points they find no triangle for (planar points outside the
    domain, points in space more than a diagonal from the surface) follow, for a bounding-box
    tree search over every triangle that could hold the closest point (that of
    :func:`~curvdetail.remesh.evaluate.hausdorff`), all points at once.

    What is exact, to rounding: always, the closest point and distance within the triangle
    returned; with ``"auto"``, the triangle itself for planar points (the trapezoid map inside
    the domain, the tree search outside it) and for points in space the tree search locates.
    For the rest, pymeshlab's grid returns the closest face on and near the surface, but not
    always away from it (a flat layer at the height of a wavy one and reaching past its edge:
    up to 0.5 % of the diagonal too far; :func:`~curvdetail.remesh.evaluate.vertex_distance`
    with ``far=True`` measures such points exactly). With ``"numpy"`` the triangle is the best
    of the candidates above.
    Far away (from ~1e6 diagonals, facing a flat part) triangles whose distances differ by less
    than 1e-13 of the distance are ties: the distance is exact to that, and the closest point
    may be any of theirs.

    Everything is computed in a frame where the mesh has unit size, so the scale and position
    of the input do not matter.

    Parameters
    ----------
    points : (k, d) float array   query points, d = 2 or 3
    V : (n, d) float array        mesh vertices, same dimension
    F : (m, 3) int array          triangles
    engine : {"auto", "numpy"}
    candidates : int              nearest centroids tried per point by the numpy engine
    chunk : int                   points per batch in the numpy engine (bounds memory)

    Returns
    -------
    face : (k,) int array          index of the nearest triangle
    bary : (k, 3) float array      barycentric coordinates of the closest point in it (>= 0, sum 1)
    distance : (k,) float array    distance from the point to that closest point

    Raises
    ------
    MeshError   malformed input (see :func:`check_points_and_mesh`): mismatched dimensions,
                dtypes that are not real numbers / integers, empty ``F``, NaN or infinite
                coordinates, triangle indices outside ``V``, zero-area triangles, a mesh of zero
                extent, coordinates beyond 1e150 or points more than 1e50 bbox diagonals away
    ValueError  an unknown ``engine``; ``candidates`` or ``chunk`` not a whole number >= 1

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0., 0.], [1., 0.], [0., 1.], [1., 1.]]); F = np.array([[0, 1, 2], [1, 3, 2]])
    >>> face, bary, dist = locate(np.array([[0.25, 0.25], [0.9, 0.8]]), V, F)
    >>> face.tolist(), np.round(bary, 3).tolist()
    ([0, 1], [[0.5, 0.25, 0.25], [0.2, 0.7, 0.1]])
    """
    P, V, F = check_points_and_mesh(points, V, F)
    engine = check_choice(engine, "engine", ("auto", "numpy"), "; use 'auto' or 'numpy'.")
    return _locate(P, V, F, engine, as_count(candidates, "candidates"), as_count(chunk, "chunk"))


#: Points per block of the exact closest-point step of :func:`_locate` (bounds its temporaries
#: to ~70 MB; the same results as one block).
EXACT_BLOCK = 200_000


def _locate(P, V, F, engine="auto", candidates=8, chunk=20_000):
    """:func:`locate` on arrays that passed :func:`check_points_and_mesh`."""
    if P.shape[0] == 0:
        return np.empty(0, dtype=np.int64), np.empty((0, 3)), np.empty(0)
    # in a frame where the mesh has unit size at the origin: the grid, the trapezoid map and
    # the closest-point arithmetic then work alike for meshes of any scale and position
    P, V, scale = _unit_frame(P, V)
    if engine == "numpy":
        face, bary, dist = _locate_kdtree(P, V, F, candidates, chunk)
        return face, bary, dist * scale
    face = np.full(P.shape[0], -1, dtype=np.int64)
    gap = _box_gap(P, V)
    near = np.flatnonzero(gap <= FAR_POINTS)       # the far ones are left to the tree search below
    if near.size:
        face[near] = _trifinder(P[near], V, F) if V.shape[1] == 2 else _nearest_face_meshlab(P[near], V, F)
    # and the points neither found (planar ones outside the domain, points in space more than a
    # diagonal from the surface) the tree search too: the numpy engine's candidates miss a large
    # triangle beside small ones (just outside a long boundary edge: 0.069 too far)
    bad = np.flatnonzero(face < 0)             # the far points among them
    if bad.size:
        face[bad] = _nearest_face_tree(P[bad], V, F)
    bary, dist = np.empty((P.shape[0], 3)), np.empty(P.shape[0])
    # in blocks: the region formulas' temporaries for all points at once were the transfer's
    # peak (1.46M edge samples: 508 MB of 746 MB)
    for lo in range(0, P.shape[0], EXACT_BLOCK):
        part = slice(lo, lo + EXACT_BLOCK)
        b, d = _closest_barycentric(P[part, None, :], V[F[face[part]]][:, None])
        bary[part], dist[part] = b[:, 0], d[:, 0]
    return face, bary, dist * scale


def check_points_and_mesh(points, V, F, names=("points", "V", "F")):
    """``(P, V, F)`` as float64 / float64 / int64 arrays, or MeshError: dtypes and shapes as in
    :func:`~curvdetail.curvature.check_mesh` (``V`` and ``points`` (k, 2) or (k, 3), alike),
    NaN or infinite coordinates, triangle indices outside ``V`` or repeated in a triangle,
    zero-area triangles or a mesh of zero extent, coordinates beyond 1e150 (``as_vertices``) and
    points further than ``MAX_RELATIVE_DISTANCE`` bbox diagonals. ``names``: the three
    arguments as the caller calls them, for the messages."""
    P = _as_coordinates(points, names[0], allow_empty=True)
    V = _as_coordinates(V, names[1])
    if P.shape[1] != V.shape[1]:
        raise MeshError(f"{names[0]} {P.shape} and {names[1]} {V.shape} must both be (k, 2) or both (k, 3).")
    F = as_faces(F, V.shape[0], names[2])
    _check_areas(V, F, names)
    far = _box_gap(P, V) / _diagonal(V) if P.shape[0] else np.zeros(0)
    if far.size and far.max() > MAX_RELATIVE_DISTANCE:
        raise MeshError(f"{names[0]}: {np.count_nonzero(far > MAX_RELATIVE_DISTANCE)} points lie more than "
                        f"{MAX_RELATIVE_DISTANCE:.0e} bbox diagonals of {names[1]} from it (first: "
                        f"{first_indices(np.flatnonzero(far > MAX_RELATIVE_DISTANCE))}; up to {far.max():.3g}); "
                        "the closest-point arithmetic overflows there: pass points near the mesh.")
    return P, V, F


def _as_coordinates(X, name, allow_empty=False):
    """``X`` as a C-contiguous (k, 2) or (k, 3) float64 array, checked by ``as_vertices``."""
    try:
        arr = np.asarray(X)
    except Exception:
        return as_vertices(X, name)                  # raises its "could not be read" MeshError
    if arr.ndim != 2 or arr.shape[1] not in (2, 3):
        raise MeshError(f"{name} has shape {arr.shape}; pass a (k, 2) or (k, 3) coordinate array.")
    if arr.shape[0] == 0 and allow_empty:
        as_vertices(np.zeros((1, arr.shape[1]), dtype=arr.dtype), name, dim=arr.shape[1])   # its dtype check
        return np.empty((0, arr.shape[1]))
    return as_vertices(arr, name, dim=arr.shape[1], max_coordinate=MAX_COORDINATE_HERE)


def _check_areas(V, F, names):
    """MeshError for a mesh of zero extent or with zero-area triangles (pymeshlab's grid does
    not return on a mesh collapsed to a point; closest points on a degenerate triangle are
    ill-defined)."""
    if np.ptp(V, axis=0).max() == 0:
        raise MeshError(f"{names[1]}: all {V.shape[0]} vertices are at one point (zero extent); pass a mesh "
                        "with area.")
    _, U, _ = _unit_frame(V[:0], V)             # areas relative to the unit bbox diagonal: any scale
    U = U if U.shape[1] == 3 else np.column_stack([U, np.zeros(U.shape[0])])
    zero = np.flatnonzero(face_double_areas(U, F) <= 2.0 * ZERO_AREA_RELATIVE)
    if zero.size:
        raise MeshError(f"{names[2]}: {zero.size} triangles have zero area (first: {first_indices(zero)}; "
                        f"areas up to {ZERO_AREA_RELATIVE:g} of the bbox diagonal squared count); "
                        f"{ZERO_AREA_ADVICE}.")


def _unit_frame(P, V):
    """``P`` and ``V`` moved and scaled so that ``V``'s bounding box is centred at the origin
    with unit diagonal, and that diagonal (distances in the frame times it are true distances)."""
    centre = 0.5 * (V.max(axis=0) + V.min(axis=0))
    scale = _diagonal(V)
    return (P - centre) / scale, (V - centre) / scale, scale


def _diagonal(V):
    """The bounding-box diagonal of a mesh of non-zero extent, without squaring its extents
    (which underflow below ~1e-154)."""
    extent = np.ptp(V, axis=0)
    largest = extent.max()
    return float(largest * np.linalg.norm(extent / largest))


def _box_gap(P, V):
    """Distance of each point from the bounding box of ``V`` (0 inside), shape (k,)."""
    lo, hi = V.min(axis=0), V.max(axis=0)
    return np.linalg.norm(np.maximum(np.maximum(lo - P, P - hi), 0.0), axis=1)


def _trifinder(P, V, F):
    """Containing triangle per planar point (-1 outside or where matplotlib cannot build its
    trapezoid map, e.g. over flipped triangles)."""
    from matplotlib.tri import Triangulation, TrapezoidMapTriFinder

    try:
        finder = TrapezoidMapTriFinder(Triangulation(V[:, 0], V[:, 1], F))
        return np.asarray(finder(P[:, 0], P[:, 1]), dtype=np.int64)
    except (RuntimeError, ValueError):
        return np.full(P.shape[0], -1, dtype=np.int64)


def _nearest_face_meshlab(P, V, F):
    """Nearest face per 3D point from pymeshlab's closest-point grid (-1 where it found none)."""
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32)))
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=P))
    # Every parameter explicitly: pymeshlab keeps values from earlier calls in one process. The
    # search radius is absolute, one diagonal of the mesh (V is in its unit frame): a percentage
    # is of the points' bounding box, 0 for one point, and a lone point found no face.
    ms.transfer_attributes_per_vertex(
        sourcemesh=0, targetmesh=1, vertexsampling=False, geomtransfer=False, normaltransfer=False,
        colortransfer=False, qualitytransfer=False, selectiontransfer=False, qualitydistance=False,
        savebarycentric=True, upperbound=pymeshlab.PureValue(1.0), onselected=False)
    face = np.rint(ms.mesh(1).vertex_custom_scalar_attribute_array("NearestFaceIndex")).astype(np.int64)
    face[(face < 0) | (face >= F.shape[0])] = -1
    return face


def _nearest_face_tree(P, V, F):
    """Nearest triangle per point (k, d), exact at any distance: the bounding-box tree search of
    :func:`~.evaluate._surface_distance` (every triangle that could hold the closest point,
    all points at once, ``SEARCH_POINTS`` at a time), keeping the triangle of each distance.

    The first bound is the triangle :func:`~.evaluate._greedy_triangle` picks (the search drops
    boxes within ``PRUNE_RELATIVE`` of the bound, so the triangle that set it must be known); a triangle
    closer than the bound lies in boxes closer than it, so none is missed: the face returned
    is at the least distance, to rounding and to ``PRUNE_RELATIVE`` (very far from a flat
    part, many triangles tie within that, and the face is any of them)."""
    # imported here: evaluate imports locate
    from .evaluate import SEARCH_POINTS, _box_tree, _descend, _exact_distances, _greedy_triangle

    k = P.shape[0]
    T = V[F]
    tree = _box_tree(T)
    Q = np.ascontiguousarray(P.T)
    face = np.empty(k, dtype=np.int64)
    for lo in range(0, k, SEARCH_POINTS):
        face[lo:lo + SEARCH_POINTS] = _greedy_triangle(tree, Q[:, lo:lo + SEARCH_POINTS])
    best = _exact_distances(P, T, np.arange(k), face)
    todo = [np.arange(lo, min(k, lo + SEARCH_POINTS)) for lo in range(0, k, SEARCH_POINTS)]
    while todo:
        idx = todo.pop()
        pairs = _descend(tree, Q[:, idx], best[idx])
        if pairs is None:                       # too many pairs at once: half the points
            todo += [idx[:idx.size // 2], idx[idx.size // 2:]]
            continue
        pt, tri = pairs
        if pt.size:
            d = _exact_distances(P, T, idx[pt], tri)
            order = np.lexsort((d, pt))             # per point, its nearest pair first
            win = order[np.flatnonzero(np.r_[True, pt[order][1:] != pt[order][:-1]])]
            rows = idx[pt[win]]
            better = d[win] < best[rows]
            best[rows[better]] = d[win][better]
            face[rows[better]] = tri[win][better]
    return face


def _locate_kdtree(P, V, F, candidates, chunk):
    """The numpy engine of :func:`locate`."""
    k = P.shape[0]
    face = np.empty(k, dtype=np.int64)
    bary = np.empty((k, 3))
    dist = np.empty(k)
    if k == 0:
        return face, bary, dist
    T = V[F]
    centroid = T.mean(axis=1)
    radius = np.linalg.norm(T - centroid[:, None, :], axis=-1).max(axis=1)
    eps = 1e-12 * bbox_diagonal(V)
    tree_c = cKDTree(centroid)
    tree_v = cKDTree(V)
    ring = _padded_rings(F, V.shape[0])
    for lo in range(0, k, chunk):
        hi = min(k, lo + chunk)
        Q = P[lo:hi]
        _, near_v = tree_v.query(Q, k=1, workers=-1)
        todo = np.arange(Q.shape[0])
        best_d = np.full(Q.shape[0], np.inf)
        # A second round with more centroids where the first is not certain: a triangle whose
        # centroid is further than (best distance + its centroid-to-corner radius) cannot be
        # closer; the radius is taken as the largest among the first candidates (a local
        # heuristic, exact on meshes of bounded triangle size variation).
        for c in (int(candidates), 4 * int(candidates)):
            c = min(c, F.shape[0])
            dc, near_f = tree_c.query(Q[todo], k=c, workers=-1)
            near_f = near_f.reshape(todo.size, c)
            dc = dc.reshape(todo.size, c)
            if c > candidates:   # second round: add the nearest vertex's triangles as well
                near_f = np.concatenate([near_f, ring[near_v[todo]]], axis=1)
                near_f = np.where(near_f < 0, near_f[:, :1], near_f)
            cand = near_f
            b, d = _closest_barycentric(Q[todo, None, :], T[cand])
            best = np.argmin(d, axis=1)
            r = np.arange(todo.size)
            better = d[r, best] < best_d[todo]
            idx = todo[better]
            face[lo + idx] = cand[r, best][better]
            bary[lo + idx] = b[r, best][better]
            best_d[idx] = d[r, best][better]
            if c == F.shape[0]:
                break
            local = radius[cand].max(axis=1)
            todo = todo[(best_d[todo] > eps) & (dc[:, -1] <= best_d[todo] + local)]
            if todo.size == 0:
                break
        dist[lo:hi] = best_d
    return face, bary, dist


def _padded_rings(F, n):
    """Triangles around each vertex, padded with -1 to the largest valence: (n, max_valence)."""
    m = F.shape[0]
    rows = F.ravel()
    cols = np.repeat(np.arange(m), 3)
    order = np.argsort(rows, kind="stable")
    rows, cols = rows[order], cols[order]
    counts = np.bincount(rows, minlength=n)
    width = max(int(counts.max()), 1)
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    slot = np.arange(rows.size) - start[rows]
    out = np.full((n, width), -1, dtype=np.int64)
    out[rows, slot] = cols
    return out


def _closest_barycentric(P, T):
    """Barycentric coordinates of the closest point of triangles ``T`` (..., 3, d) to points
    ``P`` (..., d), and the distance (Ericson, Real-Time Collision Detection, 5.1.5), vectorized.
    Zero-area triangles are not measured exactly (a collinear one can come out farther than it
    is); every caller passes meshes whose triangles were checked to have area."""
    # every region's formula is evaluated for every point and only the right one kept: the
    # others may overflow or divide by ~0 (far points) and are discarded
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        return _closest_barycentric_all(P, T)


def _dot(a, b):
    """Row-wise dot product over the last axis (einsum: ~5x a product and a sum over 3 terms)."""
    return np.einsum("...i,...i->...", a, b)


def _closest_barycentric_all(P, T):
    A, B, C = T[..., 0, :], T[..., 1, :], T[..., 2, :]
    AB, AC, AP = B - A, C - A, P - A
    d1 = _dot(AB, AP)
    d2 = _dot(AC, AP)
    BP = P - B
    d3 = _dot(AB, BP)
    d4 = _dot(AC, BP)
    CP = P - C
    d5 = _dot(AB, CP)
    d6 = _dot(AC, CP)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    tiny = np.finfo(float).tiny
    # the Voronoi regions in Ericson's order; np.select takes the first that holds
    t_ab = d1 / np.where(np.abs(d1 - d3) > tiny, d1 - d3, tiny)
    t_ac = d2 / np.where(np.abs(d2 - d6) > tiny, d2 - d6, tiny)
    t_bc = (d4 - d3) / np.where(np.abs((d4 - d3) + (d5 - d6)) > tiny, (d4 - d3) + (d5 - d6), tiny)
    s = va + vb + vc
    s = np.where(np.abs(s) > tiny, s, tiny)
    regions = [(d1 <= 0) & (d2 <= 0),                                   # vertex A
               (d3 >= 0) & (d4 <= d3),                                  # vertex B
               (d6 >= 0) & (d5 <= d6),                                  # vertex C
               (vc <= 0) & (d1 >= 0) & (d3 <= 0),                       # edge AB
               (vb <= 0) & (d2 >= 0) & (d6 <= 0),                       # edge AC
               (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)]         # edge BC
    u = np.select(regions, [1.0, 0.0, 0.0, 1 - t_ab, 1 - t_ac, 0.0], default=va / s)   # else: interior
    v = np.select(regions, [0.0, 1.0, 0.0, t_ab, 0.0, 1 - t_bc], default=vb / s)
    w = np.select(regions, [0.0, 0.0, 1.0, 0.0, t_ac, t_bc], default=vc / s)
    bary = np.clip(np.stack([u, v, w], axis=-1), 0.0, 1.0)
    bary /= np.maximum(bary.sum(-1, keepdims=True), tiny)
    X = np.einsum("...k,...kd->...d", bary, T)
    return bary, np.linalg.norm(X - P, axis=-1)


def _located(F, face, bary, what):
    """``(F, face, bary)`` as arrays, or MeshError if they do not fit each other (the callers
    check ``F`` against their vertex count)."""
    F = np.asarray(F)
    face = np.asarray(face)
    bary = np.asarray(bary)
    if F.ndim != 2 or F.shape[1] != 3 or face.ndim != 1 or bary.shape != (face.shape[0], 3):
        raise MeshError(f"{what}: F {F.shape}, face {face.shape} and bary {bary.shape} must be (m, 3), "
                        "(k,) and (k, 3), as locate() returns them.")
    for name, X in (("F", F), ("face", face)):
        if X.size and X.dtype.kind not in "iu":       # floats would be truncated, bools mean 0/1
            raise MeshError(f"{what}: {name} has dtype {X.dtype}; pass integer indices, as locate() uses them.")
    if bary.dtype.kind not in "fiu":
        raise MeshError(f"{what}: bary has dtype {bary.dtype}; pass the (k, 3) float barycentric coordinates "
                        "locate() returns.")
    F = F.astype(np.int64, copy=False)
    face = face.astype(np.int64, copy=False)
    bary = bary.astype(np.float64, copy=False)
    bad = np.flatnonzero((face < 0) | (face >= F.shape[0]))
    if bad.size:
        raise MeshError(f"{what}: {bad.size} face indices are outside [0, {F.shape[0]}) (first: "
                        f"{first_indices(face[bad])}, at positions {first_indices(bad)}); pass the faces "
                        "locate() found in this F.")
    if F.size and F.min() < 0:
        raise MeshError(f"{what}: F has negative vertex indices; indices are 0-based.")
    # weights far outside [0, 1] or not summing to 1 would extrapolate (and break spread's
    # conservation) silently; locate()'s own are exact to rounding
    tol = BARY_TOLERANCE
    with np.errstate(invalid="ignore"):
        off = ~(np.isfinite(bary).all(axis=1) & (bary >= -tol).all(axis=1) & (bary <= 1 + tol).all(axis=1)
                & (np.abs(bary.sum(axis=1) - 1.0) <= tol))
    if off.any():
        bad = np.flatnonzero(off)
        raise MeshError(f"{what}: {bad.size} rows of bary are not barycentric coordinates (first: "
                        f"{first_indices(bad)}): each must be finite, in [0, 1] and sum to 1 (within {tol:g}); "
                        "pass the coordinates locate() returns.")
    return F, face, bary


def _as_point_values(values, count, what, per):
    """``values`` as a float array of shape (count,) or (count, c), finite, or MeshError naming
    ``values``, the expected leading length ``count`` and ``per`` (what one row stands for)."""
    try:
        vals = np.asarray(values)
    except Exception as exc:               # ragged lists and the like
        raise MeshError(f"{what}: values could not be read as an array ({exc}); pass a ({count},) or "
                        f"({count}, c) float array, one value (or row) per {per}.") from None
    if vals.dtype.kind not in "fiu":       # strings, None (object), complex; bools would mean 0/1
        raise MeshError(f"{what}: values has dtype {vals.dtype}; pass a ({count},) or ({count}, c) array of "
                        f"real numbers, one value (or row) per {per}.")
    if vals.ndim not in (1, 2):
        raise MeshError(f"{what}: values has shape {vals.shape}; pass a ({count},) or ({count}, c) array, one "
                        f"value (or row) per {per}.")
    vals = vals.astype(np.float64, copy=False)
    if not np.isfinite(vals).all():
        bad = np.flatnonzero(~np.isfinite(vals.reshape(vals.shape[0], -1)).all(axis=1))
        raise MeshError(f"{what}: values has {bad.size} NaN or infinite rows (first: {first_indices(bad)}); "
                        "repair them first.")
    return vals


def interpolate(values, F, face, bary):
    """Values at located points: ``sum_k bary_k values[F[face, k]]``.

    Parameters
    ----------
    values : (n,) or (n, c) float array   finite, one value (or row) per vertex of the mesh ``F``
                                          indexes (at least ``F.max() + 1``)
    F : (m, 3) int array                  triangles
    face : (k,) int array                 triangle of each point, as :func:`locate` returns it
    bary : (k, 3) float array             barycentric coordinates in that triangle (rows in [0, 1]
                                          summing to 1, within ``BARY_TOLERANCE``)

    Returns
    -------
    (k,) or (k, c) float array   the interpolated values, as ``values`` is 1-D or 2-D

    Raises
    ------
    MeshError   any of the above not so

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> V, F = grid(3, 3)
    >>> face, bary, _ = locate(np.array([[0.25, 0.25], [0.6, 0.1]]), V[:, :2], F)
    >>> interpolate(V, F, face, bary)[:, :2].round(12).tolist()      # linear data is reproduced
    [[0.25, 0.25], [0.6, 0.1]]
    """
    F, face, bary = _located(F, face, bary, "interpolate")
    need = int(F.max()) + 1 if F.size else 0
    vals = _as_point_values(values, need, "interpolate", "vertex of the mesh F indexes")
    if vals.shape[0] < need:          # the values, not F, are what does not fit
        raise MeshError(f"interpolate: values has {vals.shape[0]} rows but F references vertex {need - 1}; "
                        f"pass one value (or row) per vertex of the mesh F indexes (at least {need}).")
    corner = vals[F[face]]                                   # (k, 3) or (k, 3, c)
    if corner.ndim == 2:
        return (bary * corner).sum(1)
    return (bary[:, :, None] * corner).sum(1)


def spread(values, F, face, bary, n):
    """Adjoint of :func:`interpolate`: each point's value split over the 3 corners of its
    triangle by barycentric weights and summed per vertex. The sum is conserved exactly (up to
    rounding), since the weights of a point sum to 1.

    Parameters
    ----------
    values : (k,) or (k, c) float array   finite, one value (or row) per located point
    F : (m, 3) int array                  triangles
    face : (k,) int array, bary : (k, 3) float array   as for :func:`interpolate`
    n : int                               vertex count of the result: a whole number, at least
                                          ``F.max() + 1`` and at most ``MAX_SPREAD_VERTICES``

    Returns
    -------
    (n,) or (n, c) float array   per-vertex sums, as ``values`` is 1-D or 2-D (zeros where no
                                 point lies on a vertex's triangles, and for no points at all)

    Raises
    ------
    ValueError   ``n`` not a whole number or too large
    MeshError    the others not as above

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> V, F = grid(3, 3)
    >>> face, bary, _ = locate(np.array([[0.25, 0.25], [0.6, 0.1]]), V[:, :2], F)
    >>> D = spread(np.array([1.0, 2.0]), F, face, bary, len(V))
    >>> D.shape, round(float(D.sum()), 12)                          # the total is kept
    ((9,), 3.0)
    """
    n = as_count(n, "n")
    if n > MAX_SPREAD_VERTICES:
        raise ValueError(f"n={n} asks for a dense ({n}, c) result, more than {MAX_SPREAD_VERTICES:,} rows; "
                         "pass the vertex count of the mesh F indexes.")
    F, face, bary = _located(F, face, bary, "spread")
    if F.size and F.max() >= n:
        raise MeshError(f"spread: F has vertex indices outside [0, n={n}) (up to {F.max()}); pass n >= "
                        f"{F.max() + 1}, the vertex count of the mesh F indexes.")
    vals = _as_point_values(values, face.shape[0], "spread", "located point")
    if vals.shape[0] != face.shape[0]:
        raise MeshError(f"spread: values has {vals.shape[0]} rows for {face.shape[0]} located "
                        "points; give one value (or row) per point.")
    rows = F[face].ravel()
    W = sp.csr_matrix((bary.ravel(), (rows, np.repeat(np.arange(face.shape[0]), 3))), shape=(n, face.shape[0]))
    return W @ vals                     # as interpolate: 1-D values give a 1-D result
