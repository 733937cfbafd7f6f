"""Mesh files that pymeshlab's loader would misread without a word, or read into corrupt
memory: found before it sees them (:func:`check_before_loading`).

Its OFF loader keeps faces whose indices are out of range and then writes out of bounds, which
can crash the process later. It also misreads: an OFF file's vertex values are one stream of
words to it (a row with a value too many shifts every later coordinate, a comment's words are
read as numbers, a vertex split over lines is read right), missing OFF rows are filled from
what follows, a line of blanks among the faces repeats the face before it, OFF and OBJ indices
and counts are read with atoi (2.5 -> 2, 2.0 -> 2) and a comment after an OBJ face becomes
further corners; OFF face rows beyond the header's count are dropped, and a decimal comma ends
an OFF or OBJ number (``1,5`` -> 1). Its OFF and OBJ coordinates are read with atof, which takes
any text for a number without a word: up to the first character that does not fit (``0.3abc`` ->
0.3, ``abc`` and ``-`` -> 0, ``1d3`` -> 1), and C's hexadecimal floats too (``0x10`` -> 16).
PLY files are scanned by :mod:`._ply_scan`, OpenCTM files (whose reader crashes on some
layouts) by :mod:`._ctm_scan`. The scans read the file once more, vectorized over its bytes
(CTM: its header and the names of its maps only).
"""

import contextlib
import functools
import io
import mmap
import os
import re
import threading

import numpy as np

from ._ctm_scan import ctm_problem
from ._file_counts import _off_header, _stl_ascii_counts, _whole
from ._ply_scan import _ply_problem
from .curvature.errors import counted

try:                                             # numpy's switch for huge pages (numpy >= 1.16; private)
    from numpy._core.multiarray import _set_madvise_hugepage
except ImportError:                              # numpy < 2
    try:
        from numpy.core.multiarray import _set_madvise_hugepage
    except ImportError:
        _set_madvise_hugepage = None


_small_pages_lock = threading.Lock()
_small_page_users = 0          # reads inside small_pages() now
_huge_pages_before = True      # numpy's setting when the first of them began


@contextlib.contextmanager
def small_pages():
    """A context in which numpy puts large arrays in ordinary pages (numpy asks the kernel for
    transparent huge pages for arrays of 4 MB and more, where the kernel leaves that to the
    program). A read's arrays (here a byte mask the file's size and the word bounds: ~280 MB for
    a million-vertex OFF file; the mesh's arrays after loading) live for a fraction of a second,
    and in a fresh process each huge page was first touched slowly (measured on a 2-core virtual
    machine: 0.6-0.9 s of a 1.0 s OFF scan more cold than warm, none in ordinary pages; warm
    no slower). The setting is numpy's and global; it is restored on leaving."""
    if _set_madvise_hugepage is None:
        yield
        return
    global _small_page_users, _huge_pages_before
    # counted: reads in several threads overlap, and only the last one out restores the
    # setting the first one in found (each restoring its own would leave it off)
    with _small_pages_lock:
        if _small_page_users == 0:
            _huge_pages_before = _set_madvise_hugepage(False)
        _small_page_users += 1
    try:
        yield
    finally:
        with _small_pages_lock:
            _small_page_users -= 1
            if _small_page_users == 0:
                _set_madvise_hugepage(_huge_pages_before)


def _small_pages(scan):
    """``scan`` run in :func:`small_pages`."""
    @functools.wraps(scan)
    def wrapped(*args, **kwargs):
        with small_pages():
            return scan(*args, **kwargs)
    return wrapped


@_small_pages
def check_before_loading(path, error=ValueError, sizes=None, counts=None):
    """Raise ``error`` for files that pymeshlab's loader would read into corrupt memory or
    misread without a word.

    ASCII OFF: faces that name vertices the file does not have (the loader keeps such faces and
    writes out of bounds; the process can crash later, even after :func:`check_loaded` has
    reported them), and rows it would misread (the vertex values are one stream of words to it,
    so a vertex row with a value too many or too few, or a comment among the values, shifts
    everything after it, while a vertex split over lines that hold exactly its values is read
    right and passes; a short face row, or a line of blanks among the rows, misplaces the faces;
    missing rows are filled from what follows), and header counts, face counts or indices that
    are not whole numbers (atoi reads 2.5 as 2; 3.0 passes). A binary OFF file, which the loader
    refuses with only "Invalid file", is named as such. OBJ: indented vertex lines (the loader
    counts them in one pass and not in the other; reading one aborted the process), a fractional
    face index (truncated; 2.0 passes) and a comment after a face (read as corners out of range;
    a one-word comment glued to the last index, ``f 1 2 3#note``, passes), and a comment before a
    vertex's z (``v 1 0#c 5`` was read as (1, 0, 5); one glued to the z, ``v 1 0 5#c``, or after
    it passes). OFF and OBJ: a comma in a number (``v 1,5 2 3`` was read as the vertex (1, 2, 3);
    commas in comments and names pass), and an x, y or z that is not a decimal number
    (``[+-](digits[.digits] | .digits)[(e|E)[+-]digits]``), inf, infinity or nan (any case; the
    loader drops such vertices, which :func:`check_loaded` reports): ``0.3abc``, ``abc``, ``-``,
    ``1.2.3``, ``1d3``, ``0x10`` were read as 0.3, 0, 0, 1.2, 1 and 16 (the vertex colours,
    normals and texture coordinates after them, which the mesh we keep lacks, and a comment
    glued to a value pass); OFF: a control character on a vertex row that changes its words (the
    reader splits them at spaces and tabs only; one that atof stops at, ``1\\x01``, passes), and
    rows after the header's faces (dropped; empty lines and comments pass).

    PLY, ASCII or binary: a header pymeshlab misparses (an element count that is not a whole
    number, or none: that crashed it) and face lists of types its importer does not read (it
    takes the faces from whatever memory held). ASCII PLY (:func:`_ply_body_problem`): every
    value fscanf would not read whole as its type (a fractional or comma'd index, ``1.5.5``),
    list counts that are not whole numbers, faces of fewer than 3 or more than 255 vertices,
    lines that hold values of two rows or a face row not on a line of its own, and fewer or more
    rows than the header declares; rows split over lines that hold exactly their values (not
    faces), blank lines, comments in the header, other elements and properties pass.

    CTM (:func:`curvdetail._ctm_scan.ctm_problem`): a vertex attribute map named "Quality" with
    none named "Color", or a map without a name that the reader's look-up of either reaches (each
    crashed the process), a file shorter than its sections (RAW: the rest was read from whatever
    memory held), and counts whose arrays OpenCTM sizes past 32 bits.

    OBJ also (:func:`_obj_face_indices`): face vertex indices outside the file (0, past the last
    ``v`` line, or negative past the vertices above the face; the loader wrote out of bounds or
    read another vertex), corners that are no whole number and faces of fewer than 3 corners;
    a UTF-8 byte order mark (the first line was lost; PLY: "damaged"), a carriage return no
    newline follows (the lines it ends were lost), and lines ending in a backslash that the
    loader joins with the next into something it misreads (:func:`_obj_continued_line`; faces
    and vertices continued over lines it reads right pass). ASCII STL: facets of other than 3 ``vertex``
    lines (the 4th was dropped). OFF: faces of fewer than 3 vertices (dropped). Binary PLY
    (:func:`curvdetail._ply_scan._ply_binary_problem`): big-endian doubles in the vertex element
    (read as garbage), a body shorter than the header's counts allow, and lists other than the
    face indices that the reader cannot skip (vertex lists counted in other than (u)char; more
    than 512 bytes of items in a row, which aborted the process).

    Other files pass unread. Returns the number of triangles the faces of an ASCII PLY, ASCII
    OFF or OBJ file make (a polygon of k vertices k - 2; pymeshlab drops triangles with a
    repeated index, PLY faces with the 'deleted' flag bit, OBJ faces with texture indices out of
    range, which the caller finds by comparing), else None. Where ``sizes`` is a list and the
    faces of such a file are known, their vertex counts (an int array, in file order) are
    appended to it (for :func:`curvdetail._file_counts.check_polygons`). Where ``counts`` is a list
    and the scan has counted what :func:`curvdetail._file_counts.declared_counts` would return
    (OBJ: its ``v`` and ``f`` lines; ASCII STL: its facets), ``(vertices, faces)`` is appended to
    it, so that :func:`curvdetail._file_counts.check_loaded` need not read the file again."""
    extension = os.path.splitext(os.fspath(path))[1].lower()
    if extension in (".off", ".ply", ".obj") and _carriage_returns_only(path):
        raise error(f"{path!r} ends its lines with carriage returns alone (classic Mac OS), which pymeshlab "
                    "reads as one long line (it failed, or read a single vertex); convert the line ends to "
                    "newlines (e.g. tr '\\r' '\\n' < old > new) and read the file again.")
    if extension in (".ply", ".obj") and _starts_with_bom(path):
        raise error(f"{path!r} starts with a UTF-8 byte order mark (the bytes EF BB BF, which some editors "
                    "write), which pymeshlab's " + ("PLY reader takes for a damaged header" if extension == ".ply"
                                                   else "OBJ loader reads as part of the first line's keyword "
                                                   "(that line, a vertex, was lost without a word)") +
                    "; save the file as UTF-8 without a byte order mark (or ASCII) and read it again.")
    if extension == ".stl":
        facets, vertex_lines = _stl_ascii_counts(path)
        if facets is not None and vertex_lines != 3 * facets:
            raise error(f"{path!r} is an ASCII STL file of {counted(facets, 'facet')} with {counted(vertex_lines, 'vertex line')}, not "
                        f"3 a facet ({3 * facets}): pymeshlab's STL loader reads each facet as the triangle of "
                        "its first 3 and drops the others without a word (a facet of 4 was read as one "
                        "triangle); split such facets into triangles and read the file again.")
        if counts is not None and facets is not None:
            # the "endfacet" words, or (where those miscount) the lines starting with one: either
            # leads check_loaded to the same verdict (it counts the lines where the words are too many)
            counts.append((None, facets))
    if extension == ".off":
        if _off_is_binary(path):
            raise error(f"{path!r} is a binary OFF file ('OFF BINARY'), which pymeshlab's OFF reader "
                        "does not read; save it as ASCII OFF, PLY or OBJ and read that.")
        made = []
        problem = _off_rows_problem(path, made)
        if problem:
            raise error(f"{path!r}: {problem}; fix the file and read it again.")
        if sizes is not None and made:
            sizes.append(made[1])
        return made[0] if made else None
    elif extension == ".ctm":
        problem = ctm_problem(path)
        if problem:
            raise error(f"{path!r}: {problem}.")
    elif extension == ".ply":
        found = []
        problem, triangles = _ply_problem(path, found)
        if sizes is not None and triangles is not None:
            sizes.append(np.concatenate(found) if found else np.zeros(0, dtype=np.int64))
        if problem:
            raise error(f"{path!r}: {problem}; fix the file and read it again.")
        return triangles
    elif extension == ".obj":
        lone = _obj_lone_carriage_return(path)
        if lone is not None:
            raise error(f"{path!r}: line {lone} ends in a carriage return not followed by a newline (a classic "
                        "Mac OS line end among Unix or Windows ones), which pymeshlab's OBJ loader does not "
                        "take for a line end: the lines it ends were read as one, and lost without a word; "
                        "convert the line ends to newlines (e.g. tr '\\r' '\\n' < old > new, or dos2unix) and "
                        "read the file again.")
        comma = _obj_comma(path)
        if comma is not None:
            raise error(f"{path!r}: line {comma[0]} ({comma[1]!r}) writes a number with a comma, which "
                        "pymeshlab's OBJ loader reads only up to the comma without a word ('v 1,5 2 3' was "
                        "read as the vertex (1, 2, 3)); write decimals with a point (and separate values with "
                        "spaces) and read the file again.")
        continued = _obj_continued_line(path)
        if continued is not None:
            raise error(f"{path!r}: line {continued[0]} ({continued[1]!r}) ends in a backslash, which "
                        "pymeshlab's OBJ loader reads as a line continued on the next one, and then " +
                        continued[2] + " and read the file again.")
        count, line = _obj_indented_vertices(path)
        if count:
            raise error(f"{path!r}: {count} vertex lines start with spaces or tabs (first: line {line}), "
                        "which pymeshlab's OBJ loader miscounts (it crashed reading such a file); remove "
                        "the leading whitespace and read the file again.")
        bad = _obj_bad_coordinate(path)
        if bad is not None:
            raise error(f"{path!r}: line {bad[0]} ({bad[1]!r}) {bad[2]}; fix the file and read it again.")
        odd = _obj_odd_face(path)
        if odd is not None and odd[1] == ".":
            raise error(f"{path!r}: the face on line {odd[0]} has a fractional index (of a vertex, texture "
                        "coordinate or normal), which pymeshlab's OBJ loader truncates without a word (1.5 "
                        "becomes 1); OBJ indices are whole numbers. Fix the face and read the file again.")
        if odd is not None:
            raise error(f"{path!r}: the face on line {odd[0]} ends in a comment, whose words pymeshlab's OBJ "
                        "loader reads as further corners (a vertex index past the file's vertices, which "
                        "can crash the process); move the comment to a line of its own and read the file "
                        "again.")
        found = []
        lines = []
        problem, triangles = _obj_face_indices(path, sizes=found, counts=lines)
        if problem:
            raise error(f"{path!r}: {problem}.")
        if counts is not None:
            counts.extend(lines)
        if sizes is not None and triangles is not None:
            sizes.append(np.concatenate(found) if found else np.zeros(0, dtype=np.int64))
        return triangles


