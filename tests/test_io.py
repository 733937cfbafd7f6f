"""read_mesh / write_mesh / save_mesh: round trips per format, overwrite refusal, atomic writes."""

import json
import re
import os
import stat
import subprocess
import sys

import numpy as np
import pymeshlab
import pytest

from curvdetail import MeshError, read_mesh, write_mesh
from curvdetail.curvature.testing import icosphere
from curvdetail.io.mesh import MeshFileError, save_mesh

from conftest import data_path


@pytest.fixture
def nose(load_mesh, rng):
    V, F = load_mesh("mannequin_nose.obj")
    return V + rng.normal(scale=1e-3, size=V.shape), F     # full float64 mantissas


@pytest.mark.parametrize("ext", ["obj", "off", "ply"])
def test_round_trip_keeps_vertices_and_faces(tmp_path, nose, ext):
    # OBJ is text with 16 decimals, OFF with 16 significant digits (error ~1 ulp at this scale); PLY is
    # binary double
    V, F = nose
    path = tmp_path / f"mesh.{ext}"
    write_mesh(path, V, F)
    W, G = read_mesh(path)
    assert W.dtype == np.float64 and G.dtype == np.int64
    assert np.array_equal(G, F)
    assert np.abs(W - V).max() <= 4 * np.finfo(float).eps * np.abs(V).max()


def test_stl_round_trip_is_float32_and_remerges_shared_vertices(tmp_path, nose):
    # STL stores every triangle's three corners as float32 and no shared vertices; pymeshlab's
    # loader merges coincident corners again: same vertex and face counts, the faces in order
    # with the same corner positions (rounded to float32), but the vertices renumbered.
    V, F = nose
    path = tmp_path / "mesh.stl"
    write_mesh(path, V, F)
    W, G = read_mesh(path)
    assert W.shape == V.shape and G.shape == F.shape
    assert np.array_equal(W[G], V[F].astype(np.float32).astype(np.float64))


def test_quality_is_saved_in_ply(tmp_path, nose):
    import pymeshlab

    V, F = nose
    q = np.linspace(0.0, 1.0, V.shape[0])
    path = tmp_path / "q.ply"
    write_mesh(path, V, F, quality=q)
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    assert np.allclose(ms.current_mesh().vertex_scalar_array(), q, atol=1e-6)   # stored as float32


def test_existing_file_is_not_overwritten(tmp_path, nose):
    V, F = nose
    path = tmp_path / "keep.obj"
    path.write_text("precious")
    # Python's argument, not the command line's option (the CLI says --overwrite)
    with pytest.raises(FileExistsError, match=r"keep.obj exists; pass overwrite=True to replace it\.$"):
        write_mesh(path, V, F)
    assert path.read_text() == "precious"


def test_overwrite_replaces_the_file(tmp_path, nose):
    V, F = nose
    path = tmp_path / "replace.off"
    path.write_text("old")
    write_mesh(path, V, F, overwrite=True)
    W, G = read_mesh(path)                  # the new mesh, to OFF's 16 digits (as the round trip)
    assert np.array_equal(G, F)
    assert np.abs(W - V).max() <= 4 * np.finfo(float).eps * np.abs(V).max()


@pytest.mark.parametrize("umask", [0o022, 0o027, 0o002], ids=["022", "027", "002"])
def test_written_file_has_the_umask_permissions_not_0600(tmp_path, nose, umask):
    # tempfile.mkstemp alone creates 0600; a normal new file gets 0666 & ~umask
    V, F = nose
    old = os.umask(umask)
    try:
        write_mesh(tmp_path / "mesh.ply", V, F)
    finally:
        os.umask(old)
    assert stat.S_IMODE(os.stat(tmp_path / "mesh.ply").st_mode) == 0o666 & ~umask


def test_overwritten_file_gets_the_umask_permissions(tmp_path, nose):
    V, F = nose
    path = tmp_path / "mesh.off"
    path.write_text("old")
    os.chmod(path, 0o600)
    old = os.umask(0o022)
    try:
        write_mesh(path, V, F, overwrite=True)
    finally:
        os.umask(old)
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o644


def test_temporary_file_keeps_the_extension_and_sits_beside_the_output(tmp_path, nose, monkeypatch):
    # pymeshlab picks the format from the extension, so the temporary name must end in it
    import pymeshlab

    seen = []
    real = pymeshlab.MeshSet.save_current_mesh

    def spy(self, path, **kwargs):
        seen.append(path)
        return real(self, path, **kwargs)

    from curvdetail.io.mesh import check_mesh_output

    check_mesh_output(tmp_path / "warm.obj")      # the format check's one-off probe writes elsewhere
    monkeypatch.setattr(pymeshlab.MeshSet, "save_current_mesh", spy)
    write_mesh(tmp_path / "mesh.obj", *nose)
    assert len(seen) == 1 and seen[0].endswith(".obj") and os.path.dirname(seen[0]) == str(tmp_path)
    assert os.listdir(tmp_path) == ["mesh.obj"]


def test_failed_write_leaves_neither_output_nor_temporary_file(tmp_path, nose, monkeypatch):
    import pymeshlab

    V, F = nose

    def broken(self, path, **kwargs):
        with open(path, "w") as fh:          # a half-written file, then a crash
            fh.write("half")
        raise RuntimeError("disk full")

    monkeypatch.setattr(pymeshlab.MeshSet, "save_current_mesh", broken)
    with pytest.raises(MeshFileError, match="could not write .*disk full"):
        write_mesh(tmp_path / "out.ply", V, F)
    assert os.listdir(tmp_path) == []


def test_unknown_extension_is_refused_and_leaves_nothing(tmp_path, nose):
    V, F = nose
    with pytest.raises(MeshFileError, match=r"pymeshlab does not write \.notaformat meshes \(Unknown format"):
        write_mesh(tmp_path / "mesh.notaformat", V, F)
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("ext", [".xyz", ".e57"])
def test_point_cloud_formats_are_refused_before_they_drop_the_triangles(tmp_path, nose, ext):
    # pymeshlab writes these without a word, and the file reads back as "no triangles"
    V, F = nose
    with pytest.raises(MeshFileError, match=f"{ext} files hold points only, so the triangles would be lost"):
        write_mesh(tmp_path / ("mesh" + ext), V, F)
    assert os.listdir(tmp_path) == []


def test_a_folder_is_never_replaced_even_with_overwrite(tmp_path, nose):
    (tmp_path / "out.ply").mkdir()
    with pytest.raises(MeshFileError, match="it is a folder; name a file"):
        write_mesh(tmp_path / "out.ply", *nose, overwrite=True)
    assert os.listdir(tmp_path) == ["out.ply"] and os.listdir(tmp_path / "out.ply") == []


def test_a_damaged_file_names_pymeshlabs_reason_not_a_missing_file(tmp_path):
    path = tmp_path / "oob.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                    "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n")
    with pytest.raises(MeshFileError, match="Bad vertex index in face. The file is damaged or incomplete"):
        read_mesh(path)


def test_missing_extension_is_refused(tmp_path, nose):
    V, F = nose
    with pytest.raises(MeshFileError, match="no file extension"):
        write_mesh(tmp_path / "mesh", V, F)


def test_missing_folder_is_refused(tmp_path, nose):
    V, F = nose
    with pytest.raises(MeshFileError, match="does not exist"):
        write_mesh(tmp_path / "nowhere" / "mesh.ply", V, F)


def test_malformed_arrays_are_refused_before_writing(tmp_path, nose):
    V, F = nose
    bad = V.copy()
    bad[3] = np.nan
    with pytest.raises(MeshError, match=r"1 vertex has NaN .*first: 3"):
        write_mesh(tmp_path / "bad.ply", bad, F)
    with pytest.raises(MeshError, match="quality has 2 values for 640 vertices"):
        write_mesh(tmp_path / "bad.ply", V, F, quality=[1.0, 2.0])
    assert os.listdir(tmp_path) == []


def test_reading_a_missing_file_raises_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError, match="mesh file not found"):
        read_mesh(tmp_path / "absent.obj")


def test_reading_garbage_raises_mesh_file_error(tmp_path):
    path = tmp_path / "garbage.ply"
    path.write_bytes(b"\x00\x01 this is not a ply file")
    with pytest.raises(MeshFileError, match="could not read"):
        read_mesh(path)


