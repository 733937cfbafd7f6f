"""The linear-deformation benchmark format (Botsch & Sorkine, IEEE TVCG 2008), and an edit run
from it.

``NAME.sel``: ``#`` comment lines, then one status per vertex in vertex order: ``0`` fixed, ``1``
free (the deformable region), ``2`` handle. ``NAME.def``: ``#`` comment lines, then a 4x4 affine
matrix acting on homogeneous handle positions, ``x' = T[:3, :3] x + T[:3, 3]``.
"""

import os

import numpy as np

from ..curvature.checks import affine_transform_problem, as_vertices, check_bool, check_choice, check_transformed_values, real_word
from ..curvature.curvature_coefficients import DEFAULT_RCOND
from ..curvature.curvature_editor import CurvatureEditor
from ..curvature.rotation_editor import DEFAULT_MAX_ITERATIONS, DEFAULT_TOL, RotationAwareEditor
from ..curvature.errors import ConstraintError, CurvdetailError, counted, first_indices
from .atomic import atomic_write

FIXED, FREE, HANDLE = 0, 1, 2
HANDLE_DETAIL_MODES = ("transform", "free")
METHODS = ("rotation", "paper")


class DeformationFileError(CurvdetailError):
    """A ``.sel`` or ``.def`` file is malformed or does not fit the mesh (``e.value`` is the file;
    ``e.count`` and ``e.first`` the bad lines' count and first line numbers where there are such)."""


def _file_error(path, problem, **facts):
    return DeformationFileError(f"{path}: {problem}", parameter="path", value=path, **facts)


def _data_lines(path, what):
    """``(line number, stripped text)`` of the lines that are neither blank nor comments."""
    if os.path.isdir(path):
        raise _file_error(path, "is a folder", hint=f"name a {what} file")
    if not os.path.isfile(path):
        raise FileNotFoundError(f"{what} file not found: {path}")
    try:
        with open(path, encoding="utf-8-sig") as fh:        # -sig: a byte-order mark is no text
            lines = fh.read().splitlines()
    except UnicodeDecodeError as exc:
        raise _file_error(path, f"byte {exc.start} is not UTF-8 text", first=[exc.start],
                          hint="save the file as UTF-8 or ASCII") from None
    return [(k + 1, line.strip()) for k, line in enumerate(lines)
            if line.strip() and not line.lstrip().startswith("#")]


def read_selection(path, n_vertices=None):
    """Read a ``.sel`` file: one status per vertex (0 fixed, 1 free, 2 handle).

    Parameters
    ----------
    path : str or os.PathLike
        The ``.sel`` file.
    n_vertices : int, optional
        The number of statuses the file must hold.

    Returns
    -------
    status : (n,) int8 array

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    DeformationFileError
        If a line is not 0, 1 or 2 (``e.count`` lines, first ``e.first`` by line number), there is
        no data, or the count differs from ``n_vertices`` (``e.count`` statuses).

    Examples
    --------
    >>> import os, tempfile
    >>> p = os.path.join(tempfile.mkdtemp(), "a.sel")
    >>> write_selection(p, [0, 1, 1, 2])
    >>> read_selection(p, 4).tolist()
    [0, 1, 1, 2]
    """
    path = os.fspath(path)
    rows = _data_lines(path, "selection")
    bad = [(no, text) for no, text in rows if text not in ("0", "1", "2")]
    if bad:
        shown = ", ".join(f"line {no}: {text[:20]!r}" for no, text in bad[:3])
        raise _file_error(path, f"{counted(len(bad), 'line', verb='are')} not a vertex status 0, 1 or 2 ({shown})",
                          count=len(bad), first=[no for no, _ in bad[:3]],
                          hint="a .sel file holds one status per vertex (0 fixed, 1 free, 2 handle)")
    if not rows:
        raise _file_error(path, "no vertex statuses found (only comments or blank lines)", count=0)
    status = np.array([int(text) for _, text in rows], dtype=np.int8)
    if n_vertices is not None and status.size != int(n_vertices):
        raise _file_error(path, f"{status.size} vertex statuses for a mesh of {int(n_vertices)} vertices",
                          count=status.size, hint="list every vertex, in the mesh's vertex order")
    return status


