"""_file_counts: the vertex and face counts a mesh file declares, and the check against what
pymeshlab loaded."""

import numpy as np
import pytest

from curvdetail import _file_counts
from curvdetail._file_counts import check_loaded, declared_counts

OBJ = b"v 0 0 0\nvt 1 1\nv\t1 0 0\r\n  v 9 9 9\nvn 0 0 1\nv 0 1 0\nf 1 2 3\nf\t1 3 4\n  f 1 1 1\nv 1 1 1"


@pytest.mark.parametrize("chunk", [1, 2, 3, 5, 64])
def test_obj_lines_are_counted_across_chunk_boundaries(tmp_path, monkeypatch, chunk):
    path = tmp_path / "m.obj"
    path.write_bytes(OBJ)
    monkeypatch.setattr(_file_counts, "_CHUNK", chunk)
    # indented lines are neither vertices nor faces to pymeshlab
    assert declared_counts(str(path)) == (4, 2)


def test_off_and_ply_headers_give_both_counts(tmp_path):
    off = tmp_path / "m.off"
    off.write_text("# comment\nOFF\n5 7 0\n")
    assert declared_counts(off) == (5, 7)
    coff = tmp_path / "m.off"
    coff.write_text("COFF 4 2 0\n")
    assert declared_counts(coff) == (4, 2)
    ply = tmp_path / "m.ply"
    ply.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\n"
                    b"element face 16\nproperty list uchar int vertex_indices\nend_header\n\x00\x01")
    assert declared_counts(ply) == (10, 16)
    assert declared_counts(tmp_path / "m.xyz") == (None, None)          # a format without counts


def _binary_stl(path, triangles, count=None):
    triangles = np.asarray(triangles, dtype="<f4")
    record = np.zeros(len(triangles), dtype=[("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attr", "<u2")])
    record["corners"] = triangles
    path.write_bytes(b"solid but binary".ljust(80, b" ") + np.uint32(count if count is not None else
                     len(triangles)).astype("<u4").tobytes() + record.tobytes())


_TRIANGLES = [[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0], [0, 1, 0]]]


@pytest.mark.parametrize("chunk", [3, 7, 64, 1 << 20])
def test_stl_triangles_are_counted_from_the_binary_header_or_the_ascii_facets(tmp_path, monkeypatch, chunk):
    monkeypatch.setattr(_file_counts, "_CHUNK", chunk)
    binary = tmp_path / "b.stl"
    _binary_stl(binary, _TRIANGLES)                  # its header starts with "solid", too
    assert declared_counts(binary) == (None, 2)
    ascii_stl = tmp_path / "a.stl"
    ascii_stl.write_text("solid t\n" + "".join(
        " facet normal 0 0 1\n  outer loop\n" + "".join(f"   vertex {x} {y} {z}\n" for x, y, z in t) +
        "  endloop\n endfacet\n" for t in _TRIANGLES) + "endsolid t\n")
    assert declared_counts(ascii_stl) == (None, 2)
    odd = tmp_path / "c.stl"
    _binary_stl(odd, _TRIANGLES, count=7)            # the size does not match the count
    odd.write_bytes(b"x" + odd.read_bytes()[1:])     # and it is not ASCII either
    assert declared_counts(odd) == (None, None)


def test_check_loaded_accepts_a_complete_load_and_names_what_is_missing(tmp_path):
    path = tmp_path / "m.off"
    path.write_text("OFF\n4 2 0\n")
    F = np.array([[0, 1, 2], [1, 3, 2]])
    check_loaded(str(path), 4, F)                                  # complete: nothing raised
    check_loaded(str(path), 4, np.vstack([F, F]))                  # polygons triangulated: more is fine
    with pytest.raises(ValueError, match=r"has 4 vertices but pymeshlab loaded 3: 1 was dropped"):
        check_loaded(str(path), 3, F[:1])
    with pytest.raises(ValueError, match=r"has 2 faces but pymeshlab loaded 1 triangles"):
        check_loaded(str(path), 4, F[:1])
    with pytest.raises(KeyError, match=r"1 face uses vertex indices outside the file's 4 vertices "
                                       r"\(first: face 1, \[1, 4, 2\]"):
        check_loaded(str(path), 4, np.array([[0, 1, 2], [1, 4, 2]]), error=KeyError)