def test_a_failed_read_leaves_the_working_directory_where_it_was(tmp_path, monkeypatch):
    # pymeshlab moves the process into the file's folder when it fails to load it: relative
    # paths of the caller's next steps then pointed elsewhere
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "garbage.ply").write_bytes(b"\x00\x01 this is not a ply file")
    monkeypatch.chdir(tmp_path)
    with pytest.raises(MeshFileError, match="could not read"):
        read_mesh("sub/garbage.ply")
    assert os.getcwd() == str(tmp_path)


def test_reading_a_point_cloud_is_refused(tmp_path):
    path = tmp_path / "points.off"
    path.write_text("OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n")
    with pytest.raises(MeshFileError, match="3 vertices but no triangles"):
        read_mesh(path)


# A unit square as two triangles, with a non-finite vertex 1 that no face uses: pymeshlab's loader
# drops vertex 1 and renumbers the faces, so without the count check read_mesh would return 4
# vertices, V[1] being the file's vertex 2.
_SQUARE = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (1.0, 1.0, 0.0)]
_SQUARE_FACES = [(0, 1, 2), (1, 3, 2)]


def _with_bad_vertex(token):
    return _SQUARE[:1] + [(token, "0", "0")] + _SQUARE[1:], [[i + (i > 0) for i in f] for f in _SQUARE_FACES]


@pytest.mark.parametrize("token", ["nan", "inf", "-inf", "1e400"])
def test_obj_with_a_non_finite_vertex_is_refused_with_both_counts(tmp_path, token):
    V, F = _with_bad_vertex(token)
    path = tmp_path / "bad.obj"
    path.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in V) +
                    "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F))
    with pytest.raises(MeshFileError, match=r"bad.obj' has 5 vertices but pymeshlab loaded 4: 1 "
                                            r"was dropped, most likely for non-finite .*Fix or remove"):
        read_mesh(path)


def test_off_with_a_nan_vertex_is_refused(tmp_path):
    V, F = _with_bad_vertex("nan")
    path = tmp_path / "bad.off"
    path.write_text("OFF\n# a comment\n5 2 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in V) +
                    "".join(f"3 {a} {b} {c}\n" for a, b, c in F))
    with pytest.raises(MeshFileError, match=r"has 5 vertices but pymeshlab loaded 4.*non-finite"):
        read_mesh(path)


@pytest.mark.parametrize("fmt", ["ascii", "binary_little_endian"])
def test_ply_with_a_nan_vertex_is_refused(tmp_path, fmt):
    V, F = _with_bad_vertex("nan")
    V = np.array(V, dtype=float)
    header = (f"ply\nformat {fmt} 1.0\nelement vertex 5\nproperty double x\nproperty double y\n"
              "property double z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n")
    if fmt == "ascii":
        body = ("".join(f"{x} {y} {z}\n" for x, y, z in V) +
                "".join(f"3 {a} {b} {c}\n" for a, b, c in F)).encode()
    else:
        faces = np.zeros(2, dtype=[("n", "u1"), ("i", "<i4", 3)])
        faces["n"], faces["i"] = 3, F
        body = V.astype("<f8").tobytes() + faces.tobytes()
    path = tmp_path / "bad.ply"
    path.write_bytes(header.encode() + body)
    with pytest.raises(MeshFileError, match=r"has 5 vertices but pymeshlab loaded 4"):
        read_mesh(path)


@pytest.mark.parametrize("bad", ["nan", "inf", "repeated"])
@pytest.mark.parametrize("binary", [True, False])
def test_stl_triangles_the_loader_drops_are_reported(tmp_path, bad, binary):
    # pymeshlab drops STL triangles with a non-finite or a repeated corner without a word
    third = {"nan": [[1, 0, 0], [np.nan, 1, 0], [2, 1, 0]], "inf": [[1, 0, 0], [np.inf, 1, 0], [2, 1, 0]],
             "repeated": [[1, 0, 0], [1, 0, 0], [2, 1, 0]]}[bad]
    triangles = [[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0], [0, 1, 0]], third]
    path = tmp_path / "bad.stl"
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(np.array(triangles[:2], dtype=float).reshape(-1, 3), np.arange(6).reshape(2, 3)))
    if binary:
        record = np.zeros(3, dtype=[("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attr", "<u2")])
        record["corners"] = triangles
        path.write_bytes(b" " * 80 + np.uint32(3).astype("<u4").tobytes() + record.tobytes())
    else:
        path.write_text("solid t\n" + "".join(
            " facet normal 0 0 1\n  outer loop\n" + "".join(f"   vertex {x} {y} {z}\n" for x, y, z in t) +
            "  endloop\n endfacet\n" for t in triangles) + "endsolid t\n")
    with pytest.raises(MeshFileError, match=r"has 3 faces but pymeshlab loaded 2 triangles: at least 1 "
                                            r"was dropped, most likely for non-finite .* repeated corner"):
        read_mesh(path)
    good = tmp_path / "good.stl"                                     # the two good ones load
    ms.save_current_mesh(str(good), binary=binary)
    V, F = read_mesh(good)
    assert F.shape == (2, 3)


