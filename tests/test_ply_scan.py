"""_ply_scan: PLY files that pymeshlab would misread or crash on, found before loading (through
_file_scan.check_before_loading, which read_mesh calls)."""

import numpy as np
import pytest

from curvdetail._file_scan import check_before_loading

_F2 = [[0, 1, 2], [0, 2, 3]]

# ASCII PLY: pymeshlab's reader (vcglib plylib) reads the body as one stream of fscanf words,
# integers with "%d" and reals with "%f", each stopping at the first character that does not
# fit; its importer keeps a face's vertex count in one byte and indices of the face before.
_PLY_HEAD = ("ply\nformat ascii 1.0\ncomment c\nelement vertex 4\nproperty float x\nproperty float y\n"
             "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n")
_PLY_V4 = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n"                # lines 11-14; the faces on 15-16


def _ply(tmp_path, text):
    path = tmp_path / "m.ply"
    path.write_bytes(text.encode())
    return path


@pytest.mark.parametrize("body, message", [
    # a face of 2 indices came back as [3, 4, 2]: the third index left from the face before
    (_PLY_V4 + "3 0 1 2\n2 2 3\n", r"a face row has fewer than 3 vertex indices \(line 16, '2 2 3'\)"),
    (_PLY_V4 + "0\n3 0 2 3\n", r"fewer than 3 vertex indices \(line 15, '0'\)"),   # the face before again
    # the last index is cut at the point (1.9 -> 1); earlier, the rest is read as the next value
    (_PLY_V4 + "3 0 1 2\n3 0 2 1.9\n", r"line 16 \('3 0 2 1.9'\) holds '1.9' where an integer"),
    (_PLY_V4 + "3 0 1 2\n3 0 2 3.0\n", r"line 16 \('3 0 2 3.0'\) holds '3.0' where an integer"),
    (_PLY_V4 + "3.0 0 1 2\n3 0 2 3\n", r"line 15 \('3.0 0 1 2'\): the count of the face row's vertex_indices "
                                       r"list, '3.0', is not a whole number"),
    # decimal commas and other values fscanf reads in part
    ("0 0 0\n1,5 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n", r"line 12 \('1,5 0 0'\) writes '1,5' with a decimal "
                                                           r"comma.*write numbers with a decimal point"),
    ("0 0 0\n1 0.5.5 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n", r"line 12 \('1 0.5.5 0'\) holds '0.5.5' where a number"),
    ("0 0 0\n1 0 0\n1 1 0\n0 1 1e\n3 0 1 2\n3 0 2 3\n", r"line 14 \('0 1 1e'\) holds '1e' where a number"),
    # rows beyond the header's count are dropped without a word
    (_PLY_V4 + "3 0 1 2\n3 0 2 3\n3 1 2 3\n", r"the header declares 4 vertex, 2 face rows, but more values follow "
                                              r"them \(from line 17, '3 1 2 3'\)"),
    # a vertex row with a value too few or too many shifts every later value
    ("0 0 0\n1 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n", r"hold a number of values other than the 3 of a vertex row "
                                                     r"\(x y z\) \(first: line 12, '1 0', 2 values\)"),
    ("0 0 0\n1 0 0 5\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n", r"\(first: line 12, '1 0 0 5', 4 values\)"),
    (_PLY_V4 + "3 0 1 2 7\n3 0 2 3\n", r"line 15 \('3 0 1 2 7'\) holds 5 values for face row 0 \(<count> "
                                       r"<vertex_indices...>\), but its counts make it 4"),
    (_PLY_V4 + "3 0 1 2\n", r"but only 1 lines after the rows before hold values for the 2 face rows"),
    ("0 0 0\n1 0 0\n1 1 0\n", r"the file ends after 3 of the 4 vertex rows"),
    (_PLY_V4 + "3 0 1 2\n3 0 2\x003\n", r"line 16 holds the control byte 0x00"),
])
def test_ply_rows_pymeshlab_misreads_are_refused_naming_the_line(tmp_path, body, message):
    with pytest.raises(ValueError, match=message):
        check_before_loading(_ply(tmp_path, _PLY_HEAD + body))


