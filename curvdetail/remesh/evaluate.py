"""Two-sided surface distances between meshes (paper Fig. 3, evaluation)."""

import numpy as np

from ..curvature._validate import (as_count, check_choice, as_faces, bbox_diagonal, check_bool, check_referenced,
                                   checked_arrays, face_double_areas)
from ..curvature.errors import MeshError, first_indices
from .locate import EXACT_BLOCK, FAR_POINTS, _locate, _unit_frame, check_points_and_mesh

#: Largest ``samples`` (per direction), well below pymeshlab's 32-bit int: 5M took 35 s with
#: pymeshlab and 1M 7 s with the kd-tree engine (grid(50, 50)), so 10M is minutes and ~2 GB of
#: samples; 2e9 effectively hung. 1,000,000 already gives ~1e-3 relative accuracy.
MAX_SAMPLE_COUNT = 10_000_000

#: Face samples per direction: ``SAMPLES_PER_FACE`` times the sampled mesh's triangle count,
#: clamped to [MIN_SAMPLES, MAX_SAMPLES].
SAMPLES_PER_FACE, MIN_SAMPLES, MAX_SAMPLES = 10, 100_000, 1_000_000


def hausdorff(Va, Fa, Vb, Fb, *, samples=None, engine="meshlab", seed=0, a_vertex_distance=None):
    """Two-sided Hausdorff distance (max) and RMS distance between two triangle meshes.

    The figures, each direction (a to b, then b to a) alike:

    * ``a_to_b_max``: the largest distance to the surface b over every vertex of a and
      ``samples`` points drawn on a's faces (uniformly by area), each distance the exact one to
      the closest point of b. The one-sided Hausdorff distance (the supremum over all of a) is
      attained either at a vertex, where this is it exactly, or inside a face, where this falls
      short of it by at most the distance from that point to the nearest sample or vertex
      (distances to b change no faster than the point moves). ``b_to_a_max`` likewise; ``max``
      is the larger of the two.
    * ``rms``: the quadratic mean of the two one-sided RMS values,
      ``sqrt((rms_ab^2 + rms_ba^2) / 2)``, each over the face samples alone (uniform by area,
      so an estimate of the RMS over the surface, independent of the sample counts; the vertices
      would give small triangles more weight). ``mean``: the mean of the two one-sided means
      of the face samples.

    The engines differ in how the face samples are drawn and measured:

    * ``"meshlab"``: pymeshlab ``get_hausdorff_distance`` in each direction (Monte Carlo face
      samples, ``samplevert=False``; closest points by a uniform grid search, in single
      precision, up to 2 diagonals), every parameter passed explicitly. Its random generator is
      pymeshlab's: a fresh process repeats the figures exactly, but another call in the same
      process draws other samples (the generator's state carries over), so the RMS, and a
      maximum inside a face, change by sampling noise from one such call to the next.
    * ``"kdtree"``: samples from numpy's ``default_rng(seed)``, the same in any process, each
      measured exactly as the vertices are (below). Its cost grows far less with the distance
      between the surfaces than that of pymeshlab's grid search, which grows with its cube
      (250 s for one zero-detail baseline on a 10k-vertex mesh): the engine for surfaces far
      apart, and, with its fixed seed, where figures must repeat. Meshes
      whose bounding boxes are more than one diagonal (of the smaller) apart are always
      measured with it: pymeshlab's search does not return there.

    The vertices (both engines) and the ``"kdtree"`` samples are measured against every
    triangle of the other mesh that could hold the closest point (a bounding-box tree, see
    :func:`_surface_distance`): exact to rounding, at any distance. Both engines work in a
    frame where the two meshes together have unit size.

    A caller that needs the distances of a's vertices anyway (a per-vertex quality, the largest
    vertex error) measures them once with ``vertex_distance(Va, Vb, Fb, far=True)``, which
    works in the same frame, and passes them as ``a_vertex_distance``: the figures are then bit
    for bit those of a call without it, and a's vertices are not searched a second time.

    Parameters
    ----------
    Va, Fa, Vb, Fb : the two meshes ((n, 3) float, (m, 3) int)
    samples : int or None   face samples per direction, 1 to ``MAX_SAMPLE_COUNT`` (10,000,000;
                            ~1,000,000 is plenty); ``None`` = 10 per triangle of
                            the sampled mesh, at least 100,000 and at most 1,000,000 (the
                            vertices are measured besides)
    engine : {"meshlab", "kdtree"}
    seed : int or None      random seed (>= 0) of the ``"kdtree"`` engine's samples (None: fresh
                            entropy, as numpy's ``default_rng``)
    a_vertex_distance : (n_a,) float array or None
                            the distance of each vertex of a to the surface b, measured already:
                            ``vertex_distance(Va, Vb, Fb, far=True)``, used for ``a_to_b_max``
                            instead of measuring them again (taken as given: other values give
                            other maxima); None measures them here

    Returns
    -------
    dict with ``max``, ``rms``, ``mean`` (absolute lengths), ``a_to_b_max``, ``b_to_a_max``,
    ``samples`` (face samples, both directions; vertices not counted), ``engine`` (the one that
    ran: "kdtree" also for meshes far apart)

    Raises
    ------
    MeshError   malformed meshes; coordinates beyond 1e150 (see :func:`locate`)
    ValueError  unknown ``engine``; ``samples`` not a whole number from 1 to 10,000,000 (bools
                refused); ``seed`` not a whole number >= 0; ``a_vertex_distance`` not of shape
                (n_a,), not real numbers, or with NaN, infinite or negative entries

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> V, F = grid(5, 5); W = V.copy(); W[:, 2] += 0.01
    >>> round(hausdorff(V, F, W, F)["rms"], 6)
    0.01
    """
    # dtypes, scale and distance first; then the meshes in a frame where the two together have
    # unit size (as pymeshlab sees them too): areas of huge or tiny meshes neither over- nor underflow
    Va, Vb, _ = check_points_and_mesh(Va, Vb, Fb, names=("Va", "Vb", "Fb"))
    if Va.shape[1] != 3:
        raise MeshError(f"Va has shape {Va.shape}; hausdorff measures surfaces in space, (n, 3).")
    Fa = as_faces(Fa, Va.shape[0], "Fa")              # named as the caller names it
    both = np.vstack([Va, Vb])
    _, both, scale = _unit_frame(both[:0], both)
    Va, Fa = checked_arrays(both[:Va.shape[0]], Fa)
    Vb, Fb = checked_arrays(both[Va.shape[0]:], Fb)
    engine = check_choice(engine, "engine", ("meshlab", "kdtree"), "; use 'meshlab' or 'kdtree'.")
    samples = _check_samples(samples)
    seed = None if seed is None else as_count(seed, "seed", minimum=0)
    given = _check_vertex_distance(a_vertex_distance, Va.shape[0])
    engine = "kdtree" if engine == "kdtree" or _apart(Va, Vb) else "meshlab"
    measure = given is None
    figures = _hausdorff_kdtree(Va, Fa, Vb, Fb, samples, seed, measure) if engine == "kdtree" else \
        _hausdorff_meshlab(Va, Fa, Vb, Fb, samples, measure)
    figures = _scaled(figures, scale)
    if given is not None:
        # after scaling: the given distances are absolute (scale * d in this frame, see
        # vertex_distance), and rounding a product is monotonic, so the maxima come out as
        # those of a call that measured the vertices here
        figures["a_to_b_max"] = float(max(figures["a_to_b_max"], given.max()))
        figures["max"] = float(max(figures["a_to_b_max"], figures["b_to_a_max"]))
    return dict(figures, engine=engine)