def test_obj_with_unreferenced_vertices_and_texture_lines_is_read_in_file_order(tmp_path):
    # pymeshlab merges nothing and keeps unreferenced vertices: vt/vn/vp, comments, groups and
    # polygon faces with texture and normal indices do not change the vertex count
    path = tmp_path / "ok.obj"
    path.write_text("# square plus an unreferenced vertex\nmtllib none.mtl\no square\n"
                    "v 0 0 0\nv 5 5 5\nv 1 0 0\r\nv\t0 1 0\nv 1 1 0 0.5 0.5 0.5\n"
                    "vt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\nvp 0.5\ng top\n"
                    "f 1/1/1 3/2/1 5/3/1 4/3/1\n")
    V, F = read_mesh(path)
    assert np.array_equal(V, [[0, 0, 0], [5, 5, 5], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    assert F.shape == (2, 3) and 1 not in F


@pytest.mark.parametrize("name, text, message", [
    ("bad.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 1 3 99\n",
     "1 face uses vertex indices outside the file's 4 vertices (first: face 1, [1, 3, 99])"),
    ("bad.obj", "v 0 0 0\n  v 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 2 0\nf 1 2 3\nf 2 4 3\n",
     "1 vertex lines start with spaces or tabs (first: line 2)"),
])
def test_files_that_crash_pymeshlab_are_refused_before_it_reads_them(tmp_path, name, text, message):
    # pymeshlab's OFF loader writes out of bounds for a face index past the vertices (the process
    # crashed at exit even after the error was reported), and its OBJ loader aborted the process
    # on an indented vertex line: the file must not reach the loader at all
    path = tmp_path / name
    path.write_text(text)
    script = ("from curvdetail.io.mesh import read_mesh, MeshFileError\n"
              "from curvdetail.filters.files import load_meshset\n"
              f"for read in (read_mesh, load_meshset):\n"
              f"    try:\n        read({str(path)!r})\n"
              "    except MeshFileError as exc:\n        print(exc)\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert len(lines) == 2 and all(message in line for line in lines)


def test_binary_off_is_refused_with_its_name(tmp_path):
    path = tmp_path / "b.off"
    path.write_bytes(b"OFF BINARY\n" + np.array([3, 1, 0], ">i4").tobytes() +
                     np.eye(3, dtype=">f4").tobytes() + np.array([3, 0, 1, 2, 0], ">i4").tobytes())
    with pytest.raises(MeshFileError, match="binary OFF file"):
        read_mesh(path)


def test_off_with_counts_on_the_header_line_and_colours_is_read(tmp_path):
    path = tmp_path / "ok.off"
    path.write_text("COFF 4 2 0\n" + "".join(f"{x} {y} {z} 255 0 0 255\n" for x, y, z in _SQUARE) +
                    "".join(f"3 {a} {b} {c}\n" for a, b, c in _SQUARE_FACES))
    V, F = read_mesh(path)
    assert np.array_equal(V, _SQUARE) and np.array_equal(F, _SQUARE_FACES)


@pytest.mark.parametrize("name, text, message", [
    # refused before loading now (pymeshlab wrote out of bounds with some such indices)
    ("out_of_range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\nf 2 9 3\n",
     r"line 7 \('f 2 9 3'\) names the vertex 9, which the file does not have"),
    ("repeated.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\nf 2 2 3\n",
     r"has 3 faces but pymeshlab loaded 2 triangles: at least 1 was dropped, most likely for vertex indices "
     r"out of range or repeated"),
])
def test_obj_faces_the_loader_drops_are_reported(tmp_path, name, text, message):
    # pymeshlab drops these faces without a word: the mesh would silently get a hole
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(MeshFileError, match=message):
        read_mesh(path)


def test_polygons_are_triangulated_not_reported(tmp_path):
    path = tmp_path / "quad.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    V, F = read_mesh(path)
    assert V.shape == (4, 3) and F.shape == (2, 3)
    assert V.tolist() == [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    # the unit square split along one diagonal, both triangles facing +z as the quad does
    up = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    assert np.allclose(up[:, :2], 0.0) and np.array_equal(up[:, 2], [1.0, 1.0])     # doubled areas
    assert 0.5 * up[:, 2].sum() == 1.0
    assert {frozenset(f) for f in F.tolist()} in ({frozenset({0, 1, 2}), frozenset({0, 2, 3})},
                                                  {frozenset({0, 1, 3}), frozenset({1, 2, 3})})


def test_reads_the_shipped_meshes_in_file_order():
    V, F = read_mesh(data_path("terrainA_1k.obj"))
    assert V.shape == (1089, 3) and F.shape == (2048, 3)
    first = open(data_path("terrainA_1k.obj")).read().split("\nv ", 1)[1].split("\n", 1)[0]
    assert np.allclose(V[0], [float(t) for t in first.split()[:3]])


@pytest.mark.parametrize("quality, message", [
    (np.full(4, np.nan), "quality: 4 values are NaN or infinite"),
    (np.ones(4) + 1j, "quality has dtype complex128"),
])
def test_write_mesh_refuses_quality_it_would_write_wrong(tmp_path, quality, message):
    with pytest.raises(MeshError, match=message):
        write_mesh(tmp_path / "q.ply", _SQUARE, _SQUARE_FACES, quality=quality)
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("read", ["read_mesh", "load_meshset"])
def test_paths_that_are_not_mesh_files_are_named(tmp_path, read):
    from curvdetail.filters.files import load_meshset

    function = {"read_mesh": read_mesh, "load_meshset": load_meshset}[read]
    with pytest.raises(MeshFileError, match="a mesh path must be a str or os.PathLike; got NoneType"):
        function(None)
    with pytest.raises(MeshFileError, match="is a folder; name a mesh file in it"):
        function(tmp_path)
    with pytest.raises(FileNotFoundError, match="mesh file not found"):
        function(tmp_path / "none.obj")
    os.mkfifo(tmp_path / "pipe.obj")          # there, not "not found"; never opened (it would block)
    with pytest.raises(MeshFileError, match="is not a regular file"):
        function(tmp_path / "pipe.obj")


def test_bytes_paths_read_and_write(tmp_path):
    path = os.fsencode(tmp_path / "m.obj")
    write_mesh(path, _SQUARE, _SQUARE_FACES)
    V, F = read_mesh(path)
    assert np.allclose(V, _SQUARE)


def test_save_mesh_refuses_to_overwrite(tmp_path):
    import pymeshlab

    path = tmp_path / "m.ply"
    path.write_text("x")
    mesh = pymeshlab.Mesh(vertex_matrix=np.eye(3), face_matrix=np.array([[0, 1, 2]], dtype=np.int32))
    with pytest.raises(FileExistsError, match=r"m.ply exists; pass overwrite=True to replace it\.$"):
        save_mesh(path, mesh)
    assert path.read_text() == "x" and os.listdir(tmp_path) == ["m.ply"]


def test_save_mesh_refuses_custom_attribute_options_instead_of_crashing(tmp_path):
    # pymeshlab segfaults exporting custom attributes of a mesh copied into a fresh MeshSet
    import pymeshlab

    mesh = pymeshlab.Mesh(vertex_matrix=np.eye(3), face_matrix=np.array([[0, 1, 2]], dtype=np.int32),
                          v_scalar_array=np.arange(3.0))
    with pytest.raises(MeshFileError, match=r"cannot save custom attributes \(__ca_vs__foo\).*save_current_mesh"):
        save_mesh(tmp_path / "m.ply", mesh, __ca_vs__foo=True)
    assert os.listdir(tmp_path) == []


def test_failed_overwrite_keeps_the_old_file(tmp_path, nose, monkeypatch):
    import pymeshlab

    def broken(self, path, **kwargs):
        raise RuntimeError("disk full")

    path = tmp_path / "keep.ply"
    path.write_text("old")
    monkeypatch.setattr(pymeshlab.MeshSet, "save_current_mesh", broken)
    with pytest.raises(MeshFileError, match="could not write .*keep.ply.*disk full"):
        write_mesh(path, *nose, overwrite=True)
    assert path.read_text() == "old" and os.listdir(tmp_path) == ["keep.ply"]


def test_docstring_examples_run():
    import doctest
    import importlib

    result = doctest.testmod(importlib.import_module("curvdetail.io"), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0, result


def test_written_off_is_plain_geometry_that_other_readers_take(tmp_path):
    # pymeshlab's defaults wrote "NCOFF" with RGBA colours and normals on every vertex line,
    # a header libigl's readOFF refuses
    V, F = icosphere(subdivisions=1)
    write_mesh(tmp_path / "s.off", V, F)
    lines = (tmp_path / "s.off").read_text().splitlines()
    assert lines[0] == "OFF"
    assert lines[1].split() == [str(V.shape[0]), str(F.shape[0]), "0"]
    vertex_lines = lines[2:2 + V.shape[0]]
    assert all(len(line.split()) == 3 for line in vertex_lines)
    np.testing.assert_allclose(np.array([line.split() for line in vertex_lines], dtype=float), V, rtol=0, atol=1e-15)


def test_written_ply_holds_positions_faces_and_quality_only(tmp_path):
    V, F = icosphere(subdivisions=1)
    write_mesh(tmp_path / "s.ply", V, F, quality=V[:, 0])
    raw = (tmp_path / "s.ply").read_bytes()
    header = raw[:raw.index(b"end_header")].decode()
    properties = [line.split()[-1] for line in header.splitlines() if line.startswith("property")]
    assert properties == ["x", "y", "z", "quality", "vertex_indices"]


@pytest.mark.parametrize("rows, message", [
    ("0 0 0\n1 0 0 7\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n",
     "1 vertex rows hold a number of values other than 3 (x y z) (first: vertex 1, 4 values)"),
    ("0 0 0\n1 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n",
     "1 vertex rows hold a number of values other than 3 (x y z) (first: vertex 1, 2 values)"),
    ("0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n",
     "the header declares 4 vertices and 2 faces, but the file holds 5 rows after it"),
    ("0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2\n3 0 2 3\n",
     "face 0 is the row '4 0 1 2', which is not a vertex count followed by that many integer"),
    ("0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2.5 3\n",
     "face 1 is the row '3 0 2.5 3', which is not a vertex count"),
])
def test_off_rows_the_loader_would_misread_are_refused(tmp_path, rows, message):
    # pymeshlab reads OFF as one stream of numbers: a vertex row with a value too many came back
    # as vertex (7, 1, 1), a two-value row as a duplicated triangle, both without a word
    path = tmp_path / "rows.off"
    path.write_text("OFF\n4 2 0\n" + rows)
    with pytest.raises(MeshFileError, match=re.escape(message)):
        read_mesh(path)


def test_off_face_rows_with_colours_and_polygons_are_read(tmp_path):
    path = tmp_path / "ok.off"
    path.write_text("OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3 255 0 0\n")
    V, F = read_mesh(path)
    assert np.array_equal(V, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]) and F.shape == (2, 3)


def test_written_ply_without_quality_holds_no_quality_field(tmp_path):
    # pymeshlab's meshes always carry a quality: without ours it was written as zeros, which
    # MeshLab shows as zero error everywhere (curvdetail remesh --no-evaluate)
    V, F = icosphere(subdivisions=1)
    write_mesh(tmp_path / "s.ply", V, F)
    raw = (tmp_path / "s.ply").read_bytes()
    header = raw[:raw.index(b"end_header")].decode()
    properties = [line.split()[-1] for line in header.splitlines() if line.startswith("property")]
    assert properties == ["x", "y", "z", "vertex_indices"]
    W, G = read_mesh(tmp_path / "s.ply")
    assert np.array_equal(W, V) and np.array_equal(G, F)


def test_a_file_pymeshlab_reads_as_nothing_is_not_called_a_mesh_without_triangles(tmp_path):
    path = tmp_path / "notes.txt"
    path.write_text("hello world\n")
    with pytest.raises(MeshFileError, match=r"pymeshlab read nothing from .*notes.txt' \(no vertices, no "
                                            r"triangles\); is it a mesh file\?"):
        read_mesh(path)


@pytest.mark.parametrize("faces, message", [
    ("f 1 2 3\nf 2.5 4 3\n", "the face on line 8 has a fractional index"),
    ("f 1 2 3\n# a comment line. fine\nf 2 4 3 # second\n", "the face on line 9 ends in a comment"),
])
def test_obj_faces_the_loader_would_misread_are_refused_before_loading(tmp_path, faces, message):
    # 2.5 became 2 without a word; "f 1/1 2/1 3/1 # face no. 1" came back as two triangles, one
    # with a vertex index past the file's vertices (the test process crashed at exit)
    path = tmp_path / "f.obj"
    path.write_text("v 0.5 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0.5 0.5\n# faces.\n" + faces)
    with pytest.raises(MeshFileError, match=message):
        read_mesh(path)


def test_obj_decimals_and_comments_outside_faces_are_read(tmp_path):
    path = tmp_path / "f.obj"
    path.write_text("# made by hand. v 1\nv 0.5 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5 0.5\nf 1/1 2/1 3/1\n"
                    "# the end.\n")
    assert read_mesh(path)[1].tolist() == [[0, 1, 2]]


def test_coff_rows_with_and_without_a_colour_are_read(tmp_path):
    # with a prefixed keyword pymeshlab reads row by row: a colour on some rows only is fine
    path = tmp_path / "c.off"
    path.write_text("COFF\n4 2 0\n0 0 0 255 0 0 255\n1 0 0\n0 1 0 255 0 0 255\n1 1 0\n3 0 1 2\n3 1 3 2\n")
    V, F = read_mesh(path)
    assert np.array_equal(V, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]) and F.tolist() == [[0, 1, 2], [1, 3, 2]]
    path.write_text("COFF\n4 2 0\n0 0 0 255 0 0 255\n1 0\n0 1 0\n1 1 0\n3 0 1 2\n3 1 3 2\n")
    with pytest.raises(MeshFileError, match="1 vertex rows hold fewer than 3 values"):
        read_mesh(path)


# What each format keeps of the coordinates (pymeshlab's writers, measured): OBJ 16 decimals
# ("%.16f"), OFF and ASCII PLY 16 significant digits ("%.16g"), binary PLY doubles, STL and 3DS
# float32. write_mesh and save_mesh refuse, before writing, what a format cannot hold.
def _raw_round_trip(path, V, F, **options):
    """What pymeshlab itself writes and reads back (no checks): the loss write_mesh guards."""
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32)))
    ms.save_current_mesh(str(path), **options)
    back = pymeshlab.MeshSet()
    back.load_new_mesh(str(path))
    return back.current_mesh().vertex_matrix()


