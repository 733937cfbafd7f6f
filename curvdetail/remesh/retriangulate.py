"""Retriangulate a surface, keeping its boundary curves (paper Fig. 3, step 1)."""

import math

import numpy as np

from ..curvature.checks import as_count, as_float, check_bool, check_choice
from ..curvature.geometry import bbox_diagonal, face_double_areas
from ..curvature.topology import boundary_edges
from ..curvature.errors import MeshError, counted
from ..curvature.topology import vertex_components
from ._disk import Polyline, RemeshError, check_surface, euler_characteristic
from .units import as_bbox_length

METHODS = ("isotropic", "decimate")

#: Most isotropic remeshing iterations taken (each a full pass; pymeshlab's parameter is a 32-bit int).
MAX_ITERATIONS = 1000

#: The target edge length is refused when it would give fewer / more target vertices than this.
MIN_VERTICES, MAX_VERTICES = 50, 5_000_000
#: From this many estimated target vertices the experiment takes minutes and says so beforehand
#: (measured: 199k-263k target vertices 61-104 s, about half of it or more the isotropic
#: remeshing; 2.25M vertices: the remeshing alone 554 s; see `long_run_reason`).
BIG_TARGET = 200_000


class LongRunWarning(UserWarning):
    """Said by the ``generate_curvature_remeshing`` filter before a run that will take minutes
    (a retriangulation of more than ``BIG_TARGET`` estimated vertices, see
    `long_run_vertices`), with what takes the time; silence it with
    ``warnings.simplefilter("ignore", LongRunWarning)``."""

#: Most triangles meeting at one vertex that the isotropic remeshing is given: pymeshlab's
#: time grows about with the cube of it (a fan disk at a 3 % target edge: 1,000 triangles at
#: the centre 1.6 s, 2,000 11 s, 5,000 212 s and a degenerate result, 20,000 over 25 minutes;
#: a 3,000-triangle fan refilled by meshing_close_holes(refinehole=True) had 46 at most).
MAX_VALENCE = 1000

#: A boundary vertex of the remesher's result further than this (x the target edge length) from
#: the source boundary polyline is an error; closer ones are projected onto the polyline. The
#: isotropic remesher's smoothing step slides boundary vertices along a curved boundary and so
#: moves them off it by up to ~1e-4 of the bbox diagonal (a flat disk of 24 rings at 3 %).
BOUNDARY_SNAP = 0.1


def estimated_vertices(V, F, target_edge):
    """Vertices of an equilateral triangulation of the surface with edges ``target_edge`` (absolute
    length): ``2 area / (sqrt(3) h^2)``."""
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    area = 0.5 * face_double_areas(V, F).sum()
    # divided twice rather than by h**2 (OverflowError beyond 1e154); inf for a tiny h is refused
    with np.errstate(over="ignore", divide="ignore"):
        return 2.0 * area / np.sqrt(3.0) / float(target_edge) / float(target_edge)


def long_run_vertices(V, F, target_edge, method="isotropic", evaluate=True):
    """The estimated target vertex count (`estimated_vertices`) where a run of the
    experiment with target edges ``target_edge`` (absolute) takes minutes; else None.

    That is above ``BIG_TARGET``, up to the ``MAX_VERTICES`` the remesher accepts; for
    ``method="decimate"`` only a target coarser than the source (a finer one is refused at
    once) and with ``evaluate`` (the decimation, transfer and rebuild alone took 18 s for 490k
    -> 251k vertices). None also where the mesh is too malformed to estimate: its checks will
    say why."""
    if method == "decimate" and not evaluate:
        return None
    try:
        with np.errstate(all="ignore"):
            count = float(estimated_vertices(V, F, target_edge))
            refused = method == "decimate" and _decimation_refines(count, np.shape(F)[0])
    except (ValueError, IndexError, ArithmeticError, TypeError):
        return None
    return count if BIG_TARGET < count <= MAX_VERTICES and not refused else None


