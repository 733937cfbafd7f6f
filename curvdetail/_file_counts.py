"""What a mesh file declares, to catch what pymeshlab's loader drops without a word.

pymeshlab's loader silently drops OBJ/OFF/PLY vertices with NaN or infinite coordinates (and the
faces using them, renumbering the rest), drops OBJ faces whose vertex indices are out of range
or repeated and STL triangles with a non-finite or repeated corner. :func:`check_loaded`
compares the loaded mesh with the counts the file declares (OFF/PLY headers, the binary STL
header, a streamed count of OBJ ``v`` and ``f`` lines and of ASCII STL facets, never the whole
file in memory) and with its own vertex count. What the loader would misread or read into
corrupt memory is looked for before loading, in :mod:`curvdetail._file_scan`.
"""

import itertools
import os
import re

import numpy as np

from .curvature.errors import counted

_CHUNK = 1 << 20
_HEADER_LINES = 10_000


def _obj_counts(path):
    """Numbers of ``v`` and ``f`` lines of an OBJ file, counted in 1 MiB chunks. Like pymeshlab's
    loader, such a line starts at the beginning of a line with ``v`` / ``f`` and a space or tab
    (``vt``, ``vn``, ``vp`` and indented lines do not count)."""
    v, v_tab, f, f_tab = _streamed_counts(path, (b"\nv ", b"\nv\t", b"\nf ", b"\nf\t"), start=b"\n")
    return v + v_tab, f + f_tab


def _streamed_counts(path, needles, start=b""):
    """Occurrences of each of ``needles`` in the file, read in ``_CHUNK`` pieces (never whole);
    ``start`` is put before the first byte (a newline makes line-start patterns match there)."""
    counts = [0] * len(needles)
    keep = max(len(n) for n in needles) - 1
    tail = start
    with open(path, "rb") as f:
        while True:
            chunk = f.read(_CHUNK)
            if not chunk:
                return counts
            text = tail + chunk          # a match may straddle two chunks, never lie in tail alone
            for i, needle in enumerate(needles):
                counts[i] += text.count(needle)
            tail = text[max(0, len(text) - keep):]


def _off_counts(path):
    """``(nv, nf)`` from an ASCII OFF header (``[ST][C][N][4]OFF`` then ``nv nf ne``, on the same
    line or the next one, comments allowed), or ``(None, None)`` if it is not of that form or the
    counts are not whole numbers (:func:`_whole`)."""
    with open(path, "rb") as f:
        header = _off_header(f)
    if header is None:
        return None, None
    nv, nf = (_whole(word) for word in header[0])
    return (nv, nf) if nv is not None and nf is not None and nv >= 0 and nf >= 0 else (None, None)


def _off_header(lines):
    """``((nv word, nf word), length of the header in bytes, keyword)`` from an OFF file's lines
    (bytes, newlines kept), or None: not that form ("OFF BINARY", nOFF with its dimension first,
    too short). The counts are the words as written (bytes); :func:`_whole` reads them."""
    words, length = [], 0
    for line in itertools.islice(lines, _HEADER_LINES):
        length += len(line)
        words += line.split(b"#", 1)[0].split()
        if len(words) >= 3:
            break
    first = words[0].decode("ascii", "replace") if words else ""
    keyword = "OFF" if first == "off" else first
    if len(words) < 3 or not keyword.endswith("OFF") or "n" in keyword:
        return None
    return (words[1], words[2]), length, keyword


#: A count or index written as a whole number: what C's atoi, which pymeshlab's OFF and OBJ
#: readers use, reads as the number written (it stops at the first character not a digit).
_WHOLE = re.compile(rb"[+-]?([0-9]+)(?:\.0*)?")


def _whole(word):
    """The whole number ``word`` (bytes) is written as, where pymeshlab's loaders read that very
    number: ``3``, ``+3``, ``3.0``, ``3.`` (atoi reads 3 from each); else None (``2.5``, ``1e1``,
    ``x``, ``#``: atoi reads 2, 1, 0 and 0)."""
    match = _WHOLE.fullmatch(word)
    if match is None:
        return None
    return -int(match[1]) if word[:1] == b"-" else int(match[1])


def _ply_counts(path):
    """``N`` of ``element vertex N`` and ``element face N`` in a PLY header (ASCII or binary; only
    the header is read); None where absent."""
    found = {}
    with open(path, "rb") as f:
        if f.readline().strip() != b"ply":
            return None, None
        for _ in range(_HEADER_LINES):
            words = f.readline().split()
            if not words or words[0] == b"end_header":
                break
            if words[0] == b"element" and len(words) == 3 and _whole(words[2]) is not None:
                found[words[1]] = _whole(words[2])          # "3.0" as the reader and the scan read it
    return found.get(b"vertex"), found.get(b"face")


