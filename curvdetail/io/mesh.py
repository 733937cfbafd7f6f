"""Mesh files as ``(V, F)`` arrays: `read_mesh`, `write_mesh`.

PLY goes through plyfile (`ply`, doubles kept), every other format is read by pymeshlab.
What a file yields then passes the checks any array input passes (finite coordinates, face
indices in range, no repeated corner), and the counts the file states must be those loaded:
PLY element counts (plyfile reads exactly those), the OFF header's, and an OBJ file's ``v`` and
``f`` lines. OBJ and OFF are written as exact decimals (``%.17g``); every write goes through
`atomic.atomic_write`.
"""

import contextlib
import errno
import os
import re
import shutil

import numpy as np

from ..curvature.checks import as_faces, as_vertices
from ..curvature.errors import MeshError, counted
from .atomic import atomic_write, check_output_path
from .ply import read_ply, triangles, write_ply


class MeshFileError(MeshError):
    """A mesh file cannot be read or written: ``e.parameter`` is ``"path"``, ``e.value`` the file.

    Where the loaded counts differ from the file's own, ``e.declared`` and ``e.loaded`` are the
    ``(vertices, faces)`` of each."""


def _error(path, problem, hint=None, **facts):
    return MeshFileError(problem, parameter="path", value=path, hint=hint, **facts)


#: The formats a mesh is written to: PLY, OBJ and OFF by our own writers, the others by
#: pymeshlab (which also writes .xyz / .e57, points only, so not offered here).
MESH_FORMATS = (".ply", ".obj", ".off", ".stl", ".wrl", ".dae", ".ctm", ".3ds", ".x3d")


def check_mesh_output(path, overwrite=False):
    """`atomic.check_output_path` for a mesh file, before any work: also refuses an
    extension not in `MESH_FORMATS`. Returns ``path`` as a str; raises MeshFileError
    (FileExistsError for an existing file without ``overwrite``)."""
    try:
        path = os.fsdecode(check_output_path(path, overwrite))
    except MeshError as exc:                    # a folder, a missing or read-only folder
        raise MeshFileError(exc.problem, parameter=exc.parameter, value=exc.value, hint=exc.hint) from None
    if _extension(path) not in MESH_FORMATS:
        raise _error(path, f"cannot write a mesh to {path!r}: {_extension(path) or 'no extension'} is not a "
                     "mesh format written here", "use one of " + ", ".join(MESH_FORMATS))
    return path


def read_mesh(path, *, fields=False):
    """Read a triangle mesh file: PLY with plyfile, any other format pymeshlab reads.

    Parameters
    ----------
    path : str or os.PathLike
        The file; its extension picks the reader.
    fields : bool, optional
        Also return the file's other per-vertex properties: every one of a PLY file; of other
        formats the vertex colours (``red``, ``green``, ``blue``, ``alpha``, uint8) where the
        file holds them and an OFF file's normals (``nx``, ``ny``, ``nz``; an OBJ file's
        ``vn`` belong to face corners and are not read).

    Returns
    -------
    V : (n, 3) float64 array
        Vertex positions, in file order (a PLY file's doubles exactly).
    F : (m, 3) int64 array
        Triangles; polygons are fanned from their first corner (a polygon of corners
        a, b, c, d gives (a, b, c), (a, c, d)), whatever the format.
    fields : dict of str to array
        With ``fields=True``: (n,) arrays, and (n, 3) for points (see `curvdetail.io.ply`).

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    MeshFileError
        The file cannot be read (which file and why); a file named .obj is not a text OBJ
        file; fewer or more vertices or faces were
        loaded than the file states (``e.declared``, ``e.loaded``); or the arrays fail the
        checks of array input (non-finite coordinates, face indices out of range or
        repeated).

    Examples
    --------
    >>> from curvdetail.data import example_path
    >>> V, F = read_mesh(example_path())
    >>> V.dtype, F.dtype, V.shape[1], F.shape[1]
    (dtype('float64'), dtype('int64'), 3, 3)
    """
    path = _input_path(path)
    if _extension(path) != ".ply":
        import pymeshlab

        ms = pymeshlab.MeshSet()
        V, F = load_new_mesh(ms, path)
        return (V, F, _loaded_fields(ms.current_mesh(), path)) if fields else (V, F)
    try:
        V, F, extra = read_ply(path)
    except (ValueError, OSError) as exc:
        raise _error(path, f"could not read {path!r} as PLY: {_why(exc)}") from None
    V, F = _checked(path, V, F)
    return (V, F, extra) if fields else (V, F)


