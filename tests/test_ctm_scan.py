"""_ctm_scan: OpenCTM files that pymeshlab's CTM reader crashes on or misreads, found from their
header and map names before it reads them."""

import json
import lzma
import re
import struct
import subprocess
import sys

import numpy as np
import pytest

from curvdetail._ctm_scan import ctm_layout, ctm_problem, ctm_vertex_map
from curvdetail._file_scan import check_before_loading

# a unit square of two triangles
_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype="<f4")
_F = np.array([[0, 1, 2], [1, 3, 2]], dtype="<u4")


def _string(text):
    data = text if isinstance(text, bytes) else text.encode()
    return struct.pack("<I", len(data)) + data


def _packed(values):
    """OpenCTM's LZMA data for 32-bit ``values`` (n, k): bytes interleaved by significance (most
    significant first), then by column; its size, the 5 property bytes, the stream."""
    values = np.ascontiguousarray(values).view("<u4")
    planes = values.astype(">u4").view(np.uint8).reshape(values.shape[0], values.shape[1], 4)
    stream = lzma.compress(planes.transpose(2, 1, 0).tobytes(), format=lzma.FORMAT_ALONE)
    return struct.pack("<I", len(stream) - 13) + stream[:5] + stream[13:]    # less the 8-byte size


def _index_deltas(F):
    """OpenCTM's MG1 and MG2 triangles: each from its least corner, sorted; then the first corner
    as the difference to the one before, the second to the first corner (to the second corner
    before where two triangles start alike), the third to the first corner."""
    T = np.array(sorted(tuple(np.roll(t, -int(np.argmin(t)))) for t in np.asarray(F).tolist()), dtype=np.int64)
    deltas = T.copy()
    deltas[1:, 0] = np.diff(T[:, 0])
    alike = np.r_[False, T[1:, 0] == T[:-1, 0]]
    deltas[:, 1] -= np.where(alike, np.r_[0, T[:-1, 1]], T[:, 0])
    deltas[:, 2] -= T[:, 0]
    return deltas.astype("<u4")


def _ctm(method="RAW", attributes=(), uv_maps=(), normals=False, values=None):
    """The bytes of a CTM file of the square in ``method``, with attribute maps and UV maps of
    these names (values 0.5 and 0) and normals (0, 0, 1). MG2 stores the vertices as offsets in
    a grid (here one box over the unit cube), sorted by x, and the triangles renumbered so.
    ``values``: a list of (4, 4) values, one per attribute map, instead (MG2: whole multiples of
    its precision, 1/256, stored as signed magnitudes of the differences between vertices in
    that order; without ``values``, zeros)."""
    n = len(_V)
    given = values is not None
    maps = [np.full((n, 4), 0.5, "<f4")] * len(attributes) if values is None else [np.asarray(v, "<f4") for v in values]
    head = (b"OCTM" + struct.pack("<I", 5) + method.encode() + b"\0"
            + struct.pack("<5I", n, len(_F), len(uv_maps), len(attributes), int(normals)) + _string("test"))
    normal = np.tile(np.float32([0, 0, 1]), (n, 1))
    if method == "RAW":
        body = b"INDX" + _F.tobytes() + b"VERT" + _V.tobytes() + (b"NORM" + normal.tobytes() if normals else b"")
        body += b"".join(b"TEXC" + _string(u) + _string("") + np.zeros((n, 2), "<f4").tobytes() for u in uv_maps)
        body += b"".join(b"ATTR" + _string(a) + v.tobytes() for a, v in zip(attributes, maps))
    elif method == "MG1":
        body = b"INDX" + _packed(_index_deltas(_F)) + b"VERT" + _packed(_V) + (b"NORM" + _packed(normal) if normals else b"")
        body += b"".join(b"TEXC" + _string(u) + _string("") + _packed(np.zeros((n, 2), "<f4")) for u in uv_maps)
        body += b"".join(b"ATTR" + _string(a) + _packed(v) for a, v in zip(attributes, maps))
    else:
        step = 1.0 / 1024
        order = np.argsort(_V[:, 0], kind="stable")                     # (0,0), (0,1), (1,0), (1,1)
        grid = np.round(_V[order] / step).astype(np.int64)
        grid[1:, 0] = np.diff(grid[:, 0])                               # x: delta to the one before
        rank = np.argsort(order)                                        # a vertex's place in that order
        body = (b"MG2H" + struct.pack("<2f3f3f3I", step, 1 / 256, 0, 0, 0, 1, 1, 1, 1, 1, 1)
                + b"VERT" + _packed(grid.astype("<u4")) + b"GIDX" + _packed(np.zeros((n, 1), "<u4"))
                + b"INDX" + _packed(_index_deltas(rank[_F])))
        body += b"NORM" + _packed(np.zeros((n, 3), "<u4")) if normals else b""
        body += b"".join(b"TEXC" + _string(u) + _string("") + struct.pack("<f", 1 / 4096)
                         + _packed(np.zeros((n, 2), "<u4")) for u in uv_maps)
        for a, v in zip(attributes, maps):
            steps = np.round(v[order] * 256).astype(np.int64) if given else np.zeros((n, 4), np.int64)
            steps[1:] = np.diff(steps, axis=0)
            magnitudes = np.where(steps < 0, -1 - 2 * steps, 2 * steps).astype("<u4")      # the sign in bit 0
            body += b"ATTR" + _string(a) + struct.pack("<f", 1 / 256) + _packed(magnitudes)
    return head + body


