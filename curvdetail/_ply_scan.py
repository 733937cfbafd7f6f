"""Pre-scan of PLY files for :func:`curvdetail._file_scan.check_before_loading`: what
pymeshlab's PLY reader (vcglib plylib) would misread or crash on without a word.

Its header parser reads element counts with atoi and crashed on an element without one; its
importer reads only some face list types. Its ASCII reader reads the body as one stream of
fscanf words, each up to the first character that does not fit its type (``2.5`` is 2 where an
index is read, ``1,5`` is 1), ignores rows beyond the declared ones, keeps stale indices of the
face before for a face of fewer than 3 vertices and a face's count in one byte. The scan reads
the body in pieces, vectorized over its bytes.
"""

import itertools
import mmap
import os
import re

import numpy as np

from ._file_counts import _HEADER_LINES, _whole

#: How pymeshlab's ASCII PLY reader (vcglib plylib) reads a value of each PLY type: integers
#: with fscanf "%d" or "%u", reals with "%f" or "%lf". List counts are always read with "%d".
_PLY_INT, _PLY_REAL, _PLY_SHORT = 0, 1, 2     # _PLY_SHORT: face indices of type short
_PLY_KINDS = dict.fromkeys([b"char", b"int8", b"short", b"int16", b"int", b"int32", b"uchar", b"uint8",
                            b"ushort", b"uint16", b"uint", b"uint32"], _PLY_INT)
_PLY_KINDS.update(dict.fromkeys([b"float", b"float32", b"double", b"float64"], _PLY_REAL))
#: The face element's list of vertex indices, under the names pymeshlab's importer reads.
_PLY_FACE_LISTS = (b"vertex_indices", b"vertex_index")
#: pymeshlab stores a face's vertex count in one byte: a list of 256 or more indices was read as
#: a polygon of (count mod 256) vertices, and one of 1000 smashed the stack.
_PLY_MAX_CORNERS = 255
#: The PLY types by their first names (``int8`` is ``char``, ...).
_PLY_TYPE_NAMES = {b"int8": b"char", b"uint8": b"uchar", b"int16": b"short", b"uint16": b"ushort",
                   b"int32": b"int", b"uint32": b"uint", b"float32": b"float", b"float64": b"double"}
#: ``(count type, index type)`` of the face lists pymeshlab's PLY importer reads (each tried on
#: pymeshlab itself); with any other it reads no indices and keeps whatever memory held: "Bad
#: vertex index in face" in a fresh process, faces of a file read before in a longer one.
_PLY_FACE_TYPES = {
    b"vertex_indices": {(count, index) for count in (b"char", b"uchar", b"int")
                        for index in (b"short", b"int", b"uint")} | {(b"ushort", b"uint")},
    b"vertex_index": {(b"char", b"int"), (b"uchar", b"int"), (b"int", b"int")},
}
#: Of those, the ones its binary reader fails on ("Bad vertex index in face ... damaged").
_PLY_FACE_TYPES_NOT_BINARY = {(b"int", b"short"), (b"int", b"uint"), (b"ushort", b"uint")}
#: What fscanf("%f") reads whole besides decimal numbers (read as NaN or inf: pymeshlab then
#: drops the vertex, which :func:`curvdetail._file_counts.check_loaded` reports).
_PLY_WORDS = re.compile(rb"[+-]?(?:inf|infinity|nan)", re.IGNORECASE)
_PLY_INTEGER = re.compile(rb"[+-]?[0-9]+")