def _starts_with_bom(path):
    """Whether the file starts with the UTF-8 byte order mark (EF BB BF)."""
    with open(path, "rb") as f:
        return f.read(3) == b"\xef\xbb\xbf"


def _obj_lone_carriage_return(path):
    """The 1-based line of the first carriage return in the file that no newline follows (but
    for one as the file's last byte, which ends its last line), or None. Vectorized over the
    bytes of a memory map."""
    with _mapped(path) as data:
        if data is None or data.find(b"\r") < 0:
            return None
        chars = np.frombuffer(data, dtype=np.uint8)
        try:
            returns = np.flatnonzero(chars[:-1] == 13)
            lone = returns[chars[returns + 1] != 10]
            if not lone.size:
                return None
            return int(np.count_nonzero(chars[:lone[0]] == 10)) + 1
        finally:
            del chars


def _off_is_binary(path):
    """Whether an OFF file's first line is ``[ST][C][N][4][n]OFF BINARY`` (any case)."""
    with open(path, "rb") as f:
        words = f.readline(4096).split(b"#", 1)[0].upper().split()
    return len(words) >= 2 and words[0].endswith(b"OFF") and words[1] == b"BINARY"


def _carriage_returns_only(path):
    """Whether the file's first 64 KiB hold a carriage return but no newline: its lines end in
    "\\r" alone. (CRLF files hold both and are read right.)"""
    with open(path, "rb") as f:
        head = f.read(1 << 16)
    return b"\r" in head and b"\n" not in head


@contextlib.contextmanager
def _mapped(path):
    """The file's bytes as a read-only memory map (never read whole), or None for an empty file."""
    with open(path, "rb") as f:
        try:
            data = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ)
        except ValueError:                 # an empty file cannot be mapped
            yield None
            return
        with data:
            yield data


def _obj_comma(path):
    """``(1-based line, its text)`` of the first ``v``, ``vt``, ``vn``, ``vp`` or ``f`` line of
    an OBJ file with a comma before any ``#``, or None. pymeshlab's loader reads each value with
    atof or atoi, which stop at the comma: ``v 1,5 2 3`` came back as (1, 2, 3). Commas are found
    through a memory map (C speed); only lines holding one are looked at."""
    with _mapped(path) as data:
        if data is None:
            return None
        at = data.find(b",")
        while at >= 0:
            start = data.rfind(b"\n", 0, at) + 1
            end = data.find(b"\n", at)
            end = len(data) if end < 0 else end
            line = data[start:end]
            words = line.split(b"#", 1)[0].split()
            if words and words[0] in (b"v", b"vt", b"vn", b"vp", b"f") and b"," in b" ".join(words):
                text = line.decode("ascii", "replace").strip()
                line = int(np.count_nonzero(np.frombuffer(data, dtype=np.uint8, count=start) == 10)) + 1
                return line, text if len(text) <= 80 else text[:77] + "..."
            at = data.find(b",", end)
    return None


#: What pymeshlab's OBJ loader does with a line continued by a backslash, by the kind
#: :func:`_obj_continued_line` finds, and the fix (a vertex misread: built there).
_OBJ_CONTINUED = {
    "other": "loses that line's vertex without a word (a vertex (0, 0, 0) took its place); remove the "
             "backslash",
    "counted": "reads the next line, which starts with a keyword, as part of this vertex, while it counts that "
               "line on its own (the vertex or face it holds was lost and a vertex (0, 0, 0) appended, without "
               "a word; after a 'vt' line so joined the process crashed); remove the backslash",
    "crlf": "misreads the joined line without a word where a line it joins on ends in a Windows line end, CR LF "
            "(it then drops the character before the backslash too: a face was dropped or lost a corner, "
            "'v 1 0 5 \\' then '6' read as 'v 1 0 56'); join the lines into one, or end them in LF alone",
    "glued": "glues the backslash's word to the next line's first word ('f 1 2\\' and '3' were read as "
             "'f 1 23'); put a space before the backslash or join the lines into one",
}
#: A backslash that ends a line (LF or CR LF): pymeshlab's OBJ loader joins the line with the next.
_OBJ_CONTINUES = re.compile(rb"\\\r?\n")


def _obj_continued_line(path):
    """``(1-based line, its text, what pymeshlab makes of it and the fix)`` for the first line of
    an OBJ file that ends in a backslash and that pymeshlab's loader misreads, or None.

    The loader (vcglib ``TokenizeNextLine``) reads a line, drops a carriage return at its end,
    and while the line ends in a backslash removes it and appends the next line, nothing put in
    between (``f 1 2\\`` then ``3`` was read as ``f 1 23``, ``f 1 2 \\`` then ``3`` as ``f 1 2
    3``); where a line so appended ends in a carriage return, it removes one byte more of the
    line before, and the carriage return stays. It counts the vertices beforehand, one per
    ``v`` line as written. Kinds refused (:data:`_OBJ_CONTINUED`): ``"other"``, a line that is
    neither a ``v`` line nor a face (a comment line before a vertex cost that vertex, and a
    vertex (0, 0, 0) was appended in its place, without a word); ``"counted"``, a ``v`` line
    continued on a line that starts with a letter (a ``v``, ``vt`` or ``f`` line, counted on its
    own); ``"crlf"``, a line continued on a line that ends in CR LF (``f 1 2 \\`` then ``3`` CR
    LF: dropped); ``"glued"``, a backslash glued to a word, the next line starting with one
    (the two are read as one); and a ``v`` line whose joined x, y and z are not decimal numbers
    (as a line of its own, see :func:`_obj_bad_coordinate`: ``v 1 0 \\`` then ``# c`` was read
    as (1, 0, 0)). A face or vertex continued over lines that end in LF (the first may end in
    CR LF: ``v 1 0 \\`` CR LF then ``5`` LF was read as (1, 0, 5)) is read right and passes.
    Found through a memory map; only lines ending in a backslash and the lines they join are
    looked at."""
    with _mapped(path) as data:
        if data is None or data.find(b"\\") < 0:      # no backslash (a byte's search: fast)
            return None
        done = 0                                      # the end of the lines joined so far
        for match in _OBJ_CONTINUES.finditer(data):
            if match.start() < done:                  # a line of a join looked at already
                continue
            start = data.rfind(b"\n", 0, match.start()) + 1
            found = _obj_join_problem(data, start, match)
            if isinstance(found, int):
                done = found
                continue
            at, what = found
            line_start = data.rfind(b"\n", 0, at) + 1
            text = data[line_start:at + 1].decode("utf-8", "replace").strip()
            number = int(np.count_nonzero(np.frombuffer(data, dtype=np.uint8, count=line_start) == 10)) + 1
            return number, text if len(text) <= 80 else text[:77] + "...", what
    return None