def long_run_reason(method="isotropic", evaluate=True, cli=False):
    """What takes the time of a run that `long_run_vertices` announces and what shortens
    it: a sentence for the note said beforehand (``cli``: naming the command line's options,
    else the filter's parameters). Isotropic remeshing grows faster than the vertex count, the
    measurements about with it; a decimation's time is mostly the measurements."""
    no_evaluate = "--no-evaluate" if cli else "evaluate=False"
    no_check = "--no-surface-check" if cli else "surface_check=False"
    if method == "decimate":
        return f"Most of it is the measurements ({no_evaluate} skips them); the decimation itself takes seconds."
    remeshing = f"pymeshlab's isotropic remeshing ({no_check} makes it 25-50 % faster)"
    if not evaluate:
        return f"Most of it is {remeshing}."
    return (f"Half of it or more is {remeshing}, the more so the bigger the target, and most of the rest "
            f"the measurements ({no_evaluate} skips them).")


def edge_for_vertices(V, F, count):
    """The absolute edge length whose equilateral triangulation of the surface has ``count``
    vertices (the inverse of `estimated_vertices`)."""
    return float(np.sqrt(2.0 * 0.5 * face_double_areas(V, F).sum() / (np.sqrt(3.0) * count)))


def _boundary_vertex_count(F):
    """Boundary vertices of the disk ``F`` (its boundary edges: one loop)."""
    return int(boundary_edges(np.asarray(F, dtype=np.int64)).shape[0])


#: Decimation keeps the b boundary vertices, and a disk with them has at least b - 2 triangles;
#: it is asked for no fewer than this times that. Measured (terrainA_1k, a 20-ring disk, a
#: 40 x 40 grid): asked for b - 2 it ended 10-18 % above, for 1.1 (b - 2) up to 7 %, for
#: 1.25 (b - 2) within 0.3 %.
DECIMATION_BOUNDARY_MARGIN = 1.25


def _fewest_decimated_faces(F, boundary=None):
    """The fewest triangles a decimation of the disk ``F`` is asked for (see
    ``DECIMATION_BOUNDARY_MARGIN``); ``boundary``: its boundary vertex count where known."""
    if boundary is None:
        boundary = _boundary_vertex_count(F)
    return int(math.ceil(DECIMATION_BOUNDARY_MARGIN * (boundary - 2)))


def _decimation_refines(count, faces):
    """Whether a decimation to an estimated ``count`` vertices (2 ``count`` triangles) of a
    source with ``faces`` triangles asks for as many triangles as it has, or more (refused)."""
    return round(2.0 * count) >= faces


def target_edge_range(V, F, method="isotropic"):
    """``(shortest, longest)`` target edge, as fractions of the bbox diagonal (the error
    messages say them in %), that
    `retriangulate` accepts for the patch ``(V, F)`` with ``method``: from
    ``MAX_VERTICES`` to ``MIN_VERTICES`` estimated vertices; decimation, which only coarsens,
    from about the source's own edge length (fewer triangles than the source has) up. For a
    patch too small to decimate the shortest is longer than the longest. Decimation keeps every
    boundary vertex, so its longest is also the one that asks for ``DECIMATION_BOUNDARY_MARGIN``
    times the b - 2 triangles a disk with the source's b boundary vertices has at least."""
    d = bbox_diagonal(V)
    shortest = edge_for_vertices(V, F, MAX_VERTICES) / d
    longest = edge_for_vertices(V, F, MIN_VERTICES) / d
    if method == "decimate":
        # round(2 n) < faces from 2 n < faces - 1/2 on, round(2 n) >= fewest from 2 n >= fewest on
        shortest = max(shortest, edge_for_vertices(V, F, (np.shape(F)[0] - 0.5) / 2.0) / d)
        longest = min(longest, edge_for_vertices(V, F, max(_fewest_decimated_faces(F), 1) / 2.0) / d)
    return shortest, longest


