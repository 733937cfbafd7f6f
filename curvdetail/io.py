"""Mesh file input/output through pymeshlab: every format MeshLab reads and writes.

Writes are atomic (a temporary file in the same folder, then a rename), so a failed or
interrupted write never leaves a half-written file, and an existing file is never replaced
unless ``overwrite=True``.
"""

import os
import re

import numpy as np

from ._file_counts import check_loaded
from ._file_scan import check_before_loading
from ._output import atomic_output, check_output_path
from .curvature._validate import as_faces, as_vertices
from .curvature.errors import MeshError, first_indices


class MeshFileError(MeshError):
    """A mesh file cannot be read or written (unknown format, unreadable, no triangles)."""


def _meshset():
    import pymeshlab

    return pymeshlab.MeshSet()


def read_mesh(path):
    """Read a triangle mesh from any format pymeshlab reads (OBJ, OFF, PLY, STL, ...).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    V : (n, 3) float64 array   vertex positions, in file order
    F : (m, 3) int64 array     triangles (polygons are triangulated by the loader)

    Raises
    ------
    FileNotFoundError   the file does not exist
    MeshFileError       ``path`` is not a path or names a folder, the format is unknown (binary
                        OFF included), the file is unreadable or holds no triangles, a
                        face index is out of range, or (OBJ, OFF, PLY, STL) the loader dropped
                        vertices or faces: pymeshlab silently removes vertices with NaN or
                        infinite coordinates (and renumbers the rest), OBJ faces with
                        out-of-range or repeated indices, and STL triangles with a non-finite
                        or repeated corner. Checked before pymeshlab reads the file, because
                        its loader would corrupt memory or misread it without a word:
                        out-of-range face indices, fewer rows than the header declares,
                        vertex rows it would read shifted (a value too many or too few, a
                        comment among the values; a vertex split over lines that hold exactly
                        its values passes), lines of blanks, counts or indices that are not
                        whole numbers (ASCII OFF); indented vertex lines, fractional face
                        indices and comments after a face (OBJ; ``f 1 2 3#note`` passes)

    Examples
    --------
    >>> from curvdetail import read_mesh
    >>> from curvdetail.data import example_path
    >>> V, F = read_mesh(example_path())
    >>> V.shape[1], F.shape[1]
    (3, 3)
    """
    path = input_path(path)
    try:
        check_before_loading(path, error=MeshFileError)
    except OSError as exc:          # unreadable: named as the file's problem, as pymeshlab's are
        raise MeshFileError(f"could not read {path!r}: {exc.strerror or exc}.") from None
    ms = _meshset()
    try:
        ms.load_new_mesh(path)
    except Exception as exc:
        raise MeshFileError(load_failure(path, exc)) from None
    mesh = ms.current_mesh()
    V = np.ascontiguousarray(mesh.vertex_matrix(), dtype=np.float64)
    F = np.ascontiguousarray(mesh.face_matrix(), dtype=np.int64)
    check_loaded(path, V.shape[0], F, error=MeshFileError)
    if F.shape[0] == 0 and V.shape[0] == 0:       # pymeshlab "reads" some other files as nothing
        raise MeshFileError(f"pymeshlab read nothing from {path!r} (no vertices, no triangles); is it a "
                            "mesh file? Use a format MeshLab reads (.obj, .off, .ply, .stl, ...).")
    if F.shape[0] == 0:
        raise MeshFileError(f"{path!r} holds {V.shape[0]} vertices but no triangles; a surface mesh "
                            "is needed.")
    return V, F


#: Extensions whose files pymeshlab reads (and that most meshes come in): a failed read of one
#: of these means a damaged file, not the wrong format.
COMMON_FORMATS = (".ply", ".obj", ".off", ".stl")


def load_failure(path, exc):
    """The message for pymeshlab's failure to load ``path``: its whole text on one line (its
    first line alone says "Unable to open file", which reads like a missing file), and the fix
    that fits: a damaged file for the common formats, another format otherwise."""
    reason = " ".join(str(exc).split()) or type(exc).__name__
    if os.path.splitext(path)[1].lower() in COMMON_FORMATS:
        return (f"could not read {path!r}: {reason}. The file is damaged or incomplete, or a variant "
                "pymeshlab does not read (4OFF, CR-only line ends, ...); export it again, e.g. as PLY.")
    return f"could not read {path!r}: {reason}. Use a format MeshLab reads (.obj, .off, .ply, .stl, ...)."


