"""Shape editing of a patch's boundary (the paper's Fig. 2b)."""

import inspect
import math
import numbers
import warnings

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import depth_first_order

from .checks import MIN_DIAGONAL, ZERO_AREA_RELATIVE, _check_magnitude, as_faces, as_values, as_vertices, check_bool, check_choice, check_mesh
from .geometry import bbox_diagonal, face_double_areas, folded_triangles, ignoring_underflow
from .topology import _compact_ids, boundary_edges, check_oriented, vertex_components
from .cotan_laplacian import _cotan_laplacian_unchecked, laplacian_product
from .curvature_coefficients import DEFAULT_RCOND, check_rcond
from .curvature_editor import CurvatureEditor, _check_relations
from .rotation_editor import RotationAwareEditor
from .errors import ConstraintError, CurvdetailError, FoldedTrianglesWarning, MeshError, counted, first_indices
from .sparse_solver import factorize, resolve_backend


@ignoring_underflow
def edit_boundary(V, F, displacement, *, method="rotation", boundary_detail=None, relations=None,
                  rcond=DEFAULT_RCOND, backend="auto", return_info=False):
    """Move the boundary of a disk-topology patch and rebuild the surface from its detail.

    The boundary loop is moved by ``displacement``; the interior is rebuilt with the boundary's
    new positions constrained. ``method="rotation"`` (the default): the patch is moved by the
    boundary's best-fitting similarity, then a `RotationAwareEditor` turns each detail with its
    neighbourhood. ``method="paper"``: the boundary's curvature detail is
    updated (``boundary_detail="deformed"``, the paper: the details of a provisional surface, the
    boundary's best-fitting similarity applied to the patch and the rest of the move spread
    harmonically inside; ``"rest"``: kept), then a `CurvatureEditor` with the boundary's positions
    and details constrained rebuilds the interior. See docs/guide/editing.md, "Shape editing of a
    boundary".

    Parameters
    ----------
    V : (n, 3) float array
        Rest positions of a patch with exactly one boundary loop.
    F : (m, 3) int array
        Triangles.
    displacement : callable or (b, 3) float array
        ``displacement(s, P) -> (b, 3)`` with ``s`` the normalized arc length in [0, 1) of each
        boundary vertex along the loop and ``P`` their (b, 3) positions; or the displacements
        themselves, row r for ``info["boundary"][r]``. `sine_displacement` builds the
        paper's sine.
    method : {"rotation", "paper"}
        Rotation-aware edit (no fold on the paper's Fig. 2b sines) or the paper's linear edit.
    boundary_detail : {"deformed", "rest"} or None
        ``"paper"`` only (None: ``"deformed"``): how the boundary's detail is updated.
    relations : {"one-ring", "one+two-ring"} or None
        ``"paper"`` only (None: ``"one-ring"``): curvature-stage relations of `CurvatureEditor`.
    rcond : float
        Threshold of `curvature_coefficients` (``"paper"`` only).
    backend : str
        Sparse solver backend.
    return_info : bool
        Also return a dict: ``boundary`` (loop order), ``arc_length``, ``boundary_detail`` (b, 3;
        None with ``"rotation"``), ``editor`` (for re-solves; with ``"rotation"`` a
        `RotationAwareEditor` whose rest is the patch moved by this displacement's best-fitting
        similarity, so its re-solves edit that shape, not ``V``), ``iterations`` (``"rotation"``),
        ``folded_triangles`` (normal against the rest one, the boundary's rotation discounted), ``max_displacement`` / ``boundary_displacement`` (largest
        move of any / a boundary vertex over the rest bbox diagonal), ``amplification`` (their
        ratio, None for an unmoved boundary).

    Returns
    -------
    X : (n, 3) float array
        Edited positions; ``X[boundary] == V[boundary] + displacement`` exactly.
    info : dict
        Only with ``return_info=True``.

    Warns
    -----
    FoldedTrianglesWarning
        When ``folded_triangles > 0``, with the figures and what to try.

    Raises
    ------
    MeshError
        If the mesh is malformed or has not exactly one boundary loop.
    ConstraintError
        If the displacements (given or returned) have the wrong shape or dtype, are not finite or
        too large, or collapse the loop (``"deformed"``, or to one point with ``"rotation"``); if
        ``boundary_detail``, ``relations`` or another ``rcond`` is given with ``method="rotation"``.
    ValueError
        If the displacement callable does not take ``(s, P)``, or an option is not one of its values.
    SolverError
        If ``backend`` is unknown or not installed.

    Examples
    --------
    >>> import numpy as np
    >>> from curvdetail.curvature.testing import grid
    >>> V, F = grid(12, 12); V[:, 2] = 0.05 * np.sin(6 * V[:, 0]) * np.sin(6 * V[:, 1])
    >>> X, info = edit_boundary(V, F, sine_displacement(0.1, periods=2, axis=2), return_info=True)
    >>> b = info["boundary"]
    >>> bool(np.allclose(X[b, 2] - V[b, 2], 0.1 * np.sin(2 * np.pi * 2 * info["arc_length"])))
    True
    """
    # the options before the mesh and the displacement callable
    method = check_choice(method, "method", ("rotation", "paper"), "; use 'rotation' or 'paper'.")
    if boundary_detail is not None:
        boundary_detail = check_choice(boundary_detail, "boundary_detail", ("deformed", "rest"),
                                       "; use 'deformed' or 'rest'.")
    if relations is not None:
        _check_relations(relations)
    check_rcond(rcond)
    for name, value in (("boundary_detail", boundary_detail), ("relations", relations),
                        ("rcond", None if rcond == DEFAULT_RCOND else rcond)):
        if method == "rotation" and value is not None:
            raise ConstraintError(f"{name} applies to method='paper' only", parameter=name, value=value,
                                  hint=f"pass method='paper' with {name}, or leave {name} out")
    boundary_detail, relations = boundary_detail or "deformed", relations or "one-ring"
    resolve_backend(backend)
    check_bool(return_info, "return_info")
    V = as_vertices(V)
    F = as_faces(F, V.shape[0])        # the editor below runs every mesh check
    try:
        loop = boundary_loop(F)
    except MeshError:
        check_mesh(V, F)               # a malformed mesh is named as such, not as a bad boundary
        raise
    P = V[loop]
    seg = np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1)
    if not seg.sum() > 0:               # a loop of one point: its triangles have zero area
        check_mesh(V, F)
        raise MeshError("the boundary loop has length 0 (all its vertices coincide); repair the mesh.", parameter="V")
    s = np.concatenate([[0.0], np.cumsum(seg)[:-1]]) / seg.sum()
    if callable(displacement):
        _check_displacement_signature(displacement, loop.size)
        displacement = displacement(s.copy(), P.copy())     # the user's own errors reach the caller
    Q = P + as_values(displacement, loop.size, "displacement")       # the boundary's new positions
    # before any algebra: beyond 1e75 the provisional surface's areas overflow
    _check_magnitude(Q, "the displaced boundary (its positions plus the displacement)", ConstraintError,
                     "use a smaller displacement")
    s_, R, t = _similarity(P, Q)                # R also turns the rest normals for the fold count
    Db, iterations = None, None
    if method == "rotation":
        if not np.ptp(Q, axis=0).max() > 1e-12 * np.ptp(P, axis=0).max() or s_ * bbox_diagonal(V) < MIN_DIAGONAL:
            raise ConstraintError(f"the displacement moves all {loop.size} boundary vertices onto one point",
                                  parameter="displacement", count=loop.size,
                                  hint="use a displacement that keeps the loop open")
        # the patch moved by the boundary's best-fitting similarity first: a similarity of the
        # whole boundary is then the rest state of the rotation-aware energy
        editor = RotationAwareEditor(s_ * V @ R.T + t, F, loop, backend=backend)
        X = editor.solve(Q)
        iterations = editor.iterations
    else:
        editor = CurvatureEditor(V, F, loop, loop, relations=relations, rcond=rcond, backend=backend)
        if boundary_detail == "rest":
            Db = editor.detail[loop]
        else:                                   # editor.laplacian: of the rest shape
            Db = _deformed_boundary_detail(V, F, editor.laplacian, loop, P, Q, s_, R, t, backend)
        X = editor.solve(positions=Q, details=Db)
    folded = folded_triangles(V, F, X, R)          # a patch turned as a whole counts none
    diag, moved = bbox_diagonal(V), np.linalg.norm(X - V, axis=1)
    on_loop = moved[loop].max()
    figures = {"folded_triangles": int(folded.size), "max_displacement": float(moved.max() / diag),
               "boundary_displacement": float(on_loop / diag),
               "amplification": float(moved.max() / on_loop) if on_loop > 1e-12 * diag else None}
    if folded.size:
        _warn_folded(figures, folded, F.shape[0], method, boundary_detail, relations)
    if not return_info:
        return X
    return X, {"boundary": loop, "arc_length": s, "boundary_detail": Db, "editor": editor,
               "iterations": iterations, **figures}