def _percent(fraction, up):
    """``100 fraction`` to 3 significant digits, rounded up (``up``) or down, so that a bound
    of an admissible range given in a message is admissible itself."""
    value = 100.0 * fraction
    if not (np.isfinite(value) and value > 0):
        return f"{value:.3g}"
    unit = 10.0 ** (math.floor(math.log10(value)) - 2)
    steps = math.ceil(value / unit) if up else math.floor(value / unit)
    return f"{steps * unit:.3g}"


def _range_advice(V, F, method, why=True):
    """How a refusal of the target edge says what to choose instead, for ``method`` (``why``:
    say why decimation's range starts where it does)."""
    shortest, longest = target_edge_range(V, F, method)
    patch = f"this {V.shape[0]:,}-vertex patch"
    if method != "decimate":
        return f"choose a target edge between {_percent(shortest, True)} % and {_percent(longest, False)} % for {patch}"
    if shortest >= longest:
        return (f"{patch} is too small to decimate to {MIN_VERTICES} vertices or more "
                f"({counted(np.shape(F)[0], 'triangle')}); {_USE_ISOTROPIC}")
    own = " (about the source's own edge length: it only coarsens)" if why else ""
    return (f"decimation takes target edges from {_percent(shortest, True)} %{own} to "
            f"{_percent(longest, False)} % of the bbox diagonal for {patch}; choose one there or {_USE_ISOTROPIC}")


def _as(check, value, name, requirement):
    """``check(value, name)``; its ValueError re-raised as RemeshError: ``name=value requirement``."""
    try:
        return check(value, name)
    except ValueError:
        raise RemeshError(f"{name}={value!r} {requirement}", parameter=name, value=value) from None