def test_ply_polygons_pymeshlab_cannot_hold_are_refused(tmp_path):
    # 256 indices were read as no polygon (the count is kept in one byte), 1000 smashed the stack
    n = 256
    head = _PLY_HEAD.replace("vertex 4", f"vertex {n}").replace("face 2", "face 1")
    path = _ply(tmp_path, head + "0 0 0\n" * n + f"{n} " + " ".join(map(str, range(n))) + "\n")
    with pytest.raises(ValueError, match=r"a face row has more than 255 vertex indices \(line 267, 256 indices\)"):
        check_before_loading(path)


@pytest.mark.parametrize("header, message", [
    # atoi read 4.5 as 4; no count at all crashed the process (segmentation fault)
    (_PLY_HEAD.replace("vertex 4", "vertex 4.5"), r"the header's line 4 declares '4.5' vertex elements, which "
                                                  r"is not a whole number"),
    (_PLY_HEAD.replace("face 2", "face"), r"the header's line 8 \('element face'\) gives no element count, "
                                          r"which crashes pymeshlab's PLY reader"),
    # face lists of other types are not read: the faces come from whatever memory held
    (_PLY_HEAD.replace("uchar int vertex_indices", "ushort int vertex_indices"),
     r"line 9 .* declares face lists of ushort counts and int indices, which pymeshlab's PLY reader does not read"),
    (_PLY_HEAD.replace("uchar int vertex_indices", "int uint vertex_index"),
     r"declares face lists of int counts and uint indices"),
    (_PLY_HEAD.replace("uchar int vertex_indices", "uint8 float32 vertex_indices"),
     r"declares face lists of uchar counts and float indices"),
])
@pytest.mark.parametrize("fmt", ["ascii", "binary_little_endian"])
def test_ply_headers_pymeshlab_misreads_are_refused_ascii_or_binary(tmp_path, header, message, fmt):
    path = _ply(tmp_path, header.replace("format ascii", f"format {fmt}") + _PLY_V4 + "3 0 1 2\n3 0 2 3\n")
    with pytest.raises(ValueError, match=message):
        check_before_loading(path)


def test_ply_short_face_indices_that_wrap_are_refused(tmp_path):
    # "property list uchar short vertex_indices": pymeshlab reads 65537 as (short) 1
    head = _PLY_HEAD.replace("uchar int vertex_indices", "uchar short vertex_indices")
    with pytest.raises(ValueError, match=r"line 16 \('3 0 2 65537'\) holds '65537' where a vertex index of type short"):
        check_before_loading(_ply(tmp_path, head + _PLY_V4 + "3 0 1 2\n3 0 2 65537\n"))
    big = head.replace("vertex 4", "vertex 40000")
    with pytest.raises(ValueError, match=r"face indices of type short, which cannot name the 40000 vertices"):
        check_before_loading(_ply(tmp_path, big + "0 0 0\n" * 40000 + "3 0 1 2\n3 0 2 3\n"))