def _deformed_boundary_detail(V, F, L, loop, P, Q, s_, R, t, backend):
    """The boundary's details on the provisional surface: the patch moved by the boundary's
    best-fitting similarity ``(s_, R, t)``, the rest of the move spread harmonically (``L``)."""
    n = V.shape[0]
    free = np.ones(n, dtype=bool)
    free[loop] = False
    inner = np.flatnonzero(free)
    Vp = s_ * V @ R.T + t
    U = np.zeros((n, 3))
    U[loop] = Q - Vp[loop]
    if inner.size:
        Lf = L[inner][:, inner]
        U[inner] = factorize(Lf, symmetric=True, backend=backend).solve(-(L[inner][:, loop] @ U[loop]))
    Vp += U
    _check_provisional_surface(Vp, F, P, Q)
    return laplacian_product(_cotan_laplacian_unchecked(Vp, F), Vp)[loop]


def _warn_folded(figures, folded, m, method, boundary_detail, relations):
    """A `FoldedTrianglesWarning` with the figures and what to try."""
    ratio, moved, on_loop = (figures[k] for k in ("amplification", "max_displacement", "boundary_displacement"))
    how_far = (f"vertices moved up to {ratio:.1f} times as far as the boundary ({100 * moved:.3g} % against "
               f"{100 * on_loop:.3g} % of the bbox diagonal)" if ratio is not None else
               f"vertices moved up to {100 * moved:.3g} % of the bbox diagonal, the boundary not at all")
    other = "one+two-ring" if relations == "one-ring" else "one-ring"
    settings = f"boundary_detail={boundary_detail!r}, relations={relations!r}"
    if method == "rotation":
        cause, tries, settings = "", "a smaller displacement or method='paper' with boundary_detail='rest'", \
            "method='rotation'"
    elif boundary_detail == "deformed":
        cause = "; the curvature stage amplified the boundary's detail change (see docs/guide/editing.md)"
        tries = (f"relations={other!r}, a smaller displacement or boundary_detail='rest' (the inside keeps "
                 "its rest detail and follows the boundary)")
    else:
        cause, tries = "", f"a smaller displacement or relations={other!r}"
    warnings.warn(
        f"edit_boundary: {counted(folded.size, 'triangle')} of {m} folded over (normal against the rest "
        f"shape's; first: {first_indices(folded)}) with {settings}: "
        f"{how_far}{cause}. Try {tries}.", FoldedTrianglesWarning, stacklevel=3)


