"""Filter ``apply_curvature_editing``: move handles, rebuild the selection from curvature detail."""

import time

import numpy as np

from ..curvature.geometry import folded_triangles
from ..curvature.checks import affine_transform_problem, check_transformed_values, non_whole_index_error, real_word
from ..curvature.geometry import bbox_diagonal
from ..curvature.curvature_editor import CurvatureEditor
from ..curvature.rotation_editor import RotationAwareEditor
from ..curvature.errors import (warn, ConstraintError, FoldedTrianglesWarning, UndeterminedEditError, counted,
                                first_indices)
from .apply_curvature_reconstruction import BACKEND_DESCRIPTION, BACKENDS
from .errors import FilterParameterError
from .meshset import (get_mesh, layer_id, mesh_arrays, selected_vertices, set_vertex_positions,
                      set_vertex_quality)
from .parameters import BBoxLength, Parameter
from .registry import PAPER, filter

IDENTITY = "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1"

#: ``amplification`` or ``detail_amplification`` above this says that the curvature stage
#: amplified the handles' change: the threshold of ``curvdetail edit``'s warning and exit status
#: 4 (vertices moved more than 3 times as far as the handles); well-posed edits stay below it.
AMPLIFICATION_LIMIT = 3.0


class AmplifiedEditWarning(UserWarning):
    """Said by ``apply_curvature_editing`` when its result moved more than
    `AMPLIFICATION_LIMIT` times as far as the handles, or its details changed more than that
    many times as much as the edit asks, without folding triangles (folds are said with
    `FoldedTrianglesWarning`): the edit ran and the mesh is
    changed, but the curvature stage amplified the handles' change. The message gives the figures
    and what to try; the same figures are in the filter's dict. Turn it into an error with
    ``warnings.simplefilter("error", AmplifiedEditWarning)``."""


def _indices(text, n):
    """The handle indices in ``text`` (spaces or commas between them) as an int64 array: whole
    numbers, written as ints or as whole floats ("3.0", from a Python list or array of floats, as
    pymeshlab's and libigl's index arrays often are), each once, in [0, n) (n None: 0 or more)."""
    tokens = str(text).replace(",", " ").split()
    values = []
    for t in tokens:
        try:
            values.append(int(t))                   # exact, however large
        except ValueError:
            try:
                values.append(real_word(t))
            except ValueError:
                raise FilterParameterError(f"parameter 'handles' must be vertex indices separated by spaces "
                                           f"or commas; got {str(text)[:40]!r}.", parameter="handles") from None
    # the ints stand in as 0.0 (whole), keeping the positions: one beyond a double would overflow
    error = non_whole_index_error([v if isinstance(v, float) else 0.0 for v in values], "parameter 'handles'",
                                  FilterParameterError)
    if error is not None:
        error.parameter = "handles"                 # the message says "parameter 'handles'"
        raise error
    values = [int(v) for v in values]
    # before the int64 cast, which overflows; without a mesh (n None) the negative ones only
    beyond = [k for k, v in enumerate(values) if not (0 <= v and (n is None or v < n))]
    if beyond:
        where = "negative" if n is None else f"outside [0, {n})"
        raise FilterParameterError(f"parameter 'handles': {counted(len(beyond), 'index', 'indices', verb='are')} "
                                   f"{where} (first: {tokens[beyond[0]]}); indices are 0-based into "
                                   "the mesh's vertices.", parameter="handles", count=len(beyond),
                                   first=[values[k] for k in beyond[:3]])
    if n is None and values and max(values) > np.iinfo(np.int64).max:
        return None                 # outside any mesh: named with the mesh's size when the filter runs
    idx = np.asarray(values, dtype=np.int64)
    if idx.size == 0:
        raise FilterParameterError("parameter 'handles' is empty; name the handle vertices, e.g. "
                                   "handles='12 40 41'.", parameter="handles", count=0)
    uniq, counts = np.unique(idx, return_counts=True)
    if uniq.size != idx.size:
        repeated = counted(idx.size - uniq.size, 'index', 'indices', verb='are')
        raise FilterParameterError(f"parameter 'handles': {repeated} repeated (first: "
                                   f"{first_indices(uniq[counts > 1])}); list each vertex once.", parameter="handles",
                                   count=int(idx.size - uniq.size), first=uniq[counts > 1][:3].tolist())
    return idx