def _stl_binary_count(path):
    """``(count, head)``: the triangle count of a binary STL file's header where the file's size
    matches it (else None), and the file's first 84 bytes (an ASCII file starts with "solid")."""
    size = os.path.getsize(path)
    with open(path, "rb") as f:
        head = f.read(84)
    if len(head) == 84:
        count = int(np.frombuffer(head[80:84], dtype="<u4")[0])
        if size == 84 + 50 * count:
            return count, head
    return None, head


def _stl_counts(path, exact=False):
    """``(None, triangles)`` of an STL file: a binary file's header count (when the file size
    matches it), or an ASCII file's ``endfacet`` words (``exact``: lines that start with one, which
    takes ~10 times as long; a name such as "solid endfacet test" is then not counted);
    ``(None, None)`` if neither."""
    count, head = _stl_binary_count(path)
    if count is not None:
        return None, count
    if not head.lstrip().startswith(b"solid"):
        return None, None
    if not exact:
        return None, _streamed_counts(path, (b"endfacet",))[0]
    return None, _streamed_line_starts(path, (rb"endfacet(?![^ \t\r\n])",))[0]


def _stl_ascii_counts(path):
    """``(facets, vertex lines)`` of an ASCII STL file (lines that start with the word ``endfacet``
    or with ``vertex`` and a blank, streamed), or ``(None, None)`` for a binary one (its header
    count matches its size) or one that is not STL. The words are counted fast wherever they
    stand, and only where those counts disagree (3 vertices a facet) again at the lines' starts
    (~10 times as long)."""
    count, head = _stl_binary_count(path)
    if count is not None or not head.lstrip().startswith(b"solid"):
        return None, None
    facets, spaced, tabbed = _streamed_counts(path, (b"endfacet", b"vertex ", b"vertex\t"))
    if spaced + tabbed == 3 * facets:
        return facets, spaced + tabbed
    # a name ("solid my vertex model") or a stray word: count the lines that start with them
    return tuple(_streamed_line_starts(path, (rb"endfacet(?![^ \t\r\n])", rb"vertex[ \t]")))


def _streamed_line_starts(path, patterns):
    """Numbers of lines whose first word (after blanks) matches each of ``patterns`` (bytes
    regexes, matched at that word), read in ``_CHUNK`` pieces of whole lines (never whole). Words
    elsewhere in a line, as in a name on the ``solid`` line ("solid my vertex model") or after a
    facet's normal, are not counted (pymeshlab reads the words of a facet by their place)."""
    regexes = [re.compile(rb"(?:^|\n)[ \t]*" + pattern) for pattern in patterns]
    counts = [0] * len(patterns)
    tail = b""
    with open(path, "rb") as f:
        while True:
            chunk = f.read(_CHUNK)
            text = tail + chunk
            cut = text.rfind(b"\n") + 1 if chunk else len(text)   # whole lines; all at the end
            for i, regex in enumerate(regexes):
                counts[i] += sum(1 for _ in regex.finditer(text, 0, cut))
            tail = text[cut:]
            if not chunk:
                return counts


_COUNTS = {".obj": _obj_counts, ".off": _off_counts, ".ply": _ply_counts, ".stl": _stl_counts}

#: Why pymeshlab drops faces, by format (see :func:`check_loaded`).
_DROPPED_FACES = {".stl": "non-finite (NaN or inf) coordinates or a repeated corner"}


def declared_counts(path):
    """``(vertices, faces)`` the file declares (OBJ, OFF, PLY; STL: faces only), None where
    unknown."""
    counts = _COUNTS.get(os.path.splitext(os.fspath(path))[1].lower())
    return counts(path) if counts is not None else (None, None)


def check_loaded(path, n_vertices, F, error=ValueError, counts=None):
    """Raise ``error`` if the loaded mesh (``n_vertices``, triangles ``F``) lost vertices or faces
    of ``path`` or holds face indices out of range; each message names the file, the counts, the
    likely cause and the fix. ``counts``: the file's ``(vertices, faces)`` where the caller has
    them (as :func:`declared_counts` returns them, which is called where None)."""
    F = np.asarray(F)
    if F.size and (F.min() < 0 or F.max() >= n_vertices):
        bad = np.flatnonzero((F < 0).any(axis=1) | (F >= n_vertices).any(axis=1))
        raise error(f"{path!r}: {counted(bad.size, 'face', verb='use')} vertex indices outside the file's {n_vertices} "
                    f"vertices (first: face {bad[0]}, {F[bad[0]].tolist()} 0-based); fix or remove "
                    "them in the file and read it again.")
    vertices, faces = declared_counts(path) if counts is None else counts
    if vertices is not None and vertices > n_vertices:     # more than declared: a misread count
        raise error(
            f"{path!r} has {vertices} vertices but pymeshlab loaded {n_vertices}: "
            f"{counted(vertices - n_vertices, 'was', 'were')} dropped, most likely for non-finite (NaN or inf) "
            "coordinates, together with the faces using them, so the vertex order no longer "
            "matches the file. Fix or remove those vertices (and their faces) in the file and "
            "read it again.")
    # polygons are triangulated, so a complete load has at least as many triangles as faces
    if faces is not None and faces > F.shape[0] and os.path.splitext(os.fspath(path))[1].lower() == ".stl":
        faces = _stl_counts(path, exact=True)[1]       # an ASCII file's "endfacet" in a name is no facet
    if faces is not None and faces > F.shape[0]:
        cause = _DROPPED_FACES.get(os.path.splitext(os.fspath(path))[1].lower(),
                                   "vertex indices out of range or repeated within a face")
        raise error(
            f"{path!r} has {faces} faces but pymeshlab loaded {F.shape[0]} triangles: at least "
            f"{counted(faces - F.shape[0], 'was', 'were')} dropped, most likely for {cause}. Fix or remove those "
            "faces in the file and read it again.")