def retriangulate(V, F, *, method="isotropic", target_edge="1%", iterations=10, max_surface_distance=None,
                  aggressiveness=7.0, surface_check=True):
    """Retriangulate a surface (closed, with holes, several pieces or handles); every boundary
    vertex of the result stays on its source boundary loop, and the topology is kept.

    Parameters
    ----------
    V : (n, 3) float array
        Source vertex positions
    F : (m, 3) int array
        Source triangles (a manifold, consistently oriented surface)
    method : {"isotropic", "decimate"}
        ``"isotropic"``: pymeshlab ``meshing_isotropic_explicit_remeshing`` (split, collapse,
        flip, smooth, reproject) at the target edge length, every parameter passed explicitly.
        ``"decimate"``: ``fast_simplification.simplify(..., preserve_border=True)`` (quadric edge
        collapse that never touches a boundary vertex) down to the triangle count of an
        equilateral mesh with the target edge length; it can only coarsen.
    target_edge : float, str or pymeshlab.PercentageValue
        target edge length: a number in model units, or a percentage of the source's
        bounding-box diagonal (``"1%"``, ``PercentageValue(1)``; see `as_length`).
    iterations : int
        isotropic remeshing iterations, 1 to ``MAX_ITERATIONS`` (1,000).
    max_surface_distance : float, str, pymeshlab.PercentageValue or None
        isotropic only: the largest distance an edge collapse or flip may move the surface (a
        length as ``target_edge``); ``None`` = ``target_edge``. Unused with
        ``surface_check=False`` (but still checked).
    surface_check : bool
        isotropic only: pymeshlab's ``checksurfdist``, refuse an edge collapse or flip that moves
        the surface by more than ``max_surface_distance``. ``False`` skips the check, which
        costs 25-50 % of the remeshing at 100k-400k target vertices (terrainA_100k: 100k
        targets 26.1 s -> 19.9 s, 400k 252 s -> 126 s, the same output there), for large
        smooth patches. The output may then differ where the remesher's smoothing would
        leave the surface (it did on 6 of 21 small patch / target configurations, e.g.
        mannequin_ear at 3 %). Default True (the check on).
    aggressiveness : float
        decimation only: fast-simplification's ``agg``, the exponent of its collapse-threshold
        schedule. The patch is scaled so that the schedule always ends at a third of the bbox
        diagonal (see `DECIMATION_REACH`): every value reaches the target, and a higher
        one starts lower and so collapses in a more nearly greedy order (on the public patches
        5-7 keep the shape best; 1 gives 2-9x their distance to the source). If the result is
        not a disk it is retried at 3 and 1.

    Returns
    -------
    Vt : (p, 3) float array
        Target vertex positions; boundary vertices lie on the source's boundary polylines (projected
        onto them, within 1e-12 of the bbox diagonal)
    Ft : (q, 3) int array
        Target triangles, oriented as the source, with its pieces, boundary loops and Euler
        characteristic

    Raises
    ------
    MeshError
        The source is malformed or not manifold (names the edges)
    CurvdetailError
        A ``target_edge`` or ``max_surface_distance`` that is not a positive length (``parameter``
        names it)
    RemeshError
        Isotropic: a vertex with more than ``MAX_VALENCE`` (1,000) triangles around it (``first``:
        [the vertex], ``count``: its triangles); unknown method, ``iterations`` not a whole number
        from 1 to 1,000, ``aggressiveness`` outside [0, 10] (bools and strings are refused),
        ``surface_check`` not True or False, a target edge length that would give fewer than 50 or
        more than 5,000,000 vertices (the numbers are given), a decimation asked to refine, or for
        fewer than 1.25 x the b - 2 triangles its b boundary vertices (which it keeps) need, or that
        stops at more than 1.25 x the triangles asked for, or a remesher result that changed the
        topology or moved the boundary

    Examples
    --------
    >>> from curvdetail.curvature.testing import disk
    >>> V, F = disk(n_rings=12); V[:, 2] = 0.2 * (1 - (V[:, :2] ** 2).sum(1))
    >>> Vt, Ft = retriangulate(V, F, method="isotropic", target_edge="5%")
    >>> 50 < Vt.shape[0] < 5000
    True
    """
    method = check_choice(method, "method", METHODS, " is not a retriangulation method; use 'isotropic' or "
                          "'decimate'.", RemeshError)
    V, F, loops = check_surface(V, F, "the source")
    topology = _topology(F, V.shape[0], loops)
    d = bbox_diagonal(V)
    target_edge = as_bbox_length(target_edge, "target_edge").fraction(d)
    iterations = _as(as_count, iterations, "iterations",
                     "must be a whole number of at least 1 (isotropic remeshing iterations, e.g. 10).")
    if iterations > MAX_ITERATIONS:      # pymeshlab takes a 32-bit int: 2**31 raised its cast error
        raise RemeshError(f"iterations={iterations!r} is more than {MAX_ITERATIONS:,}: each is a full pass of the "
                          "isotropic remeshing (split, collapse, flip, smooth); 10 is the default.",
                          parameter="iterations", value=iterations)
    if max_surface_distance is not None:
        max_surface_distance = as_bbox_length(max_surface_distance, "max_surface_distance").fraction(d)
    aggressiveness = _check_aggressiveness(aggressiveness)
    surface_check = _as(check_bool, surface_check, "surface_check",
                        "must be True or False (check the distance an edge collapse or flip moves the surface).")
    if method == "isotropic":
        _check_valence(F)
    h = target_edge * d
    n_est = estimated_vertices(V, F, h)
    if not MIN_VERTICES <= n_est <= MAX_VERTICES:
        side, limit = ("fewer than", MIN_VERTICES) if n_est < MIN_VERTICES else ("more than", MAX_VERTICES)
        raise RemeshError(
            f"target edge {100 * target_edge:.4g} % of the bbox diagonal ({h:.4g}) would give about "
            f"{n_est:,.0f} target vertices, {side} {limit:,}; {_range_advice(V, F, method)}.",
            parameter="target_edge", value=target_edge, count=n_est)
    # Both remeshers work in a unit frame (bbox centre at the origin, diagonal 1): their
    # tolerances are absolute (fast-simplification's collapse thresholds are, so a patch 1e12
    # across came back undecimated), and the result must not depend on where the patch sits
    # or on its units.
    center = 0.5 * (V.min(axis=0) + V.max(axis=0))
    unit = (V - center) / d
    if method == "isotropic":
        surf = target_edge if max_surface_distance is None else max_surface_distance
        Ut, Ft = _isotropic(unit, F, target_edge, iterations, surf, surface_check)
        try:
            Ut, Ft, loops_t = _same_topology(Ut, Ft, topology, "the isotropic remesher's result")
        except MeshError as exc:
            # what was found, not the advice to the owner of a mesh (repair it)
            raise RemeshError(f"{exc.problem}; try another target edge.") from None
    else:
        Ut, Ft, loops_t = _decimate(unit, F, target_edge, aggressiveness, sum(map(len, loops)), topology)
    Vt = Ut * d + center
    if method == "decimate":
        Vt = _restore_kept_vertices(V, Vt, d)
    for loop_t in loops_t:
        Vt = _snap_boundary(V, loops, Vt, loop_t, d, h)
    return Vt, Ft


