"""The standard linear-deformation benchmark format (Botsch & Sorkine, IEEE TVCG 2008).

A case is a mesh, a per-vertex selection file and a handle transform:

``NAME.sel``  comment lines starting with ``#``, then one integer status per vertex, in vertex
              order: ``0`` fixed, ``1`` free (the deformable region), ``2`` handle.
``NAME.def``  comment lines starting with ``#``, then a 4x4 matrix (4 rows of 4 numbers) applied
              to homogeneous handle positions: ``x' = T[:3, :3] x + T[:3, 3]``.

:func:`edit_with_selection` runs a :class:`~curvdetail.curvature.CurvatureEditor` on such a case:
the region of interest is every vertex with status 1 or 2, fixed vertices keep their
positions, handles are moved by the transform, and the handles' curvature details are either
transformed by its linear part (``handle_detail="transform"``) or solved like the free ones
(``"free"``).
"""

import os

import numpy as np

from .io.atomic import atomic_write, check_output_path
from .curvature._validate import (affine_transform_problem, as_vertices, check_bool, check_choice,
                                  check_transformed_values, real_word)
from .curvature.curvature_coefficients import DEFAULT_RCOND
from .curvature.curvature_editor import CurvatureEditor
from .curvature.errors import ConstraintError, counted, first_indices

FIXED, FREE, HANDLE = 0, 1, 2
HANDLE_DETAIL_MODES = ("transform", "free")


class DeformationFileError(ValueError):
    """A ``.sel`` or ``.def`` file is missing, malformed or does not fit the mesh."""


def _data_lines(path, what):
    path = os.fspath(path)
    if os.path.isdir(path):
        raise DeformationFileError(f"{path} is a folder; name a {what} file.")
    if not os.path.isfile(path):
        raise FileNotFoundError(f"{what} file not found: {path}")
    try:
        # utf-8-sig: a byte-order mark (Windows editors write one) is no part of the first line
        with open(path, encoding="utf-8-sig") as fh:
            lines = fh.read().splitlines()
    except UnicodeDecodeError as exc:
        raise DeformationFileError(f"{path}: byte {exc.start} is not UTF-8 text; a {what} file is plain "
                                   "text (save it as UTF-8 or ASCII).") from None
    return [(k + 1, line.strip()) for k, line in enumerate(lines)
            if line.strip() and not line.lstrip().startswith("#")]


def read_selection(path, n_vertices=None):
    """Read a ``.sel`` file: one status per vertex (0 fixed, 1 free, 2 handle).

    Parameters
    ----------
    path : str or os.PathLike
    n_vertices : int or None   if given, the number of statuses the file must hold

    Returns
    -------
    status : (n,) int8 array

    Raises
    ------
    FileNotFoundError      no such file
    DeformationFileError   a line that is not 0, 1 or 2 (names the first ones by line number),
                           no data, or a count that differs from ``n_vertices``

    Examples
    --------
    >>> import os, tempfile
    >>> p = os.path.join(tempfile.mkdtemp(), "a.sel")
    >>> write_selection(p, [0, 1, 1, 2])
    >>> read_selection(p, 4).tolist()
    [0, 1, 1, 2]
    """
    rows = _data_lines(path, "selection")
    bad = [(no, text) for no, text in rows if text not in ("0", "1", "2")]
    if bad:
        shown = ", ".join(f"line {no}: {text[:20]!r}" for no, text in bad[:3])
        raise DeformationFileError(
            f"{path}: {counted(len(bad), 'line', verb='are')} not a vertex status 0, 1 or 2 ({shown}); a .sel file "
            "holds one status per vertex (0 fixed, 1 free, 2 handle) after '#' comment lines.")
    if not rows:
        raise DeformationFileError(f"{path}: no vertex statuses found (only comments or blank lines).")
    status = np.array([int(text) for _, text in rows], dtype=np.int8)
    if n_vertices is not None and status.size != int(n_vertices):
        raise DeformationFileError(
            f"{path}: {status.size} vertex statuses for a mesh of {int(n_vertices)} vertices; the "
            ".sel file must list every vertex, in the mesh's vertex order.")
    return status


def read_transform(path):
    """Read a ``.def`` file: a 4x4 matrix acting on homogeneous positions.

    Returns
    -------
    T : (4, 4) float array   ``x' = T[:3, :3] @ x + T[:3, 3]``

    Raises
    ------
    FileNotFoundError      no such file
    DeformationFileError   not 4 rows of 4 finite numbers, or a last row other than (0, 0, 0, 1)
                           (a projective map is not a deformation)

    Examples
    --------
    >>> import os, tempfile
    >>> p = os.path.join(tempfile.mkdtemp(), "a.def")
    >>> write_transform(p, np.eye(4))
    >>> read_transform(p).tolist() == np.eye(4).tolist()
    True
    """
    rows = _data_lines(path, "transform")
    if len(rows) != 4:
        raise DeformationFileError(f"{path}: {len(rows)} matrix rows; a .def file holds a 4x4 matrix "
                                   "(4 rows of 4 numbers) after '#' comment lines.")
    T = np.empty((4, 4))
    for r, (no, text) in enumerate(rows):
        parts = text.replace(",", " ").split()
        try:
            values = [real_word(p) for p in parts]
        except ValueError:
            raise DeformationFileError(f"{path}: line {no} ({text[:40]!r}) is not 4 numbers.") from None
        if len(values) != 4 or not np.all(np.isfinite(values)):
            raise DeformationFileError(f"{path}: line {no} has {len(values)} values (or NaN/inf); each "
                                       "matrix row needs 4 finite numbers.")
        T[r] = values
    problem = affine_transform_problem(T)
    if problem:
        raise DeformationFileError(f"{path}: {problem}.")
    return T


