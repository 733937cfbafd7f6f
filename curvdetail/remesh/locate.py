"""Locate points in a triangle mesh: the triangle of the closest point and its barycentric coordinates."""

import igl
import numpy as np
import scipy.sparse as sp

from ..curvature.checks import as_count
from ..curvature.errors import CurvdetailError, MeshError, first_indices
from .closest_point import (
    _barycentric,
    check_points_and_mesh,
    closest_in_frame,
    unit_frame,
)

#: Barycentric coordinates taken by interpolate / spread: entries in [-tol, 1 + tol], rows summing
#: to 1 within tol. locate() clips and normalizes its coordinates, so they are off by rounding only.
BARY_TOLERANCE = 1e-6

#: Most vertices spread() returns rows for: its (n, c) result is dense (0.8 GB per column here).
MAX_SPREAD_VERTICES = 100_000_000


def locate(points, V, F):
    """Triangle and barycentric coordinates of the closest point of a mesh to each point.

    In the plane (a parameter domain, ``V`` of shape (n, 2)) a point inside a triangle gets
    that triangle at distance 0, one outside the domain the closest point of its boundary; in
    space ((n, 3)) the closest point of the surface. Exact to rounding, at any distance
    (`closest_points`, libigl's AABB tree); of several triangles at the
    same distance (a point on an edge), any one.

    Parameters
    ----------
    points : (k, d) float array
        Query points, d = 2 or 3.
    V : (n, d) float array
        Mesh vertices, same dimension.
    F : (m, 3) int array
        Triangles.

    Returns
    -------
    face : (k,) int array
        Index of the triangle of the closest point.
    bary : (k, 3) float array
        Barycentric coordinates of the closest point in it (>= 0, sum 1).
    distance : (k,) float array
        Distance from the point to that closest point.

    Raises
    ------
    MeshError
        Malformed input (see `check_points_and_mesh`): mismatched
        dimensions, dtypes that are not real numbers / integers, NaN or infinite coordinates,
        triangle indices outside ``V``, zero-area triangles, a mesh of zero extent, coordinates
        beyond 1e150 or points more than 1e100 bbox diagonals away.

    Examples
    --------
    >>> V = np.array([[0., 0.], [1., 0.], [0., 1.], [1., 1.]]); F = np.array([[0, 1, 2], [1, 3, 2]])
    >>> face, bary, dist = locate(np.array([[0.25, 0.25], [0.9, 0.8]]), V, F)
    >>> face.tolist(), np.round(bary, 3).tolist()
    ([0, 1], [[0.5, 0.25, 0.25], [0.2, 0.7, 0.1]])
    """
    return _locate(*check_points_and_mesh(points, V, F))


def _locate(P, V, F):
    """`locate` on arrays that passed `check_points_and_mesh`, in
    the frame where the mesh has unit size."""
    P, V, scale = unit_frame(P, V)
    sqrD, face, _, bary = closest_in_frame(P, V, F)
    return face, bary, np.sqrt(sqrD) * scale


#: How far `own_side` steps a sample toward its own triangles: this times the least altitude of its
#: closest target triangle, at most half the way.
SIDE_STEP = 0.1


def own_side(P, inner, V, F, face, bary, dist):
    """Keep samples of a source edge on the side its triangles lie on, in place.

    A sample whose closest triangle (``face``) is neither the one closest to the sample stepped
    toward ``inner`` nor across an edge from it is located again on that one and the three across
    its edges (``face``, ``bary`` and ``dist`` rewritten). Where two sheets of the source touch
    (cow.off: two horn tips at one point, touching along a seam from a vertex they share) a
    sample on the touching edge is at distance 0 from both sheets, and only the side its
    triangles lie on tells them apart; elsewhere the two locations agree, or differ by less than
    the step near a vertex (a target equal to the source: always agree).

    Parameters
    ----------
    P : (k, 3) float array
        Samples on source edges.
    inner : (k, 3) float array
        For each, a point on the side of its edge's triangles (the mean of their corners
        opposite the edge).
    V, F : (n, 3) float and (m, 3) int arrays
        The target mesh, checked.
    face, bary, dist : (k,), (k, 3) and (k,) arrays
        The samples' locations as `locate` returns them; rewritten where they change.

    Returns
    -------
    int
        How many samples moved.
    """
    if P.shape[0] == 0:
        return 0
    # the local size: a step of the target's mean edge crossed many triangles where the target is
    # finer or thinner than on average, and moved the sample off its closest point on its own sheet
    T = V[F]
    double_area = np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    step = SIDE_STEP * (double_area / np.linalg.norm(T[:, [1, 2, 0]] - T, axis=2).max(axis=1))[face, None]
    d = inner - P
    length = np.linalg.norm(d, axis=1, keepdims=True)
    Q = P + d * np.minimum(step / np.maximum(length, np.finfo(float).tiny), 0.5)
    f_q = _locate(Q, V, F)[0]
    # the same triangle or one across an edge: one sharing a vertex alone may lie on another sheet
    # where two meet at that vertex (cow.off's two horn tips: two fans of one vertex)
    across = (F[face][:, :, None] == F[f_q][:, None, :]).sum(axis=(1, 2)) >= 2
    off = np.flatnonzero(~across)
    if off.size == 0:
        return 0
    # f_q and the (up to) three triangles across its edges, nearest to the sample
    candidates = np.column_stack([f_q[off], igl.triangle_triangle_adjacency(F)[0][f_q[off]]])
    sq = np.full(candidates.shape, np.inf)
    near = np.empty(candidates.shape + (V.shape[1],))
    for j in range(4):
        ok = candidates[:, j] >= 0
        sq[ok, j], near[ok, j] = _closest_on_triangles(P[off[ok]], V[F[candidates[ok, j]]])
    pick = np.argmin(sq, axis=1)
    rows = np.arange(off.size)
    new = candidates[rows, pick]
    moved = int((new != face[off]).sum())
    face[off], dist[off] = new, np.sqrt(sq[rows, pick])
    bary[off] = _barycentric(near[rows, pick], V[F[new]])
    return moved