def load_new_mesh(ms, path):
    """Load a mesh file into the ``pymeshlab.MeshSet`` ``ms`` as its new current layer, checked
    as `read_mesh` checks it; return the layer's ``(V, F)``.

    pymeshlab's loader reads the file (PLY too: read those with `read_mesh` to keep their
    doubles and custom properties). An OFF file's polygons are fanned from their first corner
    here, as pymeshlab fans an OBJ file's and `read_mesh` a PLY file's (its OFF loader
    cuts a quad along the other diagonal, a larger polygon into triangles of the wrong
    vertices); such a layer is built from the arrays (its normals recomputed). Raises as
    `read_mesh`.
    """
    import pymeshlab

    path = _input_path(path)
    declared = _declared_counts(path)
    fanned, polygons = _off_polygons(path, declared[1]) if declared is not None and _extension(path) == ".off" \
        else (None, None)
    into = ms if fanned is None else pymeshlab.MeshSet()
    cwd = os.getcwd()
    try:
        into.load_new_mesh(path)
    except Exception as exc:                    # pymeshlab.PyMeshLabException, or a path it refuses
        raise _error(path, f"could not read {path!r}: {_why(exc)}",
                     "check the file, or export it again, e.g. as PLY") from None
    finally:
        os.chdir(cwd)                           # a failed load left the process in the file's folder
    mesh = into.current_mesh()
    V, F = mesh.vertex_matrix(), mesh.face_matrix() if fanned is None else fanned
    if declared is not None:
        faces = polygons if fanned is not None else F.shape[0] if F.shape[0] == declared[1] else \
            len(mesh.polygonal_face_list())
        if (V.shape[0], faces) != declared:
            nv, nf = declared
            what = f"has {counted(nv, 'v line')} and {counted(nf, 'f line')}" if _extension(path) == ".obj" else \
                f"declares {counted(nv, 'vertex', 'vertices')} and {counted(nf, 'face')}"
            err = _error(path, f"{path!r} {what}, but pymeshlab loaded {counted(V.shape[0], 'vertex', 'vertices')} "
                               f"and {counted(faces, 'face')}",
                         "its loader drops rows it cannot use (a NaN coordinate, an index out of range, a "
                         "malformed line); fix those rows or export the file again, e.g. as PLY")
            err.declared, err.loaded = declared, (V.shape[0], faces)
            raise err
    V, F = _checked(path, V, F)
    if fanned is not None:
        colours = {"v_color_matrix": mesh.vertex_color_matrix()} if mesh.has_vertex_color() else {}
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32), **colours), mesh.label())
    return V, F


#: A line that may be an OFF face row of more than three corners (a vertex row of whole numbers
#: may match too: the rows are then read).
_POLYGON_ROW = re.compile(rb"(?m)^[ \t]*0*([4-9]|[1-9][0-9]+)[ \t]+[0-9]+[ \t]+[0-9]+[ \t]+[0-9]+[ \t]+[0-9]+")


def _off_polygons(path, count):
    """``(F, k)``: the last ``count`` face rows of the OFF file ``path`` (k of them) fanned from
    their first corner where one is a polygon (more than three corners), else ``(None, None)``
    (pymeshlab's triangles are the file's)."""
    with open(path, "rb") as f:
        data = f.read()
    if not _POLYGON_ROW.search(data):               # fast: no row starts as a polygon's would
        return None, None
    comments = b"#" in data
    rows = []                                       # the face rows end the file: (corners, rest)
    for line in reversed(data.splitlines()):
        if len(rows) == count:
            break
        row = (line.split(b"#", 1)[0] if comments else line).split(None, 1)
        if row:
            rows.append(row)
    rows.reverse()
    try:
        sizes = np.array([int(row[0]) for row in rows], dtype=np.int64)
        if not (sizes > 3).any():
            return None, None
        faces = np.empty(len(rows), dtype=object)
        faces[:] = [np.array(row[1].split()[:k] if len(row) > 1 else [], dtype=np.int64)
                    for row, k in zip(rows, sizes)]
        if any(len(face) != k for face, k in zip(faces, sizes)):
            raise ValueError("a face row holds fewer indices than it states")
        return triangles(faces), len(rows)
    except ValueError as exc:
        raise _error(path, f"could not read the faces of {path!r}: {_why(exc)}",
                     "check the file, or export it again, e.g. as PLY") from None


