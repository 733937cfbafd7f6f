"""What a mesh file declares, to catch what pymeshlab's loader drops without a word.

pymeshlab's loader silently drops OBJ/OFF/PLY vertices with NaN or infinite coordinates (and the
faces using them, renumbering the rest), drops OBJ faces whose vertex indices are out of range
or repeated and STL triangles with a non-finite or repeated corner, and keeps OFF faces whose
indices are out of range; its OFF loader then writes out of bounds, which can crash the process
later. It also misreads without a word: a plain OFF file is one stream of numbers to it (a row
with a value too many shifts every later coordinate), missing OFF rows are filled from what
follows, OBJ face indices are truncated (2.5 -> 2) and a comment after a face becomes further
corners. :func:`check_before_loading` looks for all of these before the loader sees the file
(reading it once more, vectorized).
:func:`check_loaded` compares the loaded mesh with the counts the file declares (OFF/PLY
headers, the binary STL header, a streamed count of OBJ ``v`` and ``f`` lines and of ASCII STL
facets, never the whole file in memory) and with its own vertex count.
"""

import io
import itertools
import mmap
import os
import re

import numpy as np

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
    line or the next one, comments allowed), or ``(None, None)`` if it is not of that form."""
    with open(path, "rb") as f:
        header = _off_header(f)
    return (None, None) if header is None else header[:2]


def _off_header(lines):
    """``(nv, nf, length of the header in bytes, keyword)`` from an OFF file's lines (bytes,
    newlines kept), or None: not that form ("OFF BINARY", nOFF with its dimension first, too
    short)."""
    words, length = [], 0
    for line in itertools.islice(lines, _HEADER_LINES):
        length += len(line)
        words += line.split(b"#", 1)[0].decode("ascii", "replace").split()
        if len(words) >= 3:
            break
    keyword = "OFF" if words and words[0] == "off" else (words[0] if words else "")
    if len(words) < 3 or not keyword.endswith("OFF") or "n" in keyword:
        return None
    try:
        return int(words[1]), int(words[2]), length, keyword
    except ValueError:
        return None


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
            if words[0] == b"element" and len(words) == 3 and words[2].isdigit():
                found[words[1]] = int(words[2])
    return found.get(b"vertex"), found.get(b"face")


def _stl_counts(path):
    """``(None, triangles)`` of an STL file: a binary file's header count (when the file size
    matches it), or an ASCII file's ``endfacet`` lines; ``(None, None)`` if neither."""
    size = os.path.getsize(path)
    with open(path, "rb") as f:
        head = f.read(84)
        if len(head) == 84:
            count = int(np.frombuffer(head[80:84], dtype="<u4")[0])
            if size == 84 + 50 * count:
                return None, count
    if not head.lstrip().startswith(b"solid"):
        return None, None
    return None, _streamed_counts(path, (b"endfacet",))[0]


_COUNTS = {".obj": _obj_counts, ".off": _off_counts, ".ply": _ply_counts, ".stl": _stl_counts}

#: Why pymeshlab drops faces, by format (see :func:`check_loaded`).
_DROPPED_FACES = {".stl": "non-finite (NaN or inf) coordinates or a repeated corner"}


def declared_counts(path):
    """``(vertices, faces)`` the file declares (OBJ, OFF, PLY; STL: faces only), None where
    unknown."""
    counts = _COUNTS.get(os.path.splitext(os.fspath(path))[1].lower())
    return counts(path) if counts is not None else (None, None)


def check_before_loading(path, error=ValueError):
    """Raise ``error`` for files that pymeshlab's loader would read into corrupt memory or
    misread without a word.

    ASCII OFF: faces that name vertices the file does not have (the loader keeps such faces and
    writes out of bounds; the process can crash later, even after :func:`check_loaded` has
    reported them), and rows it would misread (plain OFF is one stream of numbers to it, so a
    vertex row with a value too many or too few, or a short face row, shifts everything after
    it; missing rows are filled from what follows). A binary OFF file, which the loader refuses
    with only "Invalid file", is named as such. OBJ: indented vertex lines (the loader counts
    them in one pass and not in the other; reading one aborted the process), a fractional face
    index (truncated) and a comment after a face (read as corners out of range). Other files
    pass unread."""
    extension = os.path.splitext(os.fspath(path))[1].lower()
    if extension == ".off":
        if _off_is_binary(path):
            raise error(f"{path!r} is a binary OFF file ('OFF BINARY'), which pymeshlab's OFF reader "
                        "does not read; save it as ASCII OFF, PLY or OBJ and read that.")
        problem = _off_rows_problem(path)
        if problem:
            raise error(f"{path!r}: {problem}; fix those rows in the file and read it again.")
    elif extension == ".obj":
        count, line = _obj_indented_vertices(path)
        if count:
            raise error(f"{path!r}: {count} vertex lines start with spaces or tabs (first: line {line}), "
                        "which pymeshlab's OBJ loader miscounts (it crashed reading such a file); remove "
                        "the leading whitespace and read the file again.")
        odd = _obj_odd_face(path)
        if odd is not None and odd[1] == ".":
            raise error(f"{path!r}: the face on line {odd[0]} has a fractional vertex index, which "
                        "pymeshlab's OBJ loader truncates without a word (1.5 becomes 1); OBJ indices are "
                        "whole numbers. Fix the face and read the file again.")
        if odd is not None:
            raise error(f"{path!r}: the face on line {odd[0]} ends in a comment, whose words pymeshlab's OBJ "
                        "loader reads as further corners (a vertex index past the file's vertices, which "
                        "can crash the process); move the comment to a line of its own and read the file "
                        "again.")


