"""_file_scan: OFF and OBJ files that pymeshlab would misread or read into corrupt memory,
found before loading."""

import re

import numpy as np
import pytest

from curvdetail._file_scan import check_before_loading

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
    from curvdetail.io import read_mesh

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
    ("m.off", _OFF_OK + "3 1 2 3\n", r"the header declares 4 vertices and 2 faces, but 1 more rows follow the "
                                     r"last face \(first: line 9, '3 1 2 3'\)"),
    ("m.off", _OFF_OK.replace("4 2 0", "4 1 0"), r"declares 4 vertices and 1 faces, but 1 more rows follow"),
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
    from curvdetail.io import read_mesh

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