def _loaded_fields(mesh, path):
    """The vertex colours (other than the opaque white of a layer built from arrays) and (OFF)
    normals pymeshlab loaded from ``path``, named as in PLY."""
    fields = {}
    if mesh.has_vertex_color() and not np.all(mesh.vertex_color_matrix() == 1.0):
        rgba = np.rint(mesh.vertex_color_matrix() * 255.0).astype(np.uint8)
        fields.update(zip(("red", "green", "blue", "alpha"), rgba.T))
    if _extension(path) == ".off":
        with open(path, "rb") as f:
            keyword = f.read(16).split()[:1]
        if keyword and b"N" in keyword[0].removesuffix(b"OFF"):           # NOFF, CNOFF, STNOFF
            fields.update(zip(("nx", "ny", "nz"), np.array(mesh.vertex_normal_matrix(), dtype=np.float64).T))
    return fields


def _input_path(path):
    """``path`` as a str naming an existing file, or raise."""
    try:
        path = os.fsdecode(path)
    except TypeError:
        raise MeshFileError(f"a mesh path must be a str or os.PathLike, not {type(path).__name__}",
                            parameter="path", value=path) from None
    if os.path.isdir(path):
        raise _error(path, f"{path!r} is a folder", "name a mesh file in it")
    if not os.path.exists(path):
        err = FileNotFoundError(errno.ENOENT, "mesh file not found", path)
        err.parameter, err.value = "path", path
        raise err
    return path


def _extension(path):
    return os.path.splitext(os.fsdecode(path))[1].lower()


def _why(exc):
    """An exception's reason on one line."""
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    return " ".join(str(exc).split()) or type(exc).__name__


def _declared_counts(path):
    """``(vertices, faces)`` as an OBJ (its v and f lines) or OFF file (its header) states them,
    or None for other formats and OFF headers not read here; MeshFileError for an .obj file
    that is not text."""
    extension = _extension(path)
    if extension not in (".obj", ".off"):
        return None
    try:
        with open(path, "rb") as f:
            data = f.read() if extension == ".obj" else f.read(4096)
    except OSError as exc:
        raise _error(path, f"could not read {path!r}: {_why(exc)}") from None
    if extension == ".obj":
        if b"\0" in data:           # UTF-16, a binary file, random bytes: none is an OBJ file
            raise _error(path, f"{path!r} is not a text OBJ file (it holds NUL bytes: binary data, or text "
                               "in UTF-16)", "give an OBJ file in ASCII or UTF-8, or the right extension")
        return _lines(data, b"v"), _lines(data, b"f")
    words = b" ".join(line.split(b"#")[0] for line in data.splitlines()).split()
    try:
        if words[0].endswith(b"OFF") and words[1] != b"BINARY":
            return int(words[1]), int(words[2])
    except (IndexError, ValueError):
        pass
    return None


def _lines(data, keyword):
    """How many lines of ``data`` start with ``keyword`` and a blank."""
    return sum(data.count(b"\n" + keyword + blank) + data.startswith(keyword + blank) for blank in (b" ", b"\t"))


def _checked(path, V, F):
    """``as_vertices(V)``, ``as_faces(F)``, their MeshError raised as the file's MeshFileError."""
    if len(V) == 0 or len(F) == 0:
        raise _error(path, f"{path!r} holds {len(V)} vertices and {len(F)} triangles",
                     "read a triangle mesh file")
    try:
        V = as_vertices(V)
        return V, as_faces(F, V.shape[0])
    except MeshError as exc:
        raise _error(path, f"{path!r}: {exc.problem}", exc.hint, count=exc.count, first=exc.first) from None