def _check_displacement_signature(displacement, b):
    """ValueError if the signature of ``displacement`` does not take ``(s, P)`` (checked before the
    call: a TypeError inside it is the user's own); callables without a readable signature pass."""
    try:
        signature = inspect.signature(displacement)
    except (TypeError, ValueError):             # some builtins and extension types
        return
    try:
        signature.bind(None, None)
    except TypeError as exc:
        raise CurvdetailError(f"the displacement callable cannot be called as displacement(s, P) ({exc}); it "
                              f"must map the boundary's arc lengths s ({b},) and positions P ({b}, 3) to a "
                              f"({b}, 3) float array of displacements.", parameter="displacement", count=b) from None


def _check_provisional_surface(Vp, F, P, Q):
    """ConstraintError if the provisional surface ``Vp`` (the loop moved from ``P`` to ``Q``) has
    triangles of zero area, as check_mesh counts them: the displacement collapsed the loop."""
    diag = bbox_diagonal(Vp)
    dbl = face_double_areas(Vp, F)
    zero = np.flatnonzero(~(dbl > 2.0 * ZERO_AREA_RELATIVE * diag ** 2))      # NaN included
    if not zero.size:
        return
    extent = np.sort(np.ptp(Q, axis=0))[::-1]
    if not extent[0] > 1e-12 * np.ptp(P, axis=0).max():     # the rest loop's extent: rounding of P - P
        what = f"moves all {Q.shape[0]} boundary vertices onto one point"
    elif diag < MIN_DIAGONAL:
        what = f"shrinks the patch to {diag:.3g} across, where triangle areas underflow double precision"
    elif not extent[1] > 1e-12 * extent[0]:
        what = "moves the boundary loop onto a line"
    else:
        what = "collapses part of the boundary loop (e.g. a vertex onto its neighbour)"
    raise ConstraintError(
        f"the displacement {what}: {counted(zero.size, 'triangle')} of the provisional surface whose detail gives the "
        f"boundary's (boundary_detail='deformed') {'has' if zero.size == 1 else 'have'} zero area (first: {first_indices(zero)}), so the "
        "boundary's new curvature detail is undefined. Use a displacement that keeps the loop open, or "
        "boundary_detail='rest' (the boundary keeps its rest detail).", parameter="displacement",
        count=int(zero.size), first=zero[:3].tolist())