def _diagonal(V):
    return np.linalg.norm(V.max(axis=0) - V.min(axis=0))


@pytest.mark.parametrize("scale", [1e-13, 1e-20])
def test_obj_refuses_a_mesh_its_16_decimals_cannot_hold(tmp_path, scale):
    V, F = icosphere(subdivisions=1)
    V = V * scale
    # pymeshlab alone: 1e-20 comes back as all zeros, 1e-13 with 3.5e-4 of the diagonal lost
    lost = np.abs(_raw_round_trip(tmp_path / "raw.obj", V, F) - V).max() / _diagonal(V)
    assert lost > 1e-4
    with pytest.raises(MeshFileError, match=r"pymeshlab writes OBJ coordinates with 16 decimals \(an error up to "
                                            r"5e-17\), which loses up to .* of the mesh's bounding-box diagonal "
                                            r"\(.*\); the limit is 1e-09 of it. Write .ply \(binary"):
        write_mesh(tmp_path / "m.obj", V, F)
    with pytest.raises(MeshFileError, match="16 decimals"):
        save_mesh(tmp_path / "m.obj", pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32)))
    assert not (tmp_path / "m.obj").exists()
    write_mesh(tmp_path / "m.ply", V, F)                                 # binary doubles: exact
    assert np.array_equal(read_mesh(tmp_path / "m.ply")[0], V)


def test_obj_keeps_a_mesh_within_the_limit_to_1e9_of_its_diagonal(tmp_path):
    V, F = icosphere(subdivisions=1)
    V = V * 1e-7
    write_mesh(tmp_path / "m.obj", V, F)
    assert np.abs(read_mesh(tmp_path / "m.obj")[0] - V).max() <= 1e-9 * _diagonal(V)


@pytest.mark.parametrize("options", [{}, {"binary": False}])
def test_off_and_ascii_ply_refuse_coordinates_their_16_digits_cannot_hold(tmp_path, options):
    # a unit sphere 1e7 from the origin: 16 significant digits keep 1.6e-9 of its diagonal
    V, F = icosphere(subdivisions=1)
    V = V + 1e7
    ext = "off" if not options else "ply"
    assert np.abs(_raw_round_trip(tmp_path / f"raw.{ext}", V, F, **options) - V).max() > 1e-9 * _diagonal(V)
    mesh = pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32))
    with pytest.raises(MeshFileError, match=rf"writes {ext.upper()}.* coordinates with 16 significant digits, "
                                            r"which loses up to .* the limit is 1e-09\) for coordinates this far "
                                            r"from the origin \(largest 1e\+07\)"):
        save_mesh(tmp_path / f"m.{ext}", mesh, **options)
    save_mesh(tmp_path / "m.ply", mesh)                                  # binary: exact
    assert np.array_equal(read_mesh(tmp_path / "m.ply")[0], V)
    V = V - 1e7 + 1e5                                                    # nearer: within the limit
    write_mesh(tmp_path / "near.off", V, F)
    assert np.abs(read_mesh(tmp_path / "near.off")[0] - V).max() <= 1e-9 * _diagonal(V)


@pytest.mark.parametrize("ext", ["stl", "3ds"])
def test_single_precision_formats_refuse_overflow_and_underflow(tmp_path, ext):
    V, F = icosphere(subdivisions=1)
    # pymeshlab writes 1e39 as inf (its loader then drops every vertex), and a 1e-41 mesh loses
    # digits to float32's subnormals
    assert _raw_round_trip(tmp_path / f"raw.{ext}", V * 1e39, F).shape == (0, 3)
    assert b"\x00\x00\x80\x7f" in (tmp_path / f"raw.{ext}").read_bytes()          # float32 inf
    with pytest.raises(MeshFileError, match=rf"{ext.upper()} holds coordinates in single precision, whose largest "
                                            r"value is 3.403e\+38; 42 vertices exceed it \(first: 0, 1, 2\) and "
                                            r"would be written as inf"):
        write_mesh(tmp_path / f"m.{ext}", V * 1e39, F)
    with pytest.raises(MeshFileError, match=r"single precision, which keeps this mesh's coordinates \(largest .*\) "
                                            r"only to .*: values below 1.18e-38 lose digits or become 0"):
        write_mesh(tmp_path / f"m.{ext}", V * 1e-41, F)
    assert not (tmp_path / f"m.{ext}").exists()
    write_mesh(tmp_path / f"m.{ext}", V * 1e30, F)                       # float32 precision: accepted
    W = read_mesh(tmp_path / f"m.{ext}")[0]
    assert W.shape == V.shape and np.allclose(np.sort(W, axis=0), np.sort(V * 1e30, axis=0), rtol=1e-7, atol=0)


@pytest.mark.parametrize("ext", ["stl", "3ds", "dae"])
def test_single_precision_formats_refuse_a_small_mesh_far_from_the_origin(tmp_path, ext):
    # a unit sphere at 1e7 lost 0.14 of its diagonal in .3ds without a word; single precision
    # there is spaced 1 apart
    V, F = icosphere(subdivisions=1)
    with pytest.raises(MeshFileError, match=r"which loses up to .* of the mesh's bounding-box diagonal .*the limit "
                                            r"is 0.0001\) for coordinates this far from the origin"):
        write_mesh(tmp_path / f"m.{ext}", V + 1e7, F)
    assert not (tmp_path / f"m.{ext}").exists()
    write_mesh(tmp_path / f"n.{ext}", V + 10.0, F)                         # near the origin: accepted
    # and read back as written, within the 1e-4 of the diagonal the check allows (STL merges and
    # renumbers the vertices: each is matched to the nearest one written)
    W, G = read_mesh(tmp_path / f"n.{ext}")
    assert W.shape == V.shape and G.shape == F.shape
    gap = np.linalg.norm(W[:, None, :] - (V + 10.0)[None, :, :], axis=2)
    match = gap.argmin(axis=1)
    assert np.array_equal(np.sort(match), np.arange(V.shape[0]))          # one to one
    assert gap.min(axis=1).max() <= 1e-4 * np.linalg.norm(np.ptp(V, axis=0))
    def canonical(T):                                                     # each triangle from its least corner
        return sorted(tuple(np.roll(t, -int(np.argmin(t)))) for t in T.tolist())
    assert canonical(match[G]) == canonical(F)