def _check_valence(F):
    """RemeshError where a vertex of the source ``F`` has more than ``MAX_VALENCE`` triangles."""
    count = np.bincount(F.ravel())
    v = int(np.argmax(count))
    if count[v] > MAX_VALENCE:
        raise RemeshError(
            f"the source's vertex {v} has {count[v]:,} triangles around it, more than the {MAX_VALENCE:,} "
            "pymeshlab's isotropic remeshing handles in reasonable time (its time grows with the cube of it)",
            hint="spread them first, e.g. remove the vertex with pymeshlab's compute_selection_by_condition_per_"
                 f"vertex(condselect='vi=={v}') and meshing_remove_selected_vertices, then refill the hole evenly "
                 "with meshing_close_holes(maxholesize=..., refinehole=True)",
            count=int(count[v]), first=[v])


def _topology(F, n, loops):
    """``(pieces, boundary loops, Euler characteristic)`` of the checked surface ``F``."""
    return vertex_components(F, n)[1], len(loops), euler_characteristic(F, n, sum(map(len, loops)))


def _same_topology(V, F, topology, what):
    """``check_surface(V, F, what)``, or MeshError where the pieces, boundary loops or Euler
    characteristic differ from ``topology`` (the source's)."""
    V, F, loops = check_surface(V, F, what)
    found = _topology(F, V.shape[0], loops)
    if found != topology:
        raise MeshError(f"{what} has {found[0]} pieces, {found[1]} boundary loops and Euler characteristic "
                        f"{found[2]} where the source has {topology[0]}, {topology[1]} and {topology[2]}")
    return V, F, loops


def _restore_kept_vertices(V, Vt, d):
    """``Vt`` with every vertex the decimation left in place (within rounding of the frame's
    round trip, 1e-12 of the diagonal) set back to its source coordinates exactly."""
    from scipy.spatial import cKDTree

    dist, nearest = cKDTree(V).query(Vt, k=1, workers=-1)
    kept = dist <= 1e-12 * d
    Vt = Vt.copy()
    Vt[kept] = V[nearest[kept]]
    return Vt


def _check_aggressiveness(value):
    """``value`` as a float in [0, 10] (bools and strings refused), or RemeshError."""
    number = as_float(value)
    if number is None or not 0 <= number <= 10:              # NaN fails too
        raise RemeshError(f"aggressiveness={value!r} must be a number from 0 to 10 (fast-simplification's "
                          "agg; default 7).", parameter="aggressiveness", value=value)
    return number