def _handles_without_a_mesh(text):
    """The checks of `_indices` that need no mesh (numbers, whole, not negative, each once),
    run on the parameter's value (``Parameter.validate``), so that a script's check and the
    command line refuse a malformed ``handles`` before any step runs. The empty default passes
    here; the filter names it."""
    if str(text).replace(",", " ").split():
        _indices(text, None)


def _matrix(text):
    try:
        values = [real_word(t) for t in str(text).replace(",", " ").split()]
    except ValueError:
        raise FilterParameterError(f"parameter 'transform' must be 16 numbers (a 4x4 matrix, row by "
                                   f"row); got {str(text)[:40]!r}.", parameter="transform") from None
    if len(values) != 16 or not np.all(np.isfinite(values)):
        what = f"{len(values)} numbers" if len(values) != 16 else "NaN or infinite numbers"
        raise FilterParameterError(f"parameter 'transform' has {what}; it must be 16 finite numbers, a "
                                   "4x4 matrix row by row.", parameter="transform", count=len(values))
    T = np.asarray(values).reshape(4, 4)
    problem = affine_transform_problem(T)
    if problem:
        raise FilterParameterError(f"parameter 'transform': {problem}.", parameter="transform")
    return T


@filter(
    name="apply_curvature_editing",
    category="Curvature detail",
    description=f"""
        Mesh editing with curvature detail: the handle vertices are moved by a 4x4 transform and
        the region of interest - the selected vertices, the handles and, with region_radius,
        every vertex that close to a handle - is rebuilt from its curvature details. With
        method 'rotation' (the default) each rest detail turns with its neighbourhood (local
        rotations fitted to the one-rings, alternated with the embedding until no vertex has moved
        more than 1e-4 of the diagonal over the last 10 iterations). With method 'paper' the
        handles' curvature normals are transformed by the transform's linear part and scaled by
        detail_scale, and the region is rebuilt in two stages: the details of the other region
        vertices from the rotation- and
        scale-invariant curvature coefficients (min |(I - C) D|^2), then the positions from the
        details (E_Q). Vertices outside the region do not move. Vertices move in place; the vertex quality is set to
        the distance each vertex moved. Returns the largest move, how far the curvature stage
        amplified the handles' motion (amplification) and their detail change
        (detail_amplification), the triangles that folded over and the region's counts; a
        result with folded triangles is said with a
        curvdetail.curvature.errors.FoldedTrianglesWarning, one amplified more than 3 times (the
        limit of curvdetail edit's warning) with a
        curvdetail.filters.editing.AmplifiedEditWarning. {PAPER}, sections "Curvature
        coefficients" and "Mesh editing".
    """,
    parameters=[
        Parameter("handles", "str", "", "handle vertex indices, separated by spaces or commas "
                  "(from Python also a list, array, range, set or single int; whole floats such as "
                  "3.0 are indices)", validate=_handles_without_a_mesh, required=True),
        Parameter("region_radius", "PercentageValue", BBoxLength(0.0, percent=True),
                  "also put every vertex within this distance of a handle into the region of "
                  "interest (0: the selection alone); a percentage of the bbox diagonal or absolute",
                  min=0.0),
        Parameter("transform", "str", IDENTITY,
                  "4x4 handle transform, 16 numbers row by row, applied to homogeneous positions "
                  "(from Python also a 4x4 array)", shape=(4, 4), validate=_matrix),
        Parameter("method", "str", "rotation",
                  "'rotation': rest details turned with their neighbourhoods (fold-free on the "
                  "Botsch-Sorkine benchmark); 'paper': the paper's linear two-stage edit (needed for "
                  "detail_scale, move_handles=false, handle_detail and relations)",
                  choices=("rotation", "paper")),
        Parameter("detail_scale", "float", 1.0,
                  "method 'paper': factor on the handles' curvature details D = K A after the transform (1 keeps "
                  "them); below 1 flattens what the handles sit on, above 1 sharpens it "
                  "(mannequin_devil, move_handles=false, a horn's tip as handles: x0.5 makes the "
                  "horn 0.49-0.50 times as long, x2 2.01-2.02 times, region_radius 10-20 %)",
                  positive=True),
        Parameter("move_handles", "bool", True,
                  "constrain the handles' positions to the transformed ones; false constrains "
                  "their curvature normals only and lets them move"),
        Parameter("handle_detail", "str", "transform",
                  "handles' curvature normals: 'transform' (linear part x detail_scale) or 'free' "
                  "(solved like the other region vertices)", choices=("transform", "free")),
        Parameter("relations", "str", "one-ring",
                  "curvature stage: the paper's one-ring coefficients (square system) or one- and "
                  "two-ring coefficients together (least squares, steadier for rotated handles)",
                  choices=("one-ring", "one+two-ring")),
        Parameter("backend", "str", "auto", BACKEND_DESCRIPTION, choices=BACKENDS),
    ],
)
def apply_curvature_editing(ms, *, handles, region_radius, transform, method, detail_scale, move_handles,
                            handle_detail, relations, backend):
    mid = layer_id(ms)
    V, F = mesh_arrays(ms, mid)
    h = _indices(handles, V.shape[0])
    T = _matrix(transform)
    paper_only = [name for name, value, default in (("detail_scale", detail_scale, 1.0),
                                                    ("move_handles", move_handles, True),
                                                    ("handle_detail", handle_detail, "transform"),
                                                    ("relations", relations, "one-ring")) if value != default]
    if method == "rotation" and paper_only:
        raise FilterParameterError(f"{', '.join(paper_only)} apply to method='paper' only; method='rotation' "
                                   "moves the handles and turns every detail with its neighbourhood.",
                                   parameter="method", value=paper_only)
    if not move_handles and handle_detail == "free":
        raise FilterParameterError("move_handles=false with handle_detail='free' leaves the handles "
                                   "unconstrained; set one of them.", parameter="handle_detail")
    if not move_handles and detail_scale == 1.0 and np.array_equal(T[:3, :3], np.eye(3)) and T[:3, 3].any():
        # the details take the linear part alone: the translation would be dropped without a word
        raise FilterParameterError("the transform only translates, and move_handles=false keeps the handles' "
                                   "curvature normals alone, which a translation does not change: nothing "
                                   "would move. Set move_handles=true to move the handles, or give a "
                                   "rotation, scale or detail_scale to change their details.",
                                   parameter="move_handles")
    selected = selected_vertices(ms, mid)
    radius = region_radius.resolve(bbox_diagonal(V))
    if radius > 0:
        from scipy.spatial import cKDTree

        near = np.flatnonzero(cKDTree(V[h]).query(V, distance_upper_bound=radius)[0] <= radius)
        # the handles are in the region anyway (and a radius below ~1e-154 misses even them: the
        # tree compares squared distances); the radius has to bring in a vertex to rebuild
        selected = np.union1d(selected, np.setdiff1d(near, h))
    if selected.size == 0:
        # a positive radius is named as given: 1e-300 was called 0
        within = ("region_radius is 0" if region_radius.value == 0 else
                  f"no vertex but the handles lies within region_radius={region_radius} of a handle"
                  + ("" if radius == region_radius.value else f" ({radius:.3g} on this mesh)"))
        raise ConstraintError(
            f"layer {mid} ({get_mesh(ms, mid).label()!r}) has no selected vertices and {within}: the "
            "region of interest to rebuild is empty. Select it first (e.g. with "
            "compute_selection_by_condition_per_vertex) or set a larger region_radius (e.g. 20%).",
            parameter="region_radius", value=radius)
    roi = np.union1d(selected, h)
    if roi.size == V.shape[0]:
        reach = (f" plus every vertex within region_radius={region_radius} of a handle" if radius > 0 else "")
        smaller = ", or a smaller region_radius" if radius > 0 else ""
        raise ConstraintError(f"every vertex is in the region of interest (selection plus handles{reach}), so "
                              f"nothing stays fixed; leave part of the mesh unselected{smaller}.",
                              parameter="region_radius", value=radius, count=int(roi.size))
    t = time.perf_counter()
    if method == "rotation":
        return _rotation_edit(ms, mid, V, F, h, roi, T, backend, t)
    pc = h if move_handles else np.empty(0, dtype=np.int64)
    dc = h if handle_detail == "transform" else np.empty(0, dtype=np.int64)
    try:
        editor = CurvatureEditor(V, F, pc, dc, roi=roi, relations=relations, backend=backend)
    except UndeterminedEditError as exc:
        other = ("relations='one-ring', " if relations == "one+two-ring" else
                 "handle_detail='transform' (the handles' details given), " if handle_detail == "free" else "")
        raise UndeterminedEditError(exc.problem, f"Use more handles, {other}or a smaller region "
                                                 "(selection, region_radius).", parameter=exc.parameter,
                                    count=exc.count, first=exc.first) from None
    with np.errstate(over="ignore", invalid="ignore"):      # named below instead
        details = detail_scale * (editor.detail[dc] @ T[:3, :3].T) if dc.size else None
        positions = V[pc] @ T[:3, :3].T + T[:3, 3] if pc.size else None
    for values, what in ((positions, "the transform"), (details, "the transform with detail_scale")):
        check_transformed_values(values, what, "use a smaller transform or detail_scale", FilterParameterError)
    X, D = editor.solve(positions=positions, details=details, return_details=True)
    seconds = time.perf_counter() - t
    moved = np.linalg.norm(X - V, axis=1)
    if not np.all(np.isfinite(moved)):      # checked before the MeshSet is touched
        lost = counted(np.count_nonzero(~np.isfinite(moved)), "vertex", "vertices")
        raise FilterParameterError(f"the edit moved {lost} beyond double precision; use a smaller transform or "
                                   "detail_scale.")
    set_vertex_positions(ms, mid, X)
    set_vertex_quality(ms, mid, moved)
    diagonal = bbox_diagonal(V)
    folded = folded_triangles(V, F, X, T[:3, :3])
    rank_deficient, widened = _region_ring_counts(V, F, roi, editor)
    figures = {
        "max_displacement_percent_of_diagonal": float(100 * moved.max() / diagonal),
        # far above 1: the curvature stage amplified the handle details (see docs/guide/editing.md);
        # None where the handles are not placed or do not move (a ratio of rounding, or of a pure
        # detail edit, which detail_amplification measures)
        "amplification": (float(moved.max() / moved[h].max())
                          if move_handles and moved[h].max() > 1e-12 * diagonal else None),
        "detail_amplification": _detail_amplification(editor.detail, D, roi, detail_scale * T[:3, :3])
                                if dc.size else None,
        "folded_triangles": int(folded.size),
        "roi_vertices": int(roi.size),
        "handle_vertices": int(h.size),
        "rank_deficient_vertices": rank_deficient,
        "widened_ring_vertices": widened,
        "detail_island_vertices": int(editor.detail_islands),
        "iterations": None,
        "seconds": float(seconds),
    }
    _warn_if_amplified(figures, folded, F.shape[0], moved, D, editor.detail, dict(
        method="paper", relations=relations, detail_scale=detail_scale, handle_detail=handle_detail,
        handles_moved=figures["amplification"] is not None))
    return figures