def input_path(path):
    """``path`` as a str naming an existing file, or raise: MeshFileError for what is not a path
    or is a folder, FileNotFoundError for a missing file."""
    if not isinstance(path, (str, bytes, os.PathLike)):
        raise MeshFileError(f"a mesh path must be a str or os.PathLike; got {type(path).__name__}.")
    path = os.fsdecode(path)
    if os.path.isdir(path):
        raise MeshFileError(f"{path!r} is a folder; name a mesh file in it.")
    if not os.path.isfile(path):
        raise FileNotFoundError(f"mesh file not found: {path}")
    return path


#: Formats pymeshlab writes as points only: a mesh saved there loses its triangles.
POINT_FORMATS = (".xyz", ".e57", ".pts", ".ptx", ".apts", ".asc")

_MESH_HINT = "use .ply, .obj, .off, .stl, ..."
_WRITES = {}            # extension -> None (pymeshlab writes it) or why it does not


def check_mesh_output(path, overwrite=False, *, hint=_MESH_HINT):
    """Return ``path`` as a str, or raise before any work if a mesh cannot be written there:
    :func:`curvdetail._output.check_output_path` (existing file, folder, no extension), a format
    that keeps the points only (:data:`POINT_FORMATS`), or one pymeshlab does not write (found by
    writing one triangle to a temporary file, once per extension and process).

    Raises
    ------
    FileExistsError   ``path`` exists and ``overwrite`` is False
    MeshFileError     ``path`` is a folder, its folder is missing, or the format is not a mesh
                      format pymeshlab writes
    """
    path = check_output_path(path, overwrite, hint=hint, error=MeshFileError)
    extension = os.path.splitext(path)[1].lower()
    if extension in POINT_FORMATS:
        raise MeshFileError(f"cannot write {path!r}: {extension} files hold points only, so the "
                            f"triangles would be lost; {hint}")
    if extension not in _WRITES:
        _WRITES[extension] = _why_not_written(extension)
    if _WRITES[extension] is not None:
        raise MeshFileError(f"cannot write {path!r}: pymeshlab does not write {extension} meshes "
                            f"({_WRITES[extension]}); {hint}")
    return path


def _why_not_written(extension):
    """None if pymeshlab writes a triangle to a ``extension`` file, else its message."""
    import tempfile

    import pymeshlab

    with tempfile.TemporaryDirectory(prefix="curvdetail-format-") as folder:
        ms = _meshset()
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.eye(3), face_matrix=np.array([[0, 1, 2]], dtype=np.int32)))
        try:
            ms.save_current_mesh(os.path.join(folder, "probe" + extension))
        except Exception as exc:
            return " ".join(str(exc).replace(folder + os.sep, "").split()) or type(exc).__name__
    return None


def write_mesh(path, V, F, *, quality=None, overwrite=False):
    """Write a triangle mesh atomically in the format given by the file extension.

    Parameters
    ----------
    path : str or os.PathLike   destination; its extension picks the format (.ply, .obj, .off, .stl, ...)
    V : (n, 3) float array      vertex positions
    F : (m, 3) int array        triangles
    quality : (n,) float array or None   per-vertex quality (saved where the format holds it,
                                          e.g. PLY; MeshLab colours meshes by it)
    overwrite : bool            replace an existing file; by default an existing file is refused

    Raises
    ------
    FileExistsError   ``path`` exists and ``overwrite`` is False
    MeshError         malformed ``V``, ``F`` or ``quality``
    MeshFileError     ``path`` is a folder, its folder is missing or not writable, or the format
                      is unknown or keeps points only (.xyz, ...; see :func:`check_mesh_output`)

    Examples
    --------
    >>> import os, tempfile
    >>> from curvdetail import read_mesh, write_mesh
    >>> from curvdetail.curvature.testing import icosphere
    >>> V, F = icosphere(subdivisions=1)
    >>> path = os.path.join(tempfile.mkdtemp(), "sphere.ply")
    >>> write_mesh(path, V, F, quality=V[:, 2])
    >>> W, G = read_mesh(path)
    >>> bool((W == V).all() and (G == F).all())
    True
    >>> write_mesh(path, V, F)
    Traceback (most recent call last):
    ...
    FileExistsError: ... exists; pass --overwrite (overwrite=True) to replace it.
    """
    import pymeshlab

    check_mesh_output(path, overwrite)
    V = as_vertices(V)
    F = as_faces(F, V.shape[0])
    kwargs = {}
    if quality is not None:
        q = np.asarray(quality)
        if q.dtype.kind not in "fiu":
            raise MeshError(f"quality has dtype {q.dtype}; pass one real number per vertex.")
        q = q.astype(np.float64).reshape(-1)
        if q.shape[0] != V.shape[0]:
            raise MeshError(f"quality has {q.shape[0]} values for {V.shape[0]} vertices; pass one per vertex.")
        if not np.isfinite(q).all():
            bad = np.flatnonzero(~np.isfinite(q))
            raise MeshError(f"quality: {bad.size} values are NaN or infinite (first: {first_indices(bad)}); "
                            "pass finite values.")
        kwargs["v_scalar_array"] = q
    mesh = pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32), **kwargs)
    # geometry (and quality) only: pymeshlab would add its default white colours and computed
    # normals, and its OFF writer then says NCOFF, a header libigl's readOFF refuses; and its
    # meshes always carry a quality, which without ours would be written as zeros (in MeshLab:
    # zero error everywhere)
    no_quality = quality is None and os.path.splitext(os.fspath(path))[1].lower() == ".ply"
    plain = dict(_PLAIN_OPTIONS, **({"save_vertex_quality": False} if no_quality else {}))
    save_mesh(path, mesh, overwrite=overwrite, _plain=plain)