def _closest_on_triangles(P, T):
    """Squared distance (k,) and closest point (k, 3) of each point ``P`` (k, 3) on its own
    triangle ``T`` (k, 3, 3): the projection where it falls inside, else the nearest edge point."""
    a, b, c = T[:, 0], T[:, 1], T[:, 2]
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    X = P - np.einsum("ij,ij->i", P - a, n)[:, None] * n
    inside = np.ones(P.shape[0], dtype=bool)
    for u, v, w in ((a, b, c), (b, c, a), (c, a, b)):      # X on w's side of each edge
        inside &= np.einsum("ij,ij->i", np.cross(v - u, X - u), n) >= 0
    best, sq = X, np.where(inside, np.einsum("ij,ij->i", P - X, P - X), np.inf)
    for u, v in ((a, b), (b, c), (c, a)):
        t = np.clip(np.einsum("ij,ij->i", P - u, v - u) / np.einsum("ij,ij->i", v - u, v - u), 0.0, 1.0)
        Q = u + t[:, None] * (v - u)
        d = np.einsum("ij,ij->i", P - Q, P - Q)
        closer = d < sq
        best, sq = np.where(closer[:, None], Q, best), np.where(closer, d, sq)
    return sq, best


def _located(F, face, bary, what):
    """``(F, face, bary)`` as int64 / int64 / float64 arrays, or MeshError if they do not fit
    each other (the callers check ``F`` against their vertex count)."""
    F, face, bary = np.asarray(F), np.asarray(face), np.asarray(bary)
    if F.ndim != 2 or F.shape[1] != 3 or face.ndim != 1 or bary.shape != (face.shape[0], 3):
        raise MeshError(f"{what}: F {F.shape}, face {face.shape} and bary {bary.shape} must be (m, 3), "
                        "(k,) and (k, 3)", parameter="face", value=face.shape, hint="as locate() returns them.")
    for name, X in (("F", F), ("face", face), ("bary", bary)):
        kinds = "fiu" if name == "bary" else "iu"        # floats would be truncated, bools mean 0/1
        if X.size and X.dtype.kind not in kinds:
            raise MeshError(f"{what}: {name} has dtype {X.dtype}", parameter=name, value=X.dtype,
                            hint="pass the arrays locate() returns.")
    F, face, bary = F.astype(np.int64, copy=False), face.astype(np.int64, copy=False), bary.astype(float, copy=False)
    bad = np.flatnonzero((face < 0) | (face >= F.shape[0]))
    if bad.size:
        raise MeshError(f"{what}: {bad.size} face indices are outside [0, {F.shape[0]}) (first: "
                        f"{first_indices(face[bad])}, at positions {first_indices(bad)})", parameter="face",
                        count=bad.size, first=bad[:5].tolist(), hint="pass the faces locate() found in this F.")
    if F.size and F.min() < 0:
        bad = np.flatnonzero((F < 0).any(axis=1))
        raise MeshError(f"{what}: F has negative vertex indices (first: {first_indices(bad)})", parameter="F",
                        count=bad.size, first=bad[:5].tolist(), hint="indices are 0-based.")
    # weights outside [0, 1] or not summing to 1 would extrapolate (and break spread's
    # conservation) silently; locate()'s own are exact to rounding
    tol = BARY_TOLERANCE
    with np.errstate(invalid="ignore"):
        off = ~(np.isfinite(bary).all(axis=1) & (bary >= -tol).all(axis=1) & (bary <= 1 + tol).all(axis=1)
                & (np.abs(bary.sum(axis=1) - 1.0) <= tol))
    if off.any():
        bad = np.flatnonzero(off)
        raise MeshError(f"{what}: {bad.size} rows of bary are not barycentric coordinates (first: "
                        f"{first_indices(bad)}): each must be finite, in [0, 1] and sum to 1 (within {tol:g})",
                        parameter="bary", count=bad.size, first=bad[:5].tolist(),
                        hint="pass the coordinates locate() returns.")
    return F, face, bary