def _rotation_edit(ms, mid, V, F, h, roi, T, backend, t):
    """The filter's body for method 'rotation': the handles placed, the details turned."""
    editor = RotationAwareEditor(V, F, h, roi=roi, backend=backend)
    with np.errstate(over="ignore", invalid="ignore"):      # named below instead
        positions = V[h] @ T[:3, :3].T + T[:3, 3]
    check_transformed_values(positions, "the transform", "use a smaller transform", FilterParameterError)
    X = editor.solve(positions)
    seconds = time.perf_counter() - t
    moved = np.linalg.norm(X - V, axis=1)
    set_vertex_positions(ms, mid, X)
    set_vertex_quality(ms, mid, moved)
    diagonal = bbox_diagonal(V)
    folded = folded_triangles(V, F, X, T[:3, :3])
    figures = {
        "max_displacement_percent_of_diagonal": float(100 * moved.max() / diagonal),
        "amplification": float(moved.max() / moved[h].max()) if moved[h].max() > 1e-12 * diagonal else None,
        "detail_amplification": None,
        "folded_triangles": int(folded.size),
        "roi_vertices": int(roi.size),
        "handle_vertices": int(h.size),
        "rank_deficient_vertices": None,
        "widened_ring_vertices": None,
        "detail_island_vertices": None,
        "iterations": int(editor.iterations),
        "seconds": float(seconds),
    }
    _warn_if_amplified(figures, folded, F.shape[0], moved, None, None, dict(
        method="rotation", relations=None, detail_scale=1.0, handle_detail=None,
        handles_moved=figures["amplification"] is not None))
    return figures