#: What :func:`write_mesh` turns off where the format has the option (pymeshlab refuses an
#: option the format lacks, e.g. ``save_vertex_normal`` for VRML).
_PLAIN_OPTIONS = {"save_vertex_color": False, "save_vertex_normal": False, "save_face_color": False}


def save_mesh(path, mesh, *, overwrite=False, _plain=None, **save_options):
    """Atomically save a ``pymeshlab.Mesh`` (with its quality and colours where the format holds
    them). Used by :func:`write_mesh`.

    Custom attributes are not saved: the mesh is copied into a fresh MeshSet, and pymeshlab
    crashes (segmentation fault) exporting the attributes of such a copy. A MeshSet layer with
    custom attributes is saved by :func:`curvdetail.filters.files.save_current_mesh` (what the
    filters and the CLI use), which keeps them in PLY.

    The mesh is written to a temporary file in the destination folder (with ``path``'s
    extension) and renamed over ``path`` only when the write succeeded, with the permissions the
    umask gives a new file; a failed write removes the temporary file.

    Parameters
    ----------
    path : str or os.PathLike   destination; the extension picks the format
    mesh : pymeshlab.Mesh
    overwrite : bool            replace an existing file (refused by default)
    **save_options              passed to ``MeshSet.save_current_mesh`` (e.g. ``binary=False``);
                                for PLY, ``save_vertex_quality`` defaults to True when the mesh
                                has vertex quality

    Raises
    ------
    FileExistsError   ``path`` exists and ``overwrite`` is False
    MeshFileError     no extension, a folder, missing folder, a format pymeshlab does not write
                      as a mesh, pymeshlab failed to write, or a save option that asks for a
                      custom attribute (``__ca_...``)

    Examples
    --------
    >>> import os, tempfile, numpy as np, pymeshlab
    >>> mesh = pymeshlab.Mesh(vertex_matrix=np.eye(3), face_matrix=np.array([[0, 1, 2]], dtype=np.int32))
    >>> path = os.path.join(tempfile.mkdtemp(), "triangle.off")
    >>> save_mesh(path, mesh)
    >>> os.path.exists(path)
    True
    """
    options = dict(save_options)
    custom = sorted(k for k in options if k.startswith("__ca_"))
    if custom:
        raise MeshFileError(f"save_mesh cannot save custom attributes ({', '.join(custom)}): pymeshlab "
                            "crashes exporting them from a copied mesh. Add the mesh to a MeshSet and "
                            "save it with curvdetail.filters.files.save_current_mesh.")
    check_mesh_output(path, overwrite)
    plain = _plain or {}         # options to set where the format has them (write_mesh's)
    if os.path.splitext(os.fspath(path))[1].lower() == ".ply" and mesh.has_vertex_scalar() and \
            "save_vertex_quality" not in plain:
        options.setdefault("save_vertex_quality", True)
    # the temporary file keeps path's extension: pymeshlab picks the format from it
    with atomic_output(path, overwrite=overwrite, error=MeshFileError) as tmp:
        ms = _meshset()
        ms.add_mesh(mesh)
        try:
            _save(ms, tmp, options, plain)
        except Exception as exc:
            raise MeshFileError(f"could not write {os.fspath(path)!r}: "
                                f"{str(exc).replace(tmp, os.fspath(path))}") from None


def _save(ms, path, options, optional):
    """``ms.save_current_mesh(path, **options, **optional)``, leaving out each ``optional``
    option the format does not have."""
    optional = {k: v for k, v in optional.items() if k not in options}
    while True:
        try:
            return ms.save_current_mesh(path, **options, **optional)
        except Exception as exc:
            missing = re.search(r"Parameter (\w+) not found", str(exc))
            if missing is None or missing.group(1) not in optional:
                raise
            del optional[missing.group(1)]
