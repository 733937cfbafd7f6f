"""Carry curvature detail from a source mesh to its retriangulation (paper Fig. 3, step 3)."""

import numpy as np
import scipy.sparse as sp

from ..curvature.checks import ZERO_AREA_RELATIVE, as_count, as_values, check_choice, checked_arrays
from ..curvature.geometry import face_double_areas
from ..curvature.topology import edge_keys as edge_keys
from ..curvature.errors import CurvdetailError, MeshError, counted, first_indices
from ..curvature.cotan_laplacian import cotan_laplacian
from ..curvature.mean_curvature_normal import mean_curvature_normal
from ..curvature.mixed_voronoi_area import mixed_voronoi_area
from ..curvature.sparse_solver import factorize
from ._disk import check_retriangulation
from .closest_point import as_coordinates, check_points_and_mesh, unit_frame
from .closest_point import _barycentric
from .locate import _locate, interpolate, own_side, spread
from .metric import _source_metric, rebuilt_in_metric

METHODS = ("conservative", "pointwise")
METRICS = ("source", "target")
LOCATIONS = ("closest", "uv")

#: Most edge samples the conservative transfer takes: locating them holds ~0.5 kB each, so
#: this is ~10 GB of memory.
MAX_EDGE_SAMPLES = 20_000_000


def edge_curvature_measure(V, F):
    """The curvature detail of a polyhedral surface as a measure on its edges.

    For edge e, ``c_e = sum over its triangles of |e| * (outward in-plane conormal of e in that
    triangle)`` (1 triangle on the boundary, 2 inside, more where edges are not manifold): zero on
    a flat interior edge, bending-normal on a folded one, in-plane on a boundary edge. Each vertex's detail is half the measure of its edges:
    ``D_i = (L V)_i = 1/2 sum_{e ni i} c_e`` exactly (the area gradient, edge by edge).

    Parameters
    ----------
    V : (n, 3) float array
        Vertex positions
    F : (m, 3) int array
        Triangles (non-manifold edges and unused vertices are allowed)

    Returns
    -------
    E : (k, 2) int64 array
        Undirected edges as sorted pairs (low, high), rows in lexicographic order
    c : (k, 3) float array
        Their measures, row r for edge ``E[r]``

    Raises
    ------
    MeshError
        Malformed ``V`` or ``F`` or a zero-area triangle (as `check_mesh` names them)

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> from curvdetail.curvature import curvature_detail
    >>> V, F = grid(5, 5); V[:, 2] = V[:, 0] ** 2
    >>> E, c = edge_curvature_measure(V, F)
    >>> D = np.zeros((len(V), 3)); np.add.at(D, E, c[:, None] / 2)    # half of c_e to each end
    >>> bool(np.allclose(D, curvature_detail(V, F), atol=1e-12))
    True
    """
    V, F = checked_arrays(V, F, check_manifold=False, check_unreferenced=False)
    return _edge_curvature_measure(V, F)


def _edge_curvature_measure(V, F, normals=False):
    """``(E, c)``, and with ``normals`` also each edge's normal (the sum of its triangles' unit normals)
    and a point on the side of its triangles (the mean of the corners they hold opposite it)."""
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    ends = np.stack([F[:, [1, 2]], F[:, [2, 0]], F[:, [0, 1]]], axis=1).reshape(-1, 2)   # edge k opposite corner k
    vec = V[ends[:, 1]] - V[ends[:, 0]]
    g = np.cross(vec, np.repeat(n, 3, axis=0))                                           # |e| x outward conormal
    # one int64 key per undirected edge (the same half-edge order as ends), in the (low, high)
    # lexicographic order a row-wise unique gives: at 1M vertices 0.4 s against 18 s for
    # np.unique(axis=0)
    keys, first, inverse = np.unique(edge_keys(F)[0], return_index=True, return_inverse=True)
    E = np.sort(ends[first], axis=1)
    inverse = inverse.reshape(-1)
    meas = np.column_stack([np.bincount(inverse, weights=g[:, j], minlength=keys.size) for j in range(3)])
    if not normals:
        return E, meas
    n3, opposite = np.repeat(n, 3, axis=0), V[F.ravel()]          # half-edge k of a face faces its corner k
    count = np.bincount(inverse, minlength=keys.size)[:, None]
    return E, meas, *(np.column_stack([np.bincount(inverse, weights=X[:, j], minlength=keys.size) for j in range(3)])
                      for X in (n3, opposite / count[inverse]))


