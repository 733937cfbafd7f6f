"""Map a source patch and its retriangulation onto one planar domain (paper Fig. 3, step 2)."""

import numpy as np

from ..curvature.checks import as_faces, as_index_set, as_values, as_vertices, check_choice, checked_arrays
from ..curvature.geometry import bbox_diagonal
from ..curvature.topology import check_every_component_fixed
from ..curvature.cotan_laplacian import cotan_laplacian
from ..curvature.errors import ConstraintError, CurvdetailError, MeshError
from ..curvature.sparse_solver import factorize
from ._disk import Polyline, check_disk, check_target_boundary

METHODS = ("harmonic", "meshlab_harmonic", "lscm")


def flipped_triangles(UV, F):
    """Indices of triangles whose orientation in the plane is reversed or degenerate (signed area
    <= 0 relative to the orientation of the majority, by area), shape (k,).

    The majority orientation is the sign of the total signed area (counter-clockwise when it is
    >= 0), so a map that mirrors the whole mesh flips no triangle.

    Parameters
    ----------
    UV : (n, 2) float array
        Planar positions, finite
    F : (m, 3) int array
        Triangles, indices in [0, n)

    Returns
    -------
    flipped : (k,) int64 array
        Indices into ``F``, increasing; empty when no triangle is flipped

    Raises
    ------
    MeshError
        ``UV`` not a finite (n, 2) array of real numbers, or ``F`` not an (m, 3) integer array with
        indices in [0, n) and no repeated index in a triangle

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> V, F = grid(3, 3)
    >>> flipped_triangles(V[:, :2], F).tolist(), flipped_triangles(V[:, 1::-1], F).tolist()   # x <-> y
    ([], [])
    >>> F[3] = F[3, [0, 2, 1]]                  # wind one triangle the other way
    >>> flipped_triangles(V[:, :2], F).tolist()
    [3]
    """
    # NaN UVs would compare as "not flipped" and float faces fail to index: refuse both here
    UV = as_vertices(UV, "UV", dim=2)
    F = as_faces(F, None)
    if F.max() >= UV.shape[0]:
        raise MeshError(f"F has vertex indices outside [0, {UV.shape[0]}); pass one UV row per vertex.",
                        parameter="UV", count=UV.shape[0])
    a, b, c = UV[F[:, 0]], UV[F[:, 1]], UV[F[:, 2]]
    signed = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    orientation = 1.0 if signed.sum() >= 0 else -1.0
    return np.flatnonzero(orientation * signed <= 0)


def harmonic_map(V, F, boundary, boundary_uv, *, backend="auto"):
    """Cotangent harmonic map with the boundary pinned: ``L_II U_I = -L_IB U_B``.

    Parameters
    ----------
    V : (n, 3) float array
        Vertex positions (supply the cotangent weights)
    F : (m, 3) int array
        Triangles
    boundary : (k,) int array
        Pinned vertices (or an (n,) bool mask: its true positions in increasing order)
    boundary_uv : (k, 2) float
        Their planar positions, row r for ``boundary[r]``
    backend : str
        Sparse solver backend (one factorization, two right-hand sides)

    Returns
    -------
    UV : (n, 2) float array
        Planar positions; ``UV[boundary] == boundary_uv`` exactly

    Raises
    ------
    MeshError
        Malformed mesh (as `check_mesh` names it)
    ConstraintError
        ``boundary`` empty, out of range or repeated, a piece of the mesh without a pinned vertex
        (the map is undetermined there), or ``boundary_uv`` not a finite (k, 2) array

    Examples
    --------
    A flat patch pinned at its own boundary positions maps onto itself (the cotangent Laplacian
    reproduces linear functions in the plane):

    >>> from curvdetail.curvature import boundary_vertices
    >>> from curvdetail.curvature.testing import grid
    >>> V, F = grid(5, 5)
    >>> b = boundary_vertices(F)
    >>> UV = harmonic_map(V, F, b, V[b, :2])
    >>> bool(np.allclose(UV, V[:, :2], atol=1e-12))
    True
    """
    V, F = checked_arrays(V, F)
    boundary = as_index_set(boundary, V.shape[0], "boundary")
    if boundary.size == 0:
        raise ConstraintError("boundary is empty: with no pinned vertex the harmonic map is undetermined "
                              "(any constant solves it); pin the boundary loop, e.g. "
                              "curvdetail.curvature.boundary_loop(F).", parameter="boundary", count=0)
    check_every_component_fixed(F, V.shape[0], boundary)
    return _harmonic_map(V, F, boundary, as_values(boundary_uv, boundary.size, "boundary_uv", dim=2), backend)


