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
scan reads the header and names only and seeks past the rest.
"""

import os
import struct

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
    ``truncated`` telling which."""
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
                  "normals": bool(flags & _HAS_NORMALS), "uv_maps": [], "attribute_maps": [], "problem": None,
                  "truncated": False}
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