def _ply_header(f, layout=None):
    """The header of a PLY file as pymeshlab's reader (vcglib plylib ``OpenRead``) parses it:
    ``(ascii, elements, first body line)`` with ``elements`` a list of ``(name, count,
    [(property name, kind, is list, item kind)])``; a str naming what it would misread or crash
    on; None where it refuses the header itself (it says so: no "ply", an unknown format,
    keyword or type, a blank line) or the file is not PLY. Where ``layout`` is a list and the
    header is read, its format (``b"ascii"``, ``b"binary_little_endian"``, ...) and its elements
    as :func:`_ply_binary_problem` sizes them are appended to it: ``[(name, count, [(property,
    types)])]`` with the names as str and each property's type names (first names: ``int8`` is
    ``char``; a list's ``[b"list", count type, item type]``).

    It reads the header with fgets into a 511-byte buffer (a longer line is read as several),
    splits each piece at spaces, tabs, carriage returns and newlines, and reads element counts
    with atoi (``4.5`` is 4; no count at all crashed the process). Its importer reads the face
    lists of :data:`_PLY_FACE_TYPES` only; with others it keeps whatever memory held. A face
    list of short indices (kind :data:`_PLY_SHORT`) wraps indices past 32767."""
    def pieces():
        while True:
            piece = f.readline(510)
            if not piece:
                return
            yield piece

    line = 1
    lines = pieces()
    try:
        if not next(lines).startswith(b"ply"):
            return None
        words = re.split(rb"[ \t\r\n]+", next(lines).strip(b" \t\r\n"))
    except StopIteration:
        return None
    if len(words) < 3 or words[0] != b"format" or \
            words[1] not in (b"ascii", b"binary_little_endian", b"binary_big_endian"):
        return None
    ascii_ = words[1] == b"ascii"
    fmt = words[1]
    line = 3
    elements = []
    sized = []                                             # the elements as layout has them
    for piece in itertools.islice(lines, _HEADER_LINES):
        words = [w for w in re.split(rb"[ \t\r\n]+", piece) if w]
        here = line
        line += piece.endswith(b"\n")
        if not words:
            return None                                    # "Unexpected EOF"
        if words[0] in (b"comment", b"obj_info"):
            continue
        if words[0] == b"end_header":
            if layout is not None:
                layout += [fmt, sized]
            return ascii_, elements, line
        if len(words) >= 5 and words[:2] == [b"property", b"list"] and elements and elements[-1][0] == b"face" \
                and words[4] in _PLY_FACE_TYPES:
            types = tuple(_PLY_TYPE_NAMES.get(w, w) for w in words[2:4])
            count_type, index_type = (t.decode("ascii", "replace") for t in types)
            if types not in _PLY_FACE_TYPES[words[4]] or (not ascii_ and types in _PLY_FACE_TYPES_NOT_BINARY):
                how = "it takes the faces from whatever its memory held" if ascii_ or \
                    types not in _PLY_FACE_TYPES_NOT_BINARY else "it calls the file damaged"
                return (f"the header's line {here} ({piece.decode('ascii', 'replace').strip()!r}) declares face "
                        f"lists of {count_type} counts and {index_type} indices, which pymeshlab's PLY reader "
                        f"does not read ({how}); write 'property list uchar int vertex_indices'")
            vertices = max((count for name, count, _ in elements if name == b"vertex"), default=0)
            if index_type == "short" and vertices > 32767:
                return (f"the header's line {here} declares face indices of type short, which cannot name the "
                        f"{vertices} vertices past 32767 (pymeshlab wraps them: 65536 is read as 0); write "
                        "'property list uchar int vertex_indices'")
        if words[0] == b"element":
            if len(words) < 2:
                return None
            if len(words) < 3:
                return (f"the header's line {here} ({piece.decode('ascii', 'replace').strip()!r}) gives no "
                        "element count, which crashes pymeshlab's PLY reader; write 'element <name> <count>'")
            count = _whole(words[2])
            if count is None or count < 0:
                return (f"the header's line {here} declares {words[2].decode('ascii', 'replace')!r} "
                        f"{words[1].decode('ascii', 'replace')} elements, which is not a whole number "
                        "(pymeshlab's reader takes 4.5 as 4); write the number of rows")
            elements.append((words[1], count, []))
            sized.append((words[1].decode("ascii", "replace"), count, []))
        elif words[0] == b"property" and elements and len(words) >= 3:
            sized[-1][2].append((words[-1].decode("ascii", "replace"),
                                 [_PLY_TYPE_NAMES.get(w, w) for w in words[1:-1]]))
            if words[1] == b"list":
                if len(words) < 5 or words[2] not in _PLY_KINDS or words[3] not in _PLY_KINDS:
                    return None
                short = elements[-1][0] == b"face" and words[4] in _PLY_FACE_LISTS and \
                    _PLY_TYPE_NAMES.get(words[3], words[3]) == b"short"
                elements[-1][2].append((words[4], _PLY_INT, True, _PLY_SHORT if short else _PLY_KINDS[words[3]]))
            elif words[1] in _PLY_KINDS:
                elements[-1][2].append((words[2], _PLY_KINDS[words[1]], False, None))
            else:
                return None
        else:
            return None                                    # pymeshlab: a syntax error
    return None


def _ply_problem(path, sizes=None):
    """``(problem, triangles)``: what pymeshlab's PLY reader would misread or crash on in
    ``path`` (None if nothing): a header it misparses (:func:`_ply_header`), and in an ASCII file
    the rows (:func:`_ply_body_problem`); and the number of triangles the faces of an ASCII file
    make (a polygon of k vertices k - 2), None where not known. Binary files are read by their
    types' sizes; only their header is checked. Where ``sizes`` is a list, the vertex counts of an
    ASCII file's faces (int arrays, in file order) are appended to it."""
    with open(path, "rb") as f:
        layout = []
        header = _ply_header(f, layout)
        if header is None or isinstance(header, str):
            return header, None
        ascii_, elements, first_line = header
        if not ascii_:
            return _ply_binary_problem(f, *layout), None
        offset = f.tell()
        if offset >= os.fstat(f.fileno()).st_size:
            data = b""
        else:
            data = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ)   # unmapped when unreferenced
    return _ply_body_problem(data, offset, elements, first_line, sizes)


#: Bytes of each PLY type, by its first name.
_PLY_SIZES = {b"char": 1, b"uchar": 1, b"short": 2, b"ushort": 2, b"int": 4, b"uint": 4, b"float": 4,
              b"double": 8}