def test_single_precision_keeps_a_terrain_in_utm_coordinates(tmp_path):
    # 15 km across, 5,000 km from the origin: float32 keeps it to 0.25 m, 1.2e-5 of its diagonal
    V, F = icosphere(subdivisions=1)
    V = V * 7500.0 + [5e6, 4e6, 300.0]
    write_mesh(tmp_path / "t.stl", V, F)
    assert np.abs(np.sort(read_mesh(tmp_path / "t.stl")[0], axis=0) - np.sort(V, axis=0)).max() <= 0.25


def test_stl_ascii_is_single_precision_too(tmp_path):
    V, F = icosphere(subdivisions=1)
    mesh = pymeshlab.Mesh(vertex_matrix=V * 1e39, face_matrix=F.astype(np.int32))
    with pytest.raises(MeshFileError, match="would be written as inf"):
        save_mesh(tmp_path / "m.stl", mesh, binary=False)


@pytest.mark.parametrize("ext, scale, message", [
    ("3mf", 0.1, r"writes 3MF coordinates with 6 decimals \(an error up to 1e-06\).* the limit is 1e-06 of it"),
    ("idtf", 0.1, r"writes IDTF coordinates with 6 decimals \(an error up to 5e-07\)"),
    ("dae", 1e-41, r"DAE holds coordinates in single precision"),
    ("wrl", 1e39, r"WRL holds coordinates in single precision, whose largest value"),
])
def test_other_formats_refuse_what_they_cannot_hold(tmp_path, ext, scale, message):
    V, F = icosphere(subdivisions=1)
    with pytest.raises(MeshFileError, match=message):
        write_mesh(tmp_path / f"m.{ext}", V * scale, F)
    assert not (tmp_path / f"m.{ext}").exists()


def test_nxz_coordinates_are_refused_by_the_check_itself():
    # write_mesh refuses .nxz before this check (UNWRITTEN_FORMATS); the check says why on its own
    from curvdetail.io.mesh import check_coordinates

    with pytest.raises(MeshFileError, match=r"pymeshlab's NXZ writer compresses the coordinates"):
        check_coordinates("m.nxz", icosphere(subdivisions=1)[0])


def test_ctm_is_written_lossless_and_its_lossy_compression_refused(tmp_path):
    # pymeshlab's default (MG2) put a sphere's vertices 2e-5 of its diagonal off, at radius 1e-3 2e-2
    V, F = icosphere(subdivisions=2)
    write_mesh(tmp_path / "m.ctm", V * 1e-3, F)
    raw = (tmp_path / "m.ctm").read_bytes()
    assert raw[8:11] == b"MG1"                                           # lossless: float32 values
    with pytest.raises(MeshFileError, match=r"with lossless=False pymeshlab's CTM writer compresses the coordinates"):
        save_mesh(tmp_path / "lossy.ctm", pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32)),
                  lossless=False)


def _triangles(F):
    """The triangles as a sorted list, each from its least corner (orientation kept): how MG1
    stores them."""
    return sorted(tuple(np.roll(t, -int(np.argmin(t)))) for t in np.asarray(F).tolist())


_CTM_ROUND_TRIP = """
import json, sys
import numpy as np
from curvdetail import read_mesh, write_mesh
from curvdetail.curvature.testing import icosphere
V, F = icosphere(subdivisions=2)
write_mesh(sys.argv[1], V, F)
W, G = read_mesh(sys.argv[1])
print(json.dumps({"V": W.tolist(), "F": G.tolist()}))
"""


def test_ctm_written_by_write_mesh_is_read_back(tmp_path):
    # write_mesh turned colours off, and pymeshlab's meshes always carry a quality: the file held a
    # "Quality" map and no "Color" one, on which pymeshlab's CTM reader crashed the process every
    # time. In a child process: that crash would end this one.
    path = tmp_path / "m.ctm"
    done = subprocess.run([sys.executable, "-c", _CTM_ROUND_TRIP, str(path)], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    back = json.loads(done.stdout)
    V, F = icosphere(subdivisions=2)
    # lossless CTM (MG1) keeps the float32 values and the vertex order exactly; it stores each
    # triangle from its least corner, sorted
    assert np.array_equal(back["V"], V.astype(np.float32).astype(np.float64))
    assert _triangles(back["F"]) == _triangles(F)
    from curvdetail._ctm_scan import ctm_layout

    assert ctm_layout(path)["attribute_maps"] == []                      # neither colours nor quality


def test_ctm_with_quality_is_refused_since_pymeshlab_cannot_read_it_back(tmp_path):
    V, F = icosphere(subdivisions=1)
    with pytest.raises(MeshFileError, match=r"cannot write .*m\.ctm' with quality: pymeshlab's CTM reader reads a "
                                            r"file's quality from its colour map: where there is none it crashes the "
                                            r"process .*; write \.ply \(binary: .*\) to keep the quality, or pass "
                                            r"quality=None"):
        write_mesh(tmp_path / "m.ctm", V, F, quality=V[:, 2])
    assert list(tmp_path.iterdir()) == []


def test_save_mesh_writes_no_ctm_quality_without_colours(tmp_path):
    # the layout pymeshlab's reader crashes on: quality without colours. Defaults write both (read
    # back by pymeshlab with the quality as the colours' red channel, by curvdetail from the
    # "Quality" map), no colours writes neither, and asking for the quality without colours is refused.
    from curvdetail._ctm_scan import ctm_layout

    V, F = icosphere(subdivisions=1)
    mesh = pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32), v_scalar_array=V[:, 0])
    save_mesh(tmp_path / "both.ctm", mesh)
    assert ctm_layout(tmp_path / "both.ctm")["attribute_maps"] == [b"Color", b"Quality"]
    save_mesh(tmp_path / "plain.ctm", mesh, save_vertex_color=False)
    assert ctm_layout(tmp_path / "plain.ctm")["attribute_maps"] == []
    with pytest.raises(MeshFileError, match=r"with save_vertex_quality=True and no vertex colours: pymeshlab's CTM "
                                            r"reader reads a file's quality from its colour map"):
        save_mesh(tmp_path / "q.ctm", mesh, save_vertex_color=False, save_vertex_quality=True)
    assert not (tmp_path / "q.ctm").exists()


def _coloured_ctm(path, lossless, quality=None):
    """Write an icosphere with vertex colours and a quality (10 + 3.7 z: not a colour) to the CTM
    file ``path`` with pymeshlab itself; returns V, F, the colours as pymeshlab holds them (8
    bits) and the quality."""
    V, F = icosphere(subdivisions=2)
    colours = np.c_[np.random.default_rng(7).random((len(V), 3)), np.ones(len(V))]
    quality = 10 + 3.7 * V[:, 2] if quality is None else quality
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32), v_color_matrix=colours, v_scalar_array=quality))
    ms.save_current_mesh(str(path), lossless=lossless)
    return V, F, ms.current_mesh().vertex_color_matrix(), quality


@pytest.mark.parametrize("lossless", [True, False])
def test_a_ctm_files_quality_is_read_from_its_quality_map(tmp_path, lossless):
    # pymeshlab's CTM reader read the quality from the colour map (10.0 came back as 0.64, the
    # red channel) and marked the layer as holding neither colours nor quality
    from curvdetail._ctm_scan import ctm_layout
    from curvdetail.io.mesh import load_checked

    path = tmp_path / "m.ctm"
    V, F, colours, quality = _coloured_ctm(path, lossless)
    assert ctm_layout(path)["attribute_maps"] == [b"Color", b"Quality"]
    ms = pymeshlab.MeshSet()
    mesh = load_checked(ms, str(path))
    assert mesh.has_vertex_scalar() and mesh.has_vertex_color()
    W = mesh.vertex_matrix()
    if lossless:                     # MG1: float32 values, the vertices in their order
        assert np.array_equal(W, V.astype(np.float32))
        match = np.arange(len(V))
        assert np.array_equal(mesh.vertex_scalar_array(), quality.astype(np.float32))
    else:                            # MG2: the vertices sorted, positions and the map to a grid
        match = np.argmin(((W[:, None, :] - V[None, :, :]) ** 2).sum(axis=2), axis=1)
        assert sorted(match) == list(range(len(V))) and np.abs(W - V[match]).max() < 1e-3
        assert np.abs(mesh.vertex_scalar_array() - quality[match]).max() <= 0.5 / 256     # its precision
    # 8-bit colours, read back truncated (MG2: from a 1/256 grid)
    assert np.abs(mesh.vertex_color_matrix() - colours[match]).max() <= (1 if lossless else 2) / 255 + 1e-9
    X, G = read_mesh(path)                                        # the same vertices and triangles
    assert np.array_equal(X, W) and np.array_equal(G, mesh.face_matrix())