def _off_is_binary(path):
    """Whether an OFF file's first line is ``[ST][C][N][4][n]OFF BINARY`` (any case)."""
    with open(path, "rb") as f:
        words = f.readline(4096).split(b"#", 1)[0].upper().split()
    return len(words) >= 2 and words[0].endswith(b"OFF") and words[1] == b"BINARY"


def _obj_indented_vertices(path):
    """``(number, first 1-based line)`` of ``v`` lines with leading blanks in an OBJ file; the
    file is scanned through a memory map, never read whole."""
    with open(path, "rb") as f:
        try:
            data = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ)
        except ValueError:                 # an empty file
            return 0, None
        with data:
            starts = [m.start() + 1 for m in re.finditer(rb"\n[ \t]+v[ \t]", data)]
            if re.match(rb"[ \t]+v[ \t]", data):
                starts.insert(0, 0)
            if not starts:
                return 0, None
            return len(starts), data[:starts[0]].count(b"\n") + 1


def _obj_odd_face(path):
    """``(1-based line, character)`` of the first ``f`` line of an OBJ file that holds a ``.``
    (a fractional index, which pymeshlab's loader truncates) or a ``#`` (a trailing comment,
    whose words it reads as further corners: a triangle came back with a vertex index past the
    file's vertices), or None. Vectorized over the bytes from the first face line on (~0.4 s for
    a million vertices); only lines holding one of the two characters are looked at."""
    with open(path, "rb") as f:
        try:
            data = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ)
        except ValueError:                 # an empty file
            return None
        with data:
            found = [k + 1 for k in (data.find(b"\nf "), data.find(b"\nf\t")) if k >= 0]
            first = 0 if data[:2] in (b"f ", b"f\t") else min(found, default=-1)
    if first < 0:
        return None
    chars = np.fromfile(path, dtype=np.uint8, offset=first)
    odd = np.flatnonzero((chars == 46) | (chars == 35))                  # "." and "#"
    if not odd.size:
        return None
    newlines = np.flatnonzero(chars == 10)
    line = np.searchsorted(newlines, odd)                                # lines after the first face's
    starts = np.concatenate([[0], newlines + 1])[line]
    after = chars[np.minimum(starts + 1, chars.size - 1)]
    hits = np.flatnonzero((chars[starts] == ord("f")) & ((after == 32) | (after == 9)))
    if not hits.size:
        return None
    before = int(np.count_nonzero(np.fromfile(path, dtype=np.uint8, count=first) == 10)) if first else 0
    return before + int(line[hits[0]]) + 1, chr(chars[odd[hits[0]]])