@pytest.mark.parametrize("name, header, body", [
    ("plain", _PLY_HEAD, _PLY_V4 + "3 0 1 2\n3 0 2 3\n"),
    ("CRLF, blank lines, blanks", _PLY_HEAD.replace("\n", "\r\n"),
     "\r\n0 0 0 \r\n1 0 0\r\n  1 1 0\t\r\n0 1 0\r\n\r\n3 0 1 2  \r\n   \r\n3 0 2 3\r\n\r\n"),
    ("vertex split over lines", _PLY_HEAD, "0 0 0\n1\n0 0\n1 1 0\n0 1\n0\n3 0 1 2\n3 0 2 3\n"),
    ("exponents and signs", _PLY_HEAD, "0 0e0 -0\n1. +0 .0\n1E+0 1e-0 0\n0 1.0E00 0\n3 0 1 2\n3 +0 2 3\n"),
    ("quad", _PLY_HEAD.replace("face 2", "face 1"), _PLY_V4 + "4 0 1 2 3\n"),
    ("vertex_index, int counts", _PLY_HEAD.replace("uchar int vertex_indices", "int int vertex_index"),
     _PLY_V4 + "3 0 1 2\n3 0 2 3\n"),
    ("properties around the list",
     _PLY_HEAD.replace("property float z\n", "property float z\nproperty uchar red\nproperty double quality\n")
     .replace("property list uchar int vertex_indices\n", "property int flags\nproperty list uchar int "
              "vertex_indices\nproperty list uchar float texcoord\nproperty float quality\n"),
     "0 0 0 255 0.5\n1 0 0 0 -1e-3\n1 1 0 7 2\n0 1 0 9 3.25\n"
     "0 3 0 1 2 6 0 0 1 0 1 1 0.5\n2 3 0 2 3 0 -7.5\n"),
    ("other elements", _PLY_HEAD.replace("element face 2", "element edge 1\nproperty int vertex1\n"
                                         "property int vertex2\nelement face 2")
     .replace("end_header", "element material 2\nproperty list uchar float rgb\nend_header"),
     _PLY_V4 + "0 1\n3 0 1 2\n3 0 2 3\n3 1 0.5 .25\n0\n"),
])
def test_ply_files_pymeshlab_reads_right_are_read(tmp_path, name, header, body):
    from curvdetail.io.mesh import read_mesh

    V, F = read_mesh(_ply(tmp_path, header + body))
    np.testing.assert_array_equal(V, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    assert F.tolist() == _F2                                   # the quad: fanned from its first corner


@pytest.mark.parametrize("options", [
    {},                                                        # colours, quality, texture coordinates
    {"save_vertex_normal": True, "save_vertex_flag": True, "save_vertex_radius": True, "save_face_flag": True,
     "save_face_quality": True, "save_face_color": True, "save_wedge_texcoord": True, "save_wedge_color": True},
    {"save_vertex_color": False, "save_vertex_quality": False, "save_wedge_texcoord": False, "save_face_color": False},
])
def test_ascii_ply_pymeshlab_writes_is_read(tmp_path, options):
    import pymeshlab

    from curvdetail.curvature.testing import icosphere
    from curvdetail.io.mesh import read_mesh

    V, F = icosphere(subdivisions=2)
    rng = np.random.default_rng(0)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32), v_normals_matrix=V,
                               v_color_matrix=rng.random((len(V), 4)), v_scalar_array=V[:, 0],
                               f_color_matrix=rng.random((len(F), 4)), f_scalar_array=rng.random(len(F)),
                               v_tex_coords_matrix=V[:, :2], w_tex_coords_matrix=rng.random((3 * len(F), 2))))
    ms.save_current_mesh(str(tmp_path / "m.ply"), binary=False, **options)
    W, G = read_mesh(tmp_path / "m.ply")
    np.testing.assert_allclose(W, V, rtol=0, atol=1e-15)
    assert np.array_equal(G, F)


def test_ascii_ply_with_a_custom_attribute_pymeshlab_writes_glued_is_refused(tmp_path):
    # pymeshlab's ASCII writer glues a custom scalar to the value before it ("0.92532540.850651"),
    # and the point attribute's list then shifts every later value
    import pymeshlab

    from curvdetail.curvature.testing import icosphere

    V, F = icosphere(subdivisions=1)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32), v_tex_coords_matrix=V[:, :2]))
    ms.current_mesh().add_vertex_custom_scalar_attribute(V[:, 1], "attr")
    ms.save_current_mesh(str(tmp_path / "m.ply"), binary=False, save_vertex_coord=True, __ca_vs__attr=True)
    with pytest.raises(ValueError, match=r"lines hold a number of values other than the 11 of a vertex row "
                                         r"\(x y z red green blue alpha quality texture_u texture_v attr\) "
                                         r"\(first: line \d+, '.*', 10 values\)"):
        check_before_loading(tmp_path / "m.ply")