def _ply_binary_problem(f, fmt, elements):
    """What pymeshlab's PLY reader would misread in a binary PLY file whose header (checked by
    :func:`_ply_header`, which gives its format ``fmt`` and ``elements`` as its ``layout``) ends
    where ``f`` stands, or None; from the header and the file's size:

    - big-endian doubles in the vertex element: read as garbage (0.1 came back as -1.5e-180;
      big-endian floats and little-endian doubles are read right);
    - a body shorter than the header's counts allow (each list row at its count alone): a
      225-byte file declaring 20 million vertices cost 1.6 GB and 3.3 s before "Unexpected EOF"."""
    header_end = f.tell()
    body = os.fstat(f.fileno()).st_size - header_end
    for name, _, props in elements:
        doubles = [prop for prop, types in props if types == [b"double"]]
        if fmt == b"binary_big_endian" and name == "vertex" and doubles:
            return (f"it is big-endian with vertex properties of type double ({', '.join(doubles)}), which "
                    "pymeshlab's PLY reader misreads without a word (0.1 came back as -1.5e-180); save it as "
                    "binary_little_endian or ASCII PLY")
    least = 0
    for name, count, props in elements:
        row = sum(_PLY_SIZES.get(types[1] if types[0] == b"list" else types[0], 0) for _, types in props)
        least += count * row
    if least > body:
        declared = ", ".join(f"{count} {name}" for name, count, _ in elements)
        return (f"its header declares {declared} rows, which take at least {least} bytes, but only {body} follow "
                "the header (the file is truncated, or the counts are wrong; pymeshlab would first take memory "
                "for all of them)")
    return _ply_list_rows_problem(f, fmt, elements, header_end)


#: The most bytes of items an unread list of a binary PLY row may hold: past 512 pymeshlab's
#: reader overflowed a buffer (65 doubles, 129 floats: "*** buffer overflow detected ***", the
#: process aborted; 64 and 128 were read).
_PLY_UNREAD_LIST_BYTES = 512


def _ply_list_rows_problem(f, fmt, elements, offset):
    """What pymeshlab's binary PLY reader would crash or fail on in the lists other than the face
    indices, which it skips (``elements``: ``(name, count, [(property, types)])`` with a list's
    types ``[b"list", count type, item type]``; the body starts at byte ``offset`` of ``f``), or
    None: lists of the vertex element counted in other than char or uchar (it said "Unexpected
    EOF" of a whole file), and rows whose items in such a list take more than
    :data:`_PLY_UNREAD_LIST_BYTES` bytes. The rows are looked at through strided views where
    each row's counts are those of the first (the usual file); where they differ, only the first
    row is, and the elements after it are not."""
    order = "<" if fmt == b"binary_little_endian" else ">"
    for name, _, props in elements:
        for prop, types in props:
            if name == "vertex" and types[0] == b"list" and types[1] not in (b"char", b"uchar"):
                return (f"its vertex list property {prop!r} has counts of type {types[1].decode('ascii', 'replace')}, "
                        "which pymeshlab's binary PLY reader cannot skip (it reported the whole file as ending "
                        "too soon, 'Unexpected EOF'); count it with uchar, or drop the property or save as ASCII")
    if not any(types[0] == b"list" for _, _, props in elements for _, types in props):
        return None
    with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as data:
        for name, count, props in elements:
            row, counts, lists = 0, [], []                        # the first row's layout
            for prop, types in props:
                if types[0] != b"list":
                    row += _PLY_SIZES.get(types[0], 0)
                    continue
                size, item = _PLY_SIZES.get(types[1], 0), _PLY_SIZES.get(types[2], 0)
                if not size or not item or offset + row + size > len(data):
                    return None
                dtype = np.dtype(order + {1: "u1", 2: "u2", 4: "u4"}[size])
                n = int(np.frombuffer(data, dtype=dtype, count=1, offset=offset + row)[0])
                lists.append((prop, row, dtype, n, item))
                row += size + n * item
            if not count:
                continue
            constant = offset + count * row <= len(data)
            for prop, at, dtype, n, item in lists:
                unread = not (name == "face" and prop in ("vertex_indices", "vertex_index"))
                if constant:
                    column = np.ndarray((count,), dtype=dtype, buffer=data, offset=offset + at, strides=(row,))
                    constant = bool((column == n).all())
                    del column
                if unread and n * item > _PLY_UNREAD_LIST_BYTES:
                    return (f"the first {name} row's list {prop!r} holds {n} items of {item} bytes, more than the "
                            f"{_PLY_UNREAD_LIST_BYTES} bytes pymeshlab's binary PLY reader can skip (past that it "
                            "overflowed a buffer and the process aborted); drop the property, shorten its lists, "
                            "or save the file as ASCII PLY")
            if not constant:
                return None                                   # rows of varying size: not followed further
            offset += count * row
    return None


#: Bytes per piece in which the ASCII PLY scan goes through a body (ending at a line's end): a
#: piece's arrays stay small, so they are neither faulted into memory afresh nor out of cache.
_PLY_CHUNK = 1 << 20


def _ply_pieces(data, low, high):
    """``(start, end)`` byte ranges that cover ``[low, high)`` of ``data``, each ending after a
    newline (the last one at ``high``) and about :data:`_PLY_CHUNK` long."""
    while low < high:
        end = min(low + _PLY_CHUNK, high)
        if end < high:
            cut = data.rfind(b"\n", low, end)
            end = cut + 1 if cut >= 0 else (data.find(b"\n", end, high) + 1 or high)
        yield low, end
        low = end


def _ply_tokens(piece):
    """Starts and ends (piece offsets) of the words of ``piece`` (bytes as uint8): runs of bytes
    above 32. fscanf's blanks are " \\t\\n\\v\\f\\r"; other control bytes are looked for apart."""
    visible = piece > 32
    edges = np.flatnonzero(visible[1:] != visible[:-1]) + 1
    if piece.size and visible[0]:
        edges = np.concatenate([[0], edges])
    if piece.size and visible[-1]:
        edges = np.append(edges, piece.size)
    return edges[0::2], edges[1::2], visible


#: Words are told apart from integers per line in a bit mask of their places (exact in float64
#: sums up to bit 52); lines with more words are checked one by one.
_PLY_MASK_BITS = 52