def _write_text(path, text, overwrite):
    with atomic_write(path, overwrite=overwrite) as tmp:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)


def write_selection(path, status, *, overwrite=False):
    """Write a ``.sel`` file atomically (the survey's header comments, one status per line)."""
    status = np.asarray(status).reshape(-1)
    if status.size == 0 or not np.isin(status, (FIXED, FREE, HANDLE)).all():
        raise DeformationFileError("status must be a non-empty array of 0 (fixed), 1 (free), 2 (handle).")
    text = ("# per vertex status: 0=fixed, 1=deformable-region, 2=handle\n"
            f"# {status.size} vertices\n" + "\n".join(str(int(s)) for s in status) + "\n")
    _write_text(path, text, overwrite)


def write_transform(path, T, *, overwrite=False):
    """Write a ``.def`` file atomically (one comment line, 4 rows of 4 numbers, each written with
    the 17 significant digits that read back as the same double). A matrix that
    :func:`read_transform` would refuse (not affine, or a singular linear part) is not written."""
    T = _as_transform(T, DeformationFileError)
    text = "# 4x4 handle transformation matrix\n" + "\n".join(
        " ".join(f"{v:.17g}" for v in row) for row in T) + "\n"
    _write_text(path, text, overwrite)


def _as_transform(T, error):
    """``T`` as a (4, 4) float array that :func:`read_transform` would accept (finite, affine, a
    linear part that collapses no direction), else ``error`` naming what is wrong."""
    try:
        T = np.asarray(T, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise error(f"T could not be read as a 4x4 matrix of numbers ({exc}); a handle transform is a "
                    "finite 4x4 matrix.") from None
    if T.shape != (4, 4):
        raise error(f"T has shape {T.shape}; a handle transform is a finite 4x4 matrix.")
    if not np.all(np.isfinite(T)):
        raise error("T holds NaN or infinite entries; a handle transform is a finite 4x4 matrix.")
    problem = affine_transform_problem(T)
    if problem:
        raise error(f"the handle transform T: {problem}.")
    return T


def apply_transform(T, P):
    """``P @ T[:3, :3].T + T[:3, 3]`` for (k, 3) positions ``P``."""
    T = np.asarray(T, dtype=np.float64)
    return np.asarray(P, dtype=np.float64) @ T[:3, :3].T + T[:3, 3]


def edit_with_selection(V, F, status, T, *, handle_detail="transform", relations="one-ring",
                        rcond=DEFAULT_RCOND, backend="auto", return_editor=False):
    """Deform a mesh as a benchmark case prescribes, with curvature-detail editing.

    Parameters
    ----------
    V : (n, 3) float array    rest positions
    F : (m, 3) int array      triangles
    status : (n,) int array   0 fixed, 1 free, 2 handle (see :func:`read_selection`)
    T : (4, 4) float array    handle transform (see :func:`read_transform`)
    handle_detail : {"transform", "free"}
        ``"transform"``: the handles' details are constrained to ``T[:3, :3] @ D`` (exact for a
        similarity, whose linear part ``s R`` maps the detail ``D = L V`` as it maps lengths);
        ``"free"``: the handles' details are solved in the curvature stage like the free ones
    relations, rcond, backend see :class:`~curvdetail.curvature.CurvatureEditor`
                              (``relations="one+two-ring"`` keeps rotated handle details from
                              being amplified, see docs/editing.md)
    return_editor : bool      also return the factored editor (for re-solves)

    Returns
    -------
    X : (n, 3) float array    fixed vertices exactly at ``V``, handles exactly at ``T`` applied
                              to ``V``
    editor : CurvatureEditor  only with ``return_editor=True``

    Raises
    ------
    MeshError         ``V`` not an (n, 3) array of finite numbers, or a malformed mesh
    ConstraintError   ``status`` of the wrong length or with values other than 0, 1, 2; no handle;
                      no fixed vertex; a free region that touches neither; ``T`` not a finite 4x4
                      affine matrix with an invertible linear part (as :func:`read_transform` requires)
    ValueError        unknown ``handle_detail``, ``return_editor`` not a bool

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
    handle_detail = check_choice(handle_detail, "handle_detail", HANDLE_DETAIL_MODES, "; use 'transform' or 'free'.")
    return_editor = check_bool(return_editor, "return_editor")
    V = as_vertices(V)
    status = np.asarray(status).reshape(-1)
    if status.size != V.shape[0]:
        raise ConstraintError(f"status has {status.size} entries for {V.shape[0]} vertices; give one "
                              "status per vertex.")
    bad = np.flatnonzero(~np.isin(status, (FIXED, FREE, HANDLE)))
    if bad.size:
        raise ConstraintError(f"status: {counted(bad.size, 'vertex', 'vertices', verb='have')} a status other than 0, 1, 2 (first: "
                              f"{first_indices(bad)}).")
    handles = np.flatnonzero(status == HANDLE)
    if handles.size == 0:
        raise ConstraintError("the selection has no handle (status 2): nothing to move.")
    if not np.any(status == FIXED):
        raise ConstraintError("the selection has no fixed vertex (status 0); fix part of the mesh so "
                              "that the handle transform deforms rather than moves it.")
    roi = np.flatnonzero(status != FIXED)
    T = _as_transform(T, ConstraintError)
    dc = handles if handle_detail == "transform" else np.empty(0, dtype=np.int64)
    editor = CurvatureEditor(V, F, handles, dc, roi=roi, relations=relations, rcond=rcond,
                             backend=backend)
    with np.errstate(over="ignore", invalid="ignore"):      # named below instead
        details = editor.detail[handles] @ T[:3, :3].T if handle_detail == "transform" else None
        positions = apply_transform(T, editor.V[handles])
    for values in (positions, details):
        check_transformed_values(values, "the handle transform T", "use a smaller transform")
    X = editor.solve(positions=positions, details=details)
    return (X, editor) if return_editor else X


def _camera(elev, azim):
    """Rotation taking world coordinates (z up) to the camera's (x right, y up, z to the viewer)."""
    e, a = np.radians(elev), np.radians(azim)
    Rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    Rx = np.array([[1, 0, 0], [0, np.cos(e - np.pi / 2), -np.sin(e - np.pi / 2)],
                   [0, np.sin(e - np.pi / 2), np.cos(e - np.pi / 2)]])
    return Rx @ Rz.T


def view_direction(elev, azim):
    """Unit vector (world, z up) pointing from the scene towards the viewer of
    :func:`render_panels` with this camera: "towards the reader"."""
    return _camera(elev, azim)[2].copy()


def render_panels(path, panels, *, elev=20.0, azim=-60.0, title=None, overwrite=False,
                  panel_size=4.0):
    """Save side-by-side shaded renders of meshes as a PNG (matplotlib, Agg), atomically.

    Parameters
    ----------
    path : str            destination .png
    panels : list of (V, F, label) or (V, F, label, scalar)
        meshes drawn with one shared camera; ``scalar`` (n,) colours the surface (viridis),
        otherwise it is grey. Faces are depth-sorted and Lambert-shaded (painter's algorithm).
    elev, azim : float    camera elevation and azimuth in degrees
    title : str or None   figure title
    overwrite : bool      replace an existing file
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    path = check_output_path(path, overwrite)
    R = _camera(elev, azim)          # camera frame: x right, y up, z towards the viewer
    fig, axes = plt.subplots(1, len(panels), figsize=(panel_size * len(panels), panel_size),
                             squeeze=False)
    for ax, panel in zip(axes[0], panels):
        V, F, label = panel[0], np.asarray(panel[1]), panel[2]
        scalar = panel[3] if len(panel) > 3 else None
        P = np.asarray(V, dtype=np.float64) @ R.T
        tri = P[F]
        nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
        light = np.array([0.3, 0.5, 0.8]) / np.linalg.norm([0.3, 0.5, 0.8])
        shade = 0.25 + 0.75 * np.abs(nrm @ light)
        if scalar is not None:
            s = np.asarray(scalar, dtype=np.float64)[F].mean(axis=1)
            lo, hi = np.nanmin(s), np.nanmax(s)
            rgb = plt.get_cmap("viridis")((s - lo) / (hi - lo if hi > lo else 1.0))[:, :3]
        else:
            rgb = np.full((F.shape[0], 3), 0.8)
        colors = np.clip(rgb * shade[:, None], 0, 1)
        order = np.argsort(tri[:, :, 2].mean(axis=1))        # far faces first
        ax.add_collection(PolyCollection(tri[order][:, :, :2], facecolors=colors[order],
                                         edgecolors="none", antialiased=False))
        ax.set_xlim(P[:, 0].min(), P[:, 0].max())
        ax.set_ylim(P[:, 1].min(), P[:, 1].max())
        ax.set_aspect("equal")
        ax.set_axis_off()
        ax.set_title(label, fontsize=9)
    if title:
        fig.suptitle(title, fontsize=11)
    fig.tight_layout(pad=1.6)
    try:
        with atomic_write(path, overwrite=overwrite) as tmp:
            fig.savefig(tmp, dpi=100, format="png")
    finally:
        plt.close(fig)