@pytest.mark.parametrize("header, faces, triangles", [
    # the 'deleted' flag bit (1): the first triangle is dropped, the quad's two make up the count
    (_PLY_HEAD.replace("face 2", "face 2").replace("vertex_indices\n", "vertex_indices\nproperty int flags\n"),
     "3 0 1 2 1\n4 0 1 2 3 0\n", 3),
    # a repeated index: its triangle is dropped
    (_PLY_HEAD, "3 0 1 2\n4 0 0 2 3\n", 3),
])
def test_ply_faces_pymeshlab_drops_are_reported(tmp_path, header, faces, triangles):
    # a face count cannot tell: the polygon's triangles make up for the dropped one
    from curvdetail.io.mesh import MeshFileError, read_mesh

    with pytest.raises(MeshFileError, match=rf"its faces make {triangles} triangles \(a polygon of k vertices "
                                            rf"k - 2\), but pymeshlab loaded {triangles - 1}"):
        read_mesh(_ply(tmp_path, header + _PLY_V4 + faces))


def test_the_ply_misreads_refused_are_what_pymeshlab_does(tmp_path):
    # the facts behind the refusals above, read with pymeshlab itself: no error, wrong mesh
    import pymeshlab

    def load(body):
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(_ply(tmp_path, _PLY_HEAD.replace("face 2", "face 3") + body)))
        return ms.current_mesh().vertex_matrix().tolist(), ms.current_mesh().face_matrix().tolist()

    assert load(_PLY_V4 + "3 0 1 2\n3 0 2 3\n3 1 2 3\n3 1 3 0\n")[1] == [[0, 1, 2], [0, 2, 3], [1, 2, 3]]
    assert load(_PLY_V4 + "3 0 1 2\n3 0 2 3\n3 2 3 1.9\n")[1][2] == [2, 3, 1]      # 1.9 read as 1
    assert load(_PLY_V4 + "3 0 1 2\n3 0 2 3\n2 1 2\n")[1][2] == [1, 2, 3]           # the 3 of the face before


@pytest.mark.parametrize("vertices", ["0 0 0 1 0 0\n1 1 0 0 1 0\n", "0 0 0 1 0 0 1 1 0 0 1 0\n",
                                      "0 0 0\n1 0 0 1 1 0\n0 1 0\n"])
def test_ply_vertex_lines_of_whole_rows_are_read_as_pymeshlab_reads_them(tmp_path, vertices):
    # fscanf does not see lines: whole rows on one line are read right (they were refused)
    import pymeshlab

    from curvdetail.io.mesh import read_mesh

    path = _ply(tmp_path, _PLY_HEAD + vertices + "3 0 1 2\n3 0 2 3\n")
    V, F = read_mesh(path)
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    assert np.array_equal(V, ms.current_mesh().vertex_matrix()) and F.tolist() == _F2
    assert V.tolist() == [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]


@pytest.mark.parametrize("body, where", [
    ("0 0 0 1 0\n0 1 1 0 0\n1 0\n3 0 1 2\n3 0 2 3\n",        # 5 + 5 + 2: rows cut across lines
     r"3 lines hold .* \(first: line 11, '0 0 0 1 0', 5 values\)"),
    ("0 0 0\n1 0 0\n1 1 0\n0 1 0 3 0 1\n2\n3 0 2 3\n",      # the last vertex and a face on one line
     r"1 lines hold .* \(first: line 14, '0 1 0 3 0 1', 6 values\)"),
])
def test_ply_vertex_lines_that_cut_rows_are_still_refused(tmp_path, body, where):
    with pytest.raises(ValueError, match=r"lines hold a number of values other than the 3 of a vertex row "
                                         r"\(x y z\)") as info:
        check_before_loading(_ply(tmp_path, _PLY_HEAD + body))
    assert info.match(where) and "write each row on a line of its own" in str(info.value)


@pytest.mark.parametrize("count, index, readable", [("uchar", "int", True), ("char", "uint", True),
                                                    ("int", "short", False), ("int", "uint", False),
                                                    ("ushort", "uint", False)])