def test_a_ctm_quality_that_cannot_be_decoded_is_left_out_with_a_warning(tmp_path, monkeypatch):
    # LZMA options Python's decoder lacks (OpenCTM's writer uses none): the quality is left out
    # (not read as the red channel), the colours and the geometry are read
    import curvdetail.io
    from curvdetail.io.mesh import load_checked

    def undecodable(path, name, layout=None):
        raise ValueError(f"its {name.decode()!r} map's LZMA data cannot be decoded here (lc + lp > 4)")

    path = tmp_path / "m.ctm"
    V, _, colours, _ = _coloured_ctm(path, True)
    monkeypatch.setattr(curvdetail.io, "ctm_vertex_map", undecodable)
    ms = pymeshlab.MeshSet()
    with pytest.warns(UserWarning, match=r"m\.ctm': the vertex quality is left out: its 'Quality' map's LZMA data "
                                         r"cannot be decoded here \(lc \+ lp > 4\)\. The geometry and the colours are "
                                         r"read \(pymeshlab would read the quality from the colour map\)"):
        mesh = load_checked(ms, str(path))
    assert not mesh.has_vertex_scalar() and mesh.has_vertex_color()
    assert np.array_equal(mesh.vertex_matrix(), V.astype(np.float32))
    assert np.abs(mesh.vertex_color_matrix() - colours).max() <= 1 / 255 + 1e-9


_CTM_CRASH = """
import sys
import numpy as np, pymeshlab
from curvdetail.io.mesh import read_mesh, MeshFileError
from curvdetail.filters.files import load_meshset
from curvdetail.curvature.testing import icosphere
V, F = icosphere(subdivisions=1)
for name, lossless in (("mg1.ctm", True), ("mg2.ctm", False)):
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32)))
    path = sys.argv[1] + "/" + name
    ms.save_current_mesh(path, lossless=lossless, save_vertex_color=False)      # quality, no colours
    for read in (read_mesh, load_meshset):
        try:
            read(path)
        except MeshFileError as exc:
            print(exc)
"""


def test_ctm_files_that_crash_pymeshlab_are_refused_before_it_reads_them(tmp_path):
    # pymeshlab's own CTM writer makes such files (save_vertex_color=False); its reader then
    # crashed the process: read_mesh and the filters' loader refuse them unread
    done = subprocess.run([sys.executable, "-c", _CTM_CRASH, str(tmp_path)], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    lines = done.stdout.splitlines()
    assert len(lines) == 4 and all("it holds a vertex attribute map named 'Quality' but none named 'Color'" in line
                                   and "crashes the process (segmentation fault" in line for line in lines), lines


_3DS_WRITES = """
import sys
import numpy as np, pymeshlab
from curvdetail.io.mesh import save_mesh, write_mesh
from curvdetail.curvature.testing import icosphere
V, F = icosphere(subdivisions=1)
write_mesh(sys.argv[1] + "/w.3ds", V, F)
mesh = pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32))
save_mesh(sys.argv[1] + "/s.3ds", mesh)
assert not mesh.has_face_color()                                    # the caller's mesh is left alone
"""


def test_3ds_files_are_the_same_in_every_process(tmp_path):
    # without face colours pymeshlab's 3DS writer named the faces' material from uninitialised
    # stack memory (a stack address: different in every process); two processes, as two runs
    folders = [tmp_path / "a", tmp_path / "b"]
    for folder in folders:
        folder.mkdir()
        done = subprocess.run([sys.executable, "-c", _3DS_WRITES, str(folder)], capture_output=True, text=True,
                              timeout=120)
        assert done.returncode == 0, done.stderr[-2000:]
    for name in ("w.3ds", "s.3ds"):
        assert (folders[0] / name).read_bytes() == (folders[1] / name).read_bytes(), name
    V, F = icosphere(subdivisions=1)
    W, G = read_mesh(folders[0] / "w.3ds")
    assert np.array_equal(W, V.astype(np.float32).astype(np.float64)) and np.array_equal(G, F)


def test_3ds_without_face_colours_is_refused(tmp_path):
    V, F = icosphere(subdivisions=1)
    with pytest.raises(MeshFileError, match=r"with save_face_color=False: pymeshlab's 3DS writer names each face's "
                                            r"material from uninitialised memory"):
        save_mesh(tmp_path / "m.3ds", pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32)),
                  save_face_color=False)
    assert list(tmp_path.iterdir()) == []


def test_u3d_is_refused_since_pymeshlab_writes_no_file(tmp_path):
    V, F = icosphere(subdivisions=1)
    with pytest.raises(MeshFileError, match=r"\.u3d meshes are refused: pymeshlab's writer for them is not run \(it "
                                            r"reports success but writes no file"):
        write_mesh(tmp_path / "m.u3d", V, F)
    assert list(tmp_path.iterdir()) == []


# Every format pymeshlab 2025.7 saves (pymeshlab lists none; found by saving to each extension MeshLab
# knows): the probe and write_mesh run these writers in the caller's process.
_SAVE_FORMATS = (".3ds", ".3mf", ".ctm", ".dae", ".dxf", ".e57", ".idtf", ".json", ".nxs", ".nxz", ".obj", ".off",
                 ".ply", ".stl", ".u3d", ".wrl", ".x3d", ".xyz")
_UNWRITTEN = (".nxs", ".nxz", ".u3d")


@pytest.mark.parametrize("ext", _UNWRITTEN)
def test_unsafe_writers_are_refused_without_running_them(tmp_path, monkeypatch, ext):
    # the format probe ran pymeshlab's writer on one triangle in the caller's process: for .nxz it
    # crashed a full test run (segmentation fault in the Nexus writer, which reads memory it never
    # set); .u3d wrote a fixed-name file in the shared temporary folder. No writer may run for these.
    import curvdetail.io as io
    from curvdetail.filters.files import check_output_path

    assert set(io.UNWRITTEN_FORMATS) == set(_UNWRITTEN)
    ran = []
    monkeypatch.setattr(pymeshlab.MeshSet, "save_current_mesh", lambda self, path, **kw: ran.append(path))
    monkeypatch.setattr(io, "_WRITES", {})                          # as in a fresh process
    mesh = pymeshlab.Mesh(vertex_matrix=np.eye(3), face_matrix=np.array([[0, 1, 2]], dtype=np.int32))
    for write in (lambda p: io.check_mesh_output(p), lambda p: write_mesh(p, *icosphere(subdivisions=1)),
                  lambda p: save_mesh(p, mesh), lambda p: check_output_path(p)):
        with pytest.raises(MeshFileError, match=rf"cannot write .*m\{ext}': \{ext} meshes are refused: pymeshlab's "
                                                r"writer for them is not run \("):
            write(tmp_path / f"m{ext}")
    assert ran == [] and io._WRITES == {} and list(tmp_path.iterdir()) == []
    assert io._why_not_written(ext) == io.UNWRITTEN_FORMATS[ext] and ran == []


_PERTURBED_WRITES = """
import os, sys, tempfile
import numpy as np
from curvdetail.io.mesh import MeshFileError, check_mesh_output, write_mesh
from curvdetail.curvature.testing import icosphere
V, F = icosphere(subdivisions=1)
folder = tempfile.mkdtemp()
for ext in sys.argv[1:]:
    print(ext, end=" ", flush=True)
    try:
        check_mesh_output(os.path.join(folder, "probe" + ext))
        if ext not in (".e57", ".xyz"):                 # points only: refused above
            write_mesh(os.path.join(folder, "m" + ext), 10.0 * V + 10.0, F)
        print("written", flush=True)
    except MeshFileError as exc:
        print("refused:", exc, flush=True)
"""


def _perturbed_child(extensions):
    """Probe and write each extension in a child process whose heap memory is handed out filled
    with a nonzero byte (glibc's MALLOC_PERTURB_), as memory recycled in a long run is: a writer
    that reads memory it never set crashes there every time, not once in a while."""
    env = dict(os.environ, MALLOC_PERTURB_="85", PYTHONFAULTHANDLER="1")
    done = subprocess.run([sys.executable, "-c", _PERTURBED_WRITES, *extensions], capture_output=True, text=True,
                          env=env, timeout=300)
    assert done.returncode == 0, (done.returncode, done.stdout, done.stderr[-3000:])
    return dict(line.split(" ", 1) for line in done.stdout.splitlines())