def transfer_curvature(Vs, Fs, Vt, Ft, *, method="conservative", location="closest", uv=None,
                       samples_per_edge=None, detail=None, metric=None):
    """Curvature detail ``D`` for the target mesh, carried over from the source mesh.

    The detail carried is ``detail`` where given (e.g. stored before the source's vertices were
    moved: the editing use), else the detail of the source's geometry ``Vs, Fs``; the geometry
    locates the target either way.

    ``method="pointwise"`` (the paper): the intensive mean curvature normal ``K`` of the source is
    interpolated (barycentric) at each target vertex's location and multiplied by the target's own
    mixed Voronoi area: ``D_t = K(x_t) A_t``.

    ``method="conservative"`` (the default): the source's detail as a measure, read in one
    metric. The source's detail is the weak mean curvature normal ``integral of grad(phi) .
    grad(x)`` over the source; on the target's hat functions ``phi_i`` lifted onto the source (a
    height field over each target triangle) it is ``D_i``, and their energy on the source is ``K``
    (`source_metric`: both by quadrature on the target's triangles, each point's source triangle
    found by closest point). ``X`` solves ``K X = D`` (the target's boundary kept, one vertex of
    each closed piece) and the returned detail is ``D + (L_t - K) X``: ``L_t X`` at every free
    vertex, so rebuilding the target with its boundary fixed gives ``X``, and the total is kept
    (``sum_t D_t = sum_s D_s`` to rounding). A given ``detail`` adds what it differs by from the
    geometry's, carried on the source's edges (below). ``metric="target"`` returns instead the
    measure carried on the edges: the source's detail lives on its edges
    (`edge_curvature_measure`, with ``D_i = 1/2 sum c_e`` exactly), each edge's measure is split
    evenly over sample points along it, every sample is located in a target triangle and split
    over its three corners by barycentric weights; totals are kept over any union of target
    stars, but rebuilt with the target's Laplacian, thin parts stretch by the inscribed target's
    perimeter deficit (cow.off's tail: 2 %), and read in the source's metric, the samples (source
    edges located on the target) and the quadrature points (the target's located on the source)
    disagree on folds, which the rebuild then cuts (cow.off's horns). A target equal to the source
    gets its own detail back either way (to rounding). A given ``detail`` is put on the edges as
    the measure closest (least squares) to the geometry's whose halves give it exactly:
    ``c'_e = c_e + 2 (mu_i + mu_j)`` with ``Q mu = detail - D(Vs, Fs)``, ``Q`` the signless
    Laplacian of the edge graph (degree + adjacency; positive definite on a mesh of triangles,
    well conditioned, so the correction stays near the vertices it belongs to).

    Location: ``"closest"`` = the closest point on the other surface in space (the meshes are
    two triangulations of one surface; a conservative sample whose closest target triangle
    faces away from its source edge, the other sheet where two lie close, is put on the nearest
    one that faces its way, and one on a seam where two sheets touch stays on the side its own
    triangles lie on, see `own_side`); ``"uv"`` = point location in a shared planar domain
    given as ``uv=(UVs, UVt)`` (see `parameterize`).

    Parameters
    ----------
    Vs, Fs : (n_s, 3) float, (m_s, 3) int
        Source mesh
    Vt, Ft : (n_t, 3) float, (m_t, 3) int
        Target mesh (a retriangulation of the source)
    method : {"conservative", "pointwise"}
    location : {"closest", "uv"}
    uv : tuple (UVs (n_s, 2), UVt (n_t, 2)) or None
        Required for ``location="uv"``, refused with ``"closest"`` (it would not be used)
    samples_per_edge : int or None
        Where detail is carried on the edges (``metric="target"``, or a given ``detail``): samples
        per source edge, a whole number >= 1 (the total over all edges at most 20,000,000, ~10 GB);
        ``None`` = enough that samples are at most half the target's mean edge length apart
    detail : (n_s, 3) float array or None
        The source's detail to carry (pointwise: ``K`` = ``detail`` / the source's mixed Voronoi
        area); ``None`` = the detail of ``Vs, Fs``
    metric : {"source", "target"} or None
        Conservative only: the detail and the rebuild in the source's metric (``"source"``, the
        default for ``None``), or the measure carried on the edges (``"target"``)

    Returns
    -------
    Dt : (n_t, 3) float array
        Target curvature detail (rows of boundary vertices included)

    Raises
    ------
    MeshError
        Malformed meshes or ``uv`` (dtypes, NaN, zero-area triangles in the plane)
    RemeshError
        (a ValueError) The target is not a retriangulation of the source (`check_retriangulation`:
        boundary loops, boundary vertices, every vertex within ``SURFACE_TOLERANCE``, 3 % of the
        diagonal, of the source; ``count``, ``first``: the target vertices off)
    ValueError
        Unknown method / location; ``uv`` missing, not a pair or of the wrong shape for ``"uv"``, or
        given with ``"closest"``; ``samples_per_edge`` not a whole number >= 1, too many samples, or
        given with ``"pointwise"`` or where nothing is carried on the edges; ``metric`` unknown or
        given with ``"pointwise"``
    ConstraintError
        (a ValueError) ``detail`` not a finite (n_s, 3) array

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> from curvdetail.curvature import curvature_detail
    >>> V, F = grid(9, 9); V[:, 2] = V[:, 0] ** 2
    >>> D = transfer_curvature(V, F, V, F, method="conservative")   # a mesh onto itself
    >>> bool(np.allclose(D, curvature_detail(V, F), atol=1e-12))
    True
    >>> D2 = transfer_curvature(V, F, V, F, detail=2 * D)            # a given detail is carried
    >>> bool(np.allclose(D2, 2 * D, atol=1e-12))
    True
    """
    method = check_choice(method, "method", METHODS, " is not a transfer; use 'conservative' or 'pointwise'.")
    location = check_choice(location, "location", LOCATIONS, "; use 'closest' (3D closest point) or 'uv' "
                            "(shared domain).")
    if samples_per_edge is not None:
        if method != "conservative":
            raise CurvdetailError("samples_per_edge is used by method='conservative' only; drop it for 'pointwise'.",
                                  parameter="samples_per_edge")
        samples_per_edge = as_count(samples_per_edge, "samples_per_edge")
    if metric is not None:
        if method != "conservative":
            raise CurvdetailError("metric is used by method='conservative' only; drop it for 'pointwise'.",
                                  parameter="metric")
        metric = check_choice(metric, "metric", METRICS, "; use 'source' (the rebuild consistent with the "
                              "source's metric) or 'target' (the measure as carried).")
    Vs, Fs = checked_arrays(Vs, Fs)
    Vt, Ft = checked_arrays(Vt, Ft)
    check_retriangulation(Vs, Fs, Vt, Ft)
    if detail is not None:
        detail = as_values(detail, Vs.shape[0], "detail (the source's detail)")
    elif samples_per_edge is not None and metric != "target":
        raise CurvdetailError("samples_per_edge is used where detail is carried on the edges: with metric='target' "
                              "or a given detail; drop it here (the source's own detail is integrated over the "
                              "target's triangles).", parameter="samples_per_edge")
    if location == "uv":
        src_dom, tgt_dom = _check_uv(uv, Vs.shape[0], Vt.shape[0])
        names = ("uv[0] (UVs)", "uv[1] (UVt)")
        for name, UV, T in zip(names, (src_dom, tgt_dom), (Fs, Ft)):
            squashed_in_plane(UV, T, f"the planar map {name}", "Use another parameterization (e.g. "
                              "parameterize(..., method='harmonic')), or location='closest'.", MeshError)
    elif uv is not None:
        raise CurvdetailError("uv is only used with location='uv'; pass location='uv' to locate in the shared "
                              "domain, or drop uv for the 3D closest point.", parameter="uv")
    else:
        src_dom, tgt_dom, names = Vs, Vt, ("Vs", "Vt")
    if method == "pointwise":
        if detail is None:
            K, _ = mean_curvature_normal(Vs, Fs)
        else:
            K = detail / mixed_voronoi_area(Vs, Fs)[:, None]
        face, bary, _ = _locate(*check_points_and_mesh(tgt_dom, src_dom, Fs, names=(names[1], names[0], "Fs")))
        return interpolate(K, Fs, face, bary) * mixed_voronoi_area(Vt, Ft)[:, None]
    if metric == "target":
        return _on_edges(Vs, Fs, Vt, Ft, src_dom, tgt_dom, names, location, samples_per_edge, detail, whole=True)
    K, D = _source_metric(Vs, Fs, Vt, Ft, *((src_dom, tgt_dom) if location == "uv" else (None, None)))
    if detail is not None:              # what the given detail differs by, carried on the edges
        D = D + _on_edges(Vs, Fs, Vt, Ft, src_dom, tgt_dom, names, location, samples_per_edge, detail, whole=False)
    # = L_t X at every free vertex; the metric's difference added to D keeps its total
    return D + (cotan_laplacian(Vt, Ft) - K) @ rebuilt_in_metric(K, D, Vt, Ft)