def _check_vertex_distance(d, n):
    """``a_vertex_distance`` of :func:`hausdorff` as a (n,) float64 array (None stays None), or
    ValueError saying what is wrong and what to pass."""
    if d is None:
        return None
    fix = "pass vertex_distance(Va, Vb, Fb, far=True), or None to measure them here"
    try:
        arr = np.asarray(d)
    except (TypeError, ValueError):             # ragged lists and the like
        arr = np.asarray(None)
    if arr.dtype == bool or arr.dtype.kind not in "fiu":
        raise ValueError(f"a_vertex_distance has dtype {arr.dtype}; it must hold one distance (a real "
                         f"number) per vertex of Va: {fix}.")
    if arr.shape != (n,):
        raise ValueError(f"a_vertex_distance has shape {arr.shape}, but Va has {n} vertices: it must hold one "
                         f"distance per vertex, shape ({n},); {fix}.")
    arr = arr.astype(np.float64)
    bad = np.flatnonzero(~(arr >= 0) | ~np.isfinite(arr))
    if bad.size:
        raise ValueError(f"a_vertex_distance: {bad.size} of {n} entries are NaN, infinite or negative (first: "
                         f"{first_indices(bad)}); distances are finite and >= 0: {fix}.")
    return arr


def _check_samples(samples):
    if samples is None:
        return None
    try:
        count = as_count(samples, "samples")
    except ValueError:
        raise ValueError(f"samples={samples!r} must be a whole number of at least 1, or None for "
                         "10 per triangle (100,000 to 1,000,000).") from None
    if count > MAX_SAMPLE_COUNT:
        raise ValueError(f"samples={count:,} is more than the limit of {MAX_SAMPLE_COUNT:,} per direction "
                         "(minutes of sampling and GBs beyond it); ~1,000,000 is plenty for 1e-3 relative "
                         "accuracy.")
    return count