def _harmonic_map(V, F, boundary, boundary_uv, backend="auto"):
    """`harmonic_map` on checked input."""
    n = V.shape[0]
    L = cotan_laplacian(V, F).tocsr()
    is_b = np.zeros(n, dtype=bool)
    is_b[boundary] = True
    inner = np.flatnonzero(~is_b)
    UV = np.empty((n, 2))
    UV[boundary] = boundary_uv
    if inner.size:
        rhs = -(L[inner][:, boundary] @ boundary_uv)
        UV[inner] = factorize(L[inner][:, inner], symmetric=True, backend=backend).solve(rhs)
    return UV


def circle(s, total):
    """Points on the unit circle at arc-length fractions ``s / total`` (counter-clockwise)."""
    t = 2.0 * np.pi * np.asarray(s, dtype=np.float64) / total
    return np.column_stack([np.cos(t), np.sin(t)])


def parameterize(Vs, Fs, Vt=None, Ft=None, *, method="harmonic", backend="auto"):
    """Planar parameterization of a source disk and (optionally) its retriangulation on one domain.

    The source boundary loop is walked from a common anchor (its smallest vertex index) and
    mapped to the unit circle by arc length; every target boundary vertex, which lies on the
    source boundary polyline, belongs where the source's map puts that point of the polyline:
    on the source's boundary edge there in the domain (a chord of the circle, not the circle),
    at its arc-length fraction along it. ``"harmonic"`` pins it there, so the target's
    boundary vertices lie on the source's domain boundary exactly (on the circle, they would
    lie outside the source's domain between its boundary vertices). Interiors:

    ``"harmonic"``         own cotangent harmonic map (one sparse factorization per mesh);
    ``"meshlab_harmonic"`` pymeshlab ``compute_texcoord_parametrization_harmonic``;
    ``"lscm"``             pymeshlab least-squares conformal maps (free boundary).

    The pymeshlab maps are made independently per mesh (UVs come back as float32 and only the
    longest boundary loop is mapped), so the target's map is aligned to the source's by the
    similarity that best fits the boundary correspondence (least squares). Flipped triangles
    (negative signed area in the plane) are detected and counted, not repaired: a cotangent
    map can flip triangles with obtuse angles.

    Parameters
    ----------
    Vs, Fs : source mesh (a disk)
    Vt, Ft : target mesh whose boundary vertices lie on the source boundary polyline, or None
    method : {"harmonic", "meshlab_harmonic", "lscm"}
    backend : str
        Sparse solver backend for ``"harmonic"``

    Returns
    -------
    UVs : (n_s, 2) float array
        Source domain positions
    UVt : (n_t, 2) float array or None
    info : dict
        ``method``, ``flipped_source``, ``flipped_target`` (counts) and ``boundary_mismatch``
        (largest distance, in the domain, between a target boundary vertex and where the source's
        map puts its point of the source boundary; 0 with ``"harmonic"``, which pins it there; the
        last two only with a target)

    Raises
    ------
    MeshError, NotADiskError   either mesh malformed or not a disk
    RemeshError
        A target boundary vertex off the source's boundary polyline (by more than
        ``TARGET_BOUNDARY_TOLERANCE`` = 1e-6 of the larger of the bbox diagonal and the largest
        coordinate, as ``remesh_experiment``)
    ValueError
        Unknown method; only one of ``Vt`` and ``Ft`` given

    Examples
    --------
    >>> from curvdetail.curvature.testing import disk
    >>> V, F = disk(n_rings=6); V[:, 2] = (V[:, :2] ** 2).sum(1)
    >>> UV, _, info = parameterize(V, F)
    >>> bool(abs(np.linalg.norm(UV, axis=1).max() - 1.0) < 1e-12), info["flipped_source"]
    (True, 0)
    """
    method = check_choice(method, "method", METHODS, f" is not a parameterization; use one of {', '.join(METHODS)}.")
    if (Vt is None) != (Ft is None):
        given, missing = ("Ft", "Vt") if Vt is None else ("Vt", "Ft")
        raise CurvdetailError(f"{given} was given without {missing}: pass both (the target mesh) or neither "
                              "(the source alone).", parameter=missing)
    Vs, Fs, loop_s = check_disk(Vs, Fs, "the source")
    poly = Polyline(Vs[loop_s])
    s_src = poly.s0
    info = {"method": method}
    if method == "harmonic":
        UVs = _harmonic_map(Vs, Fs, loop_s, circle(s_src, poly.total), backend=backend)
    else:
        UVs = _meshlab_uv(Vs, Fs, method)
    info["flipped_source"] = int(flipped_triangles(UVs, Fs).size)
    if Vt is None:
        return UVs, None, info
    Vt, Ft, loop_t = check_disk(Vt, Ft, "the target")
    # off the polyline its vertices would be put where their projections land, silently
    check_target_boundary(Vs[loop_s], Vt[loop_t], bbox_diagonal(Vs),
                          "Pass one made by curvdetail.remesh.retriangulate.")
    _, s_t, _ = poly.project(Vt[loop_t])
    # where the source's own map puts the target boundary points: along the source's boundary
    # edges in the domain, by arc length (chords of the circle for "harmonic", not the circle:
    # a target vertex between two source boundary vertices would lie outside the source's domain)
    seg = np.clip(np.searchsorted(poly.s0, s_t, side="right") - 1, 0, loop_s.size - 1)
    t = np.clip((s_t - poly.s0[seg]) / np.maximum(poly.length[seg], np.finfo(float).tiny), 0.0, 1.0)
    expected = (1 - t)[:, None] * UVs[loop_s[seg]] + t[:, None] * UVs[loop_s[(seg + 1) % loop_s.size]]
    if method == "harmonic":
        UVt = _harmonic_map(Vt, Ft, loop_t, expected, backend=backend)
    else:
        UVt = _meshlab_uv(Vt, Ft, method)
        UVt = _fit_similarity(UVt[loop_t], expected, UVt)
    info["flipped_target"] = int(flipped_triangles(UVt, Ft).size)
    info["boundary_mismatch"] = float(np.linalg.norm(UVt[loop_t] - expected, axis=1).max())
    return UVs, UVt, info


def _meshlab_uv(V, F, method):
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32)))
    if method == "meshlab_harmonic":
        ms.compute_texcoord_parametrization_harmonic(harm_function=1)
    else:
        ms.compute_texcoord_parametrization_least_squares_conformal_maps()
    m = ms.current_mesh()
    if m.vertex_number() != V.shape[0]:
        raise ValueError(f"pymeshlab's {method} map changed the vertex count ({V.shape[0]} -> "
                         f"{m.vertex_number()}); use method='harmonic'.")
    return np.array(m.vertex_tex_coord_matrix(), dtype=np.float64)


def _fit_similarity(X, Y, apply_to):
    """Least-squares similarity (rotation, reflection allowed, uniform scale, shift) taking
    points ``X`` (k, 2) to ``Y`` (k, 2), applied to ``apply_to``."""
    mx, my = X.mean(0), Y.mean(0)
    Xc, Yc = X - mx, Y - my
    U, S, Wt = np.linalg.svd(Xc.T @ Yc)
    R = U @ Wt
    scale = S.sum() / max((Xc ** 2).sum(), np.finfo(float).tiny)
    return (apply_to - mx) @ R * scale + my