def _obj_join_problem(data, start, match):
    """The lines pymeshlab's OBJ loader joins from the line at byte ``start`` of ``data``, whose
    backslash and line end ``match`` found: ``(the backslash's byte, what pymeshlab makes of
    them and the fix)`` where it misreads them (see :func:`_obj_continued_line`), else the byte
    after the last of them."""
    first = data[start:match.start()]
    vertex = first[:2] in (b"v ", b"v\t")
    words = first.split()
    if not vertex and (not words or words[0] != b"f"):
        return match.start(), _OBJ_CONTINUED["other"]
    joined = [first]
    at, low = match.start(), match.end()              # the backslash, and the next line's start
    while True:
        newline = data.find(b"\n", low)
        high = len(data) if newline < 0 else newline
        line = data[low:high]
        before = b"".join(joined)[-1:]
        if vertex and line[:1].isalpha():
            return at, _OBJ_CONTINUED["counted"]
        if line.endswith(b"\r"):
            return at, _OBJ_CONTINUED["crlf"]
        if before not in b" \t" and line[:1] not in b" \t":   # (an empty slice is "in" any bytes)
            return at, _OBJ_CONTINUED["glued"]
        if newline < 0 or not line.endswith(b"\\"):
            joined.append(line[:-1] if line.endswith(b"\\") else line)   # the file's last byte: on nothing
            break
        joined.append(line[:-1])                      # continued again
        at, low = high - 1, newline + 1
    if vertex:
        misread = _obj_joined_vertex_problem(b"".join(joined))
        if misread:
            return match.start(), misread
    return high + 1


def _obj_joined_vertex_problem(joined):
    """What pymeshlab's OBJ loader misreads in the ``v`` line ``joined`` (lines it joined at a
    backslash) and the fix, or None: an x, y or z that is not a decimal number, inf or nan (a
    comment glued to the z passes), a comma before any comment, or a control character."""
    words = re.split(rb"[ \t\r]+", joined.strip(b" \t\r"))
    reason = None
    if _CONTROL.search(joined):
        reason = "a control character"
    elif b"," in b" ".join(joined.split(b"#", 1)[0].split()):
        reason = "a number written with a comma (read only up to the comma)"
    for rank, word in enumerate(words[1:4] if reason is None else (), 1):
        number = word.split(b"#", 1)[0] if rank == 3 else word
        if _NUMBER.fullmatch(number) is None:
            reason = ("a comment among its coordinates, whose words pymeshlab reads as coordinates" if b"#" in word
                      else f"the {'xyz'[rank - 1]} coordinate {word.decode('utf-8', 'replace')!r}, which is not a "
                      "decimal number")
            break
    if reason is None:
        return None
    shown = joined.decode("utf-8", "replace").strip()
    shown = shown if len(shown) <= 80 else shown[:77] + "..."
    read = "(" + ", ".join(_atof(word) for word in words[1:4]) + ")"
    return (f"reads the joined line {shown!r} as the vertex {read} without a word: it holds {reason}; write the "
            "vertex on one line with its coordinates as decimal numbers (e.g. -1.5e-3)")


def _obj_indented_vertices(path):
    """``(number, first 1-based line)`` of ``v`` lines with leading blanks in an OBJ file; the
    file is scanned through a memory map, never read whole."""
    with _mapped(path) as data:
        if data is None:
            return 0, None
        starts = [m.start() + 1 for m in re.finditer(rb"\n[ \t]+v[ \t]", data)]
        if re.match(rb"[ \t]+v[ \t]", data):
            starts.insert(0, 0)
        if not starts:
            return 0, None
        return len(starts), data[:starts[0]].count(b"\n") + 1


def _obj_odd_face(path):
    """``(1-based line, character)`` of the first ``f`` line of an OBJ file that pymeshlab's
    loader would misread, or None: ``"."`` for a fractional index (it reads indices with atoi,
    which truncates 2.5 to 2; a whole number written ``2.0`` is read as 2 and passes), ``"#"``
    for a comment whose words it reads as further corners (it splits the line at spaces, tabs
    and carriage returns and knows no comments after a face: a triangle came back with a vertex
    index past the file's vertices). A one-word comment glued to the last index
    (``f 1 2 3#note``) is read right, atoi stopping at the ``#``, and passes. Vectorized over the
    bytes from the first face line on (~0.4 s for a million vertices); only lines holding one of
    the two characters are looked at."""
    with _mapped(path) as data:
        if data is None:
            return None
        heads = (b"\nf ", b"\nf\t") if data.find(b"\t") >= 0 else (b"\nf ",)   # a tab's search is fast
        found = [k + 1 for k in (data.find(head) for head in heads) if k >= 0]
        first = 0 if data[:2] in (b"f ", b"f\t") else min(found, default=-1)
        if first < 0:
            return None
        # up to the end of the last face line: a "#" after it (MeshLab ends its files with
        # "# End of File") is on no face line
        end = data.find(b"\n", max([first] + [data.rfind(head) + 1 for head in heads]))
        end = len(data) if end < 0 else end + 1
        if data.find(b".", first, end) < 0 and data.find(b"#", first, end) < 0:
            return None                                  # none of the two there (fast searches)
    chars = np.fromfile(path, dtype=np.uint8, count=end - first, offset=first)
    odd = _flatnonzero_in_pieces(lambda low, high: (chars[low:high] == 46) | (chars[low:high] == 35),
                                 chars.size)                            # "." and "#"
    if not odd.size:
        return None
    newlines = _flatnonzero_in_pieces(lambda low, high: chars[low:high] == 10, chars.size)
    line = np.searchsorted(newlines, odd)                                # lines after the first face's
    starts = np.concatenate([[0], newlines + 1])[line]
    after = chars[np.minimum(starts + 1, chars.size - 1)]
    hits = np.flatnonzero((chars[starts] == ord("f")) & ((after == 32) | (after == 9)))
    if not hits.size:
        return None
    odd, line = odd[hits], line[hits]
    chars = np.append(chars, np.uint8(10))                               # each line ends in "\n"
    ends = np.append(newlines, chars.size - 1)[line]
    bad_dot, bad_hash = _obj_misread_dots_and_comments(chars, odd, line, ends)
    bad = np.concatenate([line[bad_dot], line[bad_hash]])
    if not bad.size:
        return None
    hit = int(bad.min())
    before = int(np.count_nonzero(np.fromfile(path, dtype=np.uint8, count=first) == 10)) if first else 0
    return before + hit + 1, "." if hit in line[bad_dot] else "#"


def _obj_misread_dots_and_comments(chars, odd, line, ends):
    """Which of the ``"."`` and ``"#"`` at ``odd`` (sorted; on face lines ``line`` ending at
    ``ends``, each line ending in a newline in ``chars``) make pymeshlab misread the face: a
    ``"."`` before the line's first ``"#"`` that is not in a whole number (digits, a point and
    zeros, ``2.0``, between blanks, ``/``, ``#`` or the line's end: atoi reads 2.5 as 2), and a
    line's first ``"#"`` unless it is glued to a digit and the rest of the line is one word
    (``f 1 2 3#note``: atoi stops at the ``#``; a word after a blank is read as a corner).
    Returns two boolean masks over ``odd``. Loops run once per digit or zero of the longest
    number, over the characters found only."""
    is_hash = chars[odd] == 35
    first_hash = np.full(odd.size, np.iinfo(np.int64).max)
    lines_with_hash, first = np.unique(line[is_hash], return_index=True)
    if lines_with_hash.size:
        where = np.searchsorted(lines_with_hash, line)
        has = lines_with_hash[np.minimum(where, lines_with_hash.size - 1)] == line
        first_hash[has] = odd[is_hash][first][where[has]]
    digit = (chars - np.uint8(48)) < 10
    blank = (chars == 32) | (chars == 9) | (chars == 13)
    # a point: digits back to a blank, "/" or a sign, zeros on to a blank, "/", "#" or the end
    dot = ~is_hash & (odd < first_hash)
    back = odd - 1
    whole = dot & digit[back]
    moving = whole.copy()
    while moving.any():
        back[moving] -= 1
        moving &= digit[back]
    sign = (chars[back] == 43) | (chars[back] == 45)
    back[sign] -= 1
    whole &= blank[back] | (chars[back] == 47)
    ahead = odd + 1
    moving = whole & (chars[ahead] == 48)
    while moving.any():
        ahead[moving] += 1
        moving &= chars[ahead] == 48
    whole &= blank[ahead] | np.isin(chars[ahead], (47, 35, 10))
    bad_dot = dot & ~whole
    # a comment: the line's first "#", glued to a digit, then one word at most
    bad_hash = is_hash & (odd == first_hash)
    hashes = np.flatnonzero(bad_hash)
    end = ends[hashes].copy()                                             # drop blanks at the line's end
    moving = blank[end - 1] & (end - 1 > odd[hashes])
    while moving.any():
        end[moving] -= 1
        moving &= blank[end - 1] & (end - 1 > odd[hashes])
    # a blank between the "#" and the last word: np.add.reduceat sums each [#, end) in turn
    bounds = np.column_stack([odd[hashes], end]).ravel()
    blanks = np.add.reduceat(blank, bounds)[0::2] if bounds.size else np.zeros(0, dtype=int)
    bad_hash[hashes] = ~digit[odd[hashes] - 1] | (blanks > 0)
    return bad_dot, bad_hash


# The coordinate check (:func:`_obj_bad_coordinate`, :func:`_off_bad_coordinate`). pymeshlab reads
# each coordinate with atof, which stops at the first character that does not fit and reads what
# it has so far without a word ("0.3abc" is 0.3, "abc", "-" and "." are 0, "1e" and "1d3" are 1,
# "1.2.3" is 1.2) and also reads C's hexadecimal floats ("0x10" is 16, "0x1p3" is 8). A decimal
# number, [+-](digits[.digits] | .digits)[(e|E)[+-]digits], is read right (to the nearest double),
# and so are inf, infinity and nan in any case (pymeshlab drops such vertices, which
# _file_counts.check_loaded reports). The bytes are classed as below; digits are no class: only
# the other bytes are looked at, each with the class of the one before and after it and whether
# digits lie between them, which decides a number's grammar (the table _NUMBER_STEP_OK).
_NL, _SEP, _POINT, _SIGN, _EXP, _HASH, _V, _OTHER = range(8)
_OFF_CLASS = np.full(256, _OTHER, dtype=np.uint8)
_OFF_CLASS[10] = _NL
_OFF_CLASS[[9, 13, 32]] = _SEP                 # tab, carriage return, space: the words' separators
_OFF_CLASS[46] = _POINT
_OFF_CLASS[[43, 45]] = _SIGN
_OFF_CLASS[[69, 101]] = _EXP                   # "E", "e"
_OFF_CLASS[35] = _HASH
_OBJ_CLASS = _OFF_CLASS.copy()
_OBJ_CLASS[118] = _V                           # "v": the keyword, at a line's start only