def _apart(Va, Vb):
    """True if the bounding boxes of the meshes are more than ``FAR_POINTS`` diagonals (of the
    smaller mesh) apart: pymeshlab's grid search slows down with the distance without bound
    (28 s at 0.1 diagonals for 20,000 samples on a 10k-vertex grid; no answer at 1e10)."""
    gap = np.linalg.norm(np.maximum(np.maximum(Va.min(0) - Vb.max(0), Vb.min(0) - Va.max(0)), 0.0))
    return bool(gap > FAR_POINTS * min(bbox_diagonal(Va), bbox_diagonal(Vb)))


def _scaled(figures, scale):
    return {k: v if k == "samples" else v * scale for k, v in figures.items()}


def _sample_count(samples, F):
    return int(samples) if samples else int(np.clip(SAMPLES_PER_FACE * F.shape[0], MIN_SAMPLES, MAX_SAMPLES))


def _hausdorff_meshlab(Va, Fa, Vb, Fb, samples, measure_a=True):
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=Va, face_matrix=Fa.astype(np.int32)))
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=Vb, face_matrix=Fb.astype(np.int32)))
    diag = bbox_diagonal(np.vstack([Va, Vb]))
    out = []
    for sampled, target, F in ((0, 1, Fa), (1, 0, Fb)):
        # Every parameter explicitly: pymeshlab keeps values from earlier calls in one process.
        r = ms.get_hausdorff_distance(sampledmesh=sampled, targetmesh=target, savesample=False,
                                      samplevert=False, sampleedge=False, samplefauxedge=False,
                                      sampleface=True, samplenum=_sample_count(samples, F),
                                      maxdist=pymeshlab.PureValue(2.0 * diag))
        out.append(r)
    n1, n2 = out[0]["n_samples"], out[1]["n_samples"]
    rms = np.sqrt(0.5 * (out[0]["RMS"] ** 2 + out[1]["RMS"] ** 2))
    mean = 0.5 * (out[0]["mean"] + out[1]["mean"])
    # the maxima also over every vertex, measured exactly: face samples miss them, and a
    # maximum sits at a vertex more often than not (a's: by the caller, if it measured them)
    ab = max(out[0]["max"], _surface_distance(Va, Vb, Fb).max()) if measure_a else out[0]["max"]
    ba = max(out[1]["max"], _surface_distance(Vb, Va, Fa).max())
    return {"max": float(max(ab, ba)), "rms": float(rms), "mean": float(mean),
            "a_to_b_max": float(ab), "b_to_a_max": float(ba), "samples": int(n1 + n2)}