def _on_edges(Vs, Fs, Vt, Ft, src_dom, tgt_dom, names, location, samples_per_edge, detail, whole):
    """The source's detail carried to the target as a measure on the source's edges (``whole``:
    the geometry's measure, made to fit ``detail`` where given), or only the part of the fitted
    measure by which ``detail`` differs from the geometry's (``whole=False``)."""
    E, c, normal, inner = _edge_curvature_measure(Vs, Fs, normals=True)
    if detail is not None:
        c = c + _carrying(E, c, detail) if whole else _carrying(E, c, detail)
    q = _samples_per_edge(Vs, E, Vt, Ft, samples_per_edge)
    edge = np.repeat(np.arange(E.shape[0]), q)
    start = np.concatenate([[0], np.cumsum(q)[:-1]])
    t = (np.arange(edge.size) - start[edge] + 0.5) / q[edge]
    pts = (1 - t)[:, None] * src_dom[E[edge, 0]] + t[:, None] * src_dom[E[edge, 1]]
    face, bary, dist = _locate(*check_points_and_mesh(pts, tgt_dom, Ft, names=("edge samples", names[1], "Ft")))
    if location == "closest":
        own_side(pts, inner[edge], Vt, Ft, face, bary, dist)
        _facing_side(pts, normal[edge], Vt, Ft, face, bary, dist)
    return spread(c[edge] / q[edge, None], Ft, face, bary, Vt.shape[0])


