"""Pre-scan of OpenCTM files for :func:`curvdetail._file_scan.check_before_loading`: what
pymeshlab's CTM reader would crash on or misread without a word.

pymeshlab reads CTM with OpenCTM 1.0.3 and vcglib's ``ImporterCTM``, which looks the vertex
attribute maps up by name: first "Color", then "Quality", comparing each map's name with
``strcmp`` (a map with an empty name has none: a null pointer). It then reads the quality from
the *colour* map (``ctmGetFloatArray(context, colorAttrib)``), so a file with a "Quality" map
and no "Color" map crashed the process (segmentation fault) every time, and with both it reads
the colour's red channel as the quality. A RAW file shorter than its sections was read without
a word, the missing values taken from whatever memory held. Each was tried on pymeshlab
2025.7 with RAW, MG1 and MG2 files, with and without normals and UV maps.

The file format (version 5; all integers 32-bit little endian, strings a length then the
bytes): "OCTM", version, method ("RAW\\0", "MG1\\0", "MG2\\0"), vertex count, triangle count,
UV map count, attribute map count, flags (1: normals), comment; then the sections, in this
order: RAW ``INDX VERT [NORM] (TEXC name file)* (ATTR name)*``, each followed by its values;
MG1 the same, each followed by LZMA data (packed size, 5 bytes of properties, the bytes); MG2
``MG2H`` (44 bytes) ``VERT GIDX INDX [NORM]`` then ``TEXC name file precision`` and ``ATTR name
precision``, each followed by LZMA data. The map names are outside the compressed data, so the
scan reads the header and names only and seeks past the rest; :func:`ctm_vertex_map` then
decodes the one map whose values pymeshlab's reader gets wrong ("Quality").
"""

import lzma
import os
import struct

import numpy as np

_METHODS = (b"RAW\x00", b"MG1\x00", b"MG2\x00")
_HAS_NORMALS = 1
_MG2_HEADER = 44          # vertex and normal precision, grid min and max, divisions: 11 x 4 bytes
#: OpenCTM computes the byte sizes of its arrays in 32 bits (``CTMuint``): an array of 2**32
#: bytes or more wraps to a small buffer that it then fills past its end.
_SIZE_LIMIT = 1 << 32


class _Truncated(Exception):
    """The file ends inside a section."""


class _BadSection(Exception):
    """A section tag is not the one the reader expects."""


class _Reader:
    """Sequential reads and skips over an open binary file of ``size`` bytes; raises _Truncated
    where the file ends before what is asked for."""

    def __init__(self, f, size):
        self.f, self.size, self.section = f, size, "header"      # the section being read, for messages

    def read(self, n):
        if self.f.tell() + n > self.size:          # checked first: a damaged length can be 4 GB
            raise _Truncated
        return self.f.read(n)

    def uint(self):
        return struct.unpack("<I", self.read(4))[0]

    def string(self):
        return self.read(self.uint())

    def skip(self, n):
        if self.f.tell() + n > self.size:
            raise _Truncated
        self.f.seek(n, os.SEEK_CUR)

    def tag(self, expected):
        self.section = expected.decode()
        at = self.f.tell()
        found = self.read(4)
        if found != expected:
            raise _BadSection(f"it holds {found!r} at byte {at}, where its {expected.decode()!r} section should start")

    def packed(self):
        """Skip LZMA data: its size, 5 bytes of properties, the bytes."""
        self.skip(5 + self.uint())