def _isotropic(V, F, h, iterations, max_dist, surface_check=True):
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=_apart(V, F), face_matrix=F.astype(np.int32)))
    # Every parameter explicitly: pymeshlab keeps values from earlier calls in one process.
    ms.meshing_isotropic_explicit_remeshing(
        iterations=iterations, adaptive=False, selectedonly=False, targetlen=pymeshlab.PureValue(h),
        featuredeg=30.0, checksurfdist=bool(surface_check), maxsurfdist=pymeshlab.PureValue(max_dist),
        splitflag=True, collapseflag=True, swapflag=True, smoothflag=True, reprojectflag=True)
    ms.meshing_remove_unreferenced_vertices()
    m = ms.current_mesh()
    return np.array(m.vertex_matrix(), dtype=np.float64), np.array(m.face_matrix(), dtype=np.int64)


#: How far (a fraction of the way to the centroid of its neighbours) a vertex that shares its
#: position with another is moved before the isotropic remeshing, which merges such vertices
#: (cow.off has two where its surface touches itself: the remesher glued the two sheets into a
#: non-manifold edge at any target edge).
APART = 1e-6


def _apart(V, F):
    """``V`` with every vertex at the position of an earlier one moved ``APART`` of the way to
    the centroid of its neighbours (into its own sheet of the surface)."""
    order = np.lexsort(V.T[::-1])
    moved = order[1:][np.all(V[order[1:]] == V[order[:-1]], axis=1)]
    if moved.size == 0:
        return V
    is_moved = np.zeros(V.shape[0], dtype=bool)
    is_moved[moved] = True
    total, count = np.zeros_like(V), np.zeros(V.shape[0])
    for k in range(3):
        rows = F[is_moved[F[:, k]]]
        np.add.at(total, rows[:, k], V[rows[:, (k + 1) % 3]] + V[rows[:, (k + 2) % 3]])
        np.add.at(count, rows[:, k], 2.0)
    V = V.copy()
    V[moved] += APART * (total[moved] / count[moved, None] - V[moved])
    return V


# shown by retriangulate, the generate_curvature_remeshing filter and `curvdetail remesh` alike,
# so it names the parameter only: the command line says it in each command's words
_USE_ISOTROPIC = 'use method "isotropic"'


#: fast-simplification collapses, in pass i of 100, every edge whose quadric error (a sum of
#: squared distances to planes) is below 1e-9 (i + 3)^agg, an absolute schedule. Decimation
#: scales the unit-diagonal patch so that the last threshold is the squared distance
#: DECIMATION_REACH (a fraction of the diagonal). Measured on the public patches with agg 7:
#: the patch as it came (diagonals 0.9-16) or at diagonal 1 started the schedule above most
#: errors and collapsed out of order (RMS distance to the source 1.0-6.7x this frame's), and
#: with a reach of 0.003 the schedule ended before a 6 % decimation did.
DECIMATION_REACH = 1.0 / 3.0


def _decimation_scale(agg):
    """Factor from the unit frame to the one in which ``agg``'s last threshold (pass 99) is
    the squared distance ``DECIMATION_REACH``."""
    return float(np.sqrt(1e-9 * 102.0 ** agg)) / DECIMATION_REACH


#: A decimation that ends with more than this times the triangles the target edge asks for is
#: refused rather than returned as a finer retriangulation than asked (a target too close to
#: the boundary's own triangle count is refused beforehand, see ``DECIMATION_BOUNDARY_MARGIN``:
#: terrainA_1k, asked for 102 triangles with 128 boundary vertices, came back with 148).
#: Measured on the public patches it ends within 5 % of the count.
DECIMATION_SHORTFALL = 1.25


