"""Mesh file input/output through pymeshlab: every format MeshLab reads and writes.

Writes are atomic (a temporary file in the same folder, then a rename), so a failed or
interrupted write never leaves a half-written file, and an existing file is never replaced
unless ``overwrite=True``.
"""

import os

import numpy as np

from ._output import atomic_output, check_output_path
from .curvature._validate import as_faces, as_vertices
from .curvature.errors import MeshError


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
    MeshFileError       the format is unknown, the file is unreadable or holds no triangles, or
                        (OBJ, OFF, PLY) the loader dropped vertices: pymeshlab silently removes
                        vertices with NaN or infinite coordinates and the faces using them, so
                        the file's vertex order would no longer hold

    Examples
    --------
    >>> from curvdetail import read_mesh
    >>> from curvdetail.data import example_path
    >>> V, F = read_mesh(example_path())
    >>> V.shape[1], F.shape[1]
    (3, 3)
    """
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise FileNotFoundError(f"mesh file not found: {path}")
    ms = _meshset()
    try:
        ms.load_new_mesh(path)
    except Exception as exc:
        raise MeshFileError(f"could not read {path!r}: {exc}. Use a format MeshLab reads "
                            "(.obj, .off, .ply, .stl, ...).") from None
    mesh = ms.current_mesh()
    V = np.ascontiguousarray(mesh.vertex_matrix(), dtype=np.float64)
    F = np.ascontiguousarray(mesh.face_matrix(), dtype=np.int64)
    _check_vertex_count(path, V.shape[0])
    if F.shape[0] == 0:
        raise MeshFileError(f"{path!r} holds {V.shape[0]} vertices but no triangles; a surface mesh "
                            "is needed.")
    return V, F


_CHUNK = 1 << 20
_HEADER_LINES = 10_000


def _obj_vertex_count(path):
    """Number of ``v`` lines of an OBJ file, counted in 1 MiB chunks (never the whole file in
    memory). Like pymeshlab's loader, a vertex line starts at the beginning of a line with ``v``
    and a space or tab (``vt``, ``vn``, ``vp`` and indented lines are not vertices)."""
    count, tail = 0, b"\n"
    with open(path, "rb") as f:
        while True:
            chunk = f.read(_CHUNK)
            if not chunk:
                return count
            text = tail + chunk          # a match may straddle two chunks, never lie in tail alone
            count += text.count(b"\nv ") + text.count(b"\nv\t")
            tail = text[-2:]


def _off_vertex_count(path):
    """The vertex count in an ASCII OFF header (``[ST][C][N][4]OFF`` then ``nv nf ne``, on the
    same line or the next one, comments allowed), or None if the header is not of that form."""
    words = []
    with open(path, "rb") as f:
        for _ in range(_HEADER_LINES):
            line = f.readline()
            if not line:
                break
            words += line.split(b"#", 1)[0].decode("ascii", "replace").split()
            if len(words) >= 2:
                break
    if not words or not words[0].endswith("OFF") or "n" in words[0] or len(words) < 2:
        return None                      # not OFF, nOFF (dimension first) or too short
    try:
        return int(words[1])             # "OFF BINARY" is not an int: no check
    except ValueError:
        return None


def _ply_vertex_count(path):
    """``N`` of ``element vertex N`` in a PLY header (ASCII or binary; only the header is read),
    or None if there is no such header."""
    with open(path, "rb") as f:
        if f.readline().strip() != b"ply":
            return None
        for _ in range(_HEADER_LINES):
            words = f.readline().split()
            if not words or words[0] == b"end_header":
                return None
            if words[:2] == [b"element", b"vertex"] and len(words) == 3 and words[2].isdigit():
                return int(words[2])
    return None


_DECLARED_VERTEX_COUNT = {".obj": _obj_vertex_count, ".off": _off_vertex_count, ".ply": _ply_vertex_count}


def _check_vertex_count(path, loaded):
    """Raise MeshFileError if ``path`` (OBJ, OFF or PLY) declares another number of vertices than
    pymeshlab loaded. Its loader drops vertices with NaN or infinite coordinates (and the faces
    using them) without a word; ``V[i]`` would then no longer be vertex ``i`` of the file."""
    count = _DECLARED_VERTEX_COUNT.get(os.path.splitext(path)[1].lower())
    declared = count(path) if count is not None else None
    if declared is None or declared <= loaded:
        return                           # more than declared: a file our count misreads
    raise MeshFileError(
        f"{path!r} has {declared} vertices but pymeshlab loaded {loaded}: {declared - loaded} were "
        "dropped, most likely for non-finite (NaN or inf) coordinates, together with the faces "
        "using them, so the vertex order no longer matches the file. Fix or remove those vertices "
        "(and their faces) in the file and read it again.")


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
    MeshFileError     the format is unknown or the folder is not writable

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

    check_output_path(path, overwrite, error=MeshFileError)
    V = as_vertices(V)
    F = as_faces(F, V.shape[0])
    kwargs = {}
    if quality is not None:
        q = np.asarray(quality, dtype=np.float64).reshape(-1)
        if q.shape[0] != V.shape[0]:
            raise MeshError(f"quality has {q.shape[0]} values for {V.shape[0]} vertices; pass one per vertex.")
        kwargs["v_scalar_array"] = q
    mesh = pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32), **kwargs)
    save_mesh(path, mesh, overwrite=overwrite)


def save_mesh(path, mesh, *, overwrite=False, **save_options):
    """Atomically save a ``pymeshlab.Mesh`` (with its quality, colours and custom attributes where
    the format holds them). Used by :func:`write_mesh`, the filters and the CLI.

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
    MeshFileError     no extension, missing folder, or pymeshlab failed to write

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
    if os.path.splitext(os.fspath(path))[1].lower() == ".ply" and mesh.has_vertex_scalar():
        options.setdefault("save_vertex_quality", True)
    # the temporary file keeps path's extension: pymeshlab picks the format from it
    with atomic_output(path, overwrite=overwrite, error=MeshFileError) as tmp:
        ms = _meshset()
        ms.add_mesh(mesh)
        try:
            ms.save_current_mesh(tmp, **options)
        except Exception as exc:
            raise MeshFileError(f"could not write {os.fspath(path)!r}: {exc}") from None