def check_polygons(path, V, F, sizes, error=ValueError):
    """Raise ``error`` if pymeshlab's loader cut a polygon face of ``path`` into triangles that
    overlap or leave it. ``sizes`` holds the vertex count of each face of the file, in its
    order; the loader makes k - 2 triangles of a face of k vertices, in the same order (the
    caller has checked that the counts agree), here ``F`` over the vertices ``V``.

    The loader cuts a PLY polygon, and an OBJ quad, as a fan from its first vertex (measured: the
    quad ``f 1 2 3 4`` with (0, 0), (1, 0.5), (2, 0), (1, 2) came back as the triangles 1 2 3,
    facing away, and 1 3 4, which covers the dent); an OFF quad along its shorter diagonal, which
    need not lie inside it (the same quad with (1, 4) for (1, 2) was cut as the fan); larger OFF
    and OBJ polygons by ear cutting, right for a planar polygon that does not cross itself. A
    triangle facing against its polygon's vector area (the sum of its triangles', for a fan the
    polygon's own: Newell's normal) cannot be part of a triangulation of it, and a fan whose
    triangles all face with it covers the polygon once; so a polygon is refused where one of its
    triangles faces against it (a concave polygon cut along a diagonal outside it, or one that
    crosses itself or folds far from a plane). Zero-area triangles pass (collinear corners).
    Vectorized over the triangles. The message names the first such face, and for an OBJ file its
    line (:func:`curvdetail._file_scan._obj_face_line`, which reads the file again: only then)."""
    sizes = np.asarray(sizes, dtype=np.int64)
    if not sizes.size or sizes.max(initial=0) <= 3 or int((sizes - 2).sum()) != len(F):
        return
    polygon = sizes > 3
    counts = sizes[polygon] - 2                                   # triangles of each polygon, in a run
    T = np.asarray(F)[np.repeat(polygon, sizes - 2)].T
    x, y, z = np.asarray(V, dtype=np.float64).T.copy()            # columns: gathers stay cheap
    edges = [(c[T[1]] - c[T[0]], c[T[2]] - c[T[0]]) for c in (x, y, z)]
    (ux, vx), (uy, vy), (uz, vz) = edges
    areas = np.stack([uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx], axis=1)
    normal = np.repeat(np.add.reduceat(areas, np.cumsum(counts) - counts, axis=0), counts, axis=0)
    against = np.einsum("ij,ij->i", areas, normal) < 0
    if not against.any():
        return
    maybe = np.flatnonzero(against)                               # rounding: not beyond 1e-9 of the sizes
    along = np.einsum("ij,ij->i", areas[maybe], normal[maybe])
    against[maybe] = along < -1e-9 * np.linalg.norm(areas[maybe], axis=1) * np.linalg.norm(normal[maybe], axis=1)
    if not against.any():
        return
    polygons = np.unique(np.repeat(np.flatnonzero(polygon), counts)[against])
    first = int(polygons[0])
    line = None
    if os.path.splitext(os.fspath(path))[1].lower() == ".obj":    # found only now: a refusal reads the file again
        from ._file_scan import _obj_face_line
        line = _obj_face_line(path, first)
    where = f", on line {line}" if line is not None else ""
    raise error(
        f"{path!r}: {counted(polygons.size, 'polygon face')} (first: face {first} counting from 0 in the "
        f"file's order{where}, of {sizes[first]} vertices) came out of pymeshlab's loader as triangles that "
        "overlap or leave the polygon (a triangle faces the other way: the polygon is concave and was cut "
        "along a diagonal outside it, or it crosses itself or is far from planar); triangulate the file's "
        "polygons before reading it (e.g. Blender's Triangulate, or an exporter's triangulate option), or "
        "write each concave polygon as triangles, and read the file again.")