def test_binary_face_list_types_pymeshlab_cannot_read_are_named(tmp_path, count, index, readable):
    # its binary reader fails on these with "Bad vertex index in face ... damaged" (ASCII reads them)
    import struct

    import pymeshlab

    from curvdetail.io.mesh import MeshFileError, read_mesh

    codes = {"char": "b", "uchar": "B", "short": "h", "ushort": "H", "int": "i", "uint": "I"}
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
              f"property float z\nelement face 2\nproperty list {count} {index} vertex_indices\nend_header\n")
    vertices = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype="<f4").tobytes()
    faces = b"".join(struct.pack("<" + codes[count] + codes[index] * 3, 3, *f) for f in _F2)
    path = tmp_path / "b.ply"
    path.write_bytes(header.encode() + vertices + faces)
    ms = pymeshlab.MeshSet()
    try:
        ms.load_new_mesh(str(path))
        read_by_pymeshlab = ms.current_mesh().face_matrix().tolist() == _F2
    except pymeshlab.PyMeshLabException:
        read_by_pymeshlab = False
    assert read_by_pymeshlab == readable                     # the fact behind the refusal
    if readable:
        assert read_mesh(path)[1].tolist() == _F2
    else:
        with pytest.raises(MeshFileError, match=f"face lists of {count} counts and {index} indices.*calls the "
                                                r"file damaged"):
            read_mesh(path)


def test_ply_hexadecimal_reals_are_read_as_pymeshlab_reads_them(tmp_path):
    # glibc's fscanf("%f") reads 0x1p-1 as 0.5; where an index is read, 0x1 stays refused
    from curvdetail.io.mesh import read_mesh

    V, _ = read_mesh(_ply(tmp_path, _PLY_HEAD + "0 0 0\n0x1p0 0 0\n1 0x1.0p0 0\n0 0x.8p1 0\n3 0 1 2\n3 0 2 3\n"))
    assert V.tolist() == [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    with pytest.raises(ValueError, match="holds '0x1' where an integer"):
        check_before_loading(_ply(tmp_path, _PLY_HEAD + _PLY_V4 + "3 0 0x1 2\n3 0 2 3\n"))


def _binary_ply(fmt, vertex_type, vertices, body_vertices=None):
    import struct
    order = "<" if fmt == "binary_little_endian" else ">"
    code = {"float": "f", "double": "d"}[vertex_type]
    header = (f"ply\nformat {fmt} 1.0\nelement vertex {vertices}\nproperty {vertex_type} x\n"
              f"property {vertex_type} y\nproperty {vertex_type} z\nelement face 1\n"
              "property list uchar int vertex_indices\nend_header\n").encode()
    rows = [(0.1, 0.2, 0.3), (1, 0, 0), (0, 1, 0)][:vertices if body_vertices is None else body_vertices]
    return header + b"".join(struct.pack(order + 3 * code, *row) for row in rows) + struct.pack(order + "B3i", 3, 0, 1, 2)


def test_big_endian_double_vertices_are_refused_before_loading(tmp_path):
    # pymeshlab read the big-endian double 0.1 as -1.5e-180 without a word
    path = tmp_path / "be.ply"
    path.write_bytes(_binary_ply("binary_big_endian", "double", 3))
    with pytest.raises(ValueError, match=r"big-endian with vertex properties of type double \(x, y, z\).*"
                                         r"save it as binary_little_endian or ASCII PLY"):
        check_before_loading(path)


@pytest.mark.parametrize("fmt, vertex_type", [("binary_big_endian", "float"), ("binary_little_endian", "double")])
def test_binary_ply_pymeshlab_reads_right_is_read(tmp_path, fmt, vertex_type):
    from curvdetail import read_mesh
    path = tmp_path / "ok.ply"
    path.write_bytes(_binary_ply(fmt, vertex_type, 3))
    V, F = read_mesh(path)
    np.testing.assert_allclose(V, [[0.1, 0.2, 0.3], [1, 0, 0], [0, 1, 0]], rtol=1e-7)
    assert F.tolist() == [[0, 1, 2]]


def test_binary_ply_shorter_than_its_header_s_counts_is_refused_before_loading(tmp_path):
    # 20M vertices declared in a 225-byte file: pymeshlab took 1.6 GB and 3.3 s to say "Unexpected EOF"
    path = tmp_path / "short.ply"
    path.write_bytes(_binary_ply("binary_little_endian", "float", 20_000_000, body_vertices=3))
    with pytest.raises(ValueError, match=r"declares 20000000 vertex, 1 face rows, which take at least 240000001 "
                                         r"bytes, but only 49 follow the header"):
        check_before_loading(path)
    path.write_bytes(_binary_ply("binary_little_endian", "float", 5, body_vertices=3))  # 12 bytes short
    with pytest.raises(ValueError, match=r"at least 61 bytes, but only 49 follow"):
        check_before_loading(path)
    path.write_bytes(_binary_ply("binary_little_endian", "float", 3))                    # exactly complete
    assert check_before_loading(path) is None


def _ply_with_a_list(count_type, item_type, items, element="vertex", vary=False):
    import struct
    count_code, item_code = {"uchar": "B", "int": "i", "ushort": "H"}[count_type], {"double": "d", "float": "f"}[item_type]
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
              "property float z\n" + (f"property list {count_type} {item_type} feat\n" if element == "vertex" else "") +
              "element face 1\nproperty list uchar int vertex_indices\n" +
              (f"property list {count_type} {item_type} feat\n" if element == "face" else "") + "end_header\n")

    def row(n):
        return struct.pack("<" + count_code + item_code * n, n, *range(n))
    sizes = [items, 1, 2] if vary else [items] * 3
    body = b"".join(struct.pack("<3f", *v) + (row(n) if element == "vertex" else b"")
                    for v, n in zip(((0, 0, 0), (1, 0, 0), (0, 1, 0)), sizes))
    return header.encode() + body + struct.pack("<B3i", 3, 0, 1, 2) + (row(items) if element == "face" else b"")