def test_unsafe_writers_are_refused_in_a_process_where_they_crash():
    # the old probe crashed this child (segmentation fault or bus error in NexusBuilder::saturateNode)
    result = _perturbed_child(_UNWRITTEN)
    assert all(result[ext].startswith("refused: cannot write") and "meshes are refused" in result[ext]
               for ext in _UNWRITTEN), result


def test_every_other_save_format_is_probed_and_written_safely_with_recycled_memory():
    # what keeps the probe in-process: the writers left run cleanly where memory is not zero (a
    # pymeshlab upgrade whose writer crashes here belongs in UNWRITTEN_FORMATS)
    others = [ext for ext in _SAVE_FORMATS if ext not in _UNWRITTEN]
    result = _perturbed_child(others)
    assert set(result) == set(others)
    points = (".e57", ".xyz")
    assert all(result[ext] == "written" for ext in others if ext not in points), result
    assert all("hold points only" in result[ext] for ext in points), result


def test_save_mesh_refuses_non_finite_coordinates(tmp_path):
    V, F = icosphere(subdivisions=1)
    V[3, 1] = np.nan
    with pytest.raises(MeshFileError, match=r"1 vertex has NaN or infinite coordinates \(first: 3\)"):
        save_mesh(tmp_path / "m.obj", pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32)))


@pytest.mark.parametrize("ext", [".off", ".dae", ".3ds"])
def test_the_write_check_agrees_with_the_loss_measured_by_writing(tmp_path, ext):
    # the check is an estimate made before writing; here the file is written by pymeshlab itself
    # and read back: no placement losing more than the limit may pass, and none losing less than
    # a third of it may be refused (CAD parts in mm at metres, GIS data in UTM coordinates)
    from curvdetail.io.mesh import DOUBLE_TOLERANCE, OFFSET_TOLERANCE, check_coordinates

    limit = DOUBLE_TOLERANCE if ext == ".off" else OFFSET_TOLERANCE
    V0, F = icosphere(subdivisions=2)
    for radius in (0.1, 20.0, 70.0, 1000.0):
        for offset in (0.0, 1e3, 9e3, 9e6):
            V = V0 * radius + [offset, -0.7 * offset, 0.3 * offset]
            ms = pymeshlab.MeshSet()
            ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32)))
            ms.save_current_mesh(str(tmp_path / f"m{ext}"))
            back = pymeshlab.MeshSet()
            back.load_new_mesh(str(tmp_path / f"m{ext}"))
            loss = np.linalg.norm(back.current_mesh().vertex_matrix() - V, axis=1).max() / _diagonal(V)
            try:
                check_coordinates(f"m{ext}", V)
                refused = False
            except MeshFileError:
                refused = True
            assert not (loss > limit and not refused), (radius, offset, loss)
            assert not (loss < limit / 3 and refused), (radius, offset, loss)


def test_a_bytes_path_writes_what_a_str_path_writes(tmp_path):
    # b'.ply' != '.ply': write_mesh(b'x.ply', ...) wrote a quality of zeros a str path does not
    V, F = icosphere(subdivisions=1)
    write_mesh(str(tmp_path / "s.ply"), V, F)
    write_mesh(os.fsencode(tmp_path / "b.ply"), V, F)
    assert (tmp_path / "b.ply").read_bytes() == (tmp_path / "s.ply").read_bytes()
    assert b"quality" not in (tmp_path / "b.ply").read_bytes()[:400]


def test_a_failed_write_to_a_bytes_path_names_the_path(tmp_path, monkeypatch):
    # the message replaced the temporary path by the bytes path: TypeError from str.replace
    import curvdetail.io as io

    def failing(ms, path, options, optional):
        raise RuntimeError(f"Error encountered while exporting file {path}: disk full")

    monkeypatch.setattr(io, "_save", failing)
    mesh = pymeshlab.Mesh(vertex_matrix=np.eye(3), face_matrix=np.array([[0, 1, 2]], dtype=np.int32))
    with pytest.raises(MeshFileError, match=r"could not write '.*m\.off': Error encountered while exporting file "
                                            r".*m\.off: disk full"):
        save_mesh(os.fsencode(tmp_path / "m.off"), mesh)
    assert os.listdir(tmp_path) == []


def test_a_path_that_is_not_utf8_is_refused_with_the_fix(tmp_path):
    # pymeshlab takes UTF-8 paths only: a Latin-1 folder name raised TypeError from str.replace
    # (write_mesh) or from pymeshlab's argument conversion
    folder = os.path.join(os.fsencode(tmp_path), b"lat\xe9")
    os.mkdir(folder)
    V, F = icosphere(subdivisions=1)
    mesh = pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32))
    for write in (lambda p: write_mesh(p, V, F), lambda p: save_mesh(p, mesh)):
        for path in (os.path.join(folder, b"a.ply"), os.fsdecode(os.path.join(folder, b"a.ply")),
                     os.path.join(os.fsencode(tmp_path), b"caf\xe9.off")):
            with pytest.raises(MeshFileError, match=r"its path holds bytes that are not UTF-8 \(b'\\xe9' in .*\), and "
                                                    r"pymeshlab takes paths as UTF-8 text only; rename"):
                write(path)
    assert os.listdir(folder) == [] and os.listdir(tmp_path) == ["lat\udce9"]
    write_mesh(tmp_path / "caf\u00e9.off", V, F)                    # UTF-8 names are written
    assert np.allclose(read_mesh(tmp_path / "caf\u00e9.off")[0], V)


def test_a_file_in_a_folder_that_is_not_utf8_is_refused_by_its_path_not_called_damaged(tmp_path):
    # the read went to pymeshlab and came back as "The file is damaged or incomplete, ...; export
    # it again", for a sound file whose folder name holds a Latin-1 byte
    folder = os.path.join(os.fsencode(tmp_path), b"lat\xe9")
    os.mkdir(folder)
    V, F = icosphere(subdivisions=1)
    write_mesh(tmp_path / "a.obj", V, F)
    os.rename(tmp_path / "a.obj", os.path.join(folder, b"a.obj"))
    for path in (os.path.join(folder, b"a.obj"), os.fsdecode(os.path.join(folder, b"a.obj"))):
        with pytest.raises(MeshFileError, match=r"cannot read .*: its path holds bytes that are not UTF-8 "
                                                r"\(b'\\xe9' in .*\), .* rename the file or folder \(or copy the "
                                                r"file elsewhere and read it there\)"):
            read_mesh(path)
    os.rename(os.path.join(folder, b"a.obj"), tmp_path / "a.obj")
    assert np.allclose(read_mesh(tmp_path / "a.obj")[0], V)             # the same file, read


def test_dxf_coordinates_are_checked_for_its_six_decimals(tmp_path):
    # DXF went unchecked: three vertices 1e-7 apart were all written as 0.123457
    V = np.array([[0.1234567, 0, 0], [0.1234568, 0, 0], [0.1234567, 1e-7, 0]])
    with pytest.raises(MeshFileError, match=r"writes DXF coordinates with 6 decimals \(an error up to 5e-07\)"):
        write_mesh(tmp_path / "tiny.dxf", V, np.array([[0, 1, 2]]))
    assert os.listdir(tmp_path) == []
    # pymeshlab reads no .dxf: the written text is the measure ("%f" of the double; 16777217 is no float32)
    V = np.array([[0.1234567, 0, 0], [16777217.0, 2.5, 0], [3.0, 0.0000014, -7.25]])
    write_mesh(tmp_path / "big.dxf", V, np.array([[0, 1, 2]]))
    tokens = (tmp_path / "big.dxf").read_text().split("3DFACE")[1].split()
    corners = {code: float(value) for code, value in zip(tokens[2::2], tokens[3::2]) if code[0] in "123"}
    written = np.array([[corners[f"{axis}{k}"] for axis in "123"] for k in range(3)])
    assert np.array_equal(written, np.round(V, 6))


def test_every_format_write_mesh_takes_has_a_measured_precision(tmp_path):
    # a format missing from the table (.dxf was) was written unchecked
    import curvdetail.io as io
    from curvdetail.io.mesh import check_coordinates

    V, F = icosphere(subdivisions=1)
    for ext in _SAVE_FORMATS:
        if ext in io.POINT_FORMATS or ext in io.UNWRITTEN_FORMATS:
            continue
        assert io.check_mesh_output(str(tmp_path / f"m{ext}")).endswith(ext)       # written by write_mesh
        assert ext in io._COORDINATES, ext
        check_coordinates(f"m{ext}", V * 10.0)
    assert os.listdir(tmp_path) == []