#: Most samples `_facing_side` relocates one by one; more (a target wound against the
#: source) are left where they are.
MAX_RELOCATED = 10_000


def _facing_side(P, normal, Vt, Ft, face, bary, dist):
    """Relocate, in place, the samples ``P`` whose closest target triangle faces away from their
    source edge (``normal``: the sum of its triangles' normals; a negative dot product) onto the
    nearest target triangle that faces their way, among those with a centroid within
    max(4 x the sample's distance, 3 x the mean target edge). Where two sheets of a surface lie
    closer than the retriangulation's error (cow.off: its tail along its rear) the closest point
    can be on the other sheet, and the detail moved there bent the tail by 1.5 % of the diagonal."""
    import igl
    from scipy.spatial import cKDTree

    Nt = np.cross(Vt[Ft[:, 1]] - Vt[Ft[:, 0]], Vt[Ft[:, 2]] - Vt[Ft[:, 0]])
    bad = np.flatnonzero((normal * Nt[face]).sum(1) < 0)
    if bad.size == 0 or bad.size > MAX_RELOCATED:
        return
    centroids = Vt[Ft].mean(axis=1)
    reach = 3.0 * np.linalg.norm(Vt[Ft[:, 1]] - Vt[Ft[:, 0]], axis=1).mean()
    tree = cKDTree(centroids)
    for i in bad:
        near = np.asarray(tree.query_ball_point(P[i], max(4.0 * dist[i], reach)), dtype=np.int64)
        near = near[Nt[near] @ normal[i] > 0]
        if near.size == 0:
            continue
        sq, at, C = igl.point_mesh_squared_distance(P[i:i + 1], Vt, Ft[near])
        face[i] = near[at[0]]
        bary[i] = _barycentric(C, Vt[Ft[face[i:i + 1]]])[0]
        dist[i] = np.sqrt(sq[0])