@pytest.mark.parametrize("count_type, item_type, items, element, vary, message", [
    # more than 512 bytes of items: "*** buffer overflow detected ***", the process aborted
    ("uchar", "double", 65, "vertex", False, r"the first vertex row's list 'feat' holds 65 items of 8 bytes, more than "
                                             r"the 512 bytes"),
    ("uchar", "float", 129, "vertex", True, r"list 'feat' holds 129 items of 4 bytes"),
    ("uchar", "double", 100, "face", False, r"the first face row's list 'feat' holds 100 items of 8 bytes"),
    # pymeshlab said "Unexpected EOF" (a damaged file) of these
    ("int", "double", 2, "vertex", False, r"vertex list property 'feat' has counts of type int, which pymeshlab's "
                                          r"binary PLY reader cannot skip"),
    ("ushort", "double", 2, "vertex", False, r"has counts of type ushort"),
])
def test_binary_ply_lists_pymeshlab_cannot_skip_are_refused_before_loading(tmp_path, count_type, item_type, items,
                                                                          element, vary, message):
    path = tmp_path / "m.ply"
    path.write_bytes(_ply_with_a_list(count_type, item_type, items, element, vary))
    with pytest.raises(ValueError, match=message):
        check_before_loading(path)


@pytest.mark.parametrize("count_type, item_type, items, element", [
    ("uchar", "double", 64, "vertex"), ("uchar", "float", 128, "vertex"), ("uchar", "double", 64, "face"),
    ("int", "float", 2, "face"),
])
def test_binary_ply_lists_pymeshlab_skips_are_read(tmp_path, count_type, item_type, items, element):
    from curvdetail import read_mesh
    path = tmp_path / "m.ply"
    path.write_bytes(_ply_with_a_list(count_type, item_type, items, element))
    V, F = read_mesh(path)
    assert V.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0]] and F.tolist() == [[0, 1, 2]]