def test_counts_are_whole_numbers_as_atoi_reads_them():
    from curvdetail._file_counts import _whole

    assert [_whole(w) for w in (b"3", b"+3", b"-3", b"03", b"3.0", b"3.", b"3.000")] == [3, 3, -3, 3, 3, 3, 3]
    assert [_whole(w) for w in (b"2.5", b"1e1", b".0", b"x", b"#", b"", b"3#")] == [None] * 7


def test_declared_off_counts_read_whole_numbers_and_not_others(tmp_path):
    path = tmp_path / "m.off"
    path.write_text("OFF\n4.0 2. 0\n")
    assert declared_counts(path) == (4, 2)
    path.write_text("OFF\n4.5 2 0\n")
    assert declared_counts(path) == (None, None)


@pytest.mark.parametrize("chunk", [1, 3, 7, 64, 1 << 20])
def test_stl_names_and_odd_words_are_not_counted_as_vertices_or_facets(tmp_path, monkeypatch, chunk):
    # pymeshlab skips the solid line and reads the words of a facet by their place: only lines
    # that start with "vertex" or "endfacet" are corners or facet ends (it read this file right)
    facet = ("  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 1 0 0\n"
             "\tvertex 0 1 0\n    endloop\n  endfacet\n")
    path = tmp_path / "m.stl"
    path.write_text("solid my vertex endfacet model\n" + facet * 2 + "endsolid my vertex\tendfacet model")
    monkeypatch.setattr(_file_counts, "_CHUNK", chunk)
    assert _file_counts._stl_ascii_counts(path) == (2, 6)
    assert _file_counts._stl_counts(path, exact=True) == (None, 2)
    check_loaded(str(path), 3, np.array([[0, 1, 2], [0, 1, 2]]))      # its 2 triangles: nothing dropped
    with pytest.raises(ValueError, match="has 2 faces but pymeshlab loaded 1 triangles"):
        check_loaded(str(path), 3, np.array([[0, 1, 2]]))


_SCANNED_OBJ = [
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    b"v 0 0 0\r\nv\t1 0 0\r\nv 0 1 0\r\nf\t1 2 3\r\nf 1 2 3",               # CR LF, tabs, no last newline
    b"# c\nvt 0 0\nvn 0 0 1\nv 0 0 0\nv 1 0 0\nv 0 1 0\n f 1 2 3\nfoo\nf 1/1 2/1 3/1\n",   # indented f: not counted
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 \\\n3 4\nf 1 \\\n2 \\\n3\n",   # faces continued over lines
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \\\n\t3\nf 3 2 1\\",                  # a tab after the join; a last "\\"
]


@pytest.mark.parametrize("size", [1 << 20, 8])
@pytest.mark.parametrize("text", _SCANNED_OBJ)
def test_counts_the_scan_hands_on_are_those_declared_counts_reads(tmp_path, monkeypatch, text, size):
    # read_mesh gives check_loaded the counts check_before_loading found instead of reading the file
    # again: they must be declared_counts' own, lines joined by a backslash and pieces notwithstanding
    from curvdetail import _file_scan
    path = tmp_path / "m.obj"
    path.write_bytes(text)
    monkeypatch.setattr(_file_scan, "_obj_face_indices",
                        lambda p, sizes=None, counts=None, _f=_file_scan._obj_face_indices: _f(p, size, sizes, counts))
    counts = []
    _file_scan.check_before_loading(str(path), counts=counts)
    assert counts == [declared_counts(str(path))]


@pytest.mark.parametrize("text, facets", [
    (b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
     b"endsolid t\n", 1),
    (b"solid endfacet vertex\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
     b"endfacet\nendsolid t\n", 1),                                   # words in the name: lines counted
])
def test_stl_facets_the_scan_hands_on_lead_check_loaded_to_the_same_verdict(tmp_path, text, facets):
    from curvdetail._file_scan import check_before_loading
    path = str(tmp_path / "m.stl")
    with open(path, "wb") as f:
        f.write(text)
    counts = []
    check_before_loading(path, counts=counts)
    assert counts == [(None, facets)]
    for loaded in (facets, facets - 1):                                 # complete, and one dropped
        F = np.zeros((loaded, 3), dtype=np.int64)
        try:
            check_loaded(path, 3, F)
            expected = None
        except ValueError as exc:
            expected = str(exc)
        try:
            check_loaded(path, 3, F, counts=counts[0])
            got = None
        except ValueError as exc:
            got = str(exc)
        assert got == expected