def ctm_layout(path):
    """The layout of the OpenCTM file ``path`` as pymeshlab's reader sees it, or None where that
    reader refuses the file itself (not "OCTM", a version other than 5, an unknown method, no
    vertices or no triangles: it then reads nothing).

    Returns a dict: ``method`` ("RAW", "MG1", "MG2"), ``vertices``, ``triangles``, ``normals``
    (bool), ``uv_maps`` and ``attribute_maps`` (their names as bytes, in file order; ``b""`` for a
    map without a name), and ``problem``: None, or a str naming where the file ends early or
    holds a section other than the one expected (the names read up to there are kept), with
    ``truncated`` telling which, and ``attribute_offsets``: where each attribute map's values
    start in the file (RAW: the floats; MG1: the LZMA data's size; MG2: the map's precision)."""
    with open(path, "rb") as f:
        size = os.fstat(f.fileno()).st_size
        r = _Reader(f, size)
        try:
            if r.read(4) != b"OCTM" or r.uint() != 5:
                return None
            method = r.read(4)
            vertices, triangles, uv_count, attribute_count, flags = (r.uint() for _ in range(5))
        except _Truncated:
            return None                       # the reader stops at the header: nothing is read
        if method not in _METHODS or vertices == 0 or triangles == 0:
            return None
        layout = {"method": method[:3].decode(), "vertices": vertices, "triangles": triangles,
                  "normals": bool(flags & _HAS_NORMALS), "uv_maps": [], "attribute_maps": [], "attribute_offsets": [],
                  "problem": None, "truncated": False}
        raw, mg2 = method == b"RAW\x00", method == b"MG2\x00"
        try:
            r.string()                                                   # the comment
            if mg2:
                r.tag(b"MG2H")
                r.skip(_MG2_HEADER)
            order = (b"VERT", b"GIDX", b"INDX") if mg2 else (b"INDX", b"VERT")
            raw_sizes = {b"INDX": 12 * triangles, b"VERT": 12 * vertices, b"NORM": 12 * vertices}
            for tag in order + ((b"NORM",) if layout["normals"] else ()):
                r.tag(tag)
                if raw:
                    r.skip(raw_sizes[tag])
                else:
                    r.packed()
            for tag, names, values in ((b"TEXC", layout["uv_maps"], 8), (b"ATTR", layout["attribute_maps"], 16)):
                for _ in range(uv_count if tag == b"TEXC" else attribute_count):
                    r.tag(tag)
                    names.append(r.string())
                    if tag == b"TEXC":
                        r.string()                                       # the texture's file name
                    else:
                        layout["attribute_offsets"].append(r.f.tell())
                    if raw:
                        r.skip(values * vertices)
                    else:
                        r.skip(4 if mg2 else 0)                          # MG2: the map's precision
                        r.packed()
        except _Truncated:
            where = "header" if r.section == "header" else f"{r.section!r} section"
            layout["problem"] = f"the file ends ({size} bytes) inside its {where}, before the data its header declares"
            layout["truncated"] = True
        except _BadSection as exc:
            layout["problem"] = str(exc)
        return layout


def ctm_problem(path):
    """A sentence (what is wrong, and what to do) for an OpenCTM file that pymeshlab's CTM
    reader would crash on or misread, or None (also for files it refuses itself: it then reads
    nothing, which the caller reports).

    Found: a "Quality" attribute map with no "Color" map (the reader reads the quality from the
    colour map and crashed, every time); a map without a name that the reader's look-up of
    "Color" or "Quality" reaches (maps after both named ones are never compared; an empty name
    crashed it); sections that end past the end of the file or hold another tag (RAW: read from
    whatever memory held; MG1, MG2: read as nothing, or as far as the data goes); counts whose
    arrays OpenCTM sizes past 32 bits (from its source: it would write past its buffers)."""
    layout = ctm_layout(path)
    if layout is None:
        return None
    if layout["problem"] is not None:
        misread = (" (pymeshlab's CTM reader reads what a RAW file lacks from whatever memory held, without a word)"
                   if layout["method"] == "RAW" and layout["truncated"] else "")
        return f"{layout['problem']}: the file is damaged or incomplete{misread}; export it again"
    n, names = layout["vertices"], layout["attribute_maps"]
    # the map arrays are sized in 32 bits in every method, the mesh arrays only when unpacked
    sizes = [8 * n if layout["uv_maps"] else 0, 16 * n if names else 0]
    if layout["method"] != "RAW":
        sizes += [12 * n, 12 * layout["triangles"]]
    if max(sizes) >= _SIZE_LIMIT:
        return (f"it declares {n} vertices and {layout['triangles']} triangles, whose arrays OpenCTM's reader "
                f"(in pymeshlab) sizes in 32 bits ({max(sizes)} bytes wrap around), so it would write past its "
                "buffers; convert the file with another tool (OpenCTM's ctmconv in.ctm out.ply) and read that")
    for wanted in (b"Color", b"Quality"):           # the reader's look-ups, in its order
        for k, name in enumerate(names):
            if not name:
                return (f"its vertex attribute map {k} has no name, and pymeshlab's CTM reader compares the names "
                        f"with a null pointer there while looking for {wanted.decode()!r}: it crashes the process "
                        "(segmentation fault); name the map (or remove it) and read the file again")
            if name.split(b"\x00", 1)[0] == wanted:
                break
    found = {name.split(b"\x00", 1)[0] for name in names}
    if b"Quality" in found and b"Color" not in found:
        return ("it holds a vertex attribute map named 'Quality' but none named 'Color', and pymeshlab's CTM reader "
                "reads the quality from the colour map, so on such a file it crashes the process (segmentation "
                "fault; MeshLab uses the same reader); export the mesh again without quality (or with vertex "
                "colours), or convert it with OpenCTM's own tool (ctmconv in.ctm out.ply), and read that")
    return None