class _PlyLines:
    """What one pass over an ASCII PLY body (from byte ``offset`` of ``data``) finds, per line:
    ``start`` (its first byte), ``count`` (words), ``first`` (its first word's first byte, -1
    where none), ``not_int`` (bit r set where word r holds a character other than digits and a
    leading sign: fscanf("%d") would not read it whole); and apart: ``control``, the first
    control byte fscanf takes for part of a word (None if none); ``not_real``, ``(byte, line,
    rank)`` of the words fscanf("%f") would not read whole as a decimal number (words other than
    digits with one point and one exponent, a sign in front of each: ``1.5.5``, ``1,5``, ``nan``;
    normally none); ``long``, ``(start, end, line, rank)`` of integers of ``long_digits``
    digits or more (10: they may not fit 32 bits; 5 where face indices are of type short).

    Vectorized in pieces of :data:`_PLY_CHUNK` bytes; only the characters other than digits
    (points, signs, exponents) are looked at one by one, by numpy."""

    def __init__(self, data, chars, offset, long_digits=10):
        starts, counts, firsts, not_int = [], [], [], []
        not_real, long = [], []
        self.control = None
        base = 0                                                   # lines before the piece
        padded = np.empty(_PLY_CHUNK + 8, dtype=np.uint8)          # a piece between blanks
        for low, high in _ply_pieces(data, offset, chars.size):
            piece = chars[low:high]
            token_starts, token_ends, visible = _ply_tokens(piece)
            low_bytes = np.flatnonzero(piece < 32)
            kind = piece[low_bytes]
            odd_control = (kind < 9) | (kind > 13)
            if self.control is None and odd_control.any():
                self.control = low + int(low_bytes[np.flatnonzero(odd_control)[0]])
            line_starts = np.concatenate([[0], low_bytes[kind == 10] + 1])
            if line_starts[-1] == piece.size and line_starts.size > 1:
                line_starts = line_starts[:-1]
            first = np.searchsorted(token_starts, line_starts)
            count = np.diff(np.append(first, token_starts.size))
            starts.append(line_starts + low)
            counts.append(count)
            firsts.append(np.where(count > 0, token_starts[np.minimum(first, token_starts.size - 1)] + low, -1)
                          if token_starts.size else np.full(line_starts.size, -1))
            visible &= (piece - np.uint8(48)) >= 10                # now: visible and not a digit
            odd = np.flatnonzero(visible)
            mask = np.zeros(line_starts.size, dtype=np.int64)
            not_whole = np.zeros(token_starts.size, dtype=bool)
            if odd.size:
                if padded.size < piece.size + 4:
                    padded = np.empty(piece.size + 8, dtype=np.uint8)
                padded[:2] = padded[piece.size + 2:piece.size + 4] = 32
                padded[2:piece.size + 2] = piece
                token = np.searchsorted(token_starts, odd, side="right") - 1
                int_ok, real_ok = _ply_odd_characters(padded, odd, token)
                not_whole[token[~int_ok]] = True
                words = np.flatnonzero(not_whole)
                line_of_word = np.searchsorted(first, words, side="right") - 1
                rank = words - first[line_of_word]
                weights = np.ldexp(1.0, np.minimum(rank, _PLY_MASK_BITS))
                weights[rank >= _PLY_MASK_BITS] = 0.0              # such lines are checked word by word
                mask = np.bincount(line_of_word, weights=weights, minlength=line_starts.size).astype(np.int64)
                bad = np.unique(token[~real_ok])
                if bad.size:
                    line = np.searchsorted(first, bad, side="right") - 1
                    not_real.append(np.column_stack([token_starts[bad] + low, line + base, bad - first[line]]))
            not_int.append(mask)
            wide = np.flatnonzero((token_ends - token_starts >= long_digits) & ~not_whole)
            if wide.size:
                line = np.searchsorted(first, wide, side="right") - 1
                long.append(np.column_stack([token_starts[wide] + low, token_ends[wide] + low, line + base,
                                             wide - first[line]]))
            base += line_starts.size
        empty = np.zeros(0, dtype=np.int64)
        self.start = np.concatenate(starts) if starts else empty
        self.count = np.concatenate(counts) if counts else empty
        self.first = np.concatenate(firsts) if firsts else empty
        self.not_int = np.concatenate(not_int) if not_int else empty
        self.not_real = np.concatenate(not_real) if not_real else np.zeros((0, 3), dtype=np.int64)
        self.long = np.concatenate(long) if long else np.zeros((0, 4), dtype=np.int64)