def _detail_amplification(D0, D, roi, M):
    """The largest detail change in the region over the largest one the edit asks for: the
    handles' change ``D -> M D`` (``M`` = detail_scale times the transform's linear part) applied
    to every region vertex's rest detail, which is what a region following the handles fully
    would get. About 1 or below where the curvature stage spreads the handles' change (it
    interpolates it towards the fixed rest); None where the edit asks no detail change (a
    translation, or the identity with detail_scale 1)."""
    asked = np.linalg.norm(D0[roi] @ (M - np.eye(3)).T, axis=1).max()
    if not asked > 1e-12 * np.linalg.norm(D0[roi], axis=1).max():
        return None
    return float(np.linalg.norm(D[roi] - D0[roi], axis=1).max() / asked)


def _region_ring_counts(V, F, roi, editor):
    """Vertices of the region whose ring detail is rank-deficient, and those whose coefficients
    span a widened ring (``curvature_coefficients``, as the editor computed them)."""
    in_roi = np.zeros(V.shape[0], dtype=bool)
    in_roi[roi] = True
    return (int(np.count_nonzero(in_roi[editor.rank_deficient_vertices])),
            int(np.count_nonzero(in_roi[editor.widened_vertices])))


def _warn_if_amplified(figures, folded, m, moved, D, D0, options):
    """A FoldedTrianglesWarning where triangles folded, else an AmplifiedEditWarning where
    ``amplification`` or ``detail_amplification`` is above `AMPLIFICATION_LIMIT` (the
    rule of curvdetail edit's warning); nothing otherwise. The message names the figures, the
    first folded triangles and the vertices that moved and changed most, and what to try."""
    ratio, detail_ratio = figures["amplification"], figures["detail_amplification"]
    amplified = [r for r in (ratio, detail_ratio) if r is not None and r > AMPLIFICATION_LIMIT]
    if not folded.size and not amplified:
        return

    parts = []
    if folded.size:
        parts.append(f"{counted(folded.size, 'triangle')} of {m} folded over (normal against the rest "
                     f"shape's; first: {first_indices(folded)})")
    moved_most = int(np.argmax(moved))
    parts.append(f"vertices moved up to {figures['max_displacement_percent_of_diagonal']:.3g} % of the bbox diagonal "
                 f"(vertex {moved_most})" + (f", {ratio:.1f} times as far as the handles" if ratio is not None
                                             else ""))
    if detail_ratio is not None:
        changed_most = int(np.argmax(np.linalg.norm(D - D0, axis=1)))
        parts.append(f"the details changed up to {detail_ratio:.1f} times as much as the edit asks of the "
                     f"region (vertex {changed_most})")
    relations = options["relations"]
    other = "one+two-ring" if relations == "one-ring" else "one-ring"
    tries = [f"relations={other!r}"] if options["method"] == "paper" else ["method='paper'"]
    if options["handles_moved"] and options["handle_detail"] == "transform":
        tries.append("handle_detail='free'")
    tries.append("more handles")
    if options["detail_scale"] != 1:
        tries.append("a detail_scale closer to 1")
    if amplified:
        cause = "the curvature stage amplified the handles' change (ill-conditioned coefficients"
    else:
        cause = ("the region cannot follow the handles' change without folding (too large an edit for the "
                 "region, or coefficients that distort it")
        tries.append("a larger region")
    category = FoldedTrianglesWarning if folded.size else AmplifiedEditWarning
    setting = f"relations={relations!r}" if options["method"] == "paper" else "method='rotation'"
    warn(f"apply_curvature_editing with {setting}: {'; '.join(parts)}: {cause}, see "
                  "docs/guide/editing.md). "
                  f"The mesh was edited all the same; try {', '.join(tries[:-1])} or {tries[-1]} on the original.",
                  category)