def read_transform(path):
    """Read a ``.def`` file: a 4x4 affine matrix acting on homogeneous positions.

    Returns
    -------
    T : (4, 4) float array
        ``x' = T[:3, :3] @ x + T[:3, 3]``.

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    DeformationFileError
        If the file is not 4 rows (``e.count``) of 4 finite numbers (``e.first``: the bad line), or
        the matrix is not affine with an invertible linear part.

    Examples
    --------
    >>> import os, tempfile
    >>> p = os.path.join(tempfile.mkdtemp(), "a.def")
    >>> write_transform(p, np.eye(4))
    >>> read_transform(p).tolist() == np.eye(4).tolist()
    True
    """
    path = os.fspath(path)
    rows = _data_lines(path, "transform")
    if len(rows) != 4:
        raise _file_error(path, f"{len(rows)} matrix rows", count=len(rows), hint="a .def file holds 4 rows of 4 numbers")
    T = np.empty((4, 4))
    for r, (no, text) in enumerate(rows):
        try:
            T[r] = [real_word(p) for p in text.replace(",", " ").split()]
        except ValueError:               # not numbers, or not 4 of them
            T[r] = np.nan
        if not np.isfinite(T[r]).all():
            raise _file_error(path, f"line {no} ({text[:40]!r}) is not 4 finite numbers", count=1, first=[no])
    problem = affine_transform_problem(T)
    if problem:
        raise _file_error(path, problem)
    return T


def _write_text(path, text, overwrite):
    with atomic_write(path, overwrite=overwrite) as tmp:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)


def write_selection(path, status, *, overwrite=False):
    """Write a ``.sel`` file (the survey's two comment lines, one status per line), atomically.

    Raises
    ------
    DeformationFileError
        If ``status`` is empty or holds values other than 0, 1, 2.
    FileExistsError
        If ``path`` exists and ``overwrite`` is False.
    """
    status = np.asarray(status).reshape(-1)
    if status.size == 0 or not np.isin(status, (FIXED, FREE, HANDLE)).all():
        raise DeformationFileError("status must be a non-empty array of 0 (fixed), 1 (free), 2 (handle)",
                                   parameter="status")
    text = ("# per vertex status: 0=fixed, 1=deformable-region, 2=handle\n"
            f"# {status.size} vertices\n" + "\n".join(str(int(s)) for s in status) + "\n")
    _write_text(path, text, overwrite)


def write_transform(path, T, *, overwrite=False):
    """Write a ``.def`` file (a comment line, 4 rows of 4 numbers with 17 significant digits, so
    it reads back as the same doubles), atomically.

    Raises
    ------
    DeformationFileError
        If ``T`` is a matrix `read_transform` would refuse.
    FileExistsError
        If ``path`` exists and ``overwrite`` is False.
    """
    T = _as_transform(T, DeformationFileError)
    text = "# 4x4 handle transformation matrix\n" + "\n".join(
        " ".join(f"{v:.17g}" for v in row) for row in T) + "\n"
    _write_text(path, text, overwrite)


def _as_transform(T, error):
    """``T`` as a (4, 4) float array that `read_transform` would accept, else ``error``."""
    try:
        T = np.asarray(T, dtype=np.float64)
        problem = None if T.shape == (4, 4) and np.isfinite(T).all() else f"T has shape {T.shape} or is not finite"
    except (TypeError, ValueError) as exc:
        problem = f"T could not be read as numbers ({exc})"
    problem = problem or affine_transform_problem(T)
    if problem:
        raise error(f"the handle transform: {problem}", parameter="T", hint="give a finite affine 4x4 matrix")
    return T


def apply_transform(T, P):
    """``P @ T[:3, :3].T + T[:3, 3]`` for (k, 3) positions ``P``."""
    T = np.asarray(T, dtype=np.float64)
    return np.asarray(P, dtype=np.float64) @ T[:3, :3].T + T[:3, 3]