def _as_point_values(values, count, what, per):
    """``values`` as a finite float array of shape (count,) or (count, c), or MeshError
    (``per``: what one row stands for, for the message)."""
    fix = f"pass a ({count},) or ({count}, c) array of real numbers, one value (or row) per {per}."
    try:
        vals = np.asarray(values)
    except (TypeError, ValueError):        # ragged lists and the like
        vals = np.asarray(None)
    if vals.dtype.kind not in "fiu" or vals.ndim not in (1, 2):     # strings, objects, complex, bools
        raise MeshError(f"{what}: values has dtype {vals.dtype} and shape {vals.shape}", parameter="values",
                        value=vals.shape, hint=fix)
    vals = vals.astype(np.float64, copy=False)
    if not np.isfinite(vals).all():
        bad = np.flatnonzero(~np.isfinite(vals.reshape(vals.shape[0], -1)).all(axis=1))
        raise MeshError(f"{what}: values has {bad.size} NaN or infinite rows (first: {first_indices(bad)})",
                        parameter="values", count=bad.size, first=bad[:5].tolist(), hint="repair them first.")
    return vals


def interpolate(values, F, face, bary):
    """Values at located points: ``sum_k bary_k values[F[face, k]]``.

    Parameters
    ----------
    values : (n,) or (n, c) float array
        Finite, one value (or row) per vertex of the mesh ``F`` indexes (at least ``F.max() + 1``).
    F : (m, 3) int array
        Triangles.
    face : (k,) int array
        Triangle of each point, as `locate` returns it.
    bary : (k, 3) float array
        Barycentric coordinates in that triangle (rows in [0, 1] summing to 1, within
        ``BARY_TOLERANCE``).

    Returns
    -------
    (k,) or (k, c) float array
        The interpolated values, as ``values`` is 1-D or 2-D.

    Raises
    ------
    MeshError
        Any of the above not so (``e.parameter`` names the argument).

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
        raise MeshError(f"interpolate: values has {vals.shape[0]} rows but F references vertex {need - 1}",
                        parameter="values", value=vals.shape[0],
                        hint=f"pass one value (or row) per vertex of the mesh F indexes (at least {need}).")
    corner = vals[F[face]]                                   # (k, 3) or (k, 3, c)
    weights = bary if corner.ndim == 2 else bary[:, :, None]
    return (weights * corner).sum(1)


def spread(values, F, face, bary, n):
    """Adjoint of `interpolate`: each point's value split over the 3 corners of its
    triangle by its barycentric weights and summed per vertex (the total is kept, to rounding).

    Parameters
    ----------
    values : (k,) or (k, c) float array
        Finite, one value (or row) per located point.
    F, face, bary
        As for `interpolate`.
    n : int
        Vertex count of the result: at least ``F.max() + 1``, at most ``MAX_SPREAD_VERTICES``.

    Returns
    -------
    (n,) or (n, c) float array
        Per-vertex sums, as ``values`` is 1-D or 2-D (zeros where no point lies).

    Raises
    ------
    ValueError
        ``n`` not a whole number or above ``MAX_SPREAD_VERTICES``.
    MeshError
        The others not as above (``e.parameter`` names the argument).

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
        raise CurvdetailError(f"n={n} asks for a dense ({n}, c) result, more than {MAX_SPREAD_VERTICES:,} rows; "
                              "pass the vertex count of the mesh F indexes.", parameter="n", value=n)
    F, face, bary = _located(F, face, bary, "spread")
    if F.size and F.max() >= n:
        raise MeshError(f"spread: F has vertex indices outside [0, n={n}) (up to {F.max()})", parameter="n",
                        value=n, hint=f"pass n >= {F.max() + 1}, the vertex count of the mesh F indexes.")
    vals = _as_point_values(values, face.shape[0], "spread", "located point")
    if vals.shape[0] != face.shape[0]:
        raise MeshError(f"spread: values has {vals.shape[0]} rows for {face.shape[0]} located points",
                        parameter="values", value=vals.shape[0], hint="give one value (or row) per point.")
    rows = F[face].ravel()
    W = sp.csr_matrix((bary.ravel(), (rows, np.repeat(np.arange(face.shape[0]), 3))), shape=(n, face.shape[0]))
    return W @ vals                     # as interpolate: 1-D values give a 1-D result
