"""Mesh file input/output through pymeshlab: every format MeshLab reads and writes.

Writes are atomic (a temporary file in the same folder, then a rename), so a failed or
interrupted write never leaves a half-written file, and an existing file is never replaced
unless ``overwrite=True``.
"""

import os
import re

import numpy as np

from .._ctm_scan import ctm_layout, ctm_problem, ctm_vertex_map
from .._file_counts import check_loaded, check_polygons, declared_counts
from .._file_scan import check_before_loading, small_pages
from .atomic import atomic_write, check_output_path
from ..curvature._validate import as_faces, as_vertices
from ..curvature.errors import MeshError, counted, first_indices


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
                        out-of-range or repeated indices, STL triangles with a non-finite
                        or repeated corner, and ASCII PLY faces with a repeated index or the
                        'deleted' flag bit (found by the triangles the file's faces make).
                        Checked before pymeshlab reads the file, because its loader would
                        corrupt memory or misread it without a word:
                        out-of-range face indices, fewer or more rows than the header
                        declares, vertex rows it would read shifted (a value too many or too
                        few, a comment among the values; a vertex split over lines that hold
                        exactly its values passes), lines of blanks, counts or indices that
                        are not whole numbers (ASCII OFF); indented vertex lines, fractional
                        face indices and comments after a face (OBJ; ``f 1 2 3#note``
                        passes); decimal commas (OFF, OBJ, ASCII PLY); vertex coordinates
                        that are not decimal numbers, which it reads as 0 or as their first
                        digits (OFF, OBJ: ``abc``, ``0.3abc``, ``0x1p3``, ``1d3``, a comment
                        among the coordinates); OBJ lines ending in a backslash, which it
                        joins with the next, where it misreads them: other than faces and
                        vertices (the next line's vertex is lost), a vertex joined with a line
                        it counts apart (a v, vt or f line) or into x, y, z that are not
                        decimal numbers, a continued line ending in CR LF, a backslash glued
                        to both lines' words (a face or vertex continued over lines ending in
                        LF, the first in CR LF too, passes); a PLY header pymeshlab
                        misparses or crashes on, or face lists of types it does not read;
                        ASCII PLY values it would not read whole as their type, faces of
                        fewer than 3 or more than 255 vertices, a face row not on a line of
                        its own, rows with values missing or extra; CTM files with a
                        "Quality" map but no "Color" map or a map without a name (its CTM
                        reader crashed the process on each), or shorter than their sections;
                        OBJ face indices outside the file, faces of fewer than 3 corners, a
                        UTF-8 byte order mark (OBJ, PLY) or a lone carriage return (OBJ);
                        ASCII STL facets of other than 3 vertices; binary PLY files with
                        big-endian double vertices, a body shorter than the header declares,
                        or lists the reader cannot skip. After loading, the triangles of an
                        OBJ, OFF or ASCII PLY file must be as many as its faces make, and
                        none of a polygon's (OBJ, OFF, PLY) may face against it (a concave
                        polygon cut along a diagonal outside it: triangulate such polygons
                        first; :func:`curvdetail._file_counts.check_polygons`)
                        (see :func:`curvdetail._file_scan.check_before_loading`)

    Examples
    --------
    >>> from curvdetail import read_mesh
    >>> from curvdetail.data import example_path
    >>> V, F = read_mesh(example_path())
    >>> V.shape[1], F.shape[1]
    (3, 3)
    """
    path = input_path(path)
    ms = _meshset()                 # kept referenced: the mesh is a view into it
    with small_pages():             # a fresh process first touched huge pages slowly
        mesh = load_checked(ms, path, vertex_maps=False)      # V and F only: a CTM's maps are not needed
        V = np.ascontiguousarray(mesh.vertex_matrix(), dtype=np.float64)
        F = np.ascontiguousarray(mesh.face_matrix(), dtype=np.int64)
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


def load_checked(ms, path, *, vertex_maps=True):
    """Load the mesh file ``path`` into the MeshSet ``ms`` as its new current layer and return
    that ``pymeshlab.Mesh``, with the checks pymeshlab's loader lacks: before it reads the file
    (:func:`curvdetail._file_scan.check_before_loading`) and after (what it dropped:
    :func:`curvdetail._file_counts.check_loaded`, and the triangles an ASCII PLY's faces make;
    what it cut wrong: :func:`curvdetail._file_counts.check_polygons`).
    MeshFileError for each; ``path`` is expected to exist (see :func:`input_path`).

    With ``vertex_maps``, a CTM file's vertex colours and quality are set on the layer as the
    file holds them (:func:`_set_ctm_vertex_maps`: pymeshlab reads the quality from the colour
    map, and marks the layer as holding neither); without, they are left as pymeshlab read
    them (for callers that take the vertices and triangles only)."""
    _check_utf8(path, "read")
    try:
        sizes = []                  # the vertex counts of the file's faces, where known
        counts = []                 # the file's (vertices, faces), where the scan counted them
        triangles = check_before_loading(path, error=MeshFileError, sizes=sizes, counts=counts)
    except OSError as exc:          # unreadable: named as the file's problem, as pymeshlab's are
        raise MeshFileError(f"could not read {path!r}: {exc.strerror or exc}.") from None
    cwd = os.getcwd()
    try:
        ms.load_new_mesh(path)
    except Exception as exc:
        os.chdir(cwd)               # a failed load leaves the process in the file's folder
        raise MeshFileError(load_failure(path, exc)) from None
    mesh = ms.current_mesh()
    F = mesh.face_matrix()
    check_loaded(path, mesh.vertex_number(), F, error=MeshFileError, counts=counts[0] if counts else None)
    if triangles is not None and F.shape[0] and F.shape[0] != triangles:
        # polygons are triangulated, so a header's face count cannot tell a dropped face
        raise MeshFileError(
            f"{path!r}: its faces make {triangles} triangles (a polygon of k vertices k - 2), but pymeshlab "
            f"loaded {F.shape[0]}: {_DROPPED_TRIANGLES[os.path.splitext(path)[1].lower()]}. Fix or remove "
            "those faces in the file and read it again.")
    if not sizes and os.path.splitext(path)[1].lower() == ".ply":
        faces = declared_counts(path)[1]
        if faces is not None and F.shape[0] > faces:   # a binary file's polygons, fanned in the file's order
            polygons = mesh.polygonal_face_list()       # (the loader marks the fans' inner edges)
            sizes = [np.fromiter(map(len, polygons), dtype=np.int64, count=len(polygons))]
    if sizes:
        check_polygons(path, mesh.vertex_matrix(), F, sizes[0], error=MeshFileError)
    if vertex_maps and os.path.splitext(path)[1].lower() == ".ctm":
        _set_ctm_vertex_maps(ms, path)
        mesh = ms.current_mesh()
    return mesh


#: Why pymeshlab's loader drops triangles of a file's faces without a word, by format (what
#: :func:`load_checked` says where fewer come back than the faces make).
_DROPPED_TRIANGLES = {
    ".ply": "its PLY loader drops faces that repeat a vertex index and faces whose 'flags' value has the "
            "'deleted' bit (1) set (fix or remove the flags too)",
    ".obj": "its OBJ loader drops triangles that repeat a vertex index (of a polygon too: 'f 1 2 2 3' "
            "became one triangle) and those with a texture coordinate index past the file's vt lines",
    ".off": "its OFF loader drops triangles that repeat a vertex index (of a polygon too: '4 0 1 1 2' "
            "became one triangle)",
}


def _set_ctm_vertex_maps(ms, path):
    """Give the current layer of ``ms``, just loaded from the CTM file ``path``, the file's vertex
    colours ("Color" map) and quality ("Quality" map), and mark it as holding them.

    pymeshlab (2025.7; vcglib's ImporterCTM) reads the colours right but the quality from the
    *colour* map (its red channel: a quality of 10 was read as 0.64), and marks the layer as
    holding neither (``has_vertex_color()`` and ``has_vertex_scalar()`` False: its filters
    refused the quality, and saves dropped both). The quality is decoded from the file
    (:func:`curvdetail._ctm_scan.ctm_vertex_map`: its first value per vertex, as vcglib's writer
    stores it), and both are set through pymeshlab's per-vertex function filters, which mark
    the layer. A file with a "Quality" map and no "Color" one never gets here (refused before
    loading: the reader crashed on it), nor one OpenCTM read as nothing (a NaN in its
    "Quality" map was refused so). Where the quality cannot be decoded (LZMA options Python's decoder
    lacks; OpenCTM's own writer uses none of them) it is left out (the layer marked as holding
    none), with a warning, rather than read as the red channel."""
    import warnings

    from ..filters.meshset import set_vertex_quality

    layout = ctm_layout(path)
    if layout is None or ms.current_mesh().vertex_number() != layout["vertices"]:
        return                   # pymeshlab read nothing (OpenCTM refused the file): left to the caller
    names = {name.split(b"\x00", 1)[0] for name in layout["attribute_maps"]}
    if b"Color" in names:
        # the colours pymeshlab read are the file's (to 8 bits): each kept as it is, the layer marked
        ms.compute_color_by_function_per_vertex(x="r", y="g", z="b", a="a", onselected=False)
    if b"Quality" in names:
        try:
            quality = ctm_vertex_map(path, b"Quality", layout)[:, 0].astype(np.float64)
        except ValueError as exc:
            warnings.warn(f"{path!r}: the vertex quality is left out: {exc}. The geometry and the colours are read "
                          "(pymeshlab would read the quality from the colour map); export the mesh again (e.g. as "
                          "PLY) to keep the quality.", stacklevel=4)
            return
        set_vertex_quality(ms, ms.current_mesh_id(), quality)


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
    """``path`` as a str naming an existing file, or raise: MeshFileError for what is not a path,
    a folder, not a regular file (a pipe: the checks read it before pymeshlab does) or empty,
    FileNotFoundError for a missing file."""
    if not isinstance(path, (str, bytes, os.PathLike)):
        raise MeshFileError(f"a mesh path must be a str or os.PathLike; got {type(path).__name__}.")
    path = os.fsdecode(path)
    if os.path.isdir(path):
        raise MeshFileError(f"{path!r} is a folder; name a mesh file in it.")
    if not os.path.isfile(path):
        if os.path.exists(path):      # a FIFO, a device, a socket: there, but no file to read twice
            raise MeshFileError(f"{path!r} is not a regular file (a pipe or a device); write the mesh to a "
                                "file and read that.")
        raise FileNotFoundError(f"mesh file not found: {path}")
    if os.path.getsize(path) == 0:      # pymeshlab said "damaged or incomplete" in each format's words
        raise MeshFileError(f"{path!r} is empty (0 bytes): there is no mesh in it; check that the program "
                            "that wrote it finished, and write it again.")
    return path


#: Formats pymeshlab writes as points only: a mesh saved there loses its triangles.
POINT_FORMATS = (".xyz", ".e57", ".pts", ".ptx", ".apts", ".asc")

_MESH_HINT = "use .ply, .obj, .off, .stl, ..."
_WRITES = {}            # extension -> None (pymeshlab writes it) or why it does not

_NEXUS = ("its Nexus writer uses memory it never set, and crashes the process (segmentation fault or bus "
          "error in NexusBuilder::saturateNode) where that memory is not zero, as in a process that has "
          "run a while")
#: Formats whose pymeshlab writer is never run, not even on the one-triangle probe, and why
#: (pymeshlab 2025.7; the message of :func:`check_mesh_output`). ``.nxs``, ``.nxz``: the .nxz
#: probe crashed a full test run (tests/test_io.py); where malloc hands out nonzero memory
#: (glibc's ``MALLOC_PERTURB_``, as memory recycled in a long run is) every .nxs and .nxz write
#: crashed, in fresh processes and in test_io.py alike, and no other format's did.
#: ``.u3d``: it writes no file, only a fixed-name one in the shared temporary folder
#: (``$TMPDIR/<name>.u3d.idtf``, then deleted) and a LaTeX file named by the path up to its
#: first dot, wherever that is.
UNWRITTEN_FORMATS = {
    ".nxs": _NEXUS,
    ".nxz": _NEXUS,
    ".u3d": "it reports success but writes no file: its U3D converter fails without a word",
}


def check_mesh_output(path, overwrite=False, *, hint=_MESH_HINT):
    """Return ``path`` as a str, or raise before any work if a mesh cannot be written there:
    :func:`curvdetail._output.check_output_path` (existing file, folder, no extension), a format
    that keeps the points only (:data:`POINT_FORMATS`), one whose pymeshlab writer crashes or
    writes nothing (:data:`UNWRITTEN_FORMATS`: .nxs, .nxz, .u3d; never run), or one pymeshlab
    does not write (found by writing one triangle to a temporary file, once per extension and
    process).

    Raises
    ------
    FileExistsError   ``path`` exists and ``overwrite`` is False
    MeshFileError     ``path`` is a folder, its folder is missing, or the format is not a mesh
                      format pymeshlab writes
    """
    try:
        path = check_output_path(path, overwrite)
    except MeshError as exc:                    # a folder, a missing or read-only folder
        raise MeshFileError(exc.problem, parameter=exc.parameter, value=exc.value, hint=exc.hint) from None
    if not os.path.splitext(path)[1]:
        raise MeshFileError(f"cannot write {path!r}: no file extension to choose the format from ({hint})")
    _check_utf8(path)
    extension = os.path.splitext(path)[1].lower()
    if extension in POINT_FORMATS:
        raise MeshFileError(f"cannot write {path!r}: {extension} files hold points only, so the "
                            f"triangles would be lost; {hint}")
    if extension in UNWRITTEN_FORMATS:
        raise MeshFileError(f"cannot write {path!r}: {extension} meshes are refused: pymeshlab's writer for them "
                            f"is not run ({UNWRITTEN_FORMATS[extension]}); {hint}")
    if extension not in _WRITES:
        _WRITES[extension] = _why_not_written(extension)
    if _WRITES[extension] is not None:
        raise MeshFileError(f"cannot write {path!r}: pymeshlab does not write {extension} meshes "
                            f"({_WRITES[extension]}); {hint}")
    return path


def _check_utf8(path, action="write"):
    """Raise MeshFileError if pymeshlab cannot be given ``path`` (a str from
    :func:`os.fsdecode`): it takes paths as UTF-8 text, so a folder or file name holding other
    bytes (``b'lat\\xe9'``, Latin-1) was refused with a TypeError (on reading, reported as a
    damaged file), or, passed as bytes, written under another name (the byte replaced by
    U+FFFD). ``action``: "read" or "write", for the message."""
    absolute = os.path.abspath(path)
    try:
        absolute.encode("utf-8")
    except UnicodeEncodeError as exc:
        bad = os.fsencode(absolute[exc.start:exc.end])
        elsewhere = "copy the file elsewhere and read it there" if action == "read" else \
            "write elsewhere and move the file there"
        raise MeshFileError(f"cannot {action} {path!r}: its path holds bytes that are not UTF-8 ({bad!r} in "
                            f"{os.fsencode(absolute)!r}), and pymeshlab takes paths as UTF-8 text only; rename the "
                            f"file or folder (or {elsewhere}).") from None


def _why_not_written(extension):
    """None if pymeshlab writes a triangle to a ``extension`` file, else its message; the
    formats of :data:`UNWRITTEN_FORMATS` are refused without running their writer."""
    import tempfile

    import pymeshlab

    if extension in UNWRITTEN_FORMATS:
        return UNWRITTEN_FORMATS[extension]

    with tempfile.TemporaryDirectory(prefix="curvdetail-format-") as folder:
        ms = _meshset()
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.eye(3), face_matrix=np.array([[0, 1, 2]], dtype=np.int32)))
        probe = os.path.join(folder, "probe" + extension)
        try:
            ms.save_current_mesh(probe)
        except Exception as exc:
            return " ".join(str(exc).replace(folder + os.sep, "").split()) or type(exc).__name__
        if not os.path.exists(probe) or os.path.getsize(probe) == 0:
            return "it reports success but writes no file"      # .u3d: it needs a converter it lacks
    return None


#: Loss allowed in the formats that write doubles as text (.obj, .off, ASCII .ply), as a share
#: of the bounding-box diagonal: they can keep every double to an ulp or so; what they lose
#: beyond 1e-9 of the mesh's size comes from their fixed layout (16 decimals, 16 digits), not
#: from what the format is meant to hold.
DOUBLE_TOLERANCE = 1e-9
#: Loss allowed from the fixed decimals of the single-precision text formats (.3mf, .idtf), as a
#: share of the bounding-box diagonal: about the 6 to 7 digits that single precision holds.
SINGLE_TOLERANCE = 1e-6
_FLOAT32_MAX = float(np.finfo(np.float32).max)
_SAFE = ".ply (binary: doubles, every coordinate exact)"

#: How pymeshlab writes vertex coordinates, by extension, measured by writing meshes of every
#: scale and reading the files (pymeshlab 2023.12): ``("exact",)`` binary doubles; ``("digits",
#: n)`` text with n significant digits ("%.16g"); ``("decimals", n, bits, tolerance, rounding)``
#: text with n decimals after rounding (0.5) or truncating (1.0) to ``bits`` mantissa bits (52:
#: the double itself, 23: a float32 first); ``("float32",)`` single precision (binary, or text
#: of 6-7 significant digits in formats that declare single precision: COLLADA ``float``,
#: JSON ``float32``, VRML/X3D ``SFFloat``); a str: why the format cannot hold coordinates.
#: PLY and STL depend on ``binary``, CTM on ``lossless`` (see :func:`check_coordinates`).
_COORDINATES = {
    ".obj": ("decimals", 16, 52, DOUBLE_TOLERANCE, 0.5),   # "%.16f": 1e-20 is written as 0.0000000000000000
    ".off": ("digits", 16),                                # "%.16g"
    ".ply": ("exact",),                                    # binary: double x, y, z
    ".ply ascii": ("digits", 16),                          # "%.16g"
    ".stl": ("float32",),                                  # binary float32; ASCII "%e" of the float32
    ".3ds": ("float32",),
    ".ctm": ("float32",),                                  # lossless (MG1): the float32 values
    ".ctm lossy": ("with lossless=False pymeshlab's CTM writer compresses the coordinates to a grid (MG2: 2e-5 of a "
                   "sphere's bounding-box diagonal lost at radius 1, 2e-2 at 1e-3, 6e-2 at 1e-30 and 1e30); "
                   f"pass lossless=True (save_mesh's default: single precision), or write {_SAFE}"),
    ".nxs": ("float32",),
    ".nxz": ("pymeshlab's NXZ writer compresses the coordinates with a quantization whose error is not "
             f"known here; write {_SAFE}"),
    ".dae": ("float32",),                                  # "%g": 6 significant digits
    ".json": ("float32",),
    ".wrl": ("float32",),
    ".x3d": ("float32",),
    ".3mf": ("decimals", 6, 23, SINGLE_TOLERANCE, 1.0),    # float32, 6 decimals truncated
    ".idtf": ("decimals", 6, 52, SINGLE_TOLERANCE, 0.5),   # "%f"
    ".dxf": ("decimals", 6, 52, SINGLE_TOLERANCE, 0.5),    # "%f" of the double (pymeshlab reads no .dxf:
                                                           # measured in the text, 16777217 kept whole)
}
_SINGLE = (".stl", ".3ds", ".ctm", ".nxs", ".dae", ".json", ".wrl", ".x3d", ".3mf", ".idtf")
_SIX_DIGITS = (".dae", ".json", ".wrl", ".x3d")
#: Loss allowed in the single-precision formats, as a share of the bounding-box diagonal, from
#: where the mesh lies: single precision keeps ~6e-8 of the largest coordinate, so a mesh more
#: than ~1,700 diagonals from the origin is refused (a 15 km terrain in UTM coordinates passes).
OFFSET_TOLERANCE = 1e-4


def check_coordinates(path, V, *, binary=True, lossless=True, **save_options):
    """Raise MeshFileError, before anything is written, if pymeshlab would write the vertex
    coordinates ``V`` to ``path``'s format with a loss the format does not stand for; return
    None if they fit. A few numpy reductions over ``V``; ``binary`` and ``lossless`` are
    ``save_current_mesh``'s options (other options are ignored).

    What each format holds (measured by writing meshes of every scale with pymeshlab and
    reading the files back) and what is refused:

    - binary .ply: doubles, exact. Nothing is refused.
    - .obj: text with 16 decimals ("%.16f": 1e-20 becomes 0, 1e-13 keeps 3 digits). Refused
      where that loses more than :data:`DOUBLE_TOLERANCE` (1e-9) of the bounding-box diagonal:
      meshes smaller than about 5e-8.
    - .off, ASCII .ply: text with 16 significant digits ("%.16g", a few ulps). Refused where
      that loses more than 1e-9 of the diagonal: coordinates more than about 2e6 diagonals from
      the origin.
    - .stl (binary and ASCII), .3ds, .ctm (lossless), .nxs: single precision; .dae, .json,
      .wrl, .x3d: 6 significant digits, declared single precision. Accepted at that precision
      (about 6e-8 of the largest coordinate, 5e-6 for the 6-digit ones), but refused where a
      coordinate overflows it (above 3.4e38: written as inf), underflows it (a mesh so small
      that its coordinates lose more than single precision keeps, down to being written as 0),
      or where the mesh lies so far from the origin that the loss is more than
      :data:`OFFSET_TOLERANCE` (1e-4) of the diagonal.
    - .3mf (single precision, then 6 decimals truncated) and .idtf (6 decimals): as single
      precision, and refused where the decimals lose more than :data:`SINGLE_TOLERANCE` (1e-6)
      of the diagonal: meshes smaller than about 1 (.3mf) and 0.5 (.idtf).
    - .dxf: the doubles as text with 6 decimals ("%f"; pymeshlab does not read .dxf, so this was
      measured in the written text), refused as .idtf: meshes smaller than about 0.5.
    - .ctm with ``lossless=False`` and .nxz: compressed with a loss not bounded here; refused.
    - any other extension (a format whose writer was never measured): refused.

    Where the diagonal is 0 (one point) the largest coordinate stands for it. Non-finite
    coordinates are refused (pymeshlab's loaders drop such vertices). The message names the
    format's limit and a format that holds the coordinates (binary .ply)."""
    extension = os.path.splitext(os.fsdecode(path))[1].lower()
    key = extension + (" ascii" if extension == ".ply" and not binary else "") + \
        (" lossy" if extension == ".ctm" and not lossless else "")
    kind = _COORDINATES.get(key)
    where = f"cannot write {os.fsdecode(path)!r}"
    if isinstance(kind, str):
        raise MeshFileError(f"{where}: {kind}.")
    if kind is None:        # a format pymeshlab writes that was never measured: its loss is not known
        raise MeshFileError(f"{where}: how precisely pymeshlab writes {extension or 'extension-less'} coordinates "
                            f"is not known here, so the mesh could be written with a loss nothing checks; write "
                            f"{_SAFE}, or .obj, .off, .stl.")
    V = np.asarray(V, dtype=np.float64).reshape(-1, 3)
    if not V.size:
        return
    finite = np.isfinite(V).all(axis=1)
    if not finite.all():
        bad = np.flatnonzero(~finite)
        raise MeshFileError(f"{where}: {counted(bad.size, 'vertex', 'vertices', verb='have')} NaN or infinite coordinates (first: "
                            f"{first_indices(bad)}), which pymeshlab's loaders drop (renumbering the rest); "
                            "fix them first.")
    low, high = V.min(axis=0), V.max(axis=0)
    largest = float(max(np.abs(low).max(), np.abs(high).max()))
    diagonal = float(np.linalg.norm(high - low))
    scale = diagonal if diagonal > 0 else largest
    if largest == 0:
        return
    name = extension[1:].upper() + (" (ASCII)" if key.endswith("ascii") else "")
    size = f"the mesh's bounding-box diagonal ({diagonal:.3g})" if diagonal > 0 else \
        f"its largest coordinate ({largest:.3g}; all vertices coincide)"
    if kind[0] == "digits":
        loss = _digits_loss(V, kind[1])
        if loss > DOUBLE_TOLERANCE * scale:
            raise MeshFileError(
                f"{where}: pymeshlab writes {name} coordinates with {kind[1]} significant digits, which loses up "
                f"to {loss:.3g} ({loss / scale:.2g} of {size}; the limit is {DOUBLE_TOLERANCE:g}) for coordinates "
                f"this far from the origin (largest {largest:.3g}). Write {_SAFE}, or move the mesh near the "
                "origin.")
        return
    if extension in _SINGLE:
        with np.errstate(over="ignore"):
            single = V.astype(np.float32)
        over = ~np.isfinite(single).all(axis=1)
        if over.any():
            bad = np.flatnonzero(over)
            raise MeshFileError(
                f"{where}: {name} holds coordinates in single precision, whose largest value is "
                f"{_FLOAT32_MAX:.4g}; {counted(bad.size, 'vertex', 'vertices', verb='exceed')} it (first: {first_indices(bad)}) and would be "
                f"written as inf. Write {_SAFE}, or scale the mesh down.")
        difference = single - V
        error = float(np.abs(difference).max())
        if error > 2.0 ** -23 * largest:          # more than single precision's rounding: underflow
            raise MeshFileError(
                f"{where}: {name} holds coordinates in single precision, which keeps this mesh's coordinates "
                f"(largest {largest:.3g}) only to {error:.3g} ({error / largest:.2g} of the largest; single "
                f"precision keeps {2.0 ** -24:.1g}): values below {float(np.finfo(np.float32).tiny):.3g} lose "
                f"digits or become 0. Write {_SAFE}, or scale the mesh up.")
        # far from the origin single precision keeps little of a small mesh (a unit sphere at 1e7
        # lost 0.14 of its diagonal in .3ds); the 6-digit text formats keep less still
        loss = float(np.sqrt((difference ** 2).sum(axis=1).max()))          # a vertex's displacement
        if extension in _SIX_DIGITS:
            loss += _digits_loss(single, 6)
        if loss > OFFSET_TOLERANCE * scale:
            raise MeshFileError(
                f"{where}: {name} holds coordinates in single precision{' with 6 digits' if extension in _SIX_DIGITS else ''}"
                f", which loses up to {loss:.3g} ({loss / scale:.2g} of {size}; the limit is {OFFSET_TOLERANCE:g}) "
                f"for coordinates this far from the origin (largest {largest:.3g}). Write {_SAFE}, or move the mesh "
                "near the origin.")
    if kind[0] == "decimals":
        _, decimals, bits, tolerance, rounding = kind
        unit = 10.0 ** -decimals
        # values from 2**k on are spaced wider than a decimal: written (and read back) as they are
        exact = 2.0 ** np.ceil(np.log2(unit * 2.0 ** bits))
        magnitude = np.abs(V)
        per_axis = np.minimum(np.where(magnitude < exact, magnitude, 0.0).max(axis=0), rounding * unit)
        loss = float(np.linalg.norm(per_axis))                             # a vertex's displacement
        if loss > tolerance * scale:
            raise MeshFileError(
                f"{where}: pymeshlab writes {name} coordinates with {decimals} decimals (an error up to "
                f"{rounding * unit:.1g}), which loses up to {loss / scale:.2g} of {size}; the limit is "
                f"{tolerance:g} of it. Write {_SAFE}, or scale the mesh up.")


def _digits_loss(V, digits):
    """Largest displacement of a vertex written with ``digits`` significant digits: half a unit
    in the last digit of each axis's largest coordinate (1234.5678 with 6 digits: 0.005)."""
    largest = np.abs(V).max(axis=0).astype(np.float64)
    places = np.floor(np.log10(largest, where=largest > 0, out=np.zeros_like(largest)))
    unit = np.where(largest > 0, 10.0 ** (places + 1 - digits), 0.0)
    return float(0.5 * np.linalg.norm(unit))


def write_mesh(path, V, F, *, quality=None, overwrite=False):
    """Write a triangle mesh atomically in the format given by the file extension.

    Parameters
    ----------
    path : str or os.PathLike   destination; its extension picks the format (.ply, .obj, .off, .stl, ...)
    V : (n, 3) float array      vertex positions
    F : (m, 3) int array        triangles
    quality : (n,) float array or None   per-vertex quality (saved where the format holds it,
                                          e.g. PLY; MeshLab colours meshes by it); refused for
                                          CTM, whose quality pymeshlab cannot read back
    overwrite : bool            replace an existing file; by default an existing file is refused

    Raises
    ------
    FileExistsError   ``path`` exists and ``overwrite`` is False
    MeshError         malformed ``V``, ``F`` or ``quality``
    MeshFileError     ``path`` is a folder, its folder is missing or not writable, or the format
                      is unknown, keeps points only (.xyz, ...) or has a writer that crashes or
                      writes nothing (.nxs, .nxz, .u3d; see :func:`check_mesh_output`),
                      or it cannot hold the coordinates (before anything is written; see
                      :func:`check_coordinates`): binary PLY writes doubles (exact); OBJ 16
                      decimals (a mesh smaller than about 5e-8 loses more than 1e-9 of its
                      bounding-box diagonal: refused); OFF 16 significant digits (refused more
                      than about 2e6 diagonals from the origin); STL, 3DS, CTM, COLLADA, VRML,
                      X3D, JSON single precision (refused where a coordinate overflows, above
                      3.4e38, or the mesh underflows it); DXF, 3MF, IDTF 6 decimals (refused
                      for meshes smaller than about 1); ``quality`` with a .ctm path:
                      pymeshlab's CTM reader reads the quality from the colour map, and
                      crashed where there is none (without quality, a CTM file is written
                      with neither, which it reads); a path whose folder or file name is not
                      UTF-8 (pymeshlab takes UTF-8 paths only: rename it)

    Notes
    -----
    STL (and DXF) files store each triangle with its own three corners, not shared vertices:
    reading an STL file back welds coincident corners into one vertex and cannot hold
    unreferenced vertices, so ``read_mesh`` returns fewer vertices, renumbered (two separate
    triangles of 7 vertices, sharing two corner positions, come back as 4 vertices, joined), and
    float32 coordinates. Write .ply (or .obj, .off) for an exact round trip of ``V`` and ``F``.

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
    FileExistsError: ... exists; pass overwrite=True to replace it.
    """
    import pymeshlab

    path = check_mesh_output(path, overwrite)     # a str from here on: bytes compared as b'.ply'
    extension = os.path.splitext(path)[1].lower()
    if quality is not None and extension == ".ctm":
        raise MeshFileError(f"cannot write {path!r} with quality: {_CTM_QUALITY}; write {_SAFE} to keep "
                            "the quality, or pass quality=None to write the CTM file without it.")
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
    # zero error everywhere), and in CTM without colours would crash its reader
    no_quality = quality is None and extension in (".ply", ".ctm")
    plain = dict(_PLAIN_OPTIONS, **({"save_vertex_quality": False} if no_quality else {}))
    save_mesh(path, mesh, overwrite=overwrite, _plain=plain)


#: What :func:`write_mesh` turns off where the format has the option (pymeshlab refuses an
#: option the format lacks, e.g. ``save_vertex_normal`` for VRML). Not for .3ds, whose face
#: colours :func:`save_mesh` keeps (see :data:`_3DS_FACE_COLOURS`).
_PLAIN_OPTIONS = {"save_vertex_color": False, "save_vertex_normal": False, "save_face_color": False}

#: Why pymeshlab cannot read a CTM file's quality back (vcglib's ImporterCTM reads it from the
#: "Color" map): tried on RAW, MG1 and MG2 files; see :mod:`curvdetail._ctm_scan`.
_CTM_QUALITY = ("pymeshlab's CTM reader reads a file's quality from its colour map: where there is none it crashes "
                "the process (segmentation fault), and where there is one it reads the colours' red channel as "
                "the quality (MeshLab uses the same reader)")
#: Why .3ds files are written with face colours: without them pymeshlab's 3DS writer leaves each
#: face's material name unset and writes whatever its stack held there (a stack address, a
#: different name in every process), so no two writes were alike.
_3DS_FACE_COLOURS = ("pymeshlab's 3DS writer names each face's material from uninitialised memory where face colours "
                     "are not saved (a different name in every process)")


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
                                has vertex quality; for CTM, ``lossless`` to True, and
                                ``save_vertex_quality`` to False where no vertex colours are
                                saved (pymeshlab's CTM reader crashes on quality without
                                colours; with colours it reads their red channel as the
                                quality, which :func:`load_checked` corrects); for 3DS,
                                ``save_face_color`` is True (faces without a colour are
                                given white: without face colours pymeshlab's writer names
                                the faces' material from uninitialised memory)

    Raises
    ------
    FileExistsError   ``path`` exists and ``overwrite`` is False
    MeshFileError     no extension, a folder, missing folder, a format pymeshlab does not write
                      as a mesh, pymeshlab failed to write (or wrote nothing), a save option
                      that asks for a custom attribute (``__ca_...``), or coordinates the format
                      (with ``binary``, ``lossless``) cannot hold: :func:`check_coordinates`,
                      before anything is written. For CTM ``lossless`` defaults to True
                      (pymeshlab's default compresses the coordinates to a grid). CTM with
                      ``save_vertex_quality=True`` and no colours saved, 3DS with
                      ``save_face_color=False`` (see above), and a written CTM file that
                      :func:`read_mesh` would refuse (checked before it replaces ``path``)

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
    path = check_mesh_output(path, overwrite)     # a str from here on (the message's replace below)
    plain = _plain or {}         # options to set where the format has them (write_mesh's)
    extension = os.path.splitext(path)[1].lower()
    if extension == ".ply" and mesh.has_vertex_scalar() and "save_vertex_quality" not in plain:
        options.setdefault("save_vertex_quality", True)
    if extension == ".ctm":
        options.setdefault("lossless", True)     # pymeshlab's default compresses the coordinates
        colours = mesh.has_vertex_color() and options.get("save_vertex_color", plain.get("save_vertex_color", True))
        if not colours and mesh.has_vertex_scalar():
            if options.get("save_vertex_quality"):
                raise MeshFileError(f"cannot write {path!r} with save_vertex_quality=True and no vertex "
                                    f"colours: {_CTM_QUALITY}; save the colours too, or write {_SAFE}.")
            options["save_vertex_quality"] = False
    if extension == ".3ds":
        if options.get("save_face_color", True) is False:
            raise MeshFileError(f"cannot write {path!r} with save_face_color=False: {_3DS_FACE_COLOURS}; "
                                "leave save_face_color on.")
        options["save_face_color"] = True
        plain = {k: v for k, v in plain.items() if k != "save_face_color"}
    check_coordinates(path, mesh.vertex_matrix(), **options)
    # the temporary file keeps path's extension: pymeshlab picks the format from it
    with atomic_write(path, overwrite=overwrite) as tmp:
        ms = _meshset()
        ms.add_mesh(mesh)                        # a copy: the caller's mesh is not changed
        if extension == ".3ds" and not ms.current_mesh().has_face_color():
            ms.compute_color_by_function_per_face(r="255", g="255", b="255", a="255")     # white
        try:
            _save(ms, tmp, options, plain)
        except Exception as exc:
            raise MeshFileError(f"could not write {path!r}: "
                                f"{str(exc).replace(tmp, path)}") from None
        if os.path.getsize(tmp) == 0:
            raise MeshFileError(f"could not write {path!r}: pymeshlab reported success but wrote "
                                f"nothing; {_MESH_HINT}")
        problem = ctm_problem(tmp) if extension == ".ctm" else None
        if problem:                              # what the options above should have kept out
            raise MeshFileError(f"could not write {path!r}: pymeshlab wrote a CTM file that read_mesh "
                                f"refuses ({problem}); write {_SAFE}.")


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