def write_mesh(path, V, F, *, quality=None, overwrite=False):
    """Write a triangle mesh in the format of the file's extension, atomically.

    PLY is binary with double coordinates and the quality as the vertex property ``quality``
    (MeshLab colours by it); OBJ and OFF hold the coordinates as exact decimals (``%.17g``);
    other formats are written by pymeshlab, which keeps what the format holds: STL and most
    others single-precision coordinates, point formats (.xyz) no triangles, none but PLY the
    quality.

    Parameters
    ----------
    path : str or os.PathLike
        The file; its extension picks the format.
    V : (n, 3) float array
        Vertex positions.
    F : (m, 3) int array
        Triangles.
    quality : (n,) float array, optional
        Per-vertex quality.
    overwrite : bool, optional
        Replace an existing file (refused by default).

    Raises
    ------
    FileExistsError
        ``path`` exists and ``overwrite`` is False.
    MeshError
        ``V``, ``F`` or ``quality`` is malformed, or ``path``'s folder cannot be written.
    MeshFileError
        The write failed (a full disk, a format pymeshlab does not write): names the file;
        nothing is left behind.

    Examples
    --------
    >>> import os, tempfile
    >>> from curvdetail.curvature.testing import icosphere
    >>> V, F = icosphere(subdivisions=1)
    >>> path = os.path.join(tempfile.mkdtemp(), "sphere.ply")
    >>> write_mesh(path, V, F, quality=V[:, 2])
    >>> W, G = read_mesh(path)
    >>> bool((W == V).all() and (G == F).all())
    True
    """
    check_mesh_output(path, overwrite)
    V = as_vertices(V)
    F = as_faces(F, V.shape[0])
    if quality is not None:
        quality = np.asarray(quality)
        if quality.dtype.kind not in "fiu" or quality.shape != (V.shape[0],) or not np.isfinite(quality).all():
            raise MeshError(f"quality must be {V.shape[0]} finite numbers, one per vertex; got {quality.dtype} "
                            f"of shape {quality.shape}", parameter="quality", value=quality)
        quality = quality.astype(np.float64)
    write_mesh_fields(path, V, F, None if quality is None else {"quality": quality}, overwrite=overwrite)


def write_mesh_fields(path, V, F, fields=None, *, overwrite=False):
    """Write ``V``, ``F`` and per-vertex ``fields`` as they are (no checks), atomically.

    PLY keeps every field (`curvdetail.io.ply.write_ply`); other formats as
    `write_mesh` writes them, with the field ``quality`` alone. For callers whose arrays
    come from a mesh already held (a MeshSet layer). Raises as `write_mesh`.
    """
    extension = _extension(path)
    fields = fields or {}
    with _writing(path, overwrite) as tmp:
        if extension == ".ply":
            write_ply(tmp, V, F, fields)
        elif extension in (".obj", ".off"):
            _write_text(tmp, V, F)
        else:
            _write_with_pymeshlab(tmp, V, F, fields.get("quality"))


@contextlib.contextmanager
def _writing(path, overwrite):
    """`atomic.atomic_write`, a failure of the writer raised as MeshFileError naming ``path``."""
    with atomic_write(path, overwrite=overwrite) as tmp:
        try:
            yield tmp
        except Exception as exc:                # OSError (a full disk), pymeshlab's exceptions
            shown = os.fsdecode(path)
            why = _why(exc).replace(tmp, shown)
            if not isinstance(exc, OSError) and shutil.disk_usage(os.path.dirname(tmp)).free == 0:
                # pymeshlab's words for a full disk: "Error encountered while exportering ... Output Stream error"
                why = f"{os.strerror(errno.ENOSPC)} (pymeshlab: {why})"
            raise _error(shown, f"could not write {shown!r}: {why}") from exc


def _write_text(path, V, F):
    """Write an OBJ or OFF file (by ``path``'s extension) with ``%.17g`` coordinates, which read
    back as the same doubles. Writes ``path`` as it is (callers go through ``atomic_write``)."""
    with open(path, "w", encoding="ascii", newline="\n") as f:
        if _extension(path) == ".off":
            f.write(f"OFF\n{len(V)} {len(F)} 0\n")
            np.savetxt(f, V, fmt="%.17g")
            np.savetxt(f, F, fmt="3 %d %d %d")
        else:
            np.savetxt(f, V, fmt="v %.17g %.17g %.17g")
            np.savetxt(f, F + 1, fmt="f %d %d %d")


def _write_with_pymeshlab(path, V, F, quality):
    import pymeshlab

    ms = pymeshlab.MeshSet()
    extra = {} if quality is None else {"v_scalar_array": quality}
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.asarray(V, dtype=np.float64),
                               face_matrix=np.asarray(F, dtype=np.int32), **extra))
    ms.save_current_mesh(path)