def vertex_distance(V, Vs, Fs, *, far=False):
    """Distance from each point of ``V`` (k, 3) to the closest point of the surface ``(Vs, Fs)``,
    shape (k,) (e.g. per-vertex error of a rebuilt mesh against its source).

    Two searches. ``far=True``: the bounding-box tree search of :func:`hausdorff` (every
    triangle that could hold the closest point: exact at any distance), in hausdorff's frame
    (the points and the surface together of unit size), so that ``vertex_distance(Va, Vb, Fb,
    far=True)`` is bit for bit what ``hausdorff(Va, Fa, Vb, Fb)`` measures for a's vertices
    and can be passed to it as ``a_vertex_distance``; its cost grows little with the distance
    (0.32 s for mannequin_devil's 13k vertices against its zero-detail surface, up to 0.68
    diagonals away), and near the surface it takes 2-3 times locate's (0.1-0.5 s for 6k-100k
    points). ``far=False``: :func:`locate`'s (pymeshlab's closest-face grid; points more than a
    diagonal from the mesh go to its tree search), fastest near the surface but slowing down
    with the distance without bound (22-27 s in the devil's case), and not always exact away
    from the surface: the grid can return a face that is not the closest (a flat layer at the
    height of a wavy one and reaching past its edge: up to 0.7 % of the diagonal too far).
    Per-vertex figures that are written (a quality, a maximum) use ``far=True``.

    Parameters
    ----------
    V : (k, 3) float array    query points, e.g. a rebuilt mesh's vertices (k = 0 allowed); or
                              (k, 2) with a planar ``Vs``
    Vs : (n, 3) float array   the surface's vertex positions ((n, 2) for planar points)
    Fs : (m, 3) int array     its triangles
    far : bool                the tree search (exact) instead of locate's grid (see above)

    Returns
    -------
    d : (k,) float64 array    unsigned distances, in the unit of the coordinates (0, up to
                              rounding, for a point on the surface), row i for ``V[i]``; with
                              ``far=True`` rounded relative to the size of the points and the
                              surface together (as :func:`hausdorff`'s)

    Raises
    ------
    MeshError   malformed points or surface, as :func:`locate` refuses them (names ``V``,
                ``Vs`` and ``Fs``); vertices of ``Vs`` used by no triangle, as :func:`hausdorff`
                refuses them
    ValueError  ``far`` not a bool

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> Vs, Fs = grid(3, 3)                               # the unit square in z = 0
    >>> P = np.array([[0.5, 0.5, 2.0], [0.2, 0.3, 0.0], [2.0, 0.5, 0.0]])
    >>> vertex_distance(P, Vs, Fs).round(12).tolist()     # above, on, and beside the square
    [2.0, 0.0, 1.0]
    """
    check_bool(far, "far")
    P, Vs, Fs = check_points_and_mesh(V, Vs, Fs, names=("V", "Vs", "Fs"))
    # as hausdorff (check_mesh) refuses them: they measure nothing, but stretch the bounding box
    # that the frame, the zero-area test and the far-point limit are taken relative to
    check_referenced(Vs.shape[0], Fs, "Vs")
    if not far:
        return _locate(P, Vs, Fs)[2]
    # hausdorff's frame, where the points (its Va) and the surface together have unit size: the
    # same coordinates, so the same distances to the last bit
    both = np.vstack([P, Vs])
    _, both, scale = _unit_frame(both[:0], both)
    return scale * _surface_distance(both[:P.shape[0]], both[P.shape[0]:], Fs)