def edit_with_selection(V, F, status, T, *, method="rotation", handle_detail=None, relations=None,
                        rcond=DEFAULT_RCOND, scaling=False, tol=DEFAULT_TOL, max_iterations=DEFAULT_MAX_ITERATIONS,
                        backend="auto", return_editor=False):
    """Deform a mesh as a benchmark case prescribes: fixed vertices stay, handles move by ``T``.

    The region of interest is every vertex of status 1 or 2.

    Parameters
    ----------
    V : (n, 3) float array
        Rest positions.
    F : (m, 3) int array
        Triangles.
    status : (n,) int array
        0 fixed, 1 free, 2 handle (see `read_selection`).
    T : (4, 4) float array
        Affine handle transform with an invertible linear part (see `read_transform`).
    method : {"rotation", "paper"}
        ``"rotation"``: a `RotationAwareEditor`
        (the rest details turn with their neighbourhoods; fold-free on the benchmark cases);
        ``"paper"``: the paper's linear two-stage `CurvatureEditor`.
    handle_detail : {"transform", "free"}, optional
        ``method="paper"`` only (default "transform"): the handles' details constrained to
        ``T[:3, :3] @ D`` (exact for a similarity), or solved like the free ones.
    relations, rcond
        ``method="paper"`` only, as for `CurvatureEditor`
        (``relations`` default "one-ring").
    scaling, tol, max_iterations
        ``method="rotation"`` only, as for ``RotationAwareEditor``.
    backend : str
        Sparse solver backend.
    return_editor : bool
        Also return the factored editor (for re-solves).

    Returns
    -------
    X : (n, 3) float array
        Fixed vertices exactly at ``V``, handles exactly at ``T`` applied to ``V``.
    editor : RotationAwareEditor or CurvatureEditor
        Only with ``return_editor=True``.

    Raises
    ------
    MeshError
        If ``V`` or ``F`` is malformed.
    ConstraintError
        If ``status`` does not fit (length, values, no handle, no fixed vertex) or ``T`` is refused.
    ValueError
        If ``method`` or ``handle_detail`` is unknown, a paper-only option is given with
        ``method="rotation"`` (``e.parameter``), or ``return_editor`` is not a bool.

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> V, F = grid(10, 10)
    >>> status = np.where(V[:, 0] < 0.15, 0, np.where(V[:, 0] > 0.85, 2, 1))
    >>> T = np.eye(4); T[2, 3] = 0.3                          # lift the handle
    >>> X = edit_with_selection(V, F, status, T)
    >>> bool(np.all(X[status == 2, 2] == 0.3) and np.all(X[status == 0] == V[status == 0]))
    True
    """
    method = check_choice(method, "method", METHODS, "; use 'rotation' (rotation-aware) or 'paper'.")
    if method == "rotation":
        for name, value in (("handle_detail", handle_detail), ("relations", relations)):
            if value is not None:
                raise CurvdetailError(f"{name} applies to method='paper' only", parameter=name, value=value,
                                      hint="drop it, or pass method='paper'")
    handle_detail = check_choice("transform" if handle_detail is None else handle_detail, "handle_detail",
                                 HANDLE_DETAIL_MODES, "; use 'transform' or 'free'.")
    return_editor = check_bool(return_editor, "return_editor")
    V = as_vertices(V)
    status = np.asarray(status).reshape(-1)
    if status.size != V.shape[0]:
        raise ConstraintError(f"status has {status.size} entries for {V.shape[0]} vertices", parameter="status",
                              count=status.size, hint="give one status per vertex")
    bad = np.flatnonzero(~np.isin(status, (FIXED, FREE, HANDLE)))
    if bad.size:
        raise ConstraintError(f"status: {counted(bad.size, 'vertex', 'vertices', verb='have')} a status other "
                              f"than 0, 1, 2 (first: {first_indices(bad)})", parameter="status",
                              count=bad.size, first=bad[:3].tolist())
    handles = np.flatnonzero(status == HANDLE)
    if handles.size == 0:
        raise ConstraintError("the selection has no handle (status 2): nothing to move", parameter="status",
                              count=0)
    if not np.any(status == FIXED):
        raise ConstraintError("the selection has no fixed vertex (status 0)", parameter="status", count=0,
                              hint="fix part of the mesh so that the handle transform deforms rather than moves it")
    roi = np.flatnonzero(status != FIXED)
    T = _as_transform(T, ConstraintError)
    with np.errstate(over="ignore", invalid="ignore"):      # named below instead
        positions = apply_transform(T, V[handles])
    check_transformed_values(positions, "the handle transform T", "use a smaller transform")
    if method == "rotation":
        editor = RotationAwareEditor(V, F, handles, roi=roi, scaling=scaling, tol=tol,
                                     max_iterations=max_iterations, backend=backend)
        X = editor.solve(positions)
        return (X, editor) if return_editor else X
    dc = handles if handle_detail == "transform" else np.empty(0, dtype=np.int64)
    editor = CurvatureEditor(V, F, handles, dc, roi=roi, relations=relations or "one-ring", rcond=rcond,
                             backend=backend)
    with np.errstate(over="ignore", invalid="ignore"):
        details = editor.detail[handles] @ T[:3, :3].T if handle_detail == "transform" else None
    check_transformed_values(details, "the handle transform T", "use a smaller transform")
    X = editor.solve(positions=positions, details=details)
    return (X, editor) if return_editor else X
