"""Surface checks (any topology, and disks) and projection onto boundary polylines.

Used across `curvdetail.remesh`, which exports ``check_surface``, ``check_disk``,
``NotADiskError`` and ``RemeshError`` from here. A *surface* is an edge- and vertex-manifold,
consistently oriented triangle mesh: closed or with any number of boundary loops, pieces and
handles. A *disk* is one connected piece with exactly one boundary loop and Euler
characteristic 1 (no handles): the planar parameterization needs one.
"""

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..curvature.checks import as_faces, check_mesh
from ..curvature.geometry import bbox_diagonal
from ..curvature.topology import boundary_edges, check_oriented, non_manifold_edges, vertex_components
from ..curvature.boundary_editing import loop_of_boundary_edges
from ..curvature.errors import CurvdetailError, MeshError, counted, first_indices


class NotADiskError(MeshError):
    """The mesh is not a disk-topology patch (one piece, one boundary loop, no handles)."""


class RemeshError(CurvdetailError):
    """A remeshing option is out of range (e.g. a target edge length giving absurd sizes), a
    mesh the remesher cannot handle, or a remesher produced an unusable result."""


def check_disk(V, F, what="the source"):
    """Validate ``(V, F)`` as a disk and return ``(V, F, loop)``.

    ``loop`` is the boundary as an ordered (k,) vertex index array, oriented as the faces
    (the mesh lies to the left when walking it with the normals up) and starting at its
    smallest vertex index.

    Parameters
    ----------
    V : (n, 3) float array
        Vertex positions (checked as in `check_mesh`)
    F : (m, 3) int array
        Triangles, consistently oriented; every vertex used
    what : str
        How the messages name the mesh, e.g. ``"the target"``

    Returns
    -------
    V : (n, 3) float64 array
        The checked positions (C-contiguous)
    F : (m, 3) int64 array
        The checked triangles (C-contiguous)
    loop : (k,) int64 array
        The boundary loop, as above

    Raises
    ------
    MeshError
        Malformed mesh (shapes, NaN, zero-area triangles, unreferenced vertices, ...)
    NotADiskError
        (a MeshError) edges shared by more than two triangles, closed, several boundary loops,
        several pieces, a pinched boundary vertex or handles; triangles wound against their
        neighbours are named as such where they make the boundary look pinched, split or open. The
        message says what was found and what is needed

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid, icosphere
    >>> V, F, loop = check_disk(*grid(3, 3))      # vertices 0 1 2 / 3 4 5 / 6 7 8, normals +z
    >>> loop.tolist()
    [0, 1, 2, 5, 8, 7, 6, 3]
    >>> check_disk(*icosphere(subdivisions=1), what="the sphere")
    Traceback (most recent call last):
    ...
    curvdetail.remesh._disk.NotADiskError: the sphere is closed (0 boundary loops); ...
    """
    need = ("a disk-topology patch is needed: one connected piece with exactly one boundary loop "
            "and no handles (cut one out, e.g. with pymeshlab's compute_selection_by_condition_per_"
            "vertex + meshing_remove_selected_vertices, and keep its largest piece)")
    V, F = _checked(V, F, what, NotADiskError)
    n = V.shape[0]
    _, pieces = vertex_components(F, n)
    if pieces > 1:
        raise _refuse(f"{what} has {pieces} separate pieces", need, count=int(pieces))
    B = boundary_edges(F)
    if B.shape[0] == 0:
        raise _refuse(f"{what} is closed (0 boundary loops)", need, count=0)
    out_deg = np.bincount(B[:, 0], minlength=n)
    in_deg = np.bincount(B[:, 1], minlength=n)
    pinched = np.flatnonzero((out_deg > 1) | (in_deg > 1))
    if pinched.size:
        check_oriented(F, what, error=NotADiskError)
        raise _refuse(f"{what} is not vertex-manifold: the boundary passes "
                      f"{counted(pinched.size, 'vertex', 'vertices')} more than once "
                      f"(first: {first_indices(pinched)})", need, count=int(pinched.size), first=pinched[:3].tolist())
    G = sp.coo_matrix((np.ones(B.shape[0]), (B[:, 0], B[:, 1])), shape=(n, n))
    on_boundary = np.zeros(n, dtype=bool)
    on_boundary[B.ravel()] = True
    _, labels = connected_components(G, directed=False)
    loops = np.unique(labels[on_boundary]).size
    if loops != 1:
        check_oriented(F, what, error=NotADiskError)
        raise _refuse(f"{what} has {loops} boundary loops (holes)", need, count=int(loops))
    # check_mesh refused edges in more than two triangles: every interior edge is two of the 3m
    # half-edges, every boundary edge one (np.unique over the edge rows took 1.6 s at 200k faces)
    chi = euler_characteristic(F, n, B.shape[0])
    if chi != 1:
        raise _refuse(f"{what} has one boundary loop but Euler characteristic {chi} "
                      f"({counted((1 - chi) // 2, 'handle')})", need, value=int(chi))
    try:
        return V, F, loop_of_boundary_edges(B)
    except MeshError:
        check_oriented(F, what, error=NotADiskError)
        raise