def _number_step_ok(before, digits_before, this, digits_after, after):
    """Whether the non-digit byte of class ``this``, with ``before`` the class of the non-digit
    byte before it and ``after`` of the one after it (``digits_before`` / ``digits_after``:
    whether digits lie between), fits in a decimal number or between words. A ``"#"`` ends a
    number (what follows in its word is no number's), an other byte in a number fails it."""
    separator = (_NL, _SEP)
    if this in separator:                      # the byte after a word's start
        return {_POINT: True, _SIGN: not digits_after, _EXP: digits_after, _HASH: digits_after,
                _OTHER: False}.get(after, True)
    if this == _POINT:                         # a digit on one side; at most once, before an exponent
        return (digits_before or digits_after) and after in separator + (_EXP, _HASH)
    if this == _SIGN:                          # first in the word, or first in the exponent
        in_exponent = before == _EXP and not digits_before
        if after in separator + (_HASH,):
            return digits_after
        return not in_exponent and (after == _POINT or (after == _EXP and digits_after))
    if this == _EXP:
        return not digits_after if after == _SIGN else digits_after and after in separator + (_HASH,)
    if this == _V:                             # "v" then a blank, first on its line
        return before == _NL and not digits_before and after == _SEP and not digits_after
    return True                                # "#" and others: judged by the bytes before them


