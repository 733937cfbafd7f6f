"""_file_counts: the vertex and face counts a mesh file declares, and the check against what
pymeshlab loaded."""

import numpy as np
import pytest

from curvdetail import _file_counts
from curvdetail._file_counts import check_before_loading, check_loaded, declared_counts

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
    with pytest.raises(ValueError, match=r"has 4 vertices but pymeshlab loaded 3: 1 were dropped"):
        check_loaded(str(path), 3, F[:1])
    with pytest.raises(ValueError, match=r"has 2 faces but pymeshlab loaded 1 triangles"):
        check_loaded(str(path), 4, F[:1])
    with pytest.raises(KeyError, match=r"1 faces use vertex indices outside the file's 4 vertices "
                                       r"\(first: face 1, \[1, 4, 2\]"):
        check_loaded(str(path), 4, np.array([[0, 1, 2], [1, 4, 2]]), error=KeyError)


_OFF_VERTICES = "0 0 0\n1 0 0\n0 1 0\n1 1 0\n"


@pytest.mark.parametrize("faces, message", [
    ("3 0 1 2\n3 1 3 4\n", r"1 faces use vertex indices outside the file's 4 vertices \(first: face 1, \[1, 3, 4\]\)"),
    ("3 0 1 2\n3 1 3 -1\n", r"\(first: face 1, \[1, 3, -1\]\)"),
    ("3 0 1 2\n3 1 3 12\n", r"\(first: face 1, \[1, 3, 12\]\)"),            # more digits than 4
    ("3 9 1 2 0.25 0.5 0.75 1\n3 1 3 2\n", r"\(first: face 0, \[9, 1, 2\]\)"),  # colours after it
    ("4 0 1 3 7\n3 0 1 2\n", r"\(first: face 0, \[0, 1, 3, 7\]\)"),          # a quad
])
def test_off_faces_out_of_range_are_found_before_loading(tmp_path, faces, message):
    path = tmp_path / "bad.off"
    path.write_text("OFF\n# comment\n4 2 0\n" + _OFF_VERTICES + "\n" + faces)
    with pytest.raises(ValueError, match=message):
        check_before_loading(path)


@pytest.mark.parametrize("text", [
    "OFF\n4 2 0\n" + _OFF_VERTICES + "3 0 1 2\n3 1 3 2\n",
    "COFF 4 2 0\r\n" + _OFF_VERTICES.replace("\n", " 255 0 0 255\r\n") + "3 0 1 2 0.5 0.5 0.5\r\n  3 1 3 2\r\n",
    "OFF\n4 2 0\n" + _OFF_VERTICES + "3 0 1 2 # 99 in a comment\n\n   \n3 1 3 2 255 128 0\n",
    "OFF\n12 1 0\n" + "0 0 0\n" * 12 + "3 9 10 11\n",                      # two-digit indices < 12
])
def test_off_files_with_indices_in_range_pass(tmp_path, text):
    path = tmp_path / "ok.off"
    path.write_bytes(text.encode())
    check_before_loading(path)


@pytest.mark.parametrize("first_line", [b"OFF BINARY\n", b"coff binary # colours\r\n"])
def test_binary_off_is_named_as_such_before_loading(tmp_path, first_line):
    # pymeshlab refuses it with "Invalid file" and no word on why
    path = tmp_path / "b.off"
    path.write_bytes(first_line + np.array([3, 1, 0], ">i4").tobytes() + np.zeros(9, ">f4").tobytes())
    with pytest.raises(ValueError, match="binary OFF file .* save it as ASCII OFF, PLY or OBJ"):
        check_before_loading(path)


def test_off_indices_of_the_vertex_count_s_width_are_compared_by_value(tmp_path):
    path = tmp_path / "m.off"
    vertices = "0 0 0\n" * 100
    path.write_text("OFF\n100 2 0\n" + vertices + "3 97 98 99\n3 98 99 100\n")
    with pytest.raises(ValueError, match=r"1 faces .* 100 vertices \(first: face 1, \[98, 99, 100\]\)"):
        check_before_loading(path)


@pytest.mark.parametrize("text, count, line", [
    (b"v 0 0 0\n  v 1 0 0\nv 0 1 0\n\tv 1 1 0\nf 1 2 3\n", 2, 2),
    (b" v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", 1, 1),
    (b"# c\r\nv 0 0 0\r\nv 1 0 0\r\n \t v 0 1 0\r\nf 1 2 3\r\n", 1, 4),
])
def test_obj_with_indented_vertex_lines_is_refused_before_loading(tmp_path, text, count, line):
    # pymeshlab's OBJ loader aborted the process (malloc: invalid size) on such a file
    path = tmp_path / "m.obj"
    path.write_bytes(text)
    with pytest.raises(ValueError, match=rf"{count} vertex lines start with spaces or tabs \(first: line {line}\)"):
        check_before_loading(path)


@pytest.mark.parametrize("text", [b"", b"v 0 0 0\nvt 1 1\n  vt 0 1\n  vn 0 0 1\n\tf 1 1 1\n# v 1 2 3\n"])
def test_obj_without_indented_vertex_lines_passes(tmp_path, text):
    path = tmp_path / "m.obj"
    path.write_bytes(text)
    check_before_loading(path)


def test_a_short_or_odd_face_line_does_not_hide_a_bad_index_after_it(tmp_path):
    path = tmp_path / "m.off"
    path.write_text("off\n4 3 0\n" + _OFF_VERTICES + "2 0 1\n3 0 1 2\n3 1 3 7\n")
    with pytest.raises(ValueError, match=r"1 faces use vertex indices .* \(first: face 2, \[1, 3, 7\]\)"):
        check_before_loading(path)
