"""Mesh files that pymeshlab's loader would misread without a word, or read into corrupt
memory: found before it sees them (:func:`check_before_loading`).

Its OFF loader keeps faces whose indices are out of range and then writes out of bounds, which
can crash the process later. It also misreads: an OFF file's vertex values are one stream of
words to it (a row with a value too many shifts every later coordinate, a comment's words are
read as numbers, a vertex split over lines is read right), missing OFF rows are filled from
what follows, a line of blanks among the faces repeats the face before it, OFF and OBJ indices
and counts are read with atoi (2.5 -> 2, 2.0 -> 2) and a comment after an OBJ face becomes
further corners; OFF face rows beyond the header's count are dropped, and a decimal comma ends
an OFF or OBJ number (``1,5`` -> 1). PLY files are scanned by :mod:`._ply_scan`. The scans
read the file once more, vectorized over its bytes.
"""

import contextlib
import io
import mmap
import os
import re

import numpy as np

from ._file_counts import _off_header, _whole
from ._ply_scan import _ply_problem


def check_before_loading(path, error=ValueError):
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
    a one-word comment glued to the last index, ``f 1 2 3#note``, passes). OFF and OBJ: a comma
    in a number (``v 1,5 2 3`` was read as the vertex (1, 2, 3); commas in comments and names
    pass); OFF: rows after the header's faces (dropped; empty lines and comments pass).

    PLY, ASCII or binary: a header pymeshlab misparses (an element count that is not a whole
    number, or none: that crashed it) and face lists of types its importer does not read (it
    takes the faces from whatever memory held). ASCII PLY (:func:`_ply_body_problem`): every
    value fscanf would not read whole as its type (a fractional or comma'd index, ``1.5.5``),
    list counts that are not whole numbers, faces of fewer than 3 or more than 255 vertices,
    lines that hold values of two rows or a face row not on a line of its own, and fewer or more
    rows than the header declares; rows split over lines that hold exactly their values (not
    faces), blank lines, comments in the header, other elements and properties pass.

    Other files pass unread. Returns the number of triangles an ASCII PLY file's faces make (a
    polygon of k vertices k - 2; pymeshlab drops faces with a repeated index or the 'deleted'
    flag bit, which the caller finds by comparing), else None."""
    extension = os.path.splitext(os.fspath(path))[1].lower()
    if extension in (".off", ".ply", ".obj") and _carriage_returns_only(path):
        raise error(f"{path!r} ends its lines with carriage returns alone (classic Mac OS), which pymeshlab "
                    "reads as one long line (it failed, or read a single vertex); convert the line ends to "
                    "newlines (e.g. tr '\\r' '\\n' < old > new) and read the file again.")
    if extension == ".off":
        if _off_is_binary(path):
            raise error(f"{path!r} is a binary OFF file ('OFF BINARY'), which pymeshlab's OFF reader "
                        "does not read; save it as ASCII OFF, PLY or OBJ and read that.")
        problem = _off_rows_problem(path)
        if problem:
            raise error(f"{path!r}: {problem}; fix the file and read it again.")
    elif extension == ".ply":
        problem, triangles = _ply_problem(path)
        if problem:
            raise error(f"{path!r}: {problem}; fix the file and read it again.")
        return triangles
    elif extension == ".obj":
        comma = _obj_comma(path)
        if comma is not None:
            raise error(f"{path!r}: line {comma[0]} ({comma[1]!r}) writes a number with a comma, which "
                        "pymeshlab's OBJ loader reads only up to the comma without a word ('v 1,5 2 3' was "
                        "read as the vertex (1, 2, 3)); write decimals with a point (and separate values with "
                        "spaces) and read the file again.")
        count, line = _obj_indented_vertices(path)
        if count:
            raise error(f"{path!r}: {count} vertex lines start with spaces or tabs (first: line {line}), "
                        "which pymeshlab's OBJ loader miscounts (it crashed reading such a file); remove "
                        "the leading whitespace and read the file again.")
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


def _off_rows_problem(path):
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
    lines (normally none) are parsed one by one."""
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
    newlines = np.flatnonzero(chars == 10)
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
    edges = np.flatnonzero(visible[1:] != visible[:-1]) + 1    # word starts and ends, alternating
    if chars.size and visible[0]:
        edges = np.concatenate([[0], edges])
    if chars.size and visible[-1]:
        edges = np.append(edges, chars.size)
    token_starts, token_ends = edges[0::2], edges[1::2]
    per_line = np.diff(np.append(np.searchsorted(token_starts, starts), token_starts.size))
    rows = np.flatnonzero(per_line)                            # the lines that hold words
    per_row = per_line[rows]

    def text(line):
        return bytes(body[starts[line]:ends[line]]).decode("ascii", "replace").strip()

    def too_short():
        # pymeshlab fills the missing rows from what follows: a triangle came back twice
        return (f"the header declares {nv} vertices and {nf} faces, but the file holds {rows.size} rows "
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
    after = rows[taken + nf:]
    # after the faces nothing is read: an indented comment there is a comment too
    after = after[chars[token_starts[np.searchsorted(token_starts, starts[after])]] != 35] if after.size else after
    if after.size:
        # pymeshlab stops after the declared faces: the rest was dropped without a word
        extra = after[0]
        return (f"the header declares {nv} vertices and {nf} faces, but {after.size} more rows follow "
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
    owner = np.repeat(np.arange(nf), per_face)
    rank = np.arange(token_starts.size) - head[owner]
    idx = np.flatnonzero((rank >= 1) & (rank <= k[owner]))
    odd = token_starts[idx[_maybe_out_of_range(chars, token_starts[idx], token_ends[idx], nv)]]
    suspect[np.searchsorted(line_starts, odd, side="right") - 1] = True
    # a character other than a digit in the count or an index (atoi reads 2.5 as 2, "#" and "x"
    # as 0); those in colours after the indices do not matter
    other = visible[first:end] & (chars[first:end] - np.uint8(48) >= 10)
    other = np.flatnonzero(other) + first if other.any() else other[:0]
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
        if min(index) < 0 or max(index) >= nv:
            bad.append((face, index))
    if not bad:
        return None
    return (f"{len(bad)} faces use vertex indices outside the file's {nv} vertices "
            f"(first: face {bad[0][0]}, {bad[0][1]})")


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