def _c_name(name):
    """A map's name as OpenCTM's look-up compares it: a C string, up to its first zero byte."""
    return name.split(b"\x00", 1)[0]


def ctm_vertex_map(path, name, layout=None):
    """The values of the first vertex attribute map of the OpenCTM file ``path`` whose name is
    ``name`` (bytes; compared as OpenCTM's ``ctmGetNamedAttribMap`` does, as a C string), as
    OpenCTM decodes them: a (vertices, 4) float32 array, in the order of the vertices the
    reader returns (MG2 stores them sorted, and its maps so). None where no map has that name,
    or the file is one :func:`ctm_layout` finds no layout in or a problem with.

    RAW holds the floats; MG1 LZMA data of the floats' bytes, interleaved by significance (most
    significant first), then by column; MG2 the same of integers, each a signed magnitude (its
    lowest bit the sign) and a difference to the vertex before, in units of the map's precision.
    ``layout``: :func:`ctm_layout`'s answer for ``path``, where the caller has it.

    Raises ValueError where the LZMA data cannot be decoded to the map's size (OpenCTM's reader
    then reads nothing from the file) or uses options Python's LZMA decoder lacks."""
    layout = ctm_layout(path) if layout is None else layout
    if layout is None or layout["problem"] is not None:
        return None
    names = [_c_name(n) for n in layout["attribute_maps"]]
    if name not in names:
        return None
    n = layout["vertices"]
    with open(path, "rb") as f:
        r = _Reader(f, os.fstat(f.fileno()).st_size)
        f.seek(layout["attribute_offsets"][names.index(name)])
        if layout["method"] == "RAW":
            return np.frombuffer(r.read(16 * n), dtype="<f4").reshape(n, 4).astype(np.float32)
        precision = struct.unpack("<f", r.read(4))[0] if layout["method"] == "MG2" else None
        words = _unpack(r, n, 4, name)
    if precision is None:                                                # MG1: the floats' bits
        return words.view(np.float32)
    signed = np.where(words & 1, -((words.astype(np.int64) + 1) >> 1), words.astype(np.int64) >> 1)
    # OpenCTM sums the differences in 32-bit integers, then scales each in single precision
    values = np.cumsum(signed.astype(np.int32), axis=0, dtype=np.int32)
    return values.astype(np.float32) * np.float32(precision)


#: liblzma's smallest dictionary; a larger one than a stream was written with decodes it alike
_LZMA_DICTIONARY_MIN = 4096


def _unpack(r, count, width, name):
    """OpenCTM's packed 32-bit words at ``r``'s position (LZMA data: its size, 5 bytes of
    properties, the stream without an end marker) as a (count, width) uint32 array."""
    size = r.uint()
    properties = r.read(5)
    stream = r.read(size)
    pb, rest = divmod(properties[0], 45)
    lp, lc = divmod(rest, 9)
    dictionary = max(struct.unpack("<I", properties[1:])[0], _LZMA_DICTIONARY_MIN)
    wanted = 4 * count * width
    label = name.decode(errors="replace")
    try:
        decoder = lzma.LZMADecompressor(format=lzma.FORMAT_RAW, filters=[
            {"id": lzma.FILTER_LZMA1, "dict_size": dictionary, "lc": lc, "lp": lp, "pb": pb}])
        data = decoder.decompress(stream, max_length=wanted)
    except (lzma.LZMAError, ValueError) as exc:
        raise ValueError(f"its {label!r} map's LZMA data cannot be decoded here ({exc})") from None
    if len(data) != wanted:
        raise ValueError(f"its {label!r} map's LZMA data holds {len(data)} bytes of the {wanted} its header declares")
    planes = np.frombuffer(data, dtype=np.uint8).reshape(4, width, count).astype(np.uint32)
    shifts = np.array([24, 16, 8, 0], dtype=np.uint32)[:, None, None]
    return np.bitwise_or.reduce(planes << shifts, axis=0).T.copy()