def _checked(V, F, what, error=MeshError):
    """`check_mesh`, with edges shared by more than two triangles named as ``error``
    (``count``, ``first`` set) with the repair to make."""
    try:
        return check_mesh(V, F)
    except MeshError as exc:
        try:
            nm = non_manifold_edges(as_faces(F, None))    # checked: a cast would truncate 1.5 to 1
        except Exception:  # F too malformed to look at: the original message says why
            nm = None
        if nm is None or not nm.shape[0]:          # say which mesh the problem is in
            raise MeshError(f"{what}: {exc.problem}", parameter=exc.parameter, value=exc.value, hint=exc.hint,
                            count=exc.count, first=exc.first) from None
    pairs = ", ".join(f"({a}, {b})" for a, b in nm[:3])
    # a repair, not a cut: such edges are mostly a few stray triangles (a fin, a doubled face)
    problem = (f"{what} is not manifold: {counted(nm.shape[0], 'edge', verb='are')} shared by more than two "
               f"triangles (first: {pairs})")
    hint = ("repair the mesh, e.g. with pymeshlab's meshing_repair_non_manifold_edges (it deletes the smallest "
            "triangles on each such edge until two are left) and meshing_remove_unreferenced_vertices")
    raise error(problem, hint=hint, parameter="F", count=int(nm.shape[0]), first=nm[:3].tolist()) from None


def check_surface(V, F, what="the source"):
    """Validate ``(V, F)`` as an oriented manifold surface of any topology (closed, with holes,
    several pieces, handles) and return ``(V, F, loops)``.

    Parameters
    ----------
    V : (n, 3) float array
        Vertex positions (checked as in `check_mesh`)
    F : (m, 3) int array
        Triangles, consistently oriented; every vertex used
    what : str
        How the messages name the mesh

    Returns
    -------
    V : (n, 3) float64 array, F : (m, 3) int64 array
        The checked arrays
    loops : list of (k,) int64 arrays
        The boundary loops, each ordered as the faces wind and starting at its smallest vertex, by
        that vertex; [] if closed

    Raises
    ------
    MeshError
        Malformed mesh; edges shared by more than two triangles (``count``, ``first``: the first
        edges), a boundary passing a vertex twice, or misoriented triangles

    Examples
    --------
    >>> from curvdetail.curvature.testing import cylinder, icosphere
    >>> len(check_surface(*icosphere(subdivisions=1))[2]), len(check_surface(*cylinder(n_along=3))[2])
    (0, 2)
    """
    V, F = _checked(V, F, what)
    check_oriented(F, what)                 # a closed surface shows no boundary where it is not
    return V, F, boundary_loops(F, V.shape[0], what)