def _ply_odd_characters(padded, odd, token):
    """For the characters at ``odd`` (sorted positions of the visible bytes that are not digits
    in a piece, ``padded`` holding it after two blanks and before two more; ``token``: the word
    of each): whether each is allowed in an integer fscanf("%d") reads whole (a sign in front of
    a digit), and in a real "%f" reads whole as a decimal number (a sign in front of the word or
    of its exponent's digits, one point with a digit beside it and before any exponent, one
    exponent after a digit or a digit's point and before a digit or a sign and digit). A word
    passes where all its characters do (digits with one of each at most, in that order)."""
    at = odd + 2
    c, prev, nxt = padded[at], padded[at - 1], padded[at + 1]

    def digit(x):
        return (x - np.uint8(48)) < 10

    digit_prev, digit_next = digit(prev), digit(nxt)
    at_start = prev <= 32
    is_sign, is_dot, is_e = (c == 43) | (c == 45), c == 46, (c | 32) == 101
    # the odd character before it in the same word: none, a sign in front, or a point
    same = np.empty(odd.size, dtype=bool)
    same[0] = False
    np.equal(token[1:], token[:-1], out=same[1:])
    after_sign = np.empty_like(same)
    after_sign[0] = False
    np.logical_and(is_sign[:-1], at_start[:-1], out=after_sign[1:])
    after_sign &= same
    after_dot = np.empty_like(same)
    after_dot[0] = False
    after_dot[1:] = is_dot[:-1]
    after_dot &= same
    fresh = ~same | after_sign
    real = is_sign & ((at_start & (digit_next | (nxt == 46))) | (((prev | 32) == 101) & digit_next))
    real |= is_dot & fresh & (digit_prev | digit_next)
    e = np.flatnonzero(is_e)                                   # exponents: rare enough to index
    if e.size:
        real[e] = ((fresh[e] | after_dot[e]) & (digit_prev[e] | ((prev[e] == 46) & digit(padded[at[e] - 2]))) &
                   (digit_next[e] | (((nxt[e] == 43) | (nxt[e] == 45)) & digit(padded[at[e] + 2]))))
    return is_sign & at_start & digit_next, real