def test_a_format_with_no_measured_precision_is_refused(tmp_path, monkeypatch):
    import curvdetail.io as io

    monkeypatch.setitem(io._WRITES, ".new", None)                    # as if pymeshlab wrote it
    V, F = icosphere(subdivisions=1)
    with pytest.raises(MeshFileError, match=r"how precisely pymeshlab writes \.new coordinates is not known here"):
        write_mesh(tmp_path / "m.new", V, F)
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("name, text", [
    # a dropped triangle beside a polygon: the file's face count (2) no longer tells it
    ("quad_repeated.off", "OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n4 0 1 2 3\n3 1 4 4\n"),
    ("quad_repeated.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nf 1 2 3 4\nf 2 5 5\n"),
    # a quad whose texture indices name 2 vt lines of 2: pymeshlab kept one of its 2 triangles
    ("quad_vt.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nf 1/1 2/2 3/3 4/4\n"),
])
def test_triangles_dropped_beside_polygons_are_reported(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(MeshFileError, match=r"its faces make \d+ triangles \(a polygon of k vertices k - 2\), but "
                                           r"pymeshlab loaded \d+: its (OBJ|OFF) loader drops"):
        read_mesh(path)


def test_polygons_with_all_their_triangles_are_read(tmp_path):
    path = tmp_path / "poly.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nf 1 2 3 4\nf 2 5 3\n")
    V, F = read_mesh(path)
    assert F.shape == (3, 3) and V.shape == (5, 3)


# A concave quad (a dart: the corner (1, 0.5) is dented in), counter-clockwise seen from +z.
_DART = [(0, 0, 0), (1, 0.5, 0), (2, 0, 0), (1, 2, 0)]


def _polygon_file(path, corners, face):
    n = len(corners)
    rows = "".join(f"{x} {y} {z}\n" for x, y, z in corners)
    if path.suffix == ".obj":
        text = "".join(f"v {row}" for row in rows.splitlines(True)) + "f " + " ".join(str(i + 1) for i in face) + "\n"
    elif path.suffix == ".off":
        text = f"OFF\n{n} 1 0\n{rows}{len(face)} " + " ".join(map(str, face)) + "\n"
    else:
        text = (f"ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\n"
                "element face 1\nproperty list uchar int vertex_indices\nend_header\n" + rows
                + f"{len(face)} " + " ".join(map(str, face)) + "\n")
    path.write_text(text)


@pytest.mark.parametrize("suffix, corners, start", [
    # pymeshlab fans OBJ quads and PLY polygons from their first corner: the dart 1 2 3 4 came
    # back as the triangles 1 2 3 (facing -z, outside the dart) and 1 3 4 (covering the dent)
    (".obj", _DART, 0), (".obj", _DART, 2), (".ply", _DART, 0), (".ply", _DART, 2),
    # it cuts OFF quads along the shorter diagonal: here 1 3, outside the taller dart
    (".off", [(0, 0, 0), (1, 0.5, 0), (2, 0, 0), (1, 4, 0)], 0),
    (".ply", [(0, 0, 0), (2, 0, 0), (2, 1, 0), (1, 1, 0), (1, 2, 0), (0, 2, 0)], 2),   # an L from a far corner
])
def test_concave_polygons_cut_wrong_by_the_loader_are_refused(tmp_path, suffix, corners, start):
    from curvdetail.io.mesh import MeshFileError, read_mesh
    path = tmp_path / ("m" + suffix)
    n = len(corners)
    _polygon_file(path, corners, [(start + i) % n for i in range(n)])
    with pytest.raises(MeshFileError, match=rf"1 polygon face \(first: face 0 .* of {n} vertices\) came out of "
                                            r"pymeshlab's loader as triangles that overlap or leave the polygon"
                                            r".*triangulate the file's polygons"):
        read_mesh(path)


def test_concave_obj_polygon_refusal_names_its_line(tmp_path):
    # the face's line counts the file's lines: comments, blank and continued ones too
    from curvdetail.io.mesh import MeshFileError, read_mesh
    path = tmp_path / "m.obj"
    path.write_text("# a dart\n" + "".join(f"v {x} {y} {z}\n" for x, y, z in _DART) + "v 1 3 0\n\n"
                    "f 5 \\\n3 4\n# the dart, fanned across its dent\nf 1 2 3 4\n")
    with pytest.raises(MeshFileError, match=r"1 polygon face \(first: face 1 counting from 0 in the file's order, "
                                            r"on line 11, of 4 vertices\)"):
        read_mesh(path)


@pytest.mark.parametrize("suffix", [".obj", ".off", ".ply"])
@pytest.mark.parametrize("corners, start", [
    (_DART, 1),                                                   # fanned from the dent: right
    ([(0, 0, 0), (2, 0, 0), (2, 1, 0), (1, 1, 0), (1, 2, 0), (0, 2, 0)], 0),     # an L, its fan right
    ([(0, 0, 0), (1, 0, 0), (1.5, 1, 0), (1, 2, 0), (0, 2, 0)], 2),              # convex, from any corner
    ([(0, 0, 0), (0, 1, 0), (0, 1, 1), (0, 0, 1)], 3),                            # convex, in the y-z plane
])
def test_polygons_the_loader_triangulates_right_pass_with_their_area(tmp_path, suffix, corners, start):
    from curvdetail.io.mesh import read_mesh
    path = tmp_path / ("m" + suffix)
    n = len(corners)
    _polygon_file(path, corners, [(start + i) % n for i in range(n)])
    V, F = read_mesh(path)
    P = np.asarray(corners, dtype=float)
    ring = P[[(start + i) % n for i in range(n)]]
    polygon = np.cross(ring, np.roll(ring, -1, axis=0)).sum(axis=0) / 2        # Newell's vector area
    areas = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]) / 2
    assert F.shape == (n - 2, 3)
    # the triangles tile the polygon: each faces with it and their areas add up to its area
    assert np.all(areas @ polygon > 0)
    assert np.isclose(np.linalg.norm(areas, axis=1).sum(), np.linalg.norm(polygon))


def test_ascii_stl_with_vertex_in_its_name_is_read(tmp_path):
    # "vertex " in the solid line was counted as a corner, and the file refused as a facet of 4
    from curvdetail.io.mesh import read_mesh
    path = tmp_path / "m.stl"
    path.write_text("solid my vertex model\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n"
                    "   vertex 0 1 0\n  endloop\n endfacet\nendsolid my vertex model\n")
    V, F = read_mesh(path)
    assert V.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0]] and F.tolist() == [[0, 1, 2]]


@pytest.mark.parametrize("quad, triangles", [
    ([1, 2, 3, 0], [[4, 2, 3], [1, 2, 3], [1, 3, 0], [4, 3, 0]]),            # fanned from the dent: right
    ([0, 1, 2, 3], None),                                                  # fanned across the dent
])
def test_binary_ply_of_triangles_and_quads_is_read_in_order_and_checked(tmp_path, quad, triangles):
    # rows of 3 and 4 indices mixed; pymeshlab reads them right, and fans the quad
    from curvdetail.io.mesh import MeshFileError, read_mesh
    corners = np.array(_DART + [(1, 3, 0)], dtype="<f4")
    faces = [[4, 2, 3], quad, [4, 3, 0]]
    rows = b"".join(np.array([len(f)], "u1").tobytes() + np.array(f, "<i4").tobytes() for f in faces)
    path = tmp_path / "m.ply"
    path.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
                     b"property float z\nelement face 3\nproperty list uchar int vertex_indices\nend_header\n"
                     + corners.tobytes() + rows)
    if triangles is None:
        with pytest.raises(MeshFileError, match=r"1 polygon face \(first: face 1 .* of 4 vertices\) came out"):
            read_mesh(path)
    else:
        V, F = read_mesh(path)
        assert V.tolist() == corners.tolist() and F.tolist() == triangles


@pytest.mark.parametrize("suffix", [".obj", ".off", ".ply", ".stl", ".ctm"])
def test_an_empty_file_is_named_as_empty(tmp_path, suffix):
    # pymeshlab's failure read as "damaged or incomplete, or a variant pymeshlab does not read";
    # an empty file is more plainly one whose writer did not finish
    path = tmp_path / f"empty{suffix}"
    path.write_bytes(b"")
    with pytest.raises(MeshFileError, match=r"empty\.\w+' is empty \(0 bytes\): there is no mesh in it; check "
                                            r"that the program that wrote it finished, and write it again\.$"):
        read_mesh(path)