def _decimate(V, F, h, agg, boundary, topology):
    """Decimate the unit-frame surface ``V`` to an equilateral target edge ``h`` (``boundary``: the
    number of its boundary vertices, which the decimation keeps; ``topology``: what the result
    must keep, see `_topology`)."""
    import fast_simplification

    area = 0.5 * face_double_areas(V, F).sum()
    target_faces = int(round(area / (np.sqrt(3.0) / 4.0 * h * h)))
    if target_faces >= F.shape[0]:
        raise RemeshError(
            f"decimation can only coarsen: the target edge asks for about {target_faces:,} triangles "
            f"but the source has {F.shape[0]:,}; {_range_advice(V, F, 'decimate', why=False)}.",
            parameter="target_edge", count=target_faces)
    fewest = _fewest_decimated_faces(F, boundary)
    if target_faces < fewest:
        raise RemeshError(
            f"decimation keeps every boundary vertex: the target edge asks for about {target_faces:,} triangles, but "
            f"a disk with the source's {boundary:,} boundary vertices has at least {boundary - 2:,}, and it falls short of a "
            f"count below {fewest:,} ({DECIMATION_BOUNDARY_MARGIN:g} x that); "
            f"{_range_advice(V, F, 'decimate', why=False)}.", parameter="target_edge", count=target_faces)
    last = None
    for a in (agg, min(agg, 3.0), 1.0):
        scale = _decimation_scale(a)
        P, T = fast_simplification.simplify(V * scale, F.astype(np.int32), target_count=max(target_faces, 4),
                                            agg=a, verbose=False, return_collapses=False, lossless=False,
                                            preserve_border=True)
        P = np.asarray(P, dtype=np.float64) / scale
        T = np.asarray(T, dtype=np.int64)
        used = np.zeros(P.shape[0], dtype=bool)
        used[T.ravel()] = True
        remap = np.cumsum(used) - 1
        P, T = P[used], remap[T]
        try:
            P, T, loops = _same_topology(P, T, topology, "the decimated mesh")
        except ValueError as exc:  # a non-manifold edge or a zero-area triangle at high agg
            last = exc
            continue
        if T.shape[0] > DECIMATION_SHORTFALL * max(target_faces, 4):
            raise RemeshError(f"the decimation stopped at {T.shape[0]:,} triangles, more than {DECIMATION_SHORTFALL:g} x "
                              f"the {target_faces:,} the target edge asks for (fast-simplification found no more "
                              f"collapses that keep the boundary); choose a shorter target edge or {_USE_ISOTROPIC}.")
        return P, T, loops
    raise RemeshError(f"{getattr(last, 'problem', last)} (decimation with agg={agg}, 3 and 1); {_USE_ISOTROPIC}.")


def _snap_boundary(V, loops, Vt, loop_t, d, h):
    """``Vt`` with the target loop ``loop_t`` projected onto the source loop (of ``loops``) nearest
    it, or RemeshError where a vertex is further than ``BOUNDARY_SNAP * h`` from it or the loop
    does not run once around it in order."""
    best = None
    for loop in loops:
        poly = Polyline(V[loop])
        Y, _, dist = poly.project(Vt[loop_t])
        if best is None or dist.max() < best[2].max():
            best = poly, Y, dist
    if best is None:
        raise RemeshError("the remesher opened a boundary in a closed surface; try another target edge.")
    poly, Y, dist = best
    far = np.flatnonzero(dist > BOUNDARY_SNAP * h)
    if far.size:
        raise RemeshError(
            f"the remesher moved {counted(far.size, 'boundary vertex', 'boundary vertices')} off the "
            f"source boundary (largest {dist.max() / d:.2e} of the bbox diagonal, first: "
            f"{', '.join(map(str, loop_t[far[:3]]))}); try another target edge.")
    _, s, _ = poly.project(Y)
    step = np.mod(np.diff(np.append(s, s[0])), poly.total)
    if abs(step.sum() - poly.total) > 1e-6 * poly.total:
        raise RemeshError("the remesher's boundary does not run once around the source boundary in order "
                          "(it folds back); try another target edge.")
    Vt = Vt.copy()
    Vt[loop_t] = Y
    return Vt