# Which layouts crashed pymeshlab 2025.7's CTM reader (segmentation fault), the same in RAW, MG1
# and MG2, with and without normals and UV maps: "Quality" without "Color" (it reads the
# quality from the colour map), and an unnamed map that its look-up of "Color" or "Quality"
# reaches (strcmp with a null pointer). Names are compared as C strings, case and all.
_CRASHES = [("Quality",), ("Other", "Quality"), ("",), ("Color", ""), ("", "Color"), ("Color", "", "Quality"),
            (b"Quality\0note",)]
_READ = [(), ("Color",), ("Color", "Quality"), ("Quality", "Color"), ("Other",), ("quality",),
         ("Color", "Quality", ""), ("Quality", "Color", ""), (b"Color\0x", "Quality"), (b"\0", "Color")]


@pytest.mark.parametrize("method", ["RAW", "MG1", "MG2"])
@pytest.mark.parametrize("extras", [{}, {"uv_maps": ("UV",), "normals": True}])
def test_layouts_that_crash_the_reader_are_found_and_no_others(tmp_path, method, extras):
    path = tmp_path / "m.ctm"
    for attributes in _CRASHES + _READ:
        path.write_bytes(_ctm(method, attributes, **extras))
        layout = ctm_layout(path)
        assert layout["problem"] is None and layout["method"] == method
        assert layout["attribute_maps"] == [a if isinstance(a, bytes) else a.encode() for a in attributes]
        assert (ctm_problem(path) is not None) == (attributes in _CRASHES), attributes


@pytest.mark.parametrize("attributes, message", [
    (("Quality",), r"m\.ctm': it holds a vertex attribute map named 'Quality' but none named 'Color', and "
                   r"pymeshlab's CTM reader reads the quality from the colour map, so on such a file it crashes "
                   r"the process \(segmentation fault; .*\); export the mesh again without quality \(or with "
                   r"vertex colours\), or convert it with OpenCTM's own tool \(ctmconv in.ctm out.ply\)"),
    (("Color", ""), r"its vertex attribute map 1 has no name, and pymeshlab's CTM reader compares the names with a "
                    r"null pointer there while looking for 'Quality': it crashes the process"),
])
def test_check_before_loading_names_the_crash_and_the_fix(tmp_path, attributes, message):
    path = tmp_path / "m.ctm"
    path.write_bytes(_ctm("MG1", attributes))
    with pytest.raises(ValueError, match=message):
        check_before_loading(str(path))