def _similarity(P, Q):
    """``(s, R, t)`` with ``Q ~ s P R^T + t`` in least squares (Umeyama 1991): s > 0, R a
    rotation (no reflection)."""
    mp, mq = P.mean(axis=0), Q.mean(axis=0)
    A, B = P - mp, Q - mq
    spread = float((A ** 2).sum())               # > 0: a loop of one point was refused
    U, S, Wt = np.linalg.svd(B.T @ A)
    D = np.ones(3)
    D[2] = np.sign(np.linalg.det(U @ Wt)) or 1.0
    R = (U * D) @ Wt
    s = float((S * D).sum()) / spread
    if not s > 0:                   # a boundary turned inside out: no similarity part to take
        return 1.0, np.eye(3), mq - mp
    return s, R, mq - s * mp @ R.T


def sine_displacement(amplitude, periods=1, axis=1, phase=0.0):
    """The paper's boundary edit: ``amplitude * sin(2 pi (periods * s + phase))`` along one axis.

    Parameters
    ----------
    amplitude : float
        In the mesh's length unit.
    periods : float
        Number of periods along the whole loop (an integer closes it smoothly).
    axis : {0, 1, 2}
        The axis moved (x, y or z).
    phase : float
        In periods.

    Returns
    -------
    displacement : callable
        ``(s, P) -> (b, 3)``, for `edit_boundary`.

    Raises
    ------
    ValueError
        If ``axis`` is not the integer 0, 1 or 2, or another argument is not a finite number.

    Examples
    --------
    >>> f = sine_displacement(2.0, periods=1, axis=2)
    >>> f(np.array([0.0, 0.25]), np.zeros((2, 3)))[:, 2].round(12).tolist()
    [0.0, 2.0]
    """
    if isinstance(axis, (bool, np.bool_)) or not isinstance(axis, numbers.Integral) or axis not in (0, 1, 2):
        raise CurvdetailError(f"axis={axis!r}; use 0, 1 or 2 for x, y or z.", parameter="axis", value=axis)
    axis = int(axis)
    for name, value in (("amplitude", amplitude), ("periods", periods), ("phase", phase)):
        if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
            raise CurvdetailError(f"{name}={value!r} must be a finite number.", parameter=name, value=value)

    def displacement(s, P):
        out = np.zeros((np.asarray(s).size, 3))
        out[:, axis] = amplitude * np.sin(2.0 * np.pi * (periods * np.asarray(s) + phase))
        return out

    return displacement


