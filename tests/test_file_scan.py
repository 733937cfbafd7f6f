"""_file_scan: OFF and OBJ files that pymeshlab would misread or read into corrupt memory,
found before loading."""

import json
import re

import numpy as np
import pytest

from curvdetail import _file_scan
from curvdetail._file_scan import check_before_loading

_OFF_VERTICES = "0 0 0\n1 0 0\n0 1 0\n1 1 0\n"


@pytest.mark.parametrize("faces, message", [
    ("3 0 1 2\n3 1 3 4\n", r"1 face uses vertex indices outside the file's 4 vertices \(first: face 1, \[1, 3, 4\]\)"),
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
    # empty lines, "\r" lines and "#" lines are skipped (a line of blanks is not: it repeated a face)
    "OFF\n4 2 0\n" + _OFF_VERTICES + "3 0 1 2 # 99 in a comment\n\n\r\n# c\n3 1 3 2 255 128 0\n",
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
    with pytest.raises(ValueError, match=r"1 face .* 100 vertices \(first: face 1, \[98, 99, 100\]\)"):
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
    with pytest.raises(ValueError, match=r"1 face uses vertex indices .* \(first: face 2, \[1, 3, 7\]\)"):
        check_before_loading(path)


# What pymeshlab's OFF and OBJ readers read right although the rows are unusual (each checked
# against pymeshlab itself: a vertex's values are one stream of words across lines to it, and
# counts and indices are read with atoi, which stops at the first character not a digit), and
# what they misread without a word. read_mesh must take the first and refuse the second.
_V4 = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
_F2 = [[0, 1, 2], [0, 2, 3]]
_OBJ_V4 = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"


@pytest.mark.parametrize("name, text", [
    ("split vertex", "OFF\n4 2 0\n0 0 0\n1 0\n0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n"),
    ("split the other way", "OFF\n4 2 0\n0 0 0\n1\n0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n"),
    ("split in three", "OFF\n4 2 0\n0 0 0\n1\n0\n# between\n0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n"),
    ("split last vertex", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1\n0\n3 0 1 2\n3 0 2 3\n"),
    ("split, CRLF", "OFF\r\n4 2 0\r\n0 0 0\r\n1 0\r\n0\r\n\r\n1 1 0\r\n0 1 0\r\n3 0 1 2\r\n3 0 2 3\r\n"),
    ("split NOFF", "NOFF\n4 2 0\n0 0 0\n0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n3 0 2 3\n"),
    ("whole-number header counts", "OFF\n4.0 2. 0.0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n"),
    ("whole-number face rows", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3.0 0 1 2\n3 0.0 2 3.00\n"),
    ("comment glued to a value", "OFF\n4 2 0\n0 0 0#first\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2#one\n3 0 2 3\n"),
    ("first line blank", "OFF\n4 2 0\n   \n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n"),
    ("COFF, comment as colour", "COFF\n4 2 0\n0 0 0 # red\n1 0 0\n1 1 0\n0 1 0 255 0 0\n3 0 1 2\n3 0 2 3\n"),
])
def test_off_rows_pymeshlab_reads_right_are_read(tmp_path, name, text):
    _read_as_the_two_triangles(tmp_path / "m.off", text)


def _read_as_the_two_triangles(path, text):
    from curvdetail.io.mesh import read_mesh
    path.write_bytes(text.encode())
    V, F = read_mesh(path)
    np.testing.assert_array_equal(V, _V4)
    assert F.tolist() == _F2


@pytest.mark.parametrize("name, text", [
    ("glued comment", _OBJ_V4 + "f 1 2 3#x\nf 1 3 4\n"),
    ("glued after texture index", _OBJ_V4 + "vt 0 0\nf 1/1 2/1 3/1#note.\nf 1/1 3/1 4/1\n"),
    ("bare hash", _OBJ_V4 + "f 1 2 3#\nf 1 3 4\n"),
    ("glued, then blanks", _OBJ_V4.replace("\n", "\r\n") + "f 1 2 3#x \t\r\nf 1 3 4\r\n"),
    ("whole-number indices", _OBJ_V4 + "f 1.0 2. 3\nf 1 3.00 4\n"),
])
def test_obj_faces_pymeshlab_reads_right_are_read(tmp_path, name, text):
    _read_as_the_two_triangles(tmp_path / "m.obj", text)


@pytest.mark.parametrize("text, message", [
    # a value missing, then one too many: no split, pymeshlab shifts everything after it
    ("OFF\n4 2 0\n0 0 0\n1 0\n1 1 0 0\n0 1 0\n3 0 1 2\n3 0 2 3\n",
     r"2 vertex rows hold a number of values other than 3 \(x y z\) \(first: vertex 1, 2 values\) on line 4 "
     r"\('1 0'\).*split over lines only if those lines hold exactly its 3 values"),
    ("OFF\n4 2 0\n0 0 0 1\n0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n", r"\(first: vertex 0, 4 values\) on line 3"),
    ("OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0 7\n3 0 1 2\n3 0 2 3\n", r"\(first: vertex 3, 4 values\) on line 6"),
    # two short rows that add up to one vertex leave the faces a row short
    ("OFF\n4 2 0\n0 0\n1\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n",
     r"vertex 3, 4 values\) on line 7 \('3 0 1 2'\).* \(lines 3-4 were read as one vertex split over them"),
    ("OFF\n4 2 0\n0 0 0\n0 0\n1\n1 1 0\n0 1 0\n3 0 1 2\n",
     r"the file holds 6 rows after it \(truncated, or the counts are wrong\) \(lines 4-5 were read as one"),
    ("OFF\n2 1 0\n0 0 0\n1 0\n", r"holds 2 rows after it .* \(line 4 was read as the start of a vertex split"),
    ("NOFF\n4 2 0\n0 0 0\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n3 0 2 3\n",
     r"other than 6 \(x y z and the normal\) \(first: vertex 0, 3 values\).*a NOFF file is read as one stream"),
    ("STOFF\n4 2 0\n0 0 0 0 0\n1 0 0\n1 1 0 0 0\n0 1 0 0 0\n3 0 1 2\n3 0 2 3\n",
     r"other than 5 \(x y z and the texture coordinates\) \(first: vertex 1, 3 values\)"),
    # with colours the rest of the line is the colour: a split vertex takes the next row as one
    ("COFF\n4 2 0\n0 0 0\n1 0\n0 255 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n",
     r"1 vertex rows hold fewer than 3 values \(first: vertex 1, 2 values\) on line 4.*on its own line"),
    ("COFF\n4 2 0\n0 0 0 1 1 1 1 1\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n",
     r"1 vertex rows hold more than 7 values \(first: vertex 0, 8 values\)"),
    # comments are words to pymeshlab, except on lines that start with "#"
    ("OFF\n4 2 0\n0 0 0 # c\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n",
     r"line 3 \('0 0 0 # c'\) has a comment among the vertex values.*move the comment to a line of its own"),
    ("OFF\n4 2 0\n0 0 #z\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n", r"line 3 \('0 0 #z'\) has a comment"),
    ("OFF\n4 2 0\n0 0 0\n  # indented\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n", r"line 4 \('# indented'\) has a"),
    ("COFF\n4 2 0\n0 0 # c\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n", r"line 3 \('0 0 # c'\) has a comment"),
    # a line of blanks is no empty line to pymeshlab: among the faces it repeated the face before
    ("OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n \t\n3 0 2 3\n", r"line 8 holds nothing but blanks"),
    ("OFF\n4 2 0\n0 0 0\n  \n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n", r"line 4 holds nothing but blanks"),
    # counts and indices are read with atoi
    ("OFF\n4.5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n",
     r"the header's vertex and face counts '4.5 2' are not both whole numbers"),
    # a header written 4.0 is read as 4, and the rows are checked as with 4 (they were not at all)
    ("OFF\n4.0 2 0\n0 0 0 7\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n", r"\(first: vertex 0, 4 values\) on line 3"),
    ("OFF\n-4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n", r"counts '-4 2' are not both whole"),
    ("OFF\n4 2e0 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n", r"counts '4 2e0' are not both whole"),
    ("OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2e0\n3 0 2 3\n", r"face 0 is the row '3 0 1 2e0', which is not"),
    ("OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 # 2\n3 0 2 3\n", r"face 0 is the row '3 0 1 # 2', which"),
    ("OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1#x 2\n3 0 2 3\n", r"face 0 is the row '3 0 1#x 2', which"),
])
def test_off_rows_pymeshlab_misreads_are_refused_naming_the_line(tmp_path, text, message):
    path = tmp_path / "m.off"
    path.write_bytes(text.encode())
    with pytest.raises(ValueError, match=message):
        check_before_loading(path)


@pytest.mark.parametrize("index", ["2.5", "x", "+"])
def test_off_index_shorter_than_the_vertex_count_is_read_as_written(tmp_path, index):
    # with 1000 vertices a three-character "2.5" was taken for an index in range: pymeshlab read 2
    path = tmp_path / "m.off"
    path.write_text("OFF\n1000 2 0\n" + "0 0 0\n" * 1000 + f"3 997 998 999\n3 998 999 {index}\n")
    with pytest.raises(ValueError, match=re.escape(f"face 1 is the row '3 998 999 {index}', which is not a")):
        check_before_loading(path)


@pytest.mark.parametrize("face, line, message", [
    ("f 1 2 3#x y\n", 5, "ends in a comment"),           # "y" became a corner (0, 2, 4)
    ("f 1 2 3 #x\n", 5, "ends in a comment"),
    ("f 1 2 3 #\n", 5, "ends in a comment"),
    ("f 1 2#x 3\n", 5, "ends in a comment"),            # the 3 after the comment was read as a corner
    ("f 1/1 2/1 3/1#x\t7\n", 5, "ends in a comment"),
    ("f 1 2 3/#x\n", 5, "ends in a comment"),
    ("f 1 2 3\nf 1 3 4#face. 2\n", 6, "ends in a comment"),
    ("f 1 2 3.5#x\n", 5, "has a fractional index"),
    ("f 1 2 3#x\nf 1 3.5 4\n", 6, "has a fractional index"),
    # 1.5 is the texture coordinate's index here: the message must not call it a vertex's
    ("f 1 2/1.5 3\n", 5, r"has a fractional index \(of a vertex, texture coordinate or normal\)"),
])
def test_obj_faces_pymeshlab_misreads_are_refused(tmp_path, face, line, message):
    path = tmp_path / "m.obj"
    path.write_text(_OBJ_V4 + face)
    with pytest.raises(ValueError, match=f"the face on line {line} {message}"):
        check_before_loading(path)


_OFF_OK = "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n"


@pytest.mark.parametrize("name, text, message", [
    # "v 1,5 2 3" and the OFF row "1,5 2 3" were both read as the vertex (1, 2, 3)
    ("m.obj", _OBJ_V4.replace("v 1 0 0", "v 1,5 0 0") + "f 1 2 3\n", r"line 2 \('v 1,5 0 0'\) writes a number "
                                                                      r"with a comma.*decimals with a point"),
    ("m.obj", _OBJ_V4 + "vt 0,5 0\nf 1 2 3\n", r"line 5 \('vt 0,5 0'\) writes a number with a comma"),
    ("m.obj", _OBJ_V4 + "f 1,2,3\n", r"line 5 \('f 1,2,3'\) writes a number with a comma"),
    ("m.off", _OFF_OK.replace("\n1 0 0", "\n1,5 0 0"), r"line 4 \('1,5 0 0'\) writes a number with a comma.*"
                                                         r"with a point"),
    ("m.off", _OFF_OK.replace("3 0 2 3", "3 0 2 3 0,5 0 0"), r"line 8 \('3 0 2 3 0,5 0 0'\) writes a number"),
    # face rows beyond the header's count were dropped
    ("m.off", _OFF_OK + "3 1 2 3\n", r"the header declares 4 vertices and 2 faces, but 1 more row follows the "
                                     r"last face \(first: line 9, '3 1 2 3'\)"),
    ("m.off", _OFF_OK.replace("4 2 0", "4 1 0"), r"declares 4 vertices and 1 face, but 1 more row follows"),
])
def test_decimal_commas_and_extra_off_faces_are_refused(tmp_path, name, text, message):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        check_before_loading(path)


@pytest.mark.parametrize("name, text", [
    ("m.off", _OFF_OK + "\n\n# the end, really\n  \n\r\n"),        # blank lines, comments after the faces
    ("m.off", _OFF_OK + "  # indented, after the faces\n\t# and tabbed\n"),     # read as nothing, like any
    ("m.off", _OFF_OK.replace("OFF\n", "OFF\n# made by me, today\n").replace("3 0 1 2", "3 0 1 2 # a, b")),
    ("m.obj", "# made by me, today\n" + _OBJ_V4.replace("v 0 0 0", "v 0 0 0 # x, y") + "o a,b\nf 1 2 3\nf 1 3 4\n"),
])
def test_commas_in_comments_and_names_and_trailing_comments_pass(tmp_path, name, text):
    from curvdetail.io.mesh import read_mesh
    path = tmp_path / name
    path.write_text(text)
    V, F = read_mesh(path)
    np.testing.assert_array_equal(V, _V4 if name.endswith(".obj") else [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    assert F.shape == (2, 3)


@pytest.mark.parametrize("name, text", [
    ("m.off", "OFF\r4 2 0\r0 0 0\r1 0 0\r1 1 0\r0 1 0\r3 0 1 2\r3 0 2 3\r"),
    ("m.obj", "v 0 0 0\rv 1 0 0\rv 1 1 0\rv 0 1 0\rf 1 2 3\rf 1 3 4\r"),
    ("m.ply", "ply\rformat ascii 1.0\relement vertex 4\rproperty float x\rproperty float y\rproperty float z\r"
              "element face 2\rproperty list uchar int vertex_indices\rend_header\r0 0 0\r1 0 0\r1 1 0\r0 1 0\r"
              "3 0 1 2\r3 0 2 3\r"),
])
def test_carriage_return_line_ends_are_named(tmp_path, name, text):
    # pymeshlab failed ("Unable to open file", "truncated") or read the OBJ as one vertex
    path = tmp_path / name
    path.write_bytes(text.encode())
    with pytest.raises(ValueError, match="ends its lines with carriage returns alone"):
        check_before_loading(path)
    path.write_bytes(text.replace("\r", "\r\n").encode())         # CRLF is read right
    check_before_loading(path)


# Coordinates (OBJ v lines, OFF vertex rows): pymeshlab reads each with atof, which stops at the
# first character that does not fit and reads what it has without a word, and takes C's
# hexadecimal floats. Each form below was loaded with pymeshlab itself (2025.7, the value it read
# in the second column; the tests check it again); read_mesh must refuse them before loading, and
# read decimal numbers right.
_NOT_NUMBERS = [
    ("abc", "0"), ("0.3abc", "0.3"), ("-", "0"), ("+", "0"), (".", "0"), ("--1", "0"), ("+-1", "0"),
    ("1e", "1"), ("1e+", "1"), ("e5", "0"), (".e5", "0"), ("1.2.3", "1.2"), ("1e5.5", "100000"),
    ("1e5e5", "100000"), ("1-2", "1"), ("5.-", "5"), ("0x10", "16"), ("0x1p3", "8"), ("0X1P-1", "0.5"),
    ("1d3", "1"), ("1D3", "1"), ("1_000", "1"), ("1.5f", "1.5"), ("٣", "0"), ("\x015", "0"),
    ("infx", None), ("nan(1)", None),          # read as inf and NaN: the vertex is dropped
]


def _coordinate_files(form):
    """An OBJ and an OFF file of four vertices whose second is (0.5, ``form``, 2)."""
    rows = ["7 8 9", f"0.5 {form} 2", "0 1 0", "1 1 0"]
    obj = "".join(f"v {row}\n" for row in rows) + "f 1 2 3\nf 1 3 4\n"
    off = "OFF\n4 2 0\n" + "".join(f"{row}\n" for row in rows) + "3 0 1 2\n3 0 2 3\n"
    return {"m.obj": obj, "m.off": off}


# pymeshlab reads the files below wrong, by design of these tests; they are loaded in a child
# process, so that whatever a loader fed such input does to its memory stays out of the suite's
_LOADER = """
import json, sys
import pymeshlab
out = []
for path in sys.argv[1:]:
    ms = pymeshlab.MeshSet()
    try:
        ms.load_new_mesh(path)
        out.append(ms.current_mesh().vertex_matrix().tolist())
    except Exception:
        out.append(None)
print(json.dumps(out))
"""


def _pymeshlab_vertices_of(paths):
    """What pymeshlab reads from each file, in a child process: (k, 3) arrays, None where it
    refuses the file."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", _LOADER, *map(str, paths)], capture_output=True, text=True,
                          check=True, timeout=600)
    return [None if v is None else np.array(v, dtype=float).reshape(-1, 3) for v in json.loads(done.stdout)]


def _pymeshlab_vertices(path):
    V = _pymeshlab_vertices_of([path])[0]
    assert V is not None, f"pymeshlab did not read {path}"
    return V


@pytest.mark.parametrize("name", ["m.obj", "m.off"])
@pytest.mark.parametrize("form, value", _NOT_NUMBERS)
def test_coordinates_that_are_not_decimal_numbers_are_refused(tmp_path, name, form, value):
    path = tmp_path / name
    path.write_bytes(_coordinate_files(form)[name].encode())
    shown = re.escape(repr(form)[1:-1])
    if name == "m.obj":
        message = (rf"line 2 \('v 0.5 {shown} 2'\) has the y coordinate '{shown}', which is not a decimal number: "
                   rf"pymeshlab's OBJ loader reads it as {value or '(inf|nan)'} without a word \(the line was read "
                   rf"as the vertex \(0.5, {value or '(inf|nan)'}, 2\).*write the coordinates as decimal numbers")
    elif "\x01" in form:                                       # a part of a value to pymeshlab, not to the scan
        message = rf"line 4 \('0.5 {shown} 2'\) holds the control character b'\\x01', which pymeshlab's OFF"
    else:
        message = (rf"line 4 \('0.5 {shown} 2'\) holds the y coordinate '{shown}' of vertex 1, which is not a "
                   rf"decimal number: pymeshlab's OFF reader reads it as {value or '(inf|nan)'} without a word")
    with pytest.raises(ValueError, match=message):
        check_before_loading(path)
    if value is not None:                                      # what pymeshlab makes of it, as the message says
        np.testing.assert_array_equal(_pymeshlab_vertices(path)[1], [0.5, float(value), 2])


@pytest.mark.parametrize("rows, line, message, read", [
    ("v -1 0 0\nv 1 0 0\nv 0 1e 0\n", 3, r"\('v 0 1e 0'\) has the y coordinate '1e'", [0, 1, 0]),
    ("v 0x1p3 0 0\nv 1 0 0\nv 0 1 0\n", 1, r"\('v 0x1p3 0 0'\) has the x coordinate '0x1p3'.*\(8, 0, 0\)", [8, 0, 0]),
    ("v 0 0 0\r\nv 1 0 abc\r\nv 0 1 0\r\n", 2, r"\('v 1 0 abc'\) has the z coordinate 'abc'", [1, 0, 0]),
    ("v\t0\t0\t0\nv\t1\t-\t0\nv 0 1 0\n", 2, r"\('v\\t1\\t-\\t0'\) has the y coordinate '-'", [1, 0, 0]),
    ("v 0 0 0 # fine\nv 1 0 0.5.5 # not\nv 0 1 0\n", 2, r"\('v 1 0 0.5.5 # not'\) has the z coordinate '0.5.5'",
     [1, 0, 0.5]),
    # a comment before the z: its words (the "#" too, as 0) are read as coordinates
    ("v 0 0 0\nv 1 0#c 5\nv 0 1 0\n", 2, r"\('v 1 0#c 5'\) has a comment among its coordinates.*\(1, 0, 5\)",
     [1, 0, 5]),
    ("v 0 0 0\nv 1 0 # c\nv 0 1 0\n", 2, r"\('v 1 0 # c'\) has a comment among its coordinates.*\(1, 0, 0\)",
     [1, 0, 0]),
    ("v 0 0 0\nv 1 # 0 0\nv 0 1 0\n", 2, r"\('v 1 # 0 0'\) has a comment among its coordinates.*\(1, 0, 0\)",
     [1, 0, 0]),
    ("v 0 0 0\nv 1#x 0 5\nv 0 1 0\n", 2, r"\('v 1#x 0 5'\) has a comment among its coordinates.*\(1, 0, 5\)",
     [1, 0, 5]),
])
def test_obj_vertex_lines_pymeshlab_misreads_are_refused(tmp_path, rows, line, message, read):
    path = tmp_path / "m.obj"
    path.write_bytes(("# made by hand\nvt 0 0\n" + rows + "f 1 2 3\n").encode())
    with pytest.raises(ValueError, match=rf"line {line + 2} {message}"):
        check_before_loading(path)
    np.testing.assert_array_equal(_pymeshlab_vertices(path)[line - 1], read)     # as the message says


@pytest.mark.parametrize("text, message", [
    ("COFF\n3 1 0\n0 0 0 255 0 0\n1 0x1 0 255 0 0\n0 1 0\n3 0 1 2\n",
     r"line 4 \('1 0x1 0 255 0 0'\) holds the y coordinate '0x1' of vertex 1, which is not a decimal number"),
    ("NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 z 0 0 1\n3 0 1 2\n", r"line 5 .* the z coordinate 'z' of vertex 2"),
    ("OFF\n3 1 0\n0 0 0\n1\n0 1e\n0 1 0\n3 0 1 2\n", r"line 5 \('0 1e'\) holds the z coordinate '1e' of vertex 1"),
    ("OFF\r\n3 1 0\r\n0 0 0\r\n# c\r\n1 0 -0-\r\n0 1 0\r\n3 0 1 2\r\n", r"line 5 .* z coordinate '-0-' of vertex 1"),
    # a control character is part of a value to pymeshlab (it splits at spaces and tabs), not to the scan
    ("OFF\n3 1 0\n0 0 0\n1 \x010 0\n0 1 0\n3 0 1 2\n", r"line 4 .* holds the control character b'\\x01'"),
    ("NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 \x01 0 1\n0 1 0 0 0 1\n3 0 1 2\n", r"line 4 .* control character"),
    ("COFF\n3 1 0\n0 0 0\n1 \x01 0 0\n0 1 0\n3 0 1 2\n", r"line 4 .* holds the control character"),
])
def test_off_vertex_rows_pymeshlab_misreads_are_refused(tmp_path, text, message):
    path = tmp_path / "m.off"
    path.write_bytes(text.encode())
    with pytest.raises(ValueError, match=message):
        check_before_loading(path)


@pytest.mark.parametrize("name, row, expected", [
    ("m.obj", "v 1e5 1E-3 +2", [1e5, 1e-3, 2]),
    ("m.obj", "v -.5 .5 5.", [-0.5, 0.5, 5]),
    ("m.obj", "v 00012 1.e5 -0", [12, 1e5, 0]),
    ("m.obj", "v 2.5E+1 1e-400 -1.5e-3", [25, 0, -1.5e-3]),
    ("m.obj", "v 0.1 0.2 0.3#comment", [0.1, 0.2, 0.3]),
    ("m.obj", "v 0.1 0.2 0.3 # a comment, in words 1.2.3", [0.1, 0.2, 0.3]),
    ("m.obj", "v 0.1 0.2 0.3 0.25 0.5 1", [0.1, 0.2, 0.3]),         # a vertex colour
    ("m.obj", "v 0.1 0.2 0.3 1", [0.1, 0.2, 0.3]),                  # w
    ("m.obj", "v\t0.1\t 0.2  0.3\t", [0.1, 0.2, 0.3]),
    ("m.obj", "v 0.1 0.2\x01 0.3", [0.1, 0.2, 0.3]),                # atof stops at the control character
    ("m.obj", "v 0.1 \x0b0.2 0.3", [0.1, 0.2, 0.3]),                # and skips a leading vertical tab
    ("m.off", "1e5 1E-3 +2", [1e5, 1e-3, 2]),
    ("m.off", "-.5 .5 5.", [-0.5, 0.5, 5]),
    ("m.off", "0.1 0.2 0.3#comment", [0.1, 0.2, 0.3]),
    ("m.off", "0.1#comment 0.2 0.3", [0.1, 0.2, 0.3]),              # a word to pymeshlab, read up to the "#"
    ("m.off", "0.1 0.2\x01 0.3", [0.1, 0.2, 0.3]),
    ("m.off", "0.1 \x0b0.2 0.3", [0.1, 0.2, 0.3]),
])
@pytest.mark.parametrize("line_end", ["\n", "\r\n"])
def test_decimal_coordinates_are_read_right(tmp_path, name, row, expected, line_end):
    from curvdetail.io.mesh import read_mesh
    path = tmp_path / name
    rows = _coordinate_files("1")[name].split("\n")
    rows[1 if name == "m.obj" else 3] = row
    path.write_bytes(line_end.join(rows).encode())
    V, _ = read_mesh(path)
    np.testing.assert_array_equal(V, [[7, 8, 9], expected, [0, 1, 0], [1, 1, 0]])


@pytest.mark.parametrize("text", [
    "COFF\n4 2 0\n7 8 9\n0.1 0.2 0.3 red green blue\n0 1 0\n1 1 0\n3 0 1 2\n3 0 2 3\n",   # colours: not kept
    "NOFF\n4 2 0\n7 8 9 0 0 1\n0.1 0.2 0.3 up 0 1\n0 1 0 0 0 1\n1 1 0 0 0 1\n3 0 1 2\n3 0 2 3\n",  # normals
    "COFF\n4 2 0\n7 8 9\n0.1 0.2 0.3 \x01 255\x02 0\n0 1 0\n1 1 0\n3 0 1 2\n3 0 2 3\n",   # control characters too
])
def test_off_values_after_the_coordinates_are_not_judged(tmp_path, text):
    from curvdetail.io.mesh import read_mesh
    path = tmp_path / "m.off"
    path.write_text(text)
    V, _ = read_mesh(path)
    np.testing.assert_array_equal(V, [[7, 8, 9], [0.1, 0.2, 0.3], [0, 1, 0], [1, 1, 0]])


@pytest.mark.parametrize("name", ["m.obj", "m.off"])
@pytest.mark.parametrize("form", ["inf", "-Infinity", "nan", "NaN"])
def test_inf_and_nan_are_read_as_such_and_the_dropped_vertex_reported(tmp_path, name, form):
    from curvdetail.io.mesh import MeshFileError, read_mesh

    path = tmp_path / name
    path.write_text(_coordinate_files(form)[name])
    check_before_loading(path)                                 # read right: pymeshlab drops the vertex
    with pytest.raises(MeshFileError, match="1 was dropped, most likely for non-finite"):
        read_mesh(path)


# Fuzzing: small files with coordinates mutated at random; whatever the scan passes, pymeshlab
# must read as a strict reader does (a decimal number, inf or nan before any "#", control
# characters only where atof stops at or skips them), and what the scan refuses as such a
# reader would.
_STRICT_NUMBER = re.compile(rb"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|[+-]?(?:inf|infinity|nan)",
                            re.IGNORECASE)
_CONTROL_CHARACTER = re.compile(rb"[\x00-\x08\x0b\x0c\x0e-\x1f]")


def _strict_value(word, coordinate=True):
    """The value of ``word`` as a strict reader reads it, or None where it is not a number (0.0
    for a word that is no coordinate but a single word to pymeshlab and the scan alike)."""
    if _CONTROL_CHARACTER.search(word):
        match = re.fullmatch(rb"([\x00-\x08\x0b\x0c\x0e-\x1f]*)([^\x00-\x20]+)[\x00-\x08\x0b\x0c\x0e-\x1f]*", word)
        if match is None or (coordinate and match.group(1).strip(b"\x0b\x0c")):
            return None
        word = match.group(2)
    if not coordinate:
        return 0.0
    word = word.split(b"#", 1)[0]
    return float(word) if _STRICT_NUMBER.fullmatch(word) else None


def _strict_obj_vertices(text):
    vertices = []
    for line in text.split(b"\n"):
        if line[:2] in (b"v ", b"v\t"):
            words = [word for word in re.split(rb"[ \t\r]+", line) if word]
            if len(words) < 4 or b"#" in words[1] + words[2]:
                return None
            vertices.append([_strict_value(word) for word in words[1:4]])
    return None if any(None in v for v in vertices) else np.array(vertices, dtype=float)


def _strict_off_vertices(text):
    lines = text.split(b"\n")
    keyword, count = lines[0].split()[0], int(lines[1].split()[0])
    rows = [line for line in lines[2:] if line and line[:1] not in (b"#", b"\r")][:count]
    vertices = []
    for row in rows:
        words = [word for word in re.split(rb"[ \t]+", row.rstrip(b"\r")) if word]
        if not (3 <= len(words) <= 7 if keyword == b"COFF" else len(words) == (6 if keyword == b"NOFF" else 3)):
            return None
        if any(word.startswith(b"#") for word in words[:3]):
            return None
        if keyword != b"COFF" and None in [_strict_value(word, False) for word in words[3:]]:
            return None                                      # a normal the scan and pymeshlab split apart
        vertices.append([_strict_value(word) for word in words[:3]])
    return None if any(None in v for v in vertices) else np.array(vertices, dtype=float)


def _mutated(word, rng):
    alphabet = list(b"0123456789.+-eE#xXabdDpPfinINF \t,_") + [0x01, 0x0b, 0xc2]
    word = bytearray(word)
    for _ in range(rng.integers(1, 3)):
        op, char = rng.integers(5), alphabet[rng.integers(len(alphabet))]
        if op == 0 or not word:
            word.insert(rng.integers(len(word) + 1), char)
        elif op == 1:
            word[rng.integers(len(word))] = char
        elif op == 2:
            del word[rng.integers(len(word))]
        elif op == 3:
            word = bytearray(rng.choice([b"inf", b"-nan", b"1e5", b".5", b"5.", b"-.5e-3", b"0x10", b"1d3", b"abc",
                                         b"-", b"+2", b"1e", b"Infinity", b"0.3abc"]))
        else:
            word.append(char)
    return bytes(word)


def _fuzzed_file(rng, obj):
    starts = [b"0.5", b"-1.25", b"3", b"1e-2", b"0", b"2.5E1"]
    rows = [[starts[rng.integers(len(starts))] for _ in range(3)] for _ in range(5)]
    for _ in range(rng.integers(1, 3)):
        i, j = rng.integers(5), rng.integers(3)
        rows[i][j] = _mutated(rows[i][j], rng)
    end = rng.choice([b"\n", b"\r\n"])
    if obj:
        tails = [b""] * 5
        if rng.random() < 0.3:
            tails[rng.integers(5)] = rng.choice([b" # note", b"#note", b" 0.5 0.5 0.5", b" 1", b" # a b c", b" abc"])
        separator = rng.choice([b" ", b"\t", b"  "])
        return b"# fuzzed" + end + b"".join(b"v" + separator + separator.join(row) + tail + end
                                            for row, tail in zip(rows, tails)) + end.join([b"f 1 2 3", b"f 1 3 4",
                                                                                          b"f 2 4 5", b""])
    keyword = rng.choice([b"OFF", b"COFF", b"NOFF"])
    tails = [{b"OFF": b"", b"COFF": b" 255 0 0", b"NOFF": b" 0 0 1"}[keyword]] * 5
    if rng.random() < 0.3:
        i = rng.integers(5)
        tails[i] += rng.choice([b"#note", b" abc"]) if keyword == b"COFF" else b"#note"
    return keyword + end + b"5 3 0" + end + b"".join(b" ".join(row) + tail + end for row, tail in zip(rows, tails)) + \
        end.join([b"3 0 1 2", b"3 0 2 3", b"3 1 3 4", b""])


@pytest.mark.parametrize("extension", ["obj", "off"])
def test_fuzzed_coordinates_the_scan_passes_are_read_right(tmp_path, extension):
    rng = np.random.default_rng(20240611 + (extension == "off"))
    passed, refused = [], 0
    for i in range(200):
        text = _fuzzed_file(rng, extension == "obj")
        path = tmp_path / f"f{i}.{extension}"
        path.write_bytes(text)
        strict = _strict_obj_vertices(text) if extension == "obj" else _strict_off_vertices(text)
        try:
            check_before_loading(path)
        except ValueError as exc:
            if re.search("not a decimal number|comment among its coordinates|control character", str(exc)):
                refused += 1
                assert strict is None, (text, str(exc))               # refused only what is misread
            continue
        passed.append((path, text, strict))
    read = _pymeshlab_vertices_of([path for path, _, _ in passed])
    loaded = 0
    for (path, text, strict), V in zip(passed, read):
        if V is None:                                                  # pymeshlab says so: not silent
            continue
        loaded += 1
        assert strict is not None, (text, V.tolist())
        np.testing.assert_array_equal(V, strict[np.isfinite(strict).all(axis=1)], err_msg=repr(text))
    assert loaded >= 25 and refused >= 25                             # both kinds were tried (45+ each)


@pytest.mark.parametrize("text, line", [
    # pymeshlab joined the line with the next and lost that vertex: (0, 1, 0) was gone and a
    # vertex (0, 0, 0) appended (measured with pymeshlab 2025.7)
    ("v 0 0 0\nv 1 0 0 \\\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\n", 2),
    ("v 0 0 0\r\nv 1 0 0 \\\r\nv 0 1 0\r\nv 0 0 1\r\nf 1 2 3\r\n", 2),
    ("# made by hand \\\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", 1),
])
def test_obj_lines_continued_by_a_backslash_are_refused(tmp_path, text, line):
    path = tmp_path / "m.obj"
    path.write_bytes(text.encode())
    with pytest.raises(ValueError, match=rf"line {line} \(.*\) ends in a backslash, which pymeshlab's OBJ loader "
                                         "reads as a line continued"):
        check_before_loading(path)


@pytest.mark.parametrize("text, triangles", [
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 \\\n3\nf 1 3 4\n", [[0, 1, 2], [0, 2, 3]]),   # a continued face
    ("v 0 0 0\nv 1 0 0 \\ \nv 0 1 0\nf 1 2 3\n", [[0, 1, 2]]),                                # not at the line's end
])
def test_obj_backslashes_pymeshlab_reads_right_pass(tmp_path, text, triangles):
    from curvdetail.io.mesh import read_mesh
    path = tmp_path / "m.obj"
    path.write_bytes(text.encode())
    V, F = read_mesh(path)
    assert F.tolist() == triangles
    assert V[:3].tolist() == [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]


def test_ctm_files_are_scanned_whatever_the_case_of_their_extension(tmp_path):
    # a RAW OpenCTM file of one triangle with a "Quality" map and no "Color" map: pymeshlab's CTM
    # reader crashed on it (the scan itself is tested in test_ctm_scan.py)
    import struct

    def string(text):
        return struct.pack("<I", len(text)) + text

    data = (b"OCTM" + struct.pack("<I", 5) + b"RAW\0" + struct.pack("<5I", 3, 1, 0, 1, 0) + string(b"")
            + b"INDX" + struct.pack("<3I", 0, 1, 2) + b"VERT" + np.eye(3, dtype="<f4").tobytes()
            + b"ATTR" + string(b"Quality") + np.zeros((3, 4), "<f4").tobytes())
    for name in ("m.ctm", "M.CTM"):
        (tmp_path / name).write_bytes(data)
        with pytest.raises(ValueError, match=r"it holds a vertex attribute map named 'Quality' but none named 'Color'"):
            check_before_loading(str(tmp_path / name))
    (tmp_path / "ok.ctm").write_bytes(data.replace(b"Quality", b"Color\0\0"))
    assert check_before_loading(str(tmp_path / "ok.ctm")) is None


# OBJ face indices pymeshlab reads without a range check: 0 and one past the last vertex were
# written out of bounds (valgrind: invalid writes; exit 139 at times), -9 with 5 vertices and
# 4294967299 (2**32 + 3) with 3 named real vertices ([[1, 4, 2]], [[0, 1, 2]]).
_OBJ_V5 = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\n"


@pytest.mark.parametrize("text, message", [
    (_OBJ_V5 + "f 1 2 3 4\nf 2 5 0\n", r"line 7 \('f 2 5 0'\) names the vertex 0, which the file does not have"),
    (_OBJ_V5 + "f 1 2 3 4\nf 2 5 6\n", r"line 7 \('f 2 5 6'\) names the vertex 6.*\(5 v lines in all, 5 above"),
    (_OBJ_V5 + "f 2 5 -6\n", r"line 6 \('f 2 5 -6'\) names the vertex -6"),
    (_OBJ_V5 + "f 2 5 -9\n", r"names the vertex -9"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4294967299\n", r"line 4 \('f 1 2 4294967299'\) names the vertex 4294967299"),
    (_OBJ_V5 + "f 1 2 3 99\nf 2 5 3\n", r"line 6 \('f 1 2 3 99'\) names the vertex 99"),
    # negative indices count back over the vertices above the face only
    ("v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n", r"line 3 \('f -1 -2 -3'\) names the vertex -3.*\(2 v lines above"),
    (_OBJ_V5 + "f /1 2 3\n", r"line 6 \('f /1 2 3'\) has no vertex index"),
    (_OBJ_V5 + "f 1x 2 3\n", r"has the vertex index '1x'"),
    (_OBJ_V5 + "f 1 2\nf 1 2 3\n", r"line 6 \('f 1 2'\) is a face of 2 corners, which pymeshlab's OBJ loader drops"),
])
def test_obj_face_indices_outside_the_file_are_refused_before_loading(tmp_path, text, message):
    path = tmp_path / "m.obj"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        check_before_loading(path)


@pytest.mark.parametrize("text, triangles", [
    (_OBJ_V5 + "f 1 2 3 4\nf 2 5 3\n", 3),
    (_OBJ_V5 + "f 1 2 5 3 4\n", 3),                                      # a pentagon: 3 triangles
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nf -4 -3 -1\n", 2),   # negative, interleaved
    (_OBJ_V5 + "vt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 +3/1/1\nf 2//1 5//1 3.0//1\n  f 1 3 4#note\n", 3),
    (_OBJ_V5 + "f 1 2 \\\n3\nf 1 \\\n3 \\\n\\\n4\n", 2),                # continued face lines
])
def test_obj_faces_in_range_pass_and_give_their_triangles(tmp_path, text, triangles):
    from curvdetail._file_scan import _obj_face_indices
    path = tmp_path / "m.obj"
    path.write_text(text)
    assert check_before_loading(path) == triangles
    for size in (1, 7, 20):                                              # pieces of a line or a few
        assert _obj_face_indices(path, size=size) == (None, triangles)


def test_obj_face_index_scan_finds_the_first_bad_line_across_pieces(tmp_path):
    from curvdetail._file_scan import _obj_face_indices
    path = tmp_path / "m.obj"
    path.write_text(_OBJ_V5 + "f 1 2 3\n" * 50 + "f 1 2 6\n" + "f 1 2 7\n")
    for size in (1, 64, 1 << 20):
        problem, triangles = _obj_face_indices(path, size=size)
        assert triangles is None and problem.startswith("line 56 ('f 1 2 6') names the vertex 6")


@pytest.mark.parametrize("name, data, message", [
    ("m.obj", b"\xef\xbb\xbfv 9 9 9\n" + _OBJ_V4.encode() + b"f 1 2 3\n", "starts with a UTF-8 byte order mark"),
    ("m.ply", b"\xef\xbb\xbfply\nformat ascii 1.0\nelement vertex 0\nend_header\n", "byte order mark.*PLY reader"),
    # a lone CR after LF lines: the lines it ends were read as one (the second triangle was lost)
    ("m.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n# part two\rv 5 5 5\rv 6 5 5\rv 5 6 5\rf 4 5 6\r",
     r"line 5 ends in a carriage return not followed by a newline"),
    ("m.stl", b"solid q\nfacet normal 0 0 1\n outer loop\n vertex 0 0 0\n vertex 1 0 0\n vertex 1 1 0\n"
              b" vertex 0 1 0\n endloop\nendfacet\nendsolid q\n", r"1 facet with 4 vertex lines, not 3 a facet"),
    ("m.off", b"OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n4 0 1 2 3\n2 1 4\n",
     r"face 1 is the row '2 1 4', of 2 vertices, which pymeshlab's OFF reader drops"),
])
def test_byte_order_marks_lone_carriage_returns_and_odd_facets_are_refused(tmp_path, name, data, message):
    path = tmp_path / name
    path.write_bytes(data)
    with pytest.raises(ValueError, match=message):
        check_before_loading(path)


@pytest.mark.parametrize("name, data, triangles", [
    ("m.obj", b"v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r", 1),          # CRLF, a last CR alone
    ("m.stl", b"solid q\nfacet normal 0 0 1\n outer loop\n vertex 0 0 0\n vertex 1 0 0\n vertex 1 1 0\n"
              b" endloop\nendfacet\nendsolid q\n", None),
    ("m.off", b"OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n4 0 1 2 3\n5 0 1 4 2 3\n", 5),
])
def test_files_the_new_checks_pass_give_their_triangles(tmp_path, name, data, triangles):
    path = tmp_path / name
    path.write_bytes(data)
    assert check_before_loading(path) == triangles


@pytest.mark.parametrize("text, message", [
    # line numbers count the file's lines, continued ones too (they were a line short per join)
    (_OBJ_V5 + "f 1 2 \\\n3\nf 2 5 9\n", r"line 8 \('f 2 5 9'\) names the vertex 9"),
    (_OBJ_V5 + "f 1 \\\n2 \\\n3\nf 1 2\n", r"line 9 \('f 1 2'\) is a face of 2 corners"),
    (_OBJ_V5 + "f 1 2 \\\n3\n" * 3 + "f 2 5 9\n", r"line 12 \('f 2 5 9'\) names the vertex 9"),
    # pymeshlab joins the lines with nothing between: 'f 1 2\' and '3' were read as 'f 1 23'
    # (no triangle); a face line continued with CR LF line ends was dropped (measured)
    (_OBJ_V5 + "f 1 2\\\n3\n", r"line 6 \('f 1 2\\\\'\) ends in a backslash.*'f 1 23'"),
    (_OBJ_V5 + "f 1 2 \\\r\n3\r\n", r"line 6 \('f 1 2 \\\\'\) ends in a backslash.*Windows line end"),
    (_OBJ_V5 + "f 1 2 3\nf 1 3 \\\n4\r\n", r"line 7 \('f 1 3 \\\\'\) ends in a backslash.*Windows line end"),
])
def test_obj_continued_faces_are_refused_naming_their_line(tmp_path, text, message):
    from curvdetail._file_scan import _obj_face_indices
    path = tmp_path / "m.obj"
    path.write_bytes(text.encode())
    with pytest.raises(ValueError, match=message):
        check_before_loading(path)
    if "line 6" not in message and "line 7" not in message:
        for size in (1, 7, 20):                                          # pieces of a line or a few
            assert _obj_face_indices(path, size=size)[0].startswith(message.split(" \\(")[0])


@pytest.mark.parametrize("text, triangles", [
    # a face continued over several lines, and a backslash ending the file, are read right
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 \\\n2 \\\n\\\n3\nf 2 4 \\\n 3 \\", [[0, 1, 2], [1, 3, 2]]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2\\\n 4 3\n", [[0, 1, 3], [0, 3, 2]]),
])
def test_obj_faces_continued_over_lines_are_read_right(tmp_path, text, triangles):
    from curvdetail.io.mesh import read_mesh
    path = tmp_path / "m.obj"
    path.write_bytes(text.encode())
    assert read_mesh(path)[1].tolist() == triangles


def _pymeshlab_read(path):
    import pymeshlab
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    return ms.current_mesh().vertex_matrix().tolist(), ms.current_mesh().face_matrix().tolist()


_V3 = [[0.0, 0.0, 0.0], [1.0, 0.0, 5.0], [0.0, 1.0, 0.0]]


@pytest.mark.parametrize("data, vertices", [
    # pymeshlab joins a v line ending in a backslash with the next line (the backslash and line end
    # removed): 'v 1 0 \' then '5' is the vertex (1, 0, 5), the next line counted as no vertex
    (b"v 0 0 0\nv 1 0 \\\n5\nv 0 1 0\nf 1 2 3\n", _V3),
    (b"v 0 0 0\nv 1 \\\n0 \\\n5\nv 0 1 0\nf 1 2 3\n", _V3),                  # over three lines
    (b"v 0 0 0\nv 1 0 \\\r\n5\nv 0 1 0\nf 1 2 3\n", _V3),                      # CR LF, then LF: read right
    (b"v 0 0 0\nv 1 0 5 \\\n# x\nv 0 1 0\nf 1 2 3\n", _V3),                   # a comment after the z
    (b"v 0 0 0\nv 0 1 0\nv 1 0 \\\n  5\nf 1 2 3\n", [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 5.0]]),
    # the backslash right after a value, the next line starting with a blank: 'v 1 0 5', as
    # pymeshlab reads it (it was refused as "the y coordinate '0\\' ... read as the vertex (1, 0)")
    (b"v 0 0 0\nv 1 0\\\n 5\nv 0 1 0\nf 1 2 3\n", _V3),
    (b"v 0 0 0\nv 1\\\n\t0 5\nv 0 1 0\nf 1 2 3\n", _V3),
    (b"v 0 0 0\nv 1 0\\\r\n 5\nv 0 1 0\nf 1 2 3\n", _V3),                      # CR LF, then LF
    (b"v 0 0 0\nv 1 0 5\\\n \nv 0 1 0\nf 1 2 3\n", _V3),                      # continued on a blank line
])
def test_obj_vertex_lines_continued_on_values_are_read_as_pymeshlab_reads_them(tmp_path, data, vertices):
    from curvdetail.io.mesh import read_mesh
    path = tmp_path / "m.obj"
    path.write_bytes(data)
    V, F = read_mesh(path)
    assert V.tolist() == vertices and F.tolist() == [[0, 1, 2]]
    assert (V.tolist(), F.tolist()) == _pymeshlab_read(path)


@pytest.mark.parametrize("data, triangles", [
    # a face line ending in a backslash and CR LF, continued on a line ending in LF: pymeshlab drops
    # the first CR and joins the lines ('f 1 3 \' then '2' is the face 1 3 2)
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 3 \\\r\n2\nf 2 4 3\n", [[0, 2, 1], [1, 3, 2]]),
    (b"v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nv 1 1 0\r\nf 2 4 3\r\nf 1 3 \\\r\n2\n", [[1, 3, 2], [0, 2, 1]]),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 \\\r\n4 3\n", [[0, 1, 3], [0, 3, 2]]),      # a quad, fanned
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 \\\r\n-2 -1\nv 1 1 0\nf 2 4 3\n", [[0, 1, 2], [1, 3, 2]]),
])
def test_obj_faces_continued_after_a_crlf_line_end_are_read_as_pymeshlab_reads_them(tmp_path, data, triangles):
    from curvdetail.io.mesh import read_mesh
    path = tmp_path / "m.obj"
    path.write_bytes(data)
    V, F = read_mesh(path)
    assert F.tolist() == triangles
    assert (V.tolist(), F.tolist()) == _pymeshlab_read(path)


@pytest.mark.parametrize("data, message", [
    # measured with pymeshlab: 'v 1 0 \' then '# x' was read as (1, 0, 0), then '5,5' as (1, 0, 5)
    (b"v 0 0 0\nv 1 0 \\\n# x\nv 0 1 0\nf 1 2 3\n",
     r"line 2 \('v 1 0 \\\\'\) ends in a backslash.*reads the joined line 'v 1 0 # x' as the vertex \(1, 0, 0\) "
     r"without a word: it holds a comment among its coordinates"),
    (b"v 0 0 0\nv 1 0 \\\n5,5\nv 0 1 0\nf 1 2 3\n", r"line 2 .*as the vertex \(1, 0, 5\).*written with a comma"),
    (b"v 0 0 0\nv 1 \\\n0 abc\nv 0 1 0\nf 1 2 3\n", r"line 2 .*as the vertex \(1, 0, 0\).*z coordinate 'abc'"),
    # a continued line ending in CR LF: one byte more was dropped, 'v 1 0 5 \' then '6' read as (1, 0, 56)
    (b"v 0 0 0\nv 1 0 5 \\\n6\r\nv 0 1 0\nf 1 2 3\n", r"line 2 .*ends in a backslash.*Windows line end"),
    # a vt or f line joined to a vertex: counted apart (the face was lost; the vt line crashed the process)
    (b"v 0 0 0\nv 1 0 \\\nvt 0 0\nv 0 1 0\nf 1 2 3\n", r"line 2 .*ends in a backslash.*starts with a keyword"),
    (b"v 0 0 0\nv 1 0 5\nv 0 1 0 \\\nf 1 2 3\n", r"line 3 .*ends in a backslash.*starts with a keyword"),
])
def test_obj_vertex_lines_continued_into_a_misread_are_refused_saying_how(tmp_path, data, message):
    path = tmp_path / "m.obj"
    path.write_bytes(data)
    with pytest.raises(ValueError, match=message):
        check_before_loading(path)


@pytest.mark.parametrize("size", [1, 7, 20, 1 << 20])
def test_obj_face_line_counts_the_files_lines_across_pieces(tmp_path, size):
    # faces counted as the scan counts them (continued lines joined, indented ones too), lines as
    # the file has them
    from curvdetail._file_scan import _obj_face_line
    path = tmp_path / "m.obj"
    path.write_bytes(b"# c\n" + _OBJ_V5.encode() + b"f 1 2 \\\n3\n\n  f 1 3 4\nvt 0 0\nf 1 \\\r\n4 \\\n5\nf 2 3 5\n")
    assert [_obj_face_line(path, k, size=size) for k in range(5)] == [7, 10, 12, 15, None]


@pytest.mark.parametrize("piece", [1, 2, 3, 5, 1 << 18])
def test_word_edges_in_pieces_are_the_runs_of_the_whole_array(piece):
    # the OFF scan finds its words in pieces of the file's bytes (to keep them in cache): the
    # starts and ends must be those of the whole array, at the pieces' seams and the array's ends
    from curvdetail._file_scan import _word_edges
    rng = np.random.default_rng(5)
    for visible in [np.zeros(0, bool), np.ones(1, bool), np.zeros(1, bool), np.ones(7, bool),
                    *(rng.random(n) < 0.6 for n in (2, 9, 40, 1000))]:
        padded = np.concatenate([[False], visible, [False]])
        expected = np.flatnonzero(padded[1:] != padded[:-1])
        assert np.array_equal(_word_edges(visible, piece), expected)


def test_off_index_out_of_range_is_found_past_the_first_pieces_of_indices(tmp_path):
    # a large file's face indices are checked in pieces of 65536: the last face's is found
    import curvdetail
    from curvdetail.curvature.testing import grid
    V, F = grid(120, 120)
    path = tmp_path / "m.off"
    curvdetail.write_mesh(str(path), V, F)
    text = path.read_bytes().rstrip(b"\n").rsplit(b"\n", 1)[0] + b"\n3 0 1 %d\n" % len(V)
    path.write_bytes(text)
    with pytest.raises(ValueError, match=rf"1 face uses vertex indices outside the file's {len(V)} vertices "
                                         rf"\(first: face {len(F) - 1}, \[0, 1, {len(V)}\]\)"):
        check_before_loading(str(path))
    path.write_bytes(text.replace(b"\n3 0 1 %d\n" % len(V), b"\n3 0 1 %d 9 9 9\n" % len(V)))   # a colour: other path
    with pytest.raises(ValueError, match=rf"\(first: face {len(F) - 1}, \[0, 1, {len(V)}\]\)"):
        check_before_loading(str(path))


@pytest.mark.skipif(_file_scan._set_madvise_hugepage is None, reason="this numpy has no huge-page switch")
@pytest.mark.parametrize("setting", [True, False])
def test_reads_leave_numpys_huge_page_setting_as_they_found_it(tmp_path, setting):
    # read_mesh turns numpy's huge pages off while it scans (a fresh process touched them slowly),
    # and must give the setting back: after a read, a refused read, and reads in threads whose
    # spans cross (each restoring what it found left it off for good)
    import threading

    from curvdetail.curvature.testing import grid
    from curvdetail.io.mesh import MeshFileError, read_mesh, write_mesh

    switch = _file_scan._set_madvise_hugepage
    V, F = grid(30, 30)
    path = tmp_path / "g.off"
    write_mesh(path, V, F)
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nf 1 2 3\n")
    switch(setting)
    try:
        read_mesh(path)
        assert switch(setting) is setting                 # (it returns the setting it replaces)
        with pytest.raises(MeshFileError):
            read_mesh(bad)
        assert switch(setting) is setting
        entered, main_inside, left = threading.Event(), threading.Event(), threading.Event()

        def first():                                      # in first, out first
            with _file_scan.small_pages():
                entered.set()
                main_inside.wait(10)
            left.set()
        thread = threading.Thread(target=first)
        thread.start()
        entered.wait(10)
        with _file_scan.small_pages():
            main_inside.set()
            left.wait(10)
        thread.join()
        assert switch(setting) is setting
    finally:
        switch(True)


def test_index_words_are_read_as_int_reads_them():
    # the face scan reads words of up to 8 digits as one 64-bit word (digits paired by three
    # multiplications) and longer ones a digit at a time; both must be int()'s value
    from curvdetail._file_scan import _whole_values

    rng = np.random.default_rng(7)
    words = [str(int(v)) for v in rng.integers(0, 10 ** rng.integers(1, 19, 400), dtype=np.int64)]
    words += ["0", "7", "10", "99999999", "100000000", "12345678", "123456789", "999999999999999999", "00042"]
    text = " ".join(words).encode()
    chars = np.frombuffer(text, dtype=np.uint8)
    ends = np.cumsum([len(w) + 1 for w in words]) - 1              # the byte after each word
    digits = np.array([len(w) for w in words])
    for plain in (np.ones(len(words), dtype=bool), np.arange(len(words)) % 3 != 0):
        values = _whole_values(chars, ends, digits, plain)
        expected = [int(w) if p else 0 for w, p in zip(words, plain)]
        assert values.tolist() == expected
    # the usual file: every word short and plain (no gathers)
    short = [w for w in words if len(w) <= 8]
    chars = np.frombuffer(" ".join(short).encode(), dtype=np.uint8)
    ends = np.cumsum([len(w) + 1 for w in short]) - 1
    values = _whole_values(chars, ends, np.array([len(w) for w in short]), np.ones(len(short), dtype=bool))
    assert values.tolist() == [int(w) for w in short] and len(short) > 10