@pytest.mark.parametrize("method", ["RAW", "MG1", "MG2"])
def test_a_file_shorter_than_its_sections_is_refused(tmp_path, method):
    # pymeshlab read a RAW file cut inside its vertices as (0, 0, 0) for the missing ones, and one
    # cut by a byte with a z of 0.5 (a value read before); MG1 and MG2 read nothing, or all of it
    data = _ctm(method, ("Color",))
    path = tmp_path / "m.ctm"
    for cut in (1, len(data) // 3):
        path.write_bytes(data[:-cut])
        assert re.search(r"the file ends \(\d+ bytes\) inside its '(INDX|VERT|GIDX|ATTR)' section, before the data its "
                         r"header declares: the file is damaged or incomplete", ctm_problem(path))
    path.write_bytes(data + b"trailing bytes")                            # ignored by the reader
    assert ctm_problem(path) is None


def test_a_raw_file_shorter_than_its_sections_says_what_the_reader_would_read(tmp_path):
    path = tmp_path / "m.ctm"
    path.write_bytes(_ctm("RAW")[:-20])
    assert "reads what a RAW file lacks from whatever memory held, without a word" in ctm_problem(path)


def test_a_section_out_of_place_is_named(tmp_path):
    path = tmp_path / "m.ctm"
    path.write_bytes(_ctm("RAW").replace(b"VERT", b"VERX"))
    # the reader reads nothing from it ("read nothing", read_mesh would say): named here instead
    assert ctm_problem(path) == ("it holds b'VERX' at byte 68, where its 'VERT' section should start: the file is "
                                 "damaged or incomplete; export it again")


def test_counts_whose_arrays_overflow_32_bits_are_refused(tmp_path):
    # OpenCTM sizes its map arrays in 32 bits: 2**28 vertices of 16-byte attributes wrap to 0
    data = bytearray(_ctm("MG1", ("Color",)))
    struct.pack_into("<I", data, 12, 1 << 28)
    path = tmp_path / "m.ctm"
    path.write_bytes(bytes(data))
    assert "sizes in 32 bits (4294967296 bytes wrap around)" in ctm_problem(path)
    struct.pack_into("<I", data, 12, (1 << 28) - 1)
    path.write_bytes(bytes(data))
    assert ctm_problem(path) is None


@pytest.mark.parametrize("data", [b"", b"OCTM", b"XCTM" + _ctm()[4:], _ctm()[:4] + struct.pack("<I", 6) + _ctm()[8:],
                                  _ctm()[:8] + b"MG3\0" + _ctm()[12:],
                                  _ctm()[:12] + struct.pack("<I", 0) + _ctm()[16:]])
def test_files_the_reader_refuses_itself_are_left_to_it(tmp_path, data):
    # not OpenCTM 5, an unknown method, no vertices: pymeshlab reads nothing (read_mesh says so)
    path = tmp_path / "m.ctm"
    path.write_bytes(data)
    assert ctm_layout(path) is None and ctm_problem(path) is None


_LOAD = """
import sys, pymeshlab
ms = pymeshlab.MeshSet()
ms.load_new_mesh(sys.argv[1])
print(ms.current_mesh().vertex_number(), ms.current_mesh().face_number())
"""


def test_the_scan_agrees_with_pymeshlab(tmp_path):
    # the layouts refused crash pymeshlab's reader and the others load: a pymeshlab whose reader
    # is fixed (or breaks elsewhere) shows here. One child process per file: a crash ends it.
    for k, (method, attributes) in enumerate([("RAW", ("Quality",)), ("MG2", ("Color", "")),
                                              ("MG1", ("Color", "Quality")), ("MG2", ("Other",))]):
        path = tmp_path / f"m{k}.ctm"
        path.write_bytes(_ctm(method, attributes))
        done = subprocess.run([sys.executable, "-c", _LOAD, str(path)], capture_output=True, text=True, timeout=120)
        if ctm_problem(path) is None:
            assert done.returncode == 0 and done.stdout.split() == ["4", "2"], (method, attributes, done.stderr)
        else:
            assert done.returncode != 0, (method, attributes, done.stdout)


# distinct values per vertex and channel, multiples of MG2's precision (1/256), some negative
_COLOURS = (np.arange(16, dtype=np.float32).reshape(4, 4) + 1) / 32
_QUALITY = np.array([[10.5, 0, 0, 0], [-3.25, 0, 0, 0], [7, 0, 0, 0], [0.00390625, 0, 0, 0]], dtype=np.float32)


@pytest.mark.parametrize("method", ["RAW", "MG1", "MG2"])
@pytest.mark.parametrize("extras", [{}, {"uv_maps": ("UV",), "normals": True}])
def test_a_vertex_map_is_decoded_as_openctm_reads_it(tmp_path, method, extras):
    # pymeshlab reads the quality from the colour map; the "Quality" map is decoded here instead.
    # Checked two ways: the hand-made values (MG2 stores the vertices sorted by x, and its maps
    # so), and pymeshlab's own reading of the colour map's first channel (what it calls quality)
    path = tmp_path / "m.ctm"
    path.write_bytes(_ctm(method, ("Color", "Other", "Quality"), values=[_COLOURS, -_COLOURS, _QUALITY], **extras))
    order = np.argsort(_V[:, 0], kind="stable") if method == "MG2" else np.arange(4)
    assert np.array_equal(ctm_vertex_map(path, b"Quality"), _QUALITY[order])
    assert np.array_equal(ctm_vertex_map(path, b"Other"), -_COLOURS[order])
    colours = ctm_vertex_map(path, b"Color")
    assert np.array_equal(colours, _COLOURS[order]) and colours.dtype == np.float32
    assert ctm_vertex_map(path, b"quality") is None                   # names compare case and all
    done = subprocess.run([sys.executable, "-c", _QUALITY_READ, str(path)], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert np.array_equal(json.loads(done.stdout), colours[:, 0].astype(np.float64).tolist())


_QUALITY_READ = """
import json, sys, pymeshlab
ms = pymeshlab.MeshSet()
ms.load_new_mesh(sys.argv[1])
print(json.dumps(ms.current_mesh().vertex_scalar_array().tolist()))
"""


def test_a_vertex_map_name_is_compared_as_a_c_string(tmp_path):
    # OpenCTM's look-up compares names up to their first zero byte, and takes the first match
    path = tmp_path / "m.ctm"
    path.write_bytes(_ctm("MG1", (b"Quality\0note", "Quality"), values=[_QUALITY, -_QUALITY]))
    assert np.array_equal(ctm_vertex_map(path, b"Quality"), _QUALITY)


def test_a_vertex_map_of_a_damaged_file_is_not_decoded(tmp_path):
    path = tmp_path / "m.ctm"
    path.write_bytes(_ctm("MG1", ("Color", "Quality"))[:-3])
    assert ctm_layout(path)["truncated"] and ctm_vertex_map(path, b"Quality") is None


def test_a_vertex_map_whose_data_is_short_is_refused(tmp_path):
    # OpenCTM's reader fails on such a file (its LZMA data decodes to less than the map's size)
    data = _ctm("MG1", ("Color", "Quality"), values=[_COLOURS, _QUALITY])
    path = tmp_path / "m.ctm"
    path.write_bytes(data[:data.rindex(b"ATTR")] + b"ATTR" + _string("Quality") + _packed(_QUALITY[:2]))
    assert ctm_problem(path) is None
    assert np.array_equal(ctm_vertex_map(path, b"Color"), _COLOURS)
    with pytest.raises(ValueError, match=r"its 'Quality' map's LZMA data holds 32 bytes of the 64 its header declares"):
        ctm_vertex_map(path, b"Quality")