#: :func:`_number_step_ok` for ``((before * 2 + digits_before) * 16 + this * 2 + digits_after) * 8
#: + after``.
_NUMBER_STEP_OK = np.array([_number_step_ok(b // 2, b % 2, t // 2, t % 2, a)
                            for b in range(16) for t in range(16) for a in range(8)], dtype=bool)
_ATOF = re.compile(rb"[\x0b\x0c]*([+-]?(?:0[xX](?:[0-9a-fA-F]+\.?[0-9a-fA-F]*|\.[0-9a-fA-F]+)(?:[pP][+-]?[0-9]+)?"
                   rb"|(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|[iI][nN][fF](?:[iI][nN][iI][tT][yY])?"
                   rb"|[nN][aA][nN](?:\([0-9A-Za-z_]*\))?))")
_ATOF_EXAMPLES = ("it reads a value up to the first character that does not fit: '0.3abc' is 0.3, 'abc' and '-' "
                  "are 0, '1.2.3' is 1.2, '1d3' is 1; '0x10' is hexadecimal, 16")


def _atof(word):
    """What C's atof (glibc) reads from the bytes ``word``, as a string ("0.3", "16", "0")."""
    match = _ATOF.match(word)
    if not match:
        return "0"
    number = match.group(1)
    unsigned = number.lstrip(b"+-")
    if unsigned[:2] in (b"0x", b"0X"):
        value = float.fromhex(number.decode())
    elif unsigned[:1] in (b"n", b"N"):
        value = float("nan")
    else:
        value = float(number.split(b"(")[0])
    return f"{value:.15g}"


def _number_failures(chars, classes):
    """The non-digit bytes of ``chars`` (a uint8 array of whole lines, mostly digits) and where a
    word breaks a decimal number's grammar (:func:`_number_step_ok`). Returns ``(at, kind, digits,
    failed)``: the non-digit bytes' positions in ``chars`` (with two newlines put before, at -2
    and -1, and one after, at ``chars.size``), their classes (``classes`` maps bytes to them),
    whether digits follow each before the next, and the indices (into those) of a byte in each
    failing word, in order."""
    inner = np.flatnonzero((chars - np.uint8(48)) > 9)
    at = np.empty(inner.size + 3, dtype=np.int64)
    at[:2] = -2, -1
    at[2:-1] = inner
    at[-1] = chars.size
    kind = np.empty(at.size, dtype=np.uint8)
    kind[:2] = kind[-1] = _NL
    np.take(classes, chars[inner], out=kind[2:-1])
    del inner
    digits = np.subtract(at[1:], at[:-1]) > 1
    step = kind[:-1] << np.uint8(1)                                # class and "digits after", < 16
    step |= digits
    code = step[:-1].astype(np.uint16)
    code <<= 4
    code |= step[1:]
    code <<= 3
    code |= kind[2:]
    failed = np.flatnonzero(~_NUMBER_STEP_OK[code]) + 1
    failed += (kind[failed] == _NL) | (kind[failed] == _SEP)      # a separator's: the word after it
    return at, kind, digits, failed


def _failing_pieces(chars, classes, hashes_fail=False, size=1 << 18):
    """The pieces of ``chars`` (whole lines) that hold a word :func:`_number_failures` fails (or,
    with ``hashes_fail``, a ``"#"``), in order: ``(start, piece, at, kind, digits, failed)`` with
    ``piece`` the bytes ``chars[start:...]`` and the rest what :func:`_number_failures` returns
    for it. The lines are looked at in pieces of about ``size`` bytes, which keeps the arrays in
    the processor's cache (~0.1-0.15 s for the 40-60 MB of a million vertex lines, against ~0.25 s
    at once)."""
    start = 0
    while start < chars.size:
        end = start + size
        while end < chars.size:                                    # cut after a line
            newline = np.flatnonzero(chars[end:end + 4096] == 10)
            if newline.size:
                end += int(newline[0])
                break
            end += 4096
        end = min(end, chars.size)
        piece = chars[start:end]
        at, kind, digits, failed = _number_failures(piece, classes)
        if failed.size or (hashes_fail and (kind == _HASH).any()):
            yield start, piece, at, kind, digits, failed
        start = end + 1


def _word_bounds(kind, at, where):
    """``(first, end)``: the indices of the separators around the non-digit bytes ``where``
    (each in a word) among the bytes of :func:`_number_failures`."""
    separators = np.flatnonzero((kind == _NL) | (kind == _SEP))
    after = np.searchsorted(separators, where)
    return separators[after - 1], separators[after]


def _after_hash(kind, where, word_start):
    """Which of the non-digit bytes ``where`` follow a ``"#"`` in their word (that starts after
    the separator ``word_start``): no part of its number."""
    hashes = np.flatnonzero(kind == _HASH)
    if not hashes.size:
        return np.zeros(where.size, dtype=bool)
    last = hashes[np.maximum(np.searchsorted(hashes, where) - 1, 0)]
    return (last < where) & (last > word_start)


def _special_words(chars, start, end):
    """Which of the words ``chars[start:end]`` are inf, infinity or nan (any case, signed or not):
    read right (pymeshlab then drops the vertex, which check_loaded reports)."""
    start = start + ((chars[start] == 43) | (chars[start] == 45))
    length = end - start
    special = np.zeros(start.size, dtype=bool)
    for word in (b"inf", b"infinity", b"nan"):
        match = length == len(word)
        for j, letter in enumerate(word):
            some = np.flatnonzero(match)
            match[some] = (chars[start[some] + j] | np.uint8(32)) == letter
        special |= match
    return special


_CONTROL = re.compile(rb"[\x00-\x08\x0b\x0c\x0e-\x1f]")
_CONTROLLED_WORD = re.compile(rb"([\x00-\x08\x0b\x0c\x0e-\x1f]*)([^\x00-\x20]+)[\x00-\x08\x0b\x0c\x0e-\x1f\r]*")
_NUMBER = re.compile(rb"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|[+-]?(?:inf|infinity|nan)", re.IGNORECASE)


def _control_word_read_right(word, coordinate):
    """Whether pymeshlab reads the word ``word``, which holds control characters (a byte below 32
    other than a tab, newline or carriage return), as the scan's words have it: one run of other
    characters, which they end (atof stops at them) or begin (for a coordinate only vertical tabs
    and form feeds, which atof skips) and, for a ``coordinate``, a decimal number before any
    ``"#"`` (see :func:`_number_step_ok`). Control characters are no part of a mesh file; this
    keeps the few that pymeshlab reads past from being refused."""
    match = _CONTROLLED_WORD.fullmatch(word)
    if match is None:
        return False
    return not coordinate or (not match.group(1).strip(b"\x0b\x0c") and
                              _NUMBER.fullmatch(match.group(2).split(b"#", 1)[0]) is not None)


def _number_end(chars, kind, at, first, end):
    """The end (in ``chars``) of the number part of the words between the separators ``first``
    and ``end`` (indices of :func:`_number_failures`' bytes): its first ``"#"``, else its end."""
    hashes = np.flatnonzero(kind == _HASH)
    stop = at[end]
    if hashes.size:
        hash_ = hashes[np.minimum(np.searchsorted(hashes, first), hashes.size - 1)]
        stop = np.where((hash_ > first) & (hash_ < end), at[hash_], stop)
    return stop


def _obj_bad_coordinate(path):
    """``(1-based line, its text, message)`` for the first ``v`` line of an OBJ file whose x, y or
    z pymeshlab's loader would misread (not a decimal number, inf or nan; a ``"#"`` before the z:
    the comment's words are read as coordinates), or None. Only the bytes from the first ``v``
    line to the last are looked at, and of those the ones that are not digits; the words that
    fail (normally none) are then placed on their lines, keeping those in a ``v`` line's first
    three values (not its colours or comment). Indented ``v`` lines must have been refused."""
    with _mapped(path) as data:
        if data is None:
            return None
        heads = (b"\nv ", b"\nv\t") if data.find(b"\t") >= 0 else (b"\nv ",)
        first = 0 if data[:2] in (b"v ", b"v\t") else min(
            (k + 1 for k in (data.find(head) for head in heads) if k >= 0), default=-1)
        if first < 0:
            return None
        end = data.find(b"\n", max([first] + [data.rfind(head) + 1 for head in heads]))   # the last v line's
        end = len(data) if end < 0 else end
        chars = np.frombuffer(data, dtype=np.uint8)
        pieces = _failing_pieces(chars[first:end], _OBJ_CLASS, hashes_fail=True)
        found = numbers = None
        try:
            for piece, *numbers in pieces:
                found = _obj_bad_coordinate_in(*numbers)
                if found is not None:
                    break
            if found is None:
                return None
            start, stop, rank, comment, lines_before = found
            start, stop = first + piece + start, first + piece + stop
            line = int(np.count_nonzero(chars[:first + piece] == 10)) + lines_before + 1
            text = bytes(data[start:stop])
        finally:                                               # the map closes: no array may view it
            pieces.close()
            del chars, pieces, numbers
    words = re.split(rb"[ \t\r]+", text.strip(b" \t\r"))
    shown = text.decode("utf-8", "replace").strip()
    shown = shown if len(shown) <= 80 else shown[:77] + "..."
    read = "(" + ", ".join(_atof(word) for word in words[1:4]) + ")"
    if comment:
        return line, shown, (f"has a comment among its coordinates, whose words (the '#' too, as 0) pymeshlab's OBJ "
                             f"loader reads as coordinates (the line was read as the vertex {read}); move the "
                             "comment after the third coordinate or to a line of its own")
    word = words[rank].decode("utf-8", "replace")
    return line, shown, (f"has the {'xyz'[rank - 1]} coordinate {word!r}, which is not a decimal number: "
                         f"pymeshlab's OBJ loader reads it as {_atof(words[rank])} without a word (the line was "
                         f"read as the vertex {read}; {_ATOF_EXAMPLES}); write the coordinates as decimal "
                         "numbers (e.g. -1.5e-3)")


def _obj_bad_coordinate_in(chars, at, kind, digits, failed):
    """:func:`_obj_bad_coordinate` on the bytes ``chars`` (whole lines; the rest: what
    :func:`_number_failures` returns for them): ``(start, end, value, comment, line)`` of the
    first bad ``v`` line: its bounds in ``chars``, the bad value's rank (1: x, 2: y, 3: z),
    whether it is a comment, and the number of lines before it; or None."""
    hashes = np.flatnonzero(kind == _HASH)
    if not failed.size and not hashes.size:
        return None
    separator = (kind == _NL) | (kind == _SEP)
    begins = separator[:-1] & (digits | ~separator[1:])     # a word starts after the byte
    words_before = np.zeros(kind.size, dtype=np.int64)
    np.cumsum(begins, out=words_before[1:])
    newlines = np.flatnonzero(kind == _NL)

    def placed(where):
        # the line's newline, and the rank of the word holding each byte (0: the "v")
        newline = newlines[np.searchsorted(newlines, where) - 1]
        rank = words_before[where] - words_before[newline] - 1
        vertex = (kind[newline + 1] == _V) & ~digits[newline] & ~digits[newline + 1] & \
            (kind[newline + 2] == _SEP) & (chars[at[newline + 2]] != 13)
        return newline, rank, vertex

    newline, rank, vertex = placed(failed)
    keep = vertex & (rank >= 1) & (rank <= 3)
    failed, newline, rank = failed[keep], newline[keep], rank[keep]
    if failed.size:
        first, end = _word_bounds(kind, at, failed)
        keep = ~_after_hash(kind, failed, first)
        failed, newline, rank, first, end = failed[keep], newline[keep], rank[keep], first[keep], end[keep]
        keep = ~_special_words(chars, at[first] + 1, _number_end(chars, kind, at, first, end))
        # a backslash ending the line, alone or after a value ('v 1 0\\' then ' 5': read as
        # (1, 0, 5)): a v line continued on the next, whose joined values _obj_continued_line has
        # checked (and refused where the backslash glues two words)
        last = np.minimum(end + 1, kind.size - 1)
        keep &= ~((chars[at[end] - 1] == 92) &
                  ((kind[end] == _NL) | ((kind[last] == _NL) & (at[last] == at[end] + 1) &
                                         (chars[np.minimum(at[end], chars.size - 1)] == 13))))
        failed, newline, rank, first, end = failed[keep], newline[keep], rank[keep], first[keep], end[keep]
    hash_line, hash_rank, hash_vertex = placed(hashes)
    keep = hash_vertex & (hash_rank >= 1) & (hash_rank <= 2)   # a comment before the z
    hashes, hash_line = hashes[keep], hash_line[keep]
    for k in range(failed.size):                               # the few words that fail, in order
        if hashes.size and hashes[0] < failed[k]:
            break
        word = bytes(chars[at[first[k]] + 1:at[end[k]]])
        if _CONTROL.search(word) and _control_word_read_right(word, True):
            continue
        line_end = newlines[np.searchsorted(newlines, failed[k])]
        return (int(at[newline[k]]) + 1, int(at[line_end]), int(rank[k]), word.startswith(b"#"),
                int(np.searchsorted(newlines, newline[k])) - 1)
    if not hashes.size:
        return None
    line_end = newlines[np.searchsorted(newlines, hashes[0])]
    return int(at[hash_line[0]]) + 1, int(at[line_end]), 0, True, int(np.searchsorted(newlines, hash_line[0])) - 1


def _off_bad_coordinate(chars, token_starts, token_ends, starts, ends, rows, per_vertex, colours, first_line,
                        text):
    """What is wrong with the x, y and z values of an ASCII OFF file's vertex rows ``rows`` (the
    body's line numbers; whole vertices each, or in a plain file a stream of them), or None: a
    value that is not a decimal number, inf or nan (pymeshlab reads each with atof: see
    :func:`_number_failures`), or a control character on a row (the reader splits words at spaces
    and tabs only, so it is part of a word to it, which the scan's words are not). The normals,
    texture coordinates and colours after them are not looked at (not read into the mesh we keep).
    Only the rows' bytes that are not digits are looked at, and of those only the failing words'."""
    if not rows.size:
        return None
    low = int(starts[rows[0]])
    for piece, region, at, kind, _, failed in _failing_pieces(chars[low:int(ends[rows[-1]])], _OFF_CLASS):
        problem = _off_bad_coordinate_in(chars, low + piece, region, at, kind, failed, token_starts, token_ends,
                                         starts, rows, per_vertex, colours, first_line, text)
        if problem:
            return problem
    return None


def _off_bad_coordinate_in(chars, low, region, at, kind, failed, token_starts, token_ends, starts, rows,
                           per_vertex, colours, first_line, text):
    """:func:`_off_bad_coordinate` on the bytes ``region``, ``chars[low:...]`` (whole lines;
    ``at``, ``kind``, ``failed``: what :func:`_number_failures` returns for them)."""
    first, end = _word_bounds(kind, at, failed)
    where = at[failed] + low                                   # in the body
    line = np.searchsorted(starts, where, side="right") - 1
    token = np.searchsorted(token_starts, where, side="right") - 1
    inside = (token >= 0) & (where < token_ends[np.maximum(token, 0)])
    # the scan's word in each failing one (a control character is none of them)
    token = np.where(inside, token, np.searchsorted(token_starts, at[first] + 1 + low))

    def value(token):
        # (which value of its vertex, which vertex) the scan's word ``token`` is
        if colours:                                            # one vertex a row: x y z first
            row = np.searchsorted(starts, token_starts[token], side="right") - 1
            return token - np.searchsorted(token_starts, starts[row]), np.searchsorted(rows, row)
        stream = token - np.searchsorted(token_starts, starts[rows[0]])    # a stream of per_vertex each
        return stream % per_vertex, stream // per_vertex

    special = _special_words(region, at[first] + 1, _number_end(region, kind, at, first, end))
    coordinate = inside & (value(np.minimum(token, token_starts.size - 1))[0] < 3) & ~special & \
        ~_after_hash(kind, failed, first)
    control = (chars[where] < 32) & np.isin(line, rows)       # on a vertex row
    for k in np.flatnonzero(coordinate | control):             # the few words that fail, in order
        word = bytes(region[at[first[k]] + 1:at[end[k]]])
        start = low + at[first[k]] + 1
        scan_word = np.searchsorted(token_starts, start)       # the scan's first word in it, if any
        which, vertex = value(min(scan_word, token_starts.size - 1))
        row = f"line {first_line + line[k]} ({text(line[k])!r})"
        if _CONTROL.search(word):
            if colours and which >= 3:                         # a colour: the row is one vertex anyway
                continue
            if scan_word < token_starts.size and token_starts[scan_word] < start + len(word) and \
                    _control_word_read_right(word, which < 3):
                continue
            return (f"{row} holds the control character {bytes(chars[where[k]:where[k] + 1])!r}, which "
                    "pymeshlab's OFF reader takes for part of a value (it splits the values at spaces and tabs "
                    "only), shifting or misreading them; remove it")
        return (f"{row} holds the {'xyz'[which]} coordinate {word.decode('utf-8', 'replace')!r} of vertex "
                f"{vertex}, which is not a decimal number: pymeshlab's OFF reader reads it as {_atof(word)} "
                f"without a word ({_ATOF_EXAMPLES}); write the coordinates as decimal numbers (e.g. -1.5e-3)")
    return None


def _word_edges(visible, piece=1 << 18):
    """Where runs of True in the boolean array ``visible`` start and end, alternating (an end is
    the index after a run's last element; the array's ends count as False). Computed in pieces of
    ``piece`` elements, counted first so that the result is allocated once: the arrays stay in
    the processor's cache (several times as fast over the 100 MB of a million-vertex file)."""
    size = visible.size
    first = bool(size and visible[0])
    last = bool(size and visible[-1])
    pieces = [(low, min(low + piece, size - 1)) for low in range(0, max(size - 1, 0), piece)]
    counts = [int(np.count_nonzero(visible[low + 1:high + 1] != visible[low:high])) for low, high in pieces]
    edges = np.empty(first + sum(counts) + last, dtype=np.intp)
    if first:
        edges[0] = 0
    if last:
        edges[-1] = size
    at = int(first)
    for (low, high), count in zip(pieces, counts):
        out = edges[at:at + count]
        out[:] = np.flatnonzero(visible[low + 1:high + 1] != visible[low:high])
        out += low + 1
        at += count
    return edges


def _flatnonzero_in_pieces(mask, size, offset=0, piece=1 << 18):
    """``np.flatnonzero(mask(0, size)) + offset``, with ``mask(low, high)`` the boolean mask of
    ``[low, high)``, computed in pieces of ``piece`` elements: their arrays stay in the
    processor's cache (~3 times as fast over the 100 MB of a million-vertex file)."""
    found = []
    for low in range(0, size, piece):
        where = np.flatnonzero(mask(low, min(low + piece, size)))
        where += low + offset
        found.append(where)
    return np.concatenate(found) if found else np.zeros(0, dtype=np.intp)


def _off_rows_problem(path, made=None):
    """What is wrong with the rows of an ASCII OFF file, or None (also where it cannot tell: the
    loader and :func:`check_loaded` then judge): counts in the header that are not whole numbers,
    lines of blanks only among the rows, comments among the vertex values, vertex rows pymeshlab
    would read shifted (:func:`_off_vertex_rows_problem`), face rows that are not a count and
    that many whole-number indices, faces with indices out of range.

    The model is pymeshlab's OFF reader (vcglib ``ImporterOFF``): it skips empty lines and lines
    that start with ``#`` or a carriage return, and splits the others into words at spaces and
    tabs (a ``#`` further on is a word like any other). Vertex values are one stream of words
    across lines (plus, in ``COFF`` files, the rest of the line as colour); each face is the next
    line, read with atoi.

    Vectorized over the bytes (~1 s for a million vertices, against ~4.5 s for pymeshlab's own
    read): a face line whose index tokens are all unsigned digits, shorter than the vertex
    count's digits (or as long and below it), holds no index out of range, so only the other
    lines (normally none) are parsed one by one. Where nothing is wrong and ``made`` is a list,
    the number of triangles the faces make (a polygon of k vertices k - 2) is appended to it, and
    then the faces' vertex counts (an int array, in file order)."""
    with open(path, "rb") as f:
        data = f.read()
    header = _off_header(io.BytesIO(data))
    if header is None:
        return None
    counts, offset, keyword = header
    nv, nf = (_whole(word) for word in counts)
    if nv is None or nf is None or nv < 0 or nf < 0:
        # atoi reads 4.5 as 4 and 1e3 as 1; a negative count is read as a huge unsigned one
        written = " ".join(word.decode("ascii", "replace") for word in counts)
        return (f"the header's vertex and face counts {written!r} are not both whole numbers, which "
                "pymeshlab's reader would not read as written (it stops at the first character that "
                "is not a digit)")
    if nf == 0:
        return None                                            # no faces: read_mesh refuses it
    first_line = data[:offset].count(b"\n") + 1                # the body's first line, 1-based
    body = memoryview(data)[offset:]                           # no copy
    chars = np.frombuffer(body, dtype=np.uint8)
    newlines = _flatnonzero_in_pieces(lambda low, high: chars[low:high] == 10, chars.size)
    starts = np.concatenate([[0], newlines + 1])
    ends = np.concatenate([newlines, [chars.size]])
    filled = ends > starts
    lead = np.zeros(starts.size, dtype=np.uint8)
    lead[filled] = chars[starts[filled]]
    visible = chars > 32
    skipped = np.flatnonzero(filled & ((lead == 35) | (lead == 13)))    # "#" or "\r" first: skipped
    if skipped.size:
        visible = visible.copy()
        for start, end in zip(starts[skipped].tolist(), ends[skipped].tolist()):
            visible[start:end] = False
    edges = _word_edges(visible)                               # word starts and ends, alternating
    token_starts, token_ends = edges[0::2], edges[1::2]
    per_line = np.diff(np.append(np.searchsorted(token_starts, starts), token_starts.size))
    rows = np.flatnonzero(per_line)                            # the lines that hold words
    per_row = per_line[rows]

    def text(line):
        return bytes(body[starts[line]:ends[line]]).decode("utf-8", "replace").strip()

    def too_short():
        # pymeshlab fills the missing rows from what follows: a triangle came back twice
        return (f"the header declares {counted(nv, 'vertex', 'vertices')} and {counted(nf, 'face')}, but the file "
                f"holds {counted(rows.size, 'row')} "
                f"after it (truncated, or the counts are wrong)" +
                ("" if colours else _split_note(rows[:taken], per_row[:taken], per_vertex, first_line)))

    colours = "C" in keyword[:-3]
    per_vertex = 3 + 3 * ("N" in keyword[:-3]) + 2 * ("ST" in keyword[:-3])   # streamed values
    if colours:
        taken = min(nv, rows.size)                             # one row each
    elif rows.size >= nv and (per_row[:nv] == per_vertex).all():
        taken = nv                                             # the usual file: one row each
    else:                                                      # rows, cumulated, until the values
        taken = min(int(np.searchsorted(np.cumsum(per_row), per_vertex * nv)) + 1, rows.size)
    # the last line pymeshlab reads, or the last line there is
    last = rows[taken + nf - 1] if taken + nf <= rows.size else starts.size - 1

    # a line of blanks is no empty line to pymeshlab: among the vertices (but as the first line
    # after the header) it stops with "Invalid file", among the faces it read the face before
    # it once more, without a word
    read = filled & (lead != 35) & (lead != 13)               # the lines pymeshlab does not skip
    blank = np.flatnonzero(read[:last] & (per_line[:last] == 0))
    blank = blank[blank != np.flatnonzero(read)[0]] if blank.size else blank
    if blank.size:
        return (f"line {first_line + blank[0]} holds nothing but blanks (spaces or tabs), which pymeshlab's "
                "OFF reader, unlike an empty line, does not skip (among the vertices it stops with "
                "'Invalid file'; among the faces it reads the face before it a second time); delete "
                f"{'those lines' if blank.size > 1 else 'that line'} ({blank.size} in all)")
    comma = _off_comma(body, chars, visible, starts, rows[:taken + nf], first_line) if data.find(b",", offset) >= 0 \
        else None
    if comma:
        return comma
    problem = _off_vertex_rows_problem(chars if data.find(b"#", offset) >= 0 else None, visible,
                                       token_starts, starts, rows[:taken], per_row[:taken], nv, per_vertex,
                                       colours, keyword, first_line, text)
    if problem:
        return problem
    if rows.size < taken + nf or (not colours and per_row[:taken].sum() < per_vertex * nv):
        return too_short()
    problem = _off_bad_coordinate(chars, token_starts, token_ends, starts, ends, rows[:taken], per_vertex, colours,
                                  first_line, text)
    if problem:
        return problem
    after = rows[taken + nf:]
    # after the faces nothing is read: an indented comment there is a comment too
    after = after[chars[token_starts[np.searchsorted(token_starts, starts[after])]] != 35] if after.size else after
    if after.size:
        # pymeshlab stops after the declared faces: the rest was dropped without a word
        extra = after[0]
        return (f"the header declares {counted(nv, 'vertex', 'vertices')} and {counted(nf, 'face')}, but "
                f"{after.size} more {'row follows' if after.size == 1 else 'rows follow'} "
                f"the last face (first: line {first_line + extra}, {text(extra)!r}), which pymeshlab's OFF reader "
                "ignores without a word; fix the header's counts or remove those rows (comments and empty lines "
                "may follow the faces)")
    faces = rows[taken:taken + nf]
    per_face = per_row[taken:taken + nf]
    first, end = int(starts[faces[0]]), int(ends[faces[-1]])
    low, high = np.searchsorted(token_starts, [first, end])
    token_starts, token_ends = token_starts[low:high], token_ends[low:high]
    line_starts = starts[faces]
    # the vertex count k: a one-digit first token, or parsed below
    head = np.concatenate([[0], np.cumsum(per_face)[:-1]])
    one_digit = (token_ends[head] - token_starts[head] == 1) & (chars[token_starts[head]] >= 51) & \
        (chars[token_starts[head]] <= 57)
    k = np.where(one_digit, chars[token_starts[head]].astype(np.int64) - 48, 0)
    suspect = ~one_digit | (per_face < k + 1)
    # indices only (rank 1 .. k in their row): float colours after them are longer than the
    # vertex count's digits and sent every face of a coloured 1M-vertex file to the loop below
    if (per_face == k + 1).all():                              # the usual: every token after a count
        index = np.ones(token_starts.size, dtype=bool)
        index[head] = False
    else:
        owner = np.repeat(np.arange(nf), per_face)
        rank = np.arange(token_starts.size) - head[owner]
        index = (rank >= 1) & (rank <= k[owner])
        del owner, rank
    odd = []                                                   # in pieces: their arrays stay in cache
    for low in range(0, index.size, 1 << 16):
        idx = np.flatnonzero(index[low:low + (1 << 16)])
        idx += low
        at = token_starts[idx]
        odd.append(at[_maybe_out_of_range(chars, at, token_ends[idx], nv)])
    odd = np.concatenate(odd) if odd else np.zeros(0, dtype=np.intp)
    suspect[np.searchsorted(line_starts, odd, side="right") - 1] = True
    # a character other than a digit in the count or an index (atoi reads 2.5 as 2, "#" and "x"
    # as 0); those in colours after the indices do not matter
    other = _flatnonzero_in_pieces(lambda low, high: visible[first + low:first + high] &
                                   (chars[first + low:first + high] - np.uint8(48) >= 10), end - first, first)
    if other.size:
        token = np.searchsorted(token_starts, other, side="right") - 1
        face = np.searchsorted(head, token, side="right") - 1
        suspect[face[token - head[face] <= k[face]]] = True
    bad = []
    for face in np.flatnonzero(suspect):
        words = bytes(body[starts[faces[face]]:ends[faces[face]]]).split()
        count = _whole(words[0].split(b"#", 1)[0])
        index = None
        # atoi stops at a "#" glued to a word ("2#x" is 2); a "#" word is read as 0, and so are
        # the words after a "#" if they stand where indices belong
        if count is not None and count >= 1 and len(words) > count and \
                not any(b"#" in word for word in words[:count]):
            index = [_whole(word.split(b"#", 1)[0]) for word in words[1:count + 1]]
        if index is None or None in index:
            # pymeshlab reads OFF as one stream of numbers: a short or unreadable face row
            # shifts every later face (a two-value row came back as a duplicated triangle)
            return (f"face {face} is the row {text(faces[face])!r}, which is not a vertex count followed "
                    "by that many integer vertex indices (whole numbers: pymeshlab's reader takes 2.5 "
                    "as 2)")
        k[face] = count
        if min(index) < 0 or max(index) >= nv:
            bad.append((face, index))
    if bad:
        return (f"{counted(len(bad), 'face', verb='use')} vertex indices outside the file's {nv} vertices "
                f"(first: face {bad[0][0]}, {bad[0][1]})")
    few = np.flatnonzero(k < 3)
    if few.size:
        return (f"face {few[0]} is the row {text(faces[few[0]])!r}, of {k[few[0]]} vertices, which pymeshlab's OFF "
                f"reader drops without a word ({few.size} such faces); a face needs 3 or more vertices: fix or "
                "remove it and the header's face count")
    if made is not None:
        made += [int((k - 2).sum()), k]
    return None


def _off_comma(body, chars, visible, starts, rows, first_line):
    """The message for the first comma in a word of an OFF file's rows ``rows`` (body line
    numbers of the lines pymeshlab reads: the vertices and faces) before any ``#`` on its line,
    or None. pymeshlab reads the values with atof and atoi, which stop at the comma: the row
    ``1,5 2 3`` came back as the vertex (1, 2, 3). Only the commas are looked at."""
    commas = np.flatnonzero(visible & (chars == 44))
    if not commas.size or not rows.size:
        return None
    line = np.searchsorted(starts, commas, side="right") - 1
    commas = commas[np.isin(line, rows)]
    for at in commas.tolist():
        row = int(np.searchsorted(starts, at, side="right") - 1)
        if b"#" in bytes(body[starts[row]:at]):
            continue                                           # in a comment's words
        words = bytes(body[starts[row]:]).split(b"\n", 1)[0].decode("ascii", "replace").strip()
        return (f"line {first_line + row} ({words[:80]!r}) writes a number with a comma, which pymeshlab's OFF "
                "reader reads only up to the comma without a word (the row '1,5 2 3' was read as the vertex "
                "(1, 2, 3)); write decimals with a point")
    return None


def _off_vertex_rows_problem(chars, visible, token_starts, starts, rows, per_row, nv, per_vertex, colours,
                             keyword, first_line, text):
    """What is wrong with an OFF file's vertex rows (the body's line numbers ``rows`` holding
    ``per_row`` words each, as many as pymeshlab reads for ``nv`` vertices), or None. ``chars``
    is the body's bytes, None where it holds no ``#`` (no comment to look for).

    pymeshlab reads the values of a vertex (x y z, then the normal with ``N``, then the texture
    coordinates with ``ST``: ``per_vertex`` in all) as one stream of words across lines, so a
    row with a value too many or too few shifts every later coordinate without a word. Without
    ``C`` a vertex may thus be split over lines as long as those lines hold exactly its values
    and no other vertex's: each vertex starts a line, and ends one. That tells a split vertex
    (``1 2`` then ``3``) from rows with values missing or extra (``1 2`` then ``3 4 5 6`` is
    refused), and a wrong split would also leave the rows after the vertices too few for the
    faces. With ``C`` (``COFF``) the rest of the line after those values is the colour (0 to 4
    values), so each vertex must stand on its own line. A comment among the values (a ``#``
    word on a line that does not start with ``#``) is read as a number, too."""
    what = {3: "x y z", 6: "x y z and the normal", 5: "x y z and the texture coordinates",
            8: "x y z, the normal and the texture coordinates"}[per_vertex]
    if chars is not None and rows.size:                        # chars: None where the file has no "#"
        low, high = starts[rows[0]], (starts[rows[-1] + 1] if rows[-1] + 1 < starts.size else chars.size)
        hashes = np.flatnonzero(chars[low:high] == 35) + low
        hashes = hashes[visible[hashes] & ((hashes == 0) | ~visible[np.maximum(hashes - 1, 0)])]
        if hashes.size and colours:                            # a word within the vertex's values?
            line = np.searchsorted(starts, hashes, side="right") - 1
            rank = np.searchsorted(token_starts, hashes) - np.searchsorted(token_starts, starts[line])
            hashes = hashes[rank < per_vertex]
        if hashes.size:
            line = int(np.searchsorted(starts, hashes[0], side="right") - 1)
            return (f"line {first_line + line} ({text(line)!r}) has a comment among the vertex values: "
                    "pymeshlab's OFF reader skips only lines that start with '#' and reads the words of "
                    "any other comment as numbers, shifting every later coordinate; move the comment to "
                    "a line of its own")
    if colours:
        short = np.flatnonzero(per_row < per_vertex)
        long = np.flatnonzero(per_row > per_vertex + 4)
        if short.size:
            return (f"{short.size} vertex rows hold fewer than {per_vertex} values (first: vertex {short[0]}, "
                    f"{per_row[short[0]]} values) on line {first_line + rows[short[0]]} "
                    f"({text(rows[short[0]])!r}), which would shift every later coordinate: in a "
                    f"{keyword} file each vertex stands on its own line, {what} first, then its colour")
        if long.size:
            return (f"{long.size} vertex rows hold more than {per_vertex + 4} values (first: vertex "
                    f"{long[0]}, {per_row[long[0]]} values) on line {first_line + rows[long[0]]} "
                    f"({text(rows[long[0]])!r}): {what}, then at most 4 colour values")
        return None
    total = np.cumsum(per_row)
    before = total - per_row
    straddle = np.flatnonzero(before // per_vertex != (total - 1) // per_vertex)
    if not straddle.size:
        return None
    vertex = int(before[straddle[0]] // per_vertex)            # its values run past a row's end
    row = int(np.searchsorted(total, vertex * per_vertex, side="right"))   # where it starts
    count = np.count_nonzero(per_row[row:max(nv, row + 1)] != per_vertex)
    return (f"{count} vertex rows hold a number of values other than {per_vertex} ({what}) (first: vertex "
            f"{vertex}, {per_row[row]} values) on line {first_line + rows[row]} ({text(rows[row])!r}), which "
            f"would shift every later coordinate; a{' plain' if keyword == 'OFF' else ''} {keyword} file is "
            "read as one stream of numbers" + (" (colours need COFF)" if keyword == "OFF" else "") +
            f", so a vertex may be split over lines only if those lines hold exactly its {per_vertex} values" +
            _split_note(rows[:row], per_row[:row], per_vertex, first_line))


def _split_note(rows, per_row, per_vertex, first_line):
    """Where vertex rows ``rows`` (body line numbers, ``per_row`` values each, whole vertices)
    hold a vertex split over lines, a note naming the first such lines, else ``""``: rows with
    values missing that happen to add up to a vertex are read as one, which shows only later."""
    split = np.flatnonzero(per_row != per_vertex)
    if not split.size:
        return ""
    total = np.cumsum(per_row)
    start = split[0]                                           # the rows before it hold whole vertices
    end = int(np.searchsorted(total, total[start] - per_row[start] + per_vertex))
    if end < rows.size:
        return (f" (lines {first_line + rows[start]}-{first_line + rows[end]} were read as one vertex split "
                "over them; if they are rows with values missing, fix those)")
    return (f" (line {first_line + rows[start]} was read as the start of a vertex split over lines; if it is "
            "a row with values missing, fix it)")


def _maybe_out_of_range(chars, starts, ends, nv):
    """Tokens that may not be a vertex index below ``nv``: signed ones, ones with more digits
    than ``nv``, and ones with as many whose value is not below it (or that are not digits)."""
    length = ends - starts
    width = len(str(nv))
    suspect = (chars[starts] == 45) | (length > width)               # 45: "-"
    same = np.flatnonzero(length == width)
    value = np.zeros(same.size, dtype=np.int64)
    digit_only = np.ones(same.size, dtype=bool)
    for j in range(width):
        digit = chars[starts[same] + j].astype(np.int64) - 48
        digit_only &= (digit >= 0) & (digit <= 9)
        value = value * 10 + digit
    suspect[same[~digit_only | (value >= nv)]] = True
    return suspect


#: Per number of digits d (0 to 8): the mask of a uint64's top d bytes.
_TOP_BYTES = np.array([((1 << 8 * d) - 1) << (64 - 8 * d) for d in range(9)], dtype=np.uint64)


def _whole_values(chars, ends, digits, plain):
    """The values of the words of ``digits`` digits ending at ``ends`` in ``chars`` (uint8), where
    ``plain`` (1 to 18 digits, nothing else); 0 elsewhere. A word of up to 8 digits is read from the
    8 bytes that end it as one little-endian uint64 (the bytes before it masked to zeros, then the
    digits paired, 2 to 4 to 8, by three multiplications), longer ones a digit at a time."""
    short = plain & (digits <= 8)
    every = bool(short.all())                                     # the usual: no gathers needed
    which = slice(None) if every else np.flatnonzero(short)
    padded = np.zeros(chars.size + 8, dtype=np.uint8)
    padded[8:] = chars
    windows = np.ndarray((chars.size + 1,), dtype="<u8", buffer=padded, strides=(1,))   # the 8 bytes before each
    word = windows[ends[which]]
    word &= _TOP_BYTES[digits[which]]
    word &= np.uint64(0x0F0F0F0F0F0F0F0F)
    word *= np.uint64((10 << 8) + 1)
    word >>= np.uint64(8)
    word &= np.uint64(0x00FF00FF00FF00FF)
    word *= np.uint64((100 << 16) + 1)
    word >>= np.uint64(16)
    word &= np.uint64(0x0000FFFF0000FFFF)
    word *= np.uint64((10000 << 32) + 1)
    word >>= np.uint64(32)
    if every:
        return word.view(np.int64)
    values = np.zeros(ends.size, dtype=np.int64)
    values[which] = word
    long = np.flatnonzero(plain & (digits > 8))                 # normally none
    for j in range(int(digits[long].max(initial=0))):
        digit = chars[np.maximum(ends[long] - 1 - j, 0)].astype(np.int64) - 48
        values[long] += np.where(digits[long] > j, digit * 10 ** j, 0)
    return values


_OBJ_WHOLE_INDEX = re.compile(rb"[+-]?[0-9]+(?:\.0*)?")


def _obj_face_indices(path, size=1 << 20, sizes=None, counts=None):
    """``(problem, triangles)`` for the faces of an OBJ file: the message for the first face
    whose vertex index pymeshlab's loader would read as another vertex or write out of bounds
    with, or a face of fewer than 3 corners (dropped without a word), else None; and the number
    of triangles the faces make (a polygon of k corners k - 2).

    A corner's vertex index is its word up to the first ``/`` or ``#``. Positive indices count
    from 1 to the file's number of ``v`` lines; negative ones back from the vertex before the
    face (-1 is the last ``v`` line above it). pymeshlab reads the index with atoi and without a
    range check: 0 or one past the last vertex wrote out of bounds (the process crashed at exit),
    -9 with 5 vertices and 4294967299 (2**32 + 3) named real vertices. A face line is one whose
    first word is ``f`` (pymeshlab reads indented ones too). Vectorized over the bytes in pieces
    of about ``size`` bytes (whole lines), each copied out of a memory map (~0.7 s for a million
    vertices, against ~2 s for pymeshlab's read); only words that are not plain digits are
    looked at one by one. Where ``sizes`` is a list, each piece's faces' corner counts (int
    arrays, in file order) are appended to it; where ``counts`` is a list and nothing is wrong,
    ``(v lines, f lines)`` as :func:`curvdetail._file_counts._obj_counts` counts them (lines that
    start with ``v`` or ``f`` and a space or tab, before any continued lines are joined)."""
    triangles = 0
    vertices_before = 0                            # v lines before the piece
    lines_before = 0
    highest = []                                   # per piece: (largest index, its start, v lines, lines before)
    raw = [0, 0]                                   # v and f lines as _obj_counts counts them
    with _mapped(path) as data:
        if data is None:
            return None, None
        for low, high in _obj_pieces(data, size):
            piece = data[low:high]
            joined, numbers = _joined(piece)
            if numbers is not None:                # lines were joined: count the piece's own lines
                head = b"\n" + piece              # (it starts a line)
                raw[0] += head.count(b"\nv ") + head.count(b"\nv\t")
                raw[1] += head.count(b"\nf ") + head.count(b"\nf\t")
            problem, made, vertex_lines, lines, largest = _obj_face_indices_in(
                joined, numbers, None, vertices_before, lines_before, sizes, None if numbers is not None else raw)
            if problem:
                return problem, None
            triangles += made
            highest.append((largest, low, high, vertices_before, lines_before))
            vertices_before += vertex_lines
            lines_before += lines
        # positive indices are checked against the file's count once it is known: the first piece
        # with one past it is looked at again
        for largest, low, high, before, lines in highest:
            if largest > vertices_before:
                return _obj_face_indices_in(*_joined(data[low:high]), vertices_before, before, lines)[0], None
    if counts is not None:
        counts.append(tuple(raw))
    return None, triangles


def _obj_pieces(data, size):
    """``(low, high)``: the byte ranges of ``data`` (an OBJ file's bytes) in which
    :func:`_obj_face_indices` reads it, about ``size`` bytes each and ending after a line that
    is not continued by a backslash (the last one at the file's end)."""
    low = 0
    while low < len(data):
        high = min(low + size, len(data))
        if high < len(data):
            cut = data.rfind(b"\n", low, high)
            high = cut + 1 if cut >= 0 else (data.find(b"\n", high) + 1 or len(data))
            while high < len(data) and (data[high - 2:high] == b"\\\n" or data[high - 3:high] == b"\\\r\n"):
                high = data.find(b"\n", high) + 1 or len(data)       # a continued line stays whole
        yield low, high
        low = high


def _obj_face_line(path, face, size=1 << 20):
    """The 1-based line of an OBJ file on which its face ``face`` (0-based, counting the faces in
    file order as :func:`_obj_face_indices` does: lines whose first word is ``f``, continued
    lines joined) starts, or None where the file has fewer faces. For messages: it reads the
    file once more, vectorized over the bytes of each piece up to the face's."""
    lines_before = 0
    with _mapped(path) as data:
        if data is None:
            return None
        for low, high in _obj_pieces(data, size):
            piece, numbers = _joined(data[low:high])
            if not piece.endswith(b"\n"):
                piece += b"\n"
            chars = np.frombuffer(piece, dtype=np.uint8)
            newlines = np.flatnonzero(chars == 10)
            starts = np.concatenate([[0], newlines[:-1] + 1])
            visible = np.flatnonzero(chars > 32)
            first = visible[np.minimum(np.searchsorted(visible, starts), max(visible.size - 1, 0))] \
                if visible.size else newlines                          # each line's first word
            faces = np.flatnonzero((first >= starts) & (first < newlines) & (chars[first] == 102) &
                                   (chars[np.minimum(first + 1, chars.size - 1)] <= 32))   # "f", a blank
            if face < faces.size:
                line = int(faces[face])
                return lines_before + 1 + (line if numbers is None else int(numbers[0][line]))
            face -= faces.size
            lines_before += newlines.size if numbers is None else numbers[1]
    return None


def _joined(piece):
    """``(piece, lines)``: ``piece`` with lines continued by a backslash joined to the next, as
    pymeshlab's OBJ loader reads them (the backslash and the line end, LF or CR LF, removed,
    nothing put in their place; lines so continued that it misreads, as continued lines ending
    in CR LF, are refused before: :func:`_obj_continued_line`), and ``(the 0-based line of
    piece each joined line starts on, the piece's lines)`` (None where nothing was joined). A
    backslash as the file's last byte continues onto nothing and is dropped."""
    if b"\\" not in piece or (b"\\\n" not in piece and b"\\\r\n" not in piece and not piece.endswith(b"\\")):
        return piece, None                         # (a byte's search first)
    chars = np.frombuffer(piece, dtype=np.uint8)
    newlines = np.flatnonzero(chars == 10)
    before = chars[np.maximum(newlines - 1, 0)]
    joins = np.flatnonzero((before == 92) | ((before == 13) & (chars[np.maximum(newlines - 2, 0)] == 92)))   # "\\"
    lines = np.delete(np.arange(newlines.size + 1), joins + 1)
    piece = piece.replace(b"\\\r\n", b"").replace(b"\\\n", b"")
    return (piece[:-1] if piece.endswith(b"\\") else piece), (lines, newlines.size)


def _obj_face_indices_in(piece, numbers, total, vertices_before, lines_before, sizes=None, raw=None):
    """:func:`_obj_face_indices` on ``piece`` (bytes, whole lines; continued lines joined, and
    ``numbers`` as :func:`_joined` gives it: None where none were), with
    ``vertices_before`` v lines and ``lines_before`` lines before the piece; positive indices are
    checked against ``total`` vertices (None: not checked). Returns ``(problem, triangles, v
    lines, lines, largest index)`` of the piece (lines as in the file). Where ``raw`` is a list
    ``[v lines, f lines]`` (and no lines were joined), the piece's lines that start with ``v`` or
    ``f`` and a space or tab are added to it."""
    if not piece.endswith(b"\n"):
        piece += b"\n"
    chars = np.frombuffer(piece, dtype=np.uint8)
    newlines = np.flatnonzero(chars == 10)
    first_lines, line_count = numbers if numbers is not None else (None, newlines.size)
    starts = np.concatenate([[0], newlines[:-1] + 1])
    lead = chars[starts]
    second = chars[np.minimum(starts + 1, chars.size - 1)]
    vertex_line = (lead == 118) & ((second == 32) | (second == 9))
    vertex_lines = int(np.count_nonzero(vertex_line))
    if raw is not None:
        raw[0] += vertex_lines
        raw[1] += int(np.count_nonzero((lead == 102) & ((second == 32) | (second == 9))))
    if b"f" not in piece:                          # no face line
        return None, 0, vertex_lines, line_count, 0
    # words: runs of bytes above 32 (pymeshlab splits at spaces, tabs and carriage returns; other
    # control bytes end a word here, which at worst refuses a file it reads)
    separator = chars <= 32
    begins = ~separator
    begins[1:] &= separator[:-1]
    word_starts = np.flatnonzero(begins)
    per_line = np.add.reduceat(begins.view(np.uint8), starts, dtype=np.int64)
    word_line = np.repeat(np.arange(starts.size), per_line)
    first_word = np.cumsum(per_line) - per_line                # each line's first word, where it has one
    at = word_starts[np.minimum(first_word, word_starts.size - 1)]
    face_line = (per_line > 0) & (chars[at] == 102) & separator[np.minimum(at + 1, chars.size - 1)]
    if not face_line.any():
        return None, 0, vertex_lines, line_count, 0
    corner = face_line[word_line]
    corner[first_word[face_line]] = False                      # the "f" itself
    corners = word_starts[corner]
    corner_line = word_line[corner]
    faces = np.flatnonzero(face_line)
    per_face = per_line[faces] - 1
    ending = separator[1:] & ~separator[:-1]
    ends = np.flatnonzero(np.append(ending, ~separator[-1]))[corner] + 1    # the words' ends
    if b"/" in piece or b"#" in piece:                         # the vertex index ends at the first "/" or "#"
        stops = np.flatnonzero((chars == 47) | (chars == 35))
        word_of = np.cumsum(begins, dtype=np.int32)[stops] - 1
        first = np.append(True, word_of[1:] != word_of[:-1])
        stops, word_of = stops[first], word_of[first]
        where = np.searchsorted(np.flatnonzero(corner), word_of)
        hit = where < corners.size
        hit[hit] = np.flatnonzero(corner)[where[hit]] == word_of[hit]
        ends[where[hit]] = stops[hit]

    def shown(line):
        text = piece[starts[line]:newlines[line]].decode("utf-8", "replace").strip()
        number = lines_before + 1 + (line if first_lines is None else int(first_lines[line]))
        return f"line {number} ({text if len(text) <= 80 else text[:77] + '...'!r})"

    signed = (chars[corners] == 45) | (chars[corners] == 43)
    digits = ends - corners - signed
    plain = (digits > 0) & (digits <= 18)
    # bytes other than digits within an index (a sign after its first byte, ".", letters): few or none
    other = ((chars - np.uint8(48)) > 9) & ~separator & (chars != 47) & (chars != 35)
    other[at[face_line]] = False                               # the "f"s
    other = np.flatnonzero(other)
    if other.size:
        owner = np.searchsorted(corners, other, side="right") - 1
        inside = (owner >= 0) & (other < ends[np.maximum(owner, 0)])
        inside &= (other != corners[np.maximum(owner, 0)]) | ~signed[np.maximum(owner, 0)]
        plain[owner[inside]] = False
    values = _whole_values(chars, ends, digits, plain)
    for k in np.flatnonzero(~plain).tolist():                  # normally none: "2.0", "x", "", long
        word = piece[corners[k]:ends[k]]
        if not _OBJ_WHOLE_INDEX.fullmatch(word):
            what = "no vertex index" if not word else f"the vertex index {word.decode('utf-8', 'replace')!r}"
            return (f"{shown(corner_line[k])} has {what}, which pymeshlab's OBJ loader reads with atoi (up to the "
                    "first character not a digit; nothing as 0, which names no vertex and was written out of "
                    "bounds); write each corner as a whole vertex index (optionally /texture/normal indices)"
                    ), 0, 0, 0, 0
        number = int(word.split(b".", 1)[0].lstrip(b"+-"))
        values[k] = number if number < 10 ** 18 else 10 ** 18
    values[chars[corners] == 45] *= -1
    before = vertices_before + np.cumsum(vertex_line) - vertex_line    # v lines above each line
    outside = (values == 0) | (values < -before[corner_line])
    if total is not None:
        outside |= values > total
    if outside.any():
        k = int(np.flatnonzero(outside)[0])
        above = int(before[corner_line[k]])
        count = f"{total} v lines in all, {above} above the face" if total is not None else \
            f"{above} v lines above the face"
        return (f"{shown(corner_line[k])} names the vertex {int(values[k])}, which the file does not have "
                f"({count}): pymeshlab's OBJ loader reads such an "
                "index as another vertex or writes out of bounds with it (which can crash the process later); "
                "OBJ vertex indices run from 1 to the number of v lines, or from -1 back over the vertices above "
                "the face. Fix the face and read the file again"), 0, 0, 0, 0
    few = np.flatnonzero(per_face < 3)
    if few.size:
        return (f"{shown(faces[few[0]])} is a face of {per_face[few[0]]} corners, which pymeshlab's OBJ loader "
                f"drops without a word ({few.size} such faces here); a face needs 3 or more vertices (an edge is "
                "an 'l' line): fix or remove it and read the file again"), 0, 0, 0, 0
    if sizes is not None:
        sizes.append(per_face)
    return None, int((per_face - 2).sum()), vertex_lines, line_count, int(values.max(initial=0))