def boundary_loops(F, n, what="the mesh"):
    """The boundary loops of the manifold ``F`` (n vertices), as in `check_surface`."""
    B = boundary_edges(F)
    if B.shape[0] == 0:
        return []
    pinched = np.flatnonzero((np.bincount(B[:, 0], minlength=n) > 1) | (np.bincount(B[:, 1], minlength=n) > 1))
    if pinched.size:
        check_oriented(F, what)
        raise MeshError(f"{what} is not vertex-manifold: the boundary passes "
                        f"{counted(pinched.size, 'vertex', 'vertices')} more than once "
                        f"(first: {first_indices(pinched)})",
                        hint="split those vertices, e.g. with pymeshlab's meshing_repair_non_manifold_vertices",
                        count=int(pinched.size), first=pinched[:3].tolist())
    successor = np.full(n, -1, dtype=np.int64)
    successor[B[:, 0]] = B[:, 1]
    if np.any(successor[B[:, 1]] < 0):             # an edge into a vertex with none out of it
        check_oriented(F, what)
    loops, seen = [], np.zeros(n, dtype=bool)
    for start in np.sort(B[:, 0]):
        if seen[start]:
            continue
        loop = [start]
        seen[start] = True
        v = successor[start]
        while v != start:
            if v < 0 or seen[v]:
                check_oriented(F, what)
                raise MeshError(f"{what}: the boundary through vertex {start} does not close", hint="orient the "
                                "triangles consistently and repair the mesh so that each boundary is a simple loop")
            seen[v] = True
            loop.append(v)
            v = successor[v]
        loops.append(np.asarray(loop, dtype=np.int64))
    return loops


def euler_characteristic(F, n, boundary_edge_count):
    """``V - E + F`` of the manifold ``F`` with ``n`` vertices (every interior edge is two of the 3m
    half-edges, every boundary edge one)."""
    return n - (3 * F.shape[0] + boundary_edge_count) // 2 + F.shape[0]


def _refuse(problem, advice, **fields):
    """The NotADiskError ``problem; advice.``, with ``problem`` kept as its attribute ``problem``
    (where the mesh is a remesher's result, the advice to the user is another)."""
    exc = NotADiskError(f"{problem}; {advice}.", parameter="F", **fields)
    exc.problem = problem
    return exc


#: Most point-segment pairs `Polyline.project` holds at once where it projects points
#: onto more segments than their nearest (~200 bytes each while held).
PROJECT_PAIRS = 500_000