def _carrying(E, c, detail):
    """The least change (k, 3) of the edge measure ``c`` whose halves then sum to ``detail`` (n, 3)
    at the vertices of the edges ``E`` (k, 2): ``2 (mu_i + mu_j)`` with ``Q mu = detail - halves of c``."""
    n = detail.shape[0]
    residual = detail.copy()
    for end in (0, 1):
        for j in range(3):
            residual[:, j] -= 0.5 * np.bincount(E[:, end], weights=c[:, j], minlength=n)
    ones = np.ones(E.shape[0])
    adjacency = sp.coo_matrix((ones, (E[:, 0], E[:, 1])), shape=(n, n))
    degree = np.bincount(E.ravel(), minlength=n).astype(np.float64)
    # x^T Q x = sum over edges (x_i + x_j)^2: zero only on a 2-colourable graph, never with triangles
    Q = (adjacency + adjacency.T + sp.diags(degree)).tocsc()
    mu = factorize(Q).solve(residual)
    return 2.0 * (mu[E[:, 0]] + mu[E[:, 1]])


def squashed_in_plane(UV, F, what, advice, error):
    """``error`` where the planar map ``UV`` (n, 2) collapses triangles of ``F`` to zero area (as
    `locate` counts it: below ``ZERO_AREA_RELATIVE`` of the map's bbox diagonal
    squared), where no point can be located; ``what`` names the map, ``advice`` ends the message.
    Said as the map's doing: the mesh may be fine there, and locate's own refusal names the
    mesh's triangles with advice to repair it."""
    if np.ptp(UV, axis=0).max() == 0:
        raise error(f"{what} puts all {UV.shape[0]} vertices at one point. {advice}")
    _, U, _ = unit_frame(UV[:0], UV)
    zero = np.flatnonzero(face_double_areas(np.column_stack([U, np.zeros(U.shape[0])]), F)
                          <= 2.0 * ZERO_AREA_RELATIVE)
    if zero.size:
        raise error(f"{what} maps {counted(zero.size, 'triangle')} (first: {first_indices(zero)}) to zero "
                    f"area in the plane (below {ZERO_AREA_RELATIVE:g} of its diagonal squared), where no "
                    f"point can be located; the mesh itself may be fine there. {advice}", count=int(zero.size),
                    first=zero[:3].tolist())


def _check_uv(uv, n_s, n_t):
    """``uv`` as two float arrays (n_s, 2) and (n_t, 2), or ValueError / MeshError."""
    if not isinstance(uv, (tuple, list)) or len(uv) != 2:
        got = "None" if uv is None else type(uv).__name__
        raise CurvdetailError(f"location='uv' needs uv=(UVs, UVt), a pair of arrays, e.g. from "
                              f"curvdetail.remesh.parameterize; got {got}.", parameter="uv")
    UVs, UVt = (as_coordinates(u, name) for u, name in zip(uv, ("uv[0] (UVs)", "uv[1] (UVt)")))
    if UVs.shape != (n_s, 2) or UVt.shape != (n_t, 2):
        raise CurvdetailError(f"uv shapes {UVs.shape}, {UVt.shape} do not match the meshes "
                              f"({n_s}, 2), ({n_t}, 2).", parameter="uv")
    return UVs, UVt


def _samples_per_edge(Vs, E, Vt, Ft, count):
    """Samples on each source edge, shape (k,): ``count`` each, or enough that they are at most
    half the target's mean edge length apart; ValueError beyond ``MAX_EDGE_SAMPLES`` in all."""
    if count is None:
        length = np.linalg.norm(Vs[E[:, 1]] - Vs[E[:, 0]], axis=1)
        h_t = np.linalg.norm(Vt[Ft[:, [1, 2, 0]]] - Vt[Ft], axis=2).mean()
        q = np.maximum(1.0, np.ceil(2.0 * length / h_t))
        total, what = float(q.sum()), "the automatic samples_per_edge (the target is much finer than the source)"
    else:
        total, what = count * E.shape[0], f"samples_per_edge={count!r} x {E.shape[0]:,} edges"
    if total > MAX_EDGE_SAMPLES:
        raise CurvdetailError(f"{what} asks for {float(total):.3g} edge samples, more than {MAX_EDGE_SAMPLES:,} "
                              "(~10 GB); pass a smaller samples_per_edge.", parameter="samples_per_edge", value=total)
    return q.astype(np.int64) if count is None else np.full(E.shape[0], count, dtype=np.int64)