def _off_rows_problem(path):
    """What is wrong with the rows of an ASCII OFF file, or None (also where it cannot tell:
    the loader and :func:`check_loaded` then judge): vertex rows with an unusual number of
    values (:func:`_off_vertex_rows_problem`), face rows that are not a count and that many
    integer indices, faces with indices out of range.

    Vectorized over the bytes (~1 s for a million vertices, against ~4.5 s for pymeshlab's own
    read): a face line whose tokens are all unsigned and shorter than the vertex count's digits
    (or as long and below it) holds no index out of range, so only the other lines (normally
    none; float colours make them all) are parsed one by one."""
    with open(path, "rb") as f:
        data = f.read()
    header = _off_header(io.BytesIO(data))
    if header is None:
        return None
    nv, nf, offset, keyword = header
    body = data[offset:]
    if b"#" in body:
        body = re.sub(rb"#[^\n]*", b"", body)
    chars = np.frombuffer(body, dtype=np.uint8)
    visible = chars > 32
    newlines = np.flatnonzero(chars == 10)
    starts = np.concatenate([[0], newlines + 1])
    ends = np.concatenate([newlines, [chars.size]])
    filled = np.zeros(starts.size, dtype=bool)
    some = np.flatnonzero(ends > starts)
    if some.size:
        # each segment runs to the next non-empty line: this line's characters and newlines
        filled[some] = np.logical_or.reduceat(visible, starts[some])
    lines = np.flatnonzero(filled)
    if nf == 0:
        return None                                            # no faces: read_mesh refuses it
    if lines.size < nv + nf:
        # pymeshlab fills the missing rows from what follows: a triangle came back twice
        return (f"the header declares {nv} vertices and {nf} faces, but the file holds {lines.size} rows "
                f"after it (truncated, or the counts are wrong)")
    rows = lines[:nv + nf]
    faces = rows[nv:]
    first, last = int(starts[rows[0]]), int(ends[rows[-1]])
    seg = visible[first:last]
    token_starts = np.flatnonzero(seg[1:] & ~seg[:-1]) + (first + 1)
    token_ends = np.flatnonzero(seg[:-1] & ~seg[1:]) + (first + 1)
    if seg[0]:
        token_starts = np.concatenate([[first], token_starts])
    if seg[-1]:
        token_ends = np.concatenate([token_ends, [last]])
    per_row = np.diff(np.append(np.searchsorted(token_starts, starts[rows]), token_starts.size))
    problem = _off_vertex_rows_problem(per_row[:nv], plain=keyword == "OFF")
    if problem:
        return problem
    token_starts, token_ends = token_starts[per_row[:nv].sum():], token_ends[per_row[:nv].sum():]
    line_starts = starts[faces]
    per_line = per_row[nv:]
    # the vertex count k: a one-digit first token, or parsed below
    head = np.concatenate([[0], np.cumsum(per_line)[:-1]])
    one_digit = (token_ends[head] - token_starts[head] == 1) & (chars[token_starts[head]] >= 51) & \
        (chars[token_starts[head]] <= 57)
    k = np.where(one_digit, chars[token_starts[head]].astype(np.int64) - 48, 0)
    suspect = np.zeros(nf, dtype=bool)
    odd = token_starts[_maybe_out_of_range(chars, token_starts, token_ends, nv)]
    suspect[np.searchsorted(line_starts, odd, side="right") - 1] = True
    suspect |= ~one_digit | (per_line < k + 1)
    bad = []
    for face in np.flatnonzero(suspect):
        words = body[starts[faces[face]]:ends[faces[face]]].split()
        try:
            count = int(words[0])
            index = [int(w) for w in words[1:count + 1]]
        except ValueError:
            index = None
        if index is None or count < 1 or len(index) < count:
            # pymeshlab reads OFF as one stream of numbers: a short or unreadable face row
            # shifts every later face (a two-value row came back as a duplicated triangle)
            text = body[starts[faces[face]]:ends[faces[face]]].decode("ascii", "replace").strip()
            return (f"face {face} is the row {text!r}, which is not a vertex count followed by that "
                    "many integer vertex indices")
        if min(index) < 0 or max(index) >= nv:
            bad.append((face, index))
    if not bad:
        return None
    return (f"{len(bad)} faces use vertex indices outside the file's {nv} vertices "
            f"(first: face {bad[0][0]}, {bad[0][1]})")


def _off_vertex_rows_problem(values_per_row, plain):
    """What is wrong with an OFF file's vertex rows, given the number of values on each, or
    None. pymeshlab reads a plain ``OFF`` file as one stream of numbers, so there a row with a
    value too many or too few shifts every later coordinate without a word: each row must hold
    exactly x, y and z. With a prefixed keyword (``COFF``, ``NOFF``, ``STOFF``...) it reads row
    by row, and a row may carry its colour or not, but needs its three coordinates."""
    odd = np.flatnonzero(values_per_row != 3 if plain else values_per_row < 3)
    if not odd.size:
        return None
    what = "hold a number of values other than 3 (x y z)" if plain else "hold fewer than 3 values"
    return (f"{odd.size} vertex rows {what} (first: vertex {odd[0]}, {values_per_row[odd[0]]} values), "
            "which would shift every later coordinate" + (
                "; a plain OFF file is read as one stream of numbers (colours need COFF)" if plain else ""))


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


def check_loaded(path, n_vertices, F, error=ValueError):
    """Raise ``error`` if the loaded mesh (``n_vertices``, triangles ``F``) lost vertices or faces
    of ``path`` or holds face indices out of range; each message names the file, the counts, the
    likely cause and the fix."""
    F = np.asarray(F)
    if F.size and (F.min() < 0 or F.max() >= n_vertices):
        bad = np.flatnonzero((F < 0).any(axis=1) | (F >= n_vertices).any(axis=1))
        raise error(f"{path!r}: {bad.size} faces use vertex indices outside the file's {n_vertices} "
                    f"vertices (first: face {bad[0]}, {F[bad[0]].tolist()} 0-based); fix or remove "
                    "them in the file and read it again.")
    vertices, faces = declared_counts(path)
    if vertices is not None and vertices > n_vertices:     # more than declared: a misread count
        raise error(
            f"{path!r} has {vertices} vertices but pymeshlab loaded {n_vertices}: "
            f"{vertices - n_vertices} were dropped, most likely for non-finite (NaN or inf) "
            "coordinates, together with the faces using them, so the vertex order no longer "
            "matches the file. Fix or remove those vertices (and their faces) in the file and "
            "read it again.")
    # polygons are triangulated, so a complete load has at least as many triangles as faces
    if faces is not None and faces > F.shape[0]:
        cause = _DROPPED_FACES.get(os.path.splitext(os.fspath(path))[1].lower(),
                                   "vertex indices out of range or repeated within a face")
        raise error(
            f"{path!r} has {faces} faces but pymeshlab loaded {F.shape[0]} triangles: at least "
            f"{faces - F.shape[0]} were dropped, most likely for {cause}. Fix or remove those "
            "faces in the file and read it again.")