def _ply_body_problem(data, offset, elements, first_line, sizes=None):
    """``(problem, triangles)``: what is wrong with the body of an ASCII PLY file (``data``,
    bytes or a memory map, from byte ``offset``) whose header declares ``elements``
    (:func:`_ply_header`) and whose body starts on line ``first_line`` (None if nothing), and
    the number of triangles its faces make (None where a problem was found or a ``tristrips``
    element makes faces too).

    The model is pymeshlab's reader (vcglib plylib): the body is one stream of words for
    fscanf, which skips blanks and line ends alike, each element's rows in the header's order,
    each row its properties in order (a list: a count, then that many items). So a row with a
    value too many or too few shifts every value after it; a value fscanf does not read whole
    (``2.5`` or ``1,5`` where an integer or a real is read: it stops at the ``.`` or ``,`` and
    reads the rest as the next value) misplaces the rest or, at the very end, is cut without a
    word; and rows after the declared ones are ignored. The importer reads a face's vertex count
    into one byte and keeps stale indices from the face before when it is below 3: a count of 2
    came back as a triangle with the previous face's third index, one of 0 as the previous face
    again, one of 256 as no polygon at all, one of 1000 smashed the stack.

    Refused: lines of an element without lists that hold values of two rows other than whole
    rows (a row split over lines that hold exactly its values, and lines of whole rows, are read
    right and pass), a row of an element with lists
    (the faces) not on a line of its own with exactly its values, a list count that is not a
    whole number in digits, a face with fewer than 3 or more than 255 vertex indices, a value
    that is not an integer in digits fitting 32 bits where an integer is read (``2.0`` too) or
    not a number fscanf reads whole where a real is read (``nan`` and ``inf`` pass: the loader
    drops such vertices and :func:`check_loaded` says so), a decimal comma, a control byte, and
    fewer or more values than the header declares.

    One vectorized pass over the bytes (:class:`_PlyLines`), then numpy over the lines: a million
    vertices in ~1.2 s (107 MB) to ~2 s (183 MB with normals, colours and quality), against ~2.8
    and ~4.7 s for pymeshlab's own read."""
    chars = np.frombuffer(data, dtype=np.uint8) if len(data) else np.zeros(0, dtype=np.uint8)
    short = any(item == _PLY_SHORT for _, _, props in elements for _, _, _, item in props)
    lines = _PlyLines(data, chars, offset, 5 if short else 10)    # integers that may not fit their type

    def line_of(position):
        return first_line + int(np.searchsorted(lines.start, position, side="right")) - 1

    def words_of(line):
        end = data.find(b"\n", int(lines.start[line]))
        return bytes(data[int(lines.start[line]):end if end >= 0 else len(data)])

    def text(position):
        words = words_of(int(np.searchsorted(lines.start, position, side="right")) - 1)
        words = words.decode("ascii", "replace").strip()
        return words if len(words) <= 80 else words[:77] + "..."

    if lines.control is not None:
        return (f"line {line_of(lines.control)} holds the control byte {chars[lines.control]:#04x}, which "
                "pymeshlab's PLY reader takes for part of a value; remove it"), None
    rows = np.flatnonzero(lines.count)                               # the lines that hold values
    per_row = lines.count[rows]

    def name(element):
        return element.decode("ascii", "replace")

    def declared():
        return ", ".join(f"{count} {name(element)}" for element, count, _ in elements)

    def too_few(element, found, count, lines_=False):
        if lines_:
            return (f"the header declares {declared()} rows, but only {found} lines after the rows before hold "
                    f"values for the {count} {name(element)} rows (truncated, the header's counts are wrong, or "
                    "rows share a line: write each on a line of its own)"), None
        return (f"the header declares {declared()} rows, but the file ends after {found} of the {count} "
                f"{name(element)} rows (truncated, or the header's counts are wrong)"), None

    rp = 0                                                           # the next row
    triangles = 0
    layouts = []                                                     # each element's kinds of values
    for element, count, props in elements:
        if count == 0 or not props:
            continue
        if not any(is_list for _, _, is_list, _ in props):
            k = len(props)
            need = count * k
            total = np.cumsum(per_row[rp:rp + need])                 # rows rp.. hold its values
            if not total.size or total[-1] < need:
                return too_few(element, (int(total[-1]) if total.size else 0) // k, count)
            end = int(np.searchsorted(total, need))
            before = total[:end + 1] - per_row[rp:rp + end + 1]
            # a line within one row, or whole rows of this element from a row's start, is read
            # as written (fscanf does not see lines); anything else would shift the values
            within = before // k == (total[:end + 1] - 1) // k
            whole = (before % k == 0) & (per_row[rp:rp + end + 1] % k == 0) & (total[:end + 1] <= need)
            straddle = np.flatnonzero(~within & ~whole)
            if straddle.size:
                # the line where the first row whose values run past a line's end starts
                row = rp + int(np.searchsorted(total, before[straddle[0]] // k * k, side="right"))
                where = lines.first[rows[row]]
                odd = np.count_nonzero(per_row[rp:rp + end + 1] != k)
                return (f"{odd} lines hold a number of values other than the {k} of a {name(element)} row "
                        f"({' '.join(name(p[0]) for p in props)}) (first: line {line_of(where)}, {text(where)!r}, "
                        f"{per_row[row]} values): pymeshlab's PLY reader reads the values as one stream, so a "
                        "value too many or too few shifts every later value (a row split over lines that hold "
                        "exactly its values is read right); write each row on a line of its own"), None
            kinds = np.array([kind for _, kind, _, _ in props], dtype=np.int8)
            # a value's kind: its property's, from the place of the line's first value in its row
            layouts.append((rows[rp:rp + end + 1], kinds, before % k, True))
            rp += end + 1
            continue
        if rp + count > rows.size:
            return too_few(element, rows.size - rp, count, lines_=True)
        mine = rows[rp:rp + count]
        problem, layout, made = _ply_list_rows(data, chars, element, props, mine, lines, line_of, text, sizes)
        if problem:
            return problem, None
        if element == b"tristrips" or made is not None:
            triangles = None if element == b"tristrips" or triangles is None else triangles + made
        layouts.append((mine,) + layout + (False,))
        rp += count
    if rp < rows.size:
        where = lines.first[rows[rp]]
        return (f"the header declares {declared()} rows, but more values follow them (from line {line_of(where)}, "
                f"{text(where)!r}), which pymeshlab's PLY reader ignores without a word; remove them or fix the "
                "header's counts"), None
    return _ply_values_problem(lines, layouts, words_of, line_of, text), triangles


def _ply_list_rows(data, chars, element, props, rows, lines, line_of, text, sizes=None):
    """Check the rows of an element with list properties (``props``), one per line of ``rows``
    (line numbers, in order): each a line of its own with exactly its values, its list counts
    whole numbers (and, for the faces' vertex indices, 3 to 255 of them). Returns ``(problem,
    None)`` or ``(None, (kinds, bounds))``: the kinds of a row's segments (a scalar, a list's
    count, its items: an int8 array) and each row's segment ends (in words from the line's
    first; one row per line, one column per segment). The faces' vertex counts are appended to
    ``sizes`` where it is a list."""
    segment_kinds = []
    for _, kind, is_list, item_kind in props:
        segment_kinds += [_PLY_INT, item_kind] if is_list else [kind]
    segment_kinds = np.array(segment_kinds, dtype=np.int8)
    name = element.decode("ascii", "replace")
    bounds = []
    made = None                                                # triangles the faces make
    simple = props[0][2] and not any(is_list for _, _, is_list, _ in props[1:])   # the count is first
    for low_row in range(0, rows.size, 1 << 16):
        block = rows[low_row:low_row + (1 << 16)]
        count = lines.count[block]
        if simple:                                                 # the list's count is the line's first word
            starts = lines.first[block]
            first = np.zeros(block.size, dtype=np.int64)
            ends = _ply_word_ends(data, chars, starts)
        else:
            low = int(lines.start[block[0]])
            high = int(lines.start[block[-1] + 1]) if block[-1] + 1 < lines.start.size else chars.size
            token_starts, token_ends, _ = _ply_tokens(chars[low:high])
            first = np.searchsorted(token_starts, lines.first[block] - low)
        pos = first.copy()
        ends_of = []
        broken = np.zeros(block.size, dtype=bool)              # rows whose line ends too soon
        found = []                                             # (row, problem) of this block
        for prop, kind, is_list, _ in props:
            broken |= pos - first >= count
            if not is_list:
                pos = pos + 1
                ends_of.append(pos - first)
                continue
            if simple:
                word_starts, word_ends = starts, ends
            else:
                at = np.where(broken, first, pos)
                word_starts, word_ends = token_starts[at] + low, token_ends[at] + low
            n, bad = _ply_counts(data, chars, word_starts, word_ends)
            n[broken] = 0
            bad = bad[~broken[bad]]
            broken[bad] = True                                 # its count's problem is told first
            if bad.size:
                where = int(word_starts[bad[0]])
                word = bytes(data[where:int(word_ends[bad[0]])]).decode("ascii", "replace")
                found.append((int(bad[0]), f"line {line_of(where)} ({text(where)!r}): the count of the {name} row's "
                              f"{prop.decode('ascii', 'replace')} list, {word!r}, is not a whole number written "
                              "in digits, which pymeshlab's PLY reader reads only up to its first character that "
                              "is not a digit (3.0 as 3, 2.5 as 2) and then misplaces every later value; write "
                              "the number of items"))
                n[bad] = 0
            if element == b"face" and prop in _PLY_FACE_LISTS:
                made = (made or 0) + int((n - 2).sum())
                if sizes is not None:
                    sizes.append(n.copy())
                few = np.flatnonzero((n < 3) & ~broken)
                many = np.flatnonzero(n > _PLY_MAX_CORNERS)
                if few.size:
                    where = int(lines.first[block[few[0]]])
                    found.append((int(few[0]), f"a face row has fewer than 3 vertex indices (line "
                                  f"{line_of(where)}, {text(where)!r}), which pymeshlab's PLY reader completes with "
                                  "indices of the face before it (or reads as that face again) without a word; a "
                                  "face needs 3 or more vertices: fix or remove such rows and the header's face "
                                  "count"))
                if many.size:
                    where = int(lines.first[block[many[0]]])
                    found.append((int(many[0]), f"a face row has more than {_PLY_MAX_CORNERS} vertex indices (line "
                                  f"{line_of(where)}, {n[many[0]]} indices), which pymeshlab's PLY reader cannot "
                                  "hold (it keeps the count in one byte: 256 was read as no polygon, 1000 crashed "
                                  "it); split such polygons into triangles"))
            ends_of.append(pos + 1 - first)
            pos = pos + 1 + n
            ends_of.append(pos - first)
        wrong = np.flatnonzero(broken | (pos - first != count))
        if wrong.size:
            row = int(wrong[0])
            where = lines.first[block[row]]
            found.append((row + 0.5, _ply_row_length_problem(         # a row's own problem comes first
                element, props, low_row + row, count[row], None if broken[row] else int(pos[row] - first[row]),
                line_of(where), text(where))))
        if found:
            return min(found)[1], None, None
        bounds.append(np.column_stack(ends_of))
    return None, (segment_kinds, np.concatenate(bounds)), made


def _ply_word_ends(data, chars, starts, most=6):
    """The ends of the words starting at ``starts`` (bytes above 32 up to the next blank), the
    first ``most`` bytes vectorized, longer words one by one."""
    ends = np.full(starts.size, -1, dtype=np.int64)
    for j in range(1, most + 1):
        open_ = np.flatnonzero(ends < 0)
        if not open_.size:
            return ends
        at = starts[open_] + j
        done = at >= chars.size
        done[~done] = chars[at[~done]] <= 32
        ends[open_[done]] = at[done]
    for i in np.flatnonzero(ends < 0).tolist():
        ends[i] = _PLY_WORD.match(data, int(starts[i])).end()
    return ends


_PLY_WORD = re.compile(rb"[^\x00-\x20]*")


def _ply_row_length_problem(element, props, row, values, needed, line, text):
    """The message for row ``row`` of an element with lists whose line holds ``values`` values
    where its counts make it ``needed`` (None: fewer than its properties)."""
    layout = " ".join((f"<count> <{p[0].decode('ascii', 'replace')}...>" if p[2] else
                       p[0].decode("ascii", "replace")) for p in props)
    needs = f"its counts make it {needed}" if needed is not None else "that is fewer than its properties"
    return (f"line {line} ({text!r}) holds {values} values for {element.decode('ascii', 'replace')} row {row} "
            f"({layout}), but {needs}: pymeshlab's PLY reader reads the values as one stream, so a value too "
            "many or too few shifts every later row; write each row on a line of its own with exactly its "
            "values")


def _ply_counts(data, chars, starts, ends):
    """``(values, bad)``: the list counts written in the words ``[starts, ends)`` of ``chars``
    as fscanf("%d") reads them whole, and the positions of the words that are not such a count
    (digits, a sign at most, not negative). Words of up to 4 digits are read vectorized, the
    rest one by one."""
    length = ends - starts
    values = np.zeros(starts.size, dtype=np.int64)
    digits_only = length <= 4
    for j in range(4):
        has = digits_only & (length > j)
        digit = chars[np.where(has, starts + j, 0)].astype(np.int64) - 48
        digits_only &= ~has | ((digit >= 0) & (digit <= 9))
        values = np.where(has, values * 10 + digit, values)
    bad = []
    for i in np.flatnonzero(~digits_only).tolist():
        word = bytes(data[int(starts[i]):int(ends[i])])
        if _PLY_INTEGER.fullmatch(word) and 0 <= int(word) < 2 ** 31:
            values[i] = int(word)
        else:
            bad.append(i)
    return values, np.array(bad, dtype=np.int64)


def _ply_kinds(layout, row, rank):
    """The kinds of the words ``rank`` (places from their line's first) on the element's rows
    ``row`` (indices into its lines) for an element laid out as ``layout``: ``(lines, kinds,
    place, fixed)``, ``kinds`` its properties' (``fixed``: no lists; ``place`` the place of each
    line's first value in its row) or its segments' (``place`` each row's segment ends)."""
    _, kinds, place, fixed = layout
    if fixed:
        return kinds[(place[row] + rank) % kinds.size]
    return kinds[(rank[:, None] >= place[row]).sum(axis=1)]


def _ply_int_places(layout, counts):
    """Per line of ``layout`` (see :func:`_ply_kinds`) holding ``counts`` words: a bit mask of
    the places (up to :data:`_PLY_MASK_BITS`) of its words that are read as integers."""
    _, kinds, place, fixed = layout
    mask = np.zeros(counts.size, dtype=np.int64)
    if (kinds == _PLY_REAL).all():
        return mask
    if fixed:                                        # a table by the first value's place and the count
        bits = _PLY_MASK_BITS
        table = np.zeros((kinds.size, bits + 1), dtype=np.int64)
        for first in range(kinds.size):
            ints = kinds[(first + np.arange(bits)) % kinds.size] != _PLY_REAL
            table[first, 1:] = np.cumsum(np.where(ints, np.left_shift(np.int64(1), np.arange(bits)), 0))
        return table[place, np.minimum(counts, bits)]
    begin = np.zeros(counts.size, dtype=np.int64)
    for j, kind in enumerate(kinds):
        end = np.minimum(place[:, j], _PLY_MASK_BITS)
        if kind != _PLY_REAL:
            mask |= (np.left_shift(np.int64(1), end) - 1) & ~(np.left_shift(np.int64(1), begin) - 1)
        begin = end
    return mask


def _ply_values_problem(lines, layouts, words_of, line_of, text):
    """The first value that fscanf would not read whole as its property's type, or None
    (``lines``: :class:`_PlyLines`; ``layouts``: per element, see :func:`_ply_kinds`).
    Integers must be a sign and digits fitting 32 bits; reals a decimal number, ``nan`` or
    ``inf``. Per line, numpy compares the places of the words that are no integers with those
    read as integers; words no decimal number and integers of 10 digits are looked at one by
    one, and so are lines of more than :data:`_PLY_MASK_BITS` words."""
    found = []                                                       # (byte, message)

    def refuse(word, where, kind):
        shown = word.decode("ascii", "replace")
        if b"," in word:
            found.append((where, f"line {line_of(where)} ({text(where)!r}) writes {shown!r} with a decimal comma, "
                                 "which pymeshlab's PLY reader reads only up to the comma (1,5 as 1) and then "
                                 "misplaces every later value; write numbers with a decimal point"))
        else:
            what = {_PLY_INT: "an integer (digits, fitting 32 bits)", _PLY_REAL: "a number",
                    _PLY_SHORT: "a vertex index of type short (up to 32767: pymeshlab wraps larger ones)"}[kind]
            found.append((where, f"line {line_of(where)} ({text(where)!r}) holds {shown!r} where {what} is read, "
                                 "which pymeshlab's PLY reader reads only up to the first character that does not "
                                 "fit (2.5 as 2 for an index) and then misplaces or drops the rest without a "
                                 "word; fix the value"))

    def fine(word, kind):
        if kind != _PLY_REAL:
            low, high = (-2 ** 15, 2 ** 15) if kind == _PLY_SHORT else (-2 ** 31, 2 ** 32)
            return _PLY_INTEGER.fullmatch(word) is not None and low <= int(word) < high
        return _PLY_WORDS.fullmatch(word) is not None or _PLY_REAL_WORD.fullmatch(word) is not None

    line_layout = np.full(lines.start.size, -1, dtype=np.int64)     # each line's element, row
    line_row = np.zeros(lines.start.size, dtype=np.int64)
    for e, layout in enumerate(layouts):
        line_layout[layout[0]] = e
        line_row[layout[0]] = np.arange(layout[0].size)
    for e, layout in enumerate(layouts):
        mine = layout[0]
        counts = lines.count[mine]
        kinds = layout[1]
        if (kinds == _PLY_REAL).all():
            clash = np.zeros(mine.size, dtype=np.int64)
        elif (kinds != _PLY_REAL).all():
            clash = lines.not_int[mine]                            # every word is read as an integer
        else:
            clash = lines.not_int[mine] & _ply_int_places(layout, counts)
        bad = np.flatnonzero(clash)
        if bad.size:                                             # the lowest place of the first line
            line, bits = int(mine[bad[0]]), int(clash[bad[0]])
            rank = (bits & -bits).bit_length() - 1
            refuse(words_of(line).split()[rank], int(lines.first[line]),
                   int(_ply_kinds(layout, np.array([bad[0]]), np.array([rank]))[0]))
        for row in np.flatnonzero(counts > _PLY_MASK_BITS).tolist():     # checked word by word
            words = words_of(int(mine[row])).split()
            kinds = _ply_kinds(layout, np.full(len(words), row), np.arange(len(words)))
            for word, kind in zip(words, kinds.tolist()):
                if not fine(word, kind):
                    refuse(word, int(lines.first[mine[row]]), kind)
                    break
    for group, width in ((lines.not_real, 3), (lines.long, 4)):
        if not group.size:
            continue
        e = line_layout[group[:, width - 2]]
        for (where, *rest), element in zip(group.tolist(), e.tolist()):
            line, rank = rest[-2], rest[-1]
            layout = layouts[element]
            kind = int(_ply_kinds(layout, np.array([line_row[line]]), np.array([rank]))[0])
            word = words_of(line).split()[rank]
            if not fine(word, kind):
                refuse(word, where, kind)
                break
    return min(found)[1] if found else None


#: A number as fscanf("%f") reads it whole: decimal, or hexadecimal as glibc reads it (0x1p-1).
_PLY_REAL_WORD = re.compile(rb"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
                            rb"|0[xX](?:[0-9a-fA-F]+\.?[0-9a-fA-F]*|\.[0-9a-fA-F]+)(?:[pP][+-]?[0-9]+)?)")