class Polyline:
    """A closed polyline (the source boundary) with arc-length coordinates and projection.

    Parameters
    ----------
    P : (k, 3) float array
        The loop's points in order (closed: the last joins the first)
    """

    def __init__(self, P):
        self.P = np.asarray(P, dtype=np.float64)
        self.Q = np.roll(self.P, -1, axis=0)
        seg = self.Q - self.P
        self.length = np.linalg.norm(seg, axis=1)
        self.s0 = np.concatenate([[0.0], np.cumsum(self.length)[:-1]])
        self.total = float(self.length.sum())
        self._tree = cKDTree(0.5 * (self.P + self.Q))
        self._half_longest = 0.5 * float(self.length.max()) if self.length.size else 0.0

    def project(self, X, k=8):
        """Closest points on the polyline, exact (to rounding) whatever the segment lengths.

        The ``k`` segments with the nearest midpoints are tried first; a point whose result is
        not certain from them (another segment, with its midpoint further than the k-th, could
        still be closer when segments differ much in length) is projected onto every segment
        long enough to be closer, ``PROJECT_PAIRS`` point-segment pairs at a time.

        Returns ``(Y, s, dist)``: projected points (m, 3), arc-length coordinate in [0, total)
        from the first point, and distance from ``X`` (m,).
        """
        X = np.asarray(X, dtype=np.float64)
        segments = self.P.shape[0]
        k = min(k, segments)
        mid, cand = self._tree.query(X, k=k)
        cand = cand.reshape(X.shape[0], k)
        Y, s, d = self._closest(X, cand)
        if k < segments:
            # a segment whose midpoint is at least mid_k away is at least mid_k - (its half
            # length) away: the candidates' best is certain where it is no further than
            # mid_k - half the longest segment; elsewhere only the segments longer than
            # 2 (mid_k - best) can be closer, and those are tried, PROJECT_PAIRS pairs at a time
            slack = 1e-12 * max(self.total, np.finfo(float).tiny)
            gap = mid.reshape(X.shape[0], k)[:, -1] - d
            unsure = np.flatnonzero(gap < self._half_longest + slack)
            unsure = unsure[np.argsort(gap[unsure], kind="stable")]
            lo = 0
            while lo < unsure.size:
                reach = gap[unsure[lo]] - slack          # the smallest gap of the points from lo on
                tried = np.flatnonzero(0.5 * self.length >= reach) if reach > 0 else np.arange(segments)
                part = unsure[lo:lo + max(1, PROJECT_PAIRS // max(tried.size, 1))]
                Y2, s2, d2 = self._closest(X[part], np.broadcast_to(tried, (part.size, tried.size)))
                better = d2 < d[part]
                Y[part[better]], s[part[better]], d[part[better]] = Y2[better], s2[better], d2[better]
                lo += part.size
        return Y, s, d

    def _closest(self, X, cand):
        """The closest point to each ``X[i]`` on the segments ``cand[i]`` (m, c): ``(Y, s, dist)``."""
        A, B = self.P[cand], self.Q[cand]
        AB = B - A
        denom = np.maximum((AB * AB).sum(-1), np.finfo(float).tiny)
        t = np.clip(((X[:, None, :] - A) * AB).sum(-1) / denom, 0.0, 1.0)
        Y = A + t[..., None] * AB
        d = np.linalg.norm(Y - X[:, None, :], axis=-1)
        best = np.argmin(d, axis=1)
        r = np.arange(X.shape[0])
        seg = cand[r, best]
        s = np.mod(self.s0[seg] + t[r, best] * self.length[seg], self.total)
        return Y[r, best], s, d[r, best]

    def point_at(self, s):
        """Points at arc-length coordinates ``s`` (m,)."""
        s = np.mod(np.asarray(s, dtype=np.float64), self.total)
        seg = np.clip(np.searchsorted(self.s0, s, side="right") - 1, 0, self.P.shape[0] - 1)
        t = (s - self.s0[seg]) / np.maximum(self.length[seg], np.finfo(float).tiny)
        return self.P[seg] + t[:, None] * (self.Q[seg] - self.P[seg])



#: A given target's boundary vertex further than this (x the larger of the source's bbox diagonal
#: and its largest coordinate, for float32 files far from the origin) from the source's boundary
#: polyline is refused: the reconstruction pins the target's boundary where it
#: is, so a target off the source gives a large error that measures the target, not the method,
#: and a parameterization would put it where its projection lands. retriangulate() puts them
#: within 1e-12.
TARGET_BOUNDARY_TOLERANCE = 1e-6


#: The looser tolerance for a target retriangulated elsewhere (the filters take any layer):
#: pymeshlab's isotropic remeshing slides boundary vertices along a curved boundary, up to 2e-4
#: of the diagonal at 3 % edges (a flat and a wavy 24-ring disk); a different patch lies a few
#: % off.
RETRIANGULATION_TOLERANCE = 1e-3


def check_target_boundary(P, X, d, advice, tolerance=TARGET_BOUNDARY_TOLERANCE):
    """RemeshError unless every target boundary vertex ``X`` lies on a source boundary
    polyline (``P``: one loop's points, or a list of loops) within ``tolerance``
    (default ``TARGET_BOUNDARY_TOLERANCE``) times the larger of the diagonal ``d``
    and the largest coordinate (float32 files far from the origin round by more than 1e-6 of a
    small diagonal); ``advice``: the hint that ends the message (what to pass instead). The
    error's ``value`` is the largest distance found (in those units), ``count`` the vertices
    off and ``first`` the first of them (rows of ``X``)."""
    loops = P if isinstance(P, list) else [P]
    if not loops or X.shape[0] == 0:
        if len(loops) or X.shape[0]:
            raise RemeshError(f"the target has {X.shape[0]} boundary vertices and the source {len(loops)} "
                              "boundary loops: the target must be a retriangulation of the source", hint=advice)
        return
    scale = max(d, max(float(np.abs(p).max()) for p in loops), float(np.abs(X).max()))
    # exact: every segment where it must be
    dist = np.min([Polyline(p).project(X)[2] for p in loops], axis=0) / scale
    off = np.flatnonzero(dist > tolerance)
    if off.size:
        raise RemeshError(
            f"{off.size} of {X.shape[0]} target boundary vertices {'is' if off.size == 1 else 'are'} off the "
            "source's boundary polyline "
            f"(up to {dist.max():.3g} of the larger of the source's bbox diagonal and its largest "
            f"coordinate; allowed {tolerance:g}): the target must be a retriangulation of "
            "the source with its boundary vertices on the source's boundary", hint=advice,
            value=float(dist.max()), count=int(off.size), first=off[:3].tolist())


#: A target vertex further than this (x the source's bbox diagonal) from the source's surface is
#: refused as not a retriangulation of it: isotropic remeshing reprojects its vertices onto the
#: surface (1e-16 measured), a decimation to its coarsest (10 % edges, ~100 vertices: spot,
#: bunny, the nose) lies up to 1.5 % off; terrainA_1k with its heights mirrored lies up to 7 % off.
SURFACE_TOLERANCE = 0.03


def check_retriangulation(Vs, Fs, Vt, Ft, *, boundary_tolerance=RETRIANGULATION_TOLERANCE,
                          surface_tolerance=SURFACE_TOLERANCE, advice=None):
    """RemeshError unless the target ``(Vt, Ft)`` is a retriangulation of the source ``(Vs, Fs)``.

    The check `remesh_experiment` makes of a given target and `transfer_curvature` of
    every target: another surface would be given detail that is not its own, and rebuilt far off
    (terrainA_1k onto another terrain patch: 16.6 % of the diagonal) without a word. In order:

    1. as many boundary loops (a closed source, a closed target);
    2. every target boundary vertex on the source's boundary (`check_target_boundary`,
       within ``boundary_tolerance``);
    3. every target vertex within ``surface_tolerance`` x the source's bbox diagonal of the source
       surface (exact closest point, `closest_points`), plus 1e-6 of the largest coordinate
       (float32 files far from the origin).

    Parameters
    ----------
    Vs, Fs : (n_s, 3) float, (m_s, 3) int arrays
        The source, checked (e.g. by `check_surface`).
    Vt, Ft : (n_t, 3) float, (m_t, 3) int arrays
        The target, checked.
    boundary_tolerance : float
        As in `check_target_boundary` (default ``RETRIANGULATION_TOLERANCE``).
    surface_tolerance : float
        Fraction of the source's bbox diagonal (default ``SURFACE_TOLERANCE``, 3 %).
    advice : str or None
        The hint (what to pass instead).

    Raises
    ------
    RemeshError
        ``count``: the target vertices off (or the target's boundary loops, where their number
        differs), ``first``: the first of them (target vertex indices), ``value``: the largest
        distance, as a fraction of the diagonal (or the target's loop count).
    MeshError
        A boundary that is not a set of simple loops (misoriented triangles).

    Examples
    --------
    >>> from curvdetail.curvature.testing import icosphere
    >>> V, F = icosphere(subdivisions=2)
    >>> check_retriangulation(V, F, V, F)                       # a mesh is its own retriangulation
    >>> check_retriangulation(V, F, 1.2 * V, F)
    Traceback (most recent call last):
    ...
    curvdetail.remesh._disk.RemeshError: 162 of 162 target vertices lie off the source's surface ...
    """
    from .closest_point import closest_points

    advice = advice or "pass a retriangulation of the source (e.g. from curvdetail.remesh.retriangulate)"
    d = bbox_diagonal(Vs)
    loops_s = boundary_loops(Fs, Vs.shape[0], "the source")
    loops_t = boundary_loops(Ft, Vt.shape[0], "the target")
    if len(loops_s) != len(loops_t):
        raise RemeshError(f"the target has {counted(len(loops_t), 'boundary loop')} and the source "
                          f"{len(loops_s)}: the target must be a retriangulation of the source", hint=advice,
                          value=len(loops_t), count=len(loops_t), first=[int(loop[0]) for loop in loops_t[:3]])
    if loops_t:
        given = np.concatenate(loops_t)
        try:
            check_target_boundary([Vs[loop] for loop in loops_s], Vt[given], d, advice, tolerance=boundary_tolerance)
        except RemeshError as exc:          # rows of the boundary vertices, named as target vertices
            exc.first = given[exc.first].tolist()
            raise
    dist = np.sqrt(closest_points(Vt, Vs, Fs)[0]) / d
    allowed = surface_tolerance + 1e-6 * max(float(np.abs(Vs).max()), float(np.abs(Vt).max())) / d
    off = np.flatnonzero(dist > allowed)
    if off.size:
        raise RemeshError(f"{off.size} of {Vt.shape[0]} target vertices lie off the source's surface (up to "
                          f"{100 * dist.max():.3g} % of its bbox diagonal; allowed {100 * surface_tolerance:g} %, "
                          f"first: {first_indices(off)}): the target must be a retriangulation of the source",
                          hint=advice, value=float(dist.max()), count=int(off.size), first=off[:3].tolist())