def boundary_loop(F):
    """The single boundary loop of a disk-topology patch, in the orientation of its triangles.

    Parameters
    ----------
    F : (m, 3) int array
        Triangles, consistently oriented (no vertex positions are needed).

    Returns
    -------
    loop : (b,) int64 array
        Boundary vertices in order from the smallest index, each ``(loop[i], loop[i + 1])`` as in
        its triangle (counter-clockwise seen from the normals).

    Raises
    ------
    MeshError
        If ``F`` is malformed or has not one simple boundary loop (the cause named).

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> boundary_loop(grid(3, 3)[1]).tolist()      # vertices 0 1 2 / 3 4 5 / 6 7 8, normals +z
    [0, 1, 2, 5, 8, 7, 6, 3]
    """
    E = boundary_edges(F)
    try:
        return loop_of_boundary_edges(E)
    except MeshError as exc:
        problem = exc
    if E.shape[0] == 0:                 # closed: nothing more to say
        raise problem
    # name the cause where it is not the boundary itself: repeated or reversed triangles, pieces
    _, F = _compact_ids(as_faces(F, None))
    corners = np.sort(F, axis=1)
    _, first, counts = np.unique(corners, axis=0, return_index=True, return_counts=True)
    if np.any(counts > 1):
        twice = np.sort(first[counts > 1])
        raise MeshError(f"{counted(twice.size, 'triangle', verb='appear')} more than once (first: "
                        f"{', '.join(map(str, twice[:3]))}), which takes their edges off the boundary; "
                        "remove the copies (e.g. pymeshlab's meshing_remove_duplicate_faces).", parameter="F",
                        count=int(twice.size), first=twice[:3].tolist())
    check_oriented(F)
    labels, _ = vertex_components(F, int(F.max()) + 1)
    pieces = np.unique(labels[F.ravel()]).size          # unreferenced vertices are no pieces
    if pieces > 1:
        raise MeshError(f"the mesh has {pieces} separate pieces, each with its own boundary; shape "
                        "editing of a boundary needs one disk-topology patch: edit each piece on its "
                        "own (e.g. keep one with pymeshlab's meshing_remove_connected_component_by_"
                        "face_number).", parameter="F", count=int(pieces))
    raise problem


def loop_of_boundary_edges(E):
    """`boundary_loop` from the boundary edges ``E`` (k, 2) of `boundary_edges`."""
    if E.shape[0] == 0:
        raise MeshError("the mesh is closed (no boundary loop); shape editing of a boundary needs "
                        "a patch with one boundary loop.", parameter="F", count=0)
    starts, counts = np.unique(E[:, 0], return_counts=True)
    if np.any(counts > 1):
        bad = starts[counts > 1]
        raise MeshError(f"{counted(bad.size, 'boundary vertex', 'boundary vertices', verb='are')} on more than one "
                        f"boundary edge pair (first: {', '.join(map(str, bad[:3]))}); the boundary touches itself. "
                        "Repair the mesh so that its boundary is one simple loop.", parameter="F",
                        count=int(bad.size), first=bad[:3].tolist())
    # every vertex has at most one edge out: the walk is the successor graph's depth-first order
    n = int(E.max()) + 1
    successor = sp.csr_matrix((np.ones(E.shape[0], dtype=np.int8), (E[:, 0], E[:, 1])), shape=(n, n))
    start = int(E[:, 0].min())
    loop = depth_first_order(successor, start, directed=True, return_predecessors=False)
    last = int(loop[-1])
    if successor.indptr[last + 1] == successor.indptr[last]:
        raise MeshError(f"the boundary does not close: its edge into vertex {last} has no edge out of "
                        "it (triangles oriented inconsistently, or a mesh that is not manifold). "
                        "Check the mesh with check_mesh and orient it consistently.", parameter="F", first=[last])
    back = int(successor.indices[successor.indptr[last]])
    if back != start:                           # the walk ran into itself elsewhere: a vertex ends two edges
        raise MeshError(f"the boundary walk from vertex {start} runs into vertex {back}, which ends two boundary "
                        "edges: the boundary touches itself. Repair the mesh so that its boundary is one simple "
                        "loop.", parameter="F", first=[start, back])
    if loop.size != E.shape[0]:
        raise MeshError(f"the boundary has {E.shape[0]} edges but the loop through vertex {start} has "
                        f"{loop.size}: the patch has several boundary loops (holes). Fill the holes, "
                        "e.g. with pymeshlab's meshing_close_holes, or cut a disk-topology patch.", parameter="F",
                        count=int(E.shape[0]), first=[start])
    return loop.astype(np.int64, copy=False)