def _area_samples(V, F, n, rng):
    """``n`` points uniformly distributed by area, with their triangle."""
    area = face_double_areas(V, F)
    face = rng.choice(F.shape[0], size=n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    bary = np.column_stack([1 - s, s * (1 - r2), s * r2])
    return (bary[:, :, None] * V[F[face]]).sum(1), face


#: Triangles per leaf of the search tree (at most; 4 to 8).
TREE_LEAF = 8

#: Tree boxes (and triangles' boxes) closer than the distance found so far by less than this
#: fraction of it are not searched: the distances come out exact to this relative error at
#: most (to rounding, in practice), and points far from a surface, every part of which is
#: then nearly as close as the closest, are not measured against all of its triangles.
PRUNE_RELATIVE = 1e-13

#: Radius (bbox diagonals of the surface) within which the nearest centroid is sought for a
#: point's first bound; points further from every centroid take the tree's greedy descent and
#: a bound tightened at every level instead. Measured: 0.01, 0.03 and 0.1 cost the same to
#: within ~15 % near the surface and at the zero-detail baselines; without a limit the
#: kd-tree's search took 46 of 65 s for a terrain 0.3 diagonals above its copy.
KD_REACH = 0.1

#: Tree levels whose boxes tighten the bound of a point with a nearest-centroid bound on the
#: way down (their minmaxdist, see :func:`_descend`): that bound is close already, the top
#: levels catch where it is not (far above a wavy surface), and the deeper levels, which hold
#: most of the pairs, would add ~30 % to the search.
CAP_LEVELS = 10

#: Points per pass of the tree search, and the most point-node pairs a pass may hold (about
#: 150 bytes each while a level is tested) before its points are split in two: a point near
#: the centre of a sphere is as close to every triangle, and all of them must be tried.
SEARCH_POINTS, SEARCH_PAIRS = 20_000, 1_000_000


def _surface_distance(P, V, F):
    """Exact distance from each point of ``P`` (k, d) to the surface ``(V, F)`` ((n, d), (m, 3);
    d = 2 or 3), at any distance: the closest point of every triangle that could be the closest.

    An upper bound first, the distance to one triangle: the one with the nearest centroid
    (within ``KD_REACH`` diagonals of the point; else :func:`_greedy_bound`). Then a
    bounding-box tree of the triangles (median splits along the longest extent of their
    centroids, at most ``TREE_LEAF`` per leaf) is descended level by level for all points at
    once, keeping the boxes that come within the bound (which tightens on the way down, see
    :func:`_descend`), and every triangle of the leaves kept whose own box comes within it is
    measured exactly (:func:`_triangle_distance`). A triangle closer than the bound lies in
    boxes closer than the bound, so none is missed: the result is the exact distance, to
    rounding (and to ``PRUNE_RELATIVE``). No loop over points: all of them descend together,
    ``SEARCH_POINTS`` at a time."""
    from scipy.spatial import cKDTree

    k = P.shape[0]
    if k == 0:
        return np.empty(0)
    T = V[F]
    tree = _box_tree(T)
    Q = np.ascontiguousarray(P.T)
    # the first bound: the triangle of the nearest centroid within KD_REACH diagonals (a
    # kd-tree's search visits every centroid about as far as the nearest: thousands of them
    # for a point 0.3 diagonals from a rough terrain); else the tree's greedy descent, a poorer
    # bound that the search then tightens at every level
    reach = KD_REACH * bbox_diagonal(V)
    gap, near = cKDTree(T.mean(axis=1)).query(P, k=1, distance_upper_bound=reach, workers=-1)
    found = np.flatnonzero(np.isfinite(gap))
    rest = np.flatnonzero(~np.isfinite(gap))
    best = np.empty(k)
    best[found] = _exact_distances(P, T, found, near[found])
    for lo in range(0, rest.size, SEARCH_POINTS):
        part = rest[lo:lo + SEARCH_POINTS]
        best[part] = _greedy_bound(tree, Q[:, part], P[part], T)
    todo = [(group[lo:lo + SEARCH_POINTS], levels) for group, levels in ((found, CAP_LEVELS), (rest, None))
            for lo in range(0, group.size, SEARCH_POINTS)]
    while todo:
        idx, levels = todo.pop()
        pairs = _descend(tree, Q[:, idx], best[idx], levels)
        if pairs is None:                       # too many pairs at once: half the points
            todo += [(idx[:idx.size // 2], levels), (idx[idx.size // 2:], levels)]
            continue
        pt, tri = pairs
        if pt.size:
            d = _exact_distances(P, T, idx[pt], tri)
            first = np.flatnonzero(np.r_[True, pt[1:] != pt[:-1]])     # pt is sorted
            rows = idx[pt[first]]
            best[rows] = np.minimum(best[rows], np.minimum.reduceat(d, first))
    return best


def _exact_distances(P, T, point, tri):
    """Distance from ``P[point[i]]`` to triangle ``T[tri[i]]``, in blocks of ``EXACT_BLOCK``."""
    d = np.empty(point.size)
    for lo in range(0, point.size, EXACT_BLOCK):
        part = slice(lo, lo + EXACT_BLOCK)
        d[part] = _triangle_distance(P.take(point[part], axis=0), T.take(tri[part], axis=0))
    return d


def _triangle_distance(P, T):
    """Distance from points ``P`` (N, d) to triangles ``T`` (N, 3, d), d = 2 or 3, row by row:
    to the triangle's plane where the point projects inside the triangle (0 in the plane), else
    to the nearest of its three edges. The same distances as Ericson's closest point
    (:func:`~.locate._closest_barycentric`) without the barycentric coordinates, in 0.4 of
    its time, and closer to exact arithmetic on slivers."""
    def dot(a, b):
        return np.einsum("ij,ij->i", a, b)

    A, B, C = T[:, 0], T[:, 1], T[:, 2]
    e0, e1, e2 = B - A, C - A, C - B
    v, u = P - A, P - B
    d00, d01, d11, d20, d21 = dot(e0, e0), dot(e0, e1), dot(e1, e1), dot(v, e0), dot(v, e1)
    edge = None
    for w, e, along, length2 in ((v, e0, d20, d00), (v, e1, d21, d11), (u, e2, dot(u, e2), dot(e2, e2))):
        t = np.clip(along / length2, 0.0, 1.0)
        r = w - t[:, None] * e
        edge = dot(r, r) if edge is None else np.minimum(edge, dot(r, r))
    # barycentric coordinates of the projection, times the (positive) determinant
    det = d00 * d11 - d01 * d01
    s, t = d11 * d20 - d01 * d21, d00 * d21 - d01 * d20
    inside = (s >= 0) & (t >= 0) & (s + t <= det)
    if P.shape[1] == 3:
        n = np.cross(e0, e1)
        plane = dot(v, n) ** 2 / dot(n, n)
    else:
        plane = np.zeros(P.shape[0])
    return np.sqrt(np.where(inside, np.minimum(plane, edge), edge))


def _box_tree(T):
    """A complete binary tree of bounding boxes over the triangles ``T`` (m, 3, d):
    ``(lo, hi, leaves, tri_lo, tri_hi)``, ``lo[l]`` / ``hi[l]`` the (d, 2**l) box corners of
    level ``l`` (node j's children are 2j and 2j + 1 of the next level), ``leaves`` the
    (2**depth, w) triangles of each leaf (the list padded with repeats to fill the last
    leaves), ``tri_lo`` / ``tri_hi`` the (d, m) corners of each triangle's own box. Coordinates
    first (d, ...) throughout: reductions and gathers along contiguous rows."""
    m, dim = T.shape[0], T.shape[2]
    depth = max(0, int(np.ceil(np.log2(m / TREE_LEAF))))
    width = -(-m // (1 << depth))
    order = np.arange(width << depth) % m
    centroid = np.ascontiguousarray(T.mean(axis=1).T)                     # (d, m)
    for level in range(depth):          # each part split at the median of its longest extent
        C = centroid.take(order, axis=1).reshape(dim, 1 << level, -1)
        axis = np.argmax(C.max(axis=2) - C.min(axis=2), axis=0)
        key = C[axis, np.arange(1 << level)]
        half = np.argpartition(key, key.shape[1] // 2, axis=1)
        order = np.take_along_axis(order.reshape(1 << level, -1), half, axis=1).ravel()
    corners = np.ascontiguousarray(T.transpose(2, 0, 1))                  # (d, m, 3)
    leaf = corners.take(order, axis=1).reshape(dim, 1 << depth, 3 * width)
    lo, hi = [leaf.min(axis=2)], [leaf.max(axis=2)]
    for level in range(depth - 1, -1, -1):
        lo.append(lo[-1].reshape(dim, 1 << level, 2).min(axis=2))
        hi.append(hi[-1].reshape(dim, 1 << level, 2).max(axis=2))
    return lo[::-1], hi[::-1], order.reshape(1 << depth, width), corners.min(axis=2), corners.max(axis=2)


def _box_distance2(Q, pt, lo, hi, node, upper=True):
    """Squared lower and upper bounds of the distance from each point ``Q[:, pt[i]]`` to the
    part of the surface in box ``node[i]``: the distance to the box (0 inside), and its
    "minmaxdist" (Roussopoulos et al., 1995): every face of a bounding box touches what it
    bounds, so some point of that part lies on the box's nearer face along each axis, no
    further than the farthest point of that face (None with ``upper=False``). ``Q``, ``lo``,
    ``hi`` coordinates first."""
    near2, far2, gain = np.zeros(pt.size), np.zeros(pt.size), np.zeros(pt.size)
    for axis in range(Q.shape[0]):
        q = Q[axis].take(pt)
        below = q - lo[axis].take(node)             # < 0: the point is below the box
        above = hi[axis].take(node)
        above -= q                                  # < 0: the point is above it
        gap = np.minimum(np.minimum(below, above), 0.0)
        near2 += gap * gap
        if not upper:
            continue
        np.abs(below, out=below)
        np.abs(above, out=above)
        far = np.maximum(below, above)              # to the farther face along this axis
        np.minimum(below, above, out=below)         # to the nearer one
        far *= far
        below *= below
        far2 += far
        np.maximum(gain, far - below, out=gain)
    return near2, (far2 - gain if upper else None)


def _greedy_bound(tree, Q, P, T):
    """An upper bound of each point ``P[i]`` (``Q[:, i]``) to the surface: the exact distance
    to the triangle :func:`_greedy_triangle` picks, one exact distance a point. Far above a
    wavy surface it leads to the top of a wave, where the closest point is; near the surface a
    kd-tree's nearest centroid is the better bound."""
    return _exact_distances(P, T, np.arange(Q.shape[1]), _greedy_triangle(tree, Q))


def _greedy_triangle(tree, Q):
    """One triangle per point ``Q[:, i]``, found by descending the tree to the nearer child box at
    each level (of two that both hold the point, the one of the smaller minmaxdist) and taking
    the leaf's triangle whose own box comes first in that order: 2 box tests a level."""
    lo, hi, leaves, tri_lo, tri_hi = tree
    k = Q.shape[1]
    every = np.arange(k)
    node = np.zeros(k, dtype=np.int64)
    for level in range(1, len(lo)):
        left = 2 * node
        near_l, cap_l = _box_distance2(Q, every, lo[level], hi[level], left)
        near_r, cap_r = _box_distance2(Q, every, lo[level], hi[level], left + 1)
        node = left + ((near_r < near_l) | ((near_r == near_l) & (cap_r < cap_l)))
    width = leaves.shape[1]
    tri = leaves.take(node, axis=0)
    near, cap = _box_distance2(Q, np.repeat(every, width), tri_lo, tri_hi, tri.ravel())
    return tri[every, np.lexsort((cap.reshape(k, width), near.reshape(k, width)), axis=1)[:, 0]]


def _descend(tree, Q, bound, cap_levels=None):
    """The (point, triangle) pairs of :func:`_surface_distance` for points ``Q`` (d, k) with
    upper bounds ``bound``: every triangle whose box, and whose tree boxes, come within the
    bound, points in increasing order; None where more than ``SEARCH_PAIRS`` pairs would be
    held. The bound tightens by the minmaxdist of the boxes of the first ``cap_levels`` levels
    (None: of every level and of the triangles' own boxes)."""
    lo, hi, leaves, tri_lo, tri_hi = tree
    cap_levels = len(lo) + 1 if cap_levels is None else cap_levels
    # boxes within a relative 1e-13 of the bound are dropped too: a triangle in them could
    # improve the distance by no more than that (rounding, in effect), while far from the
    # surface (hundreds of diagonals and beyond) every box comes that close to the bound
    reach = bound * (1 - PRUNE_RELATIVE)
    reach2 = reach * reach
    # and the bound tightens on the way down, by each box's minmaxdist (plus a slack for
    # rounding, which must not drop the box that holds the point it stands for). Where the
    # first bound is poor (far above a wavy surface, whose closest point is its highest,
    # anywhere), this keeps the search from every box closer than it.
    cap2 = np.full(Q.shape[1], np.inf)
    slack = 1e-13 * (1.0 + np.abs(Q).max(axis=0))     # ~500 units in the last place of the coordinates
    pt = np.arange(Q.shape[1])
    node = np.zeros(Q.shape[1], dtype=np.int64)
    boxes = [(lo[level], hi[level]) for level in range(len(lo))] + [(tri_lo, tri_hi)]
    for level, (box_lo, box_hi) in enumerate(boxes):
        if pt.size == 0:                    # all within PRUNE_RELATIVE of their bound
            return pt, pt
        if level == len(lo):                # the triangles of the leaves kept
            node = leaves.take(node, axis=0).ravel()
            pt = np.repeat(pt, leaves.shape[1])
        upper = level < cap_levels
        near2, cap = _box_distance2(Q, pt, box_lo, box_hi, node, upper)
        if upper:
            first = np.flatnonzero(np.r_[True, pt[1:] != pt[:-1]])      # pt is sorted
            who = pt[first]
            cap2[who] = np.minimum(cap2[who], (np.sqrt(np.minimum.reduceat(cap, first)) + slack[who]) ** 2)
        keep = near2 <= np.minimum(reach2, cap2).take(pt)
        pt, node = pt[keep], node[keep]
        if level == len(lo):
            return pt, node
        grow = 2 if level + 1 < len(lo) else leaves.shape[1]
        if pt.size * grow > SEARCH_PAIRS and Q.shape[1] > 1:
            return None
        if level + 1 < len(lo):
            pt = np.repeat(pt, 2)
            node = np.repeat(2 * node, 2)
            node[1::2] += 1


def _hausdorff_kdtree(Va, Fa, Vb, Fb, samples, seed, measure_a=True):
    rng = np.random.default_rng(seed)
    out = []
    for (V1, F1), (V2, F2), vertices in (((Va, Fa), (Vb, Fb), measure_a), ((Vb, Fb), (Va, Fa), True)):
        n = _sample_count(samples, F1)
        P, _ = _area_samples(V1, F1, n, rng)
        d = _surface_distance(np.vstack([P, V1]) if vertices else P, V2, F2)
        out.append((d[:n], d[n:].max() if vertices else -np.inf))
    (d1, v1), (d2, v2) = out
    rms = np.sqrt(0.5 * ((d1 ** 2).mean() + (d2 ** 2).mean()))
    ab, ba = max(d1.max(), v1), max(d2.max(), v2)
    return {"max": float(max(ab, ba)), "rms": float(rms), "mean": float(0.5 * (d1.mean() + d2.mean())),
            "a_to_b_max": float(ab), "b_to_a_max": float(ba), "samples": int(d1.size + d2.size)}
