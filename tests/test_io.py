"""read_mesh / write_mesh: exact round trips, the file's own counts, refusals that name the file."""

import errno
import os
import re

import numpy as np
import plyfile
import pymeshlab
import pytest

import curvdetail.io.mesh as mesh_io
from curvdetail import MeshError, read_mesh, write_mesh
from curvdetail.io import MeshFileError


@pytest.fixture
def nose(load_mesh, rng):
    V, F = load_mesh("mannequin_nose.obj")
    V = V + rng.normal(scale=1e-3, size=V.shape)             # full float64 mantissas
    V[:3] = [[1 / 3, -0.0, 1e-300], [2.0 ** 60 + 0.5, 0.1, -7e-17], [np.pi, np.e, 1e15 + 0.3]]
    return V, F


@pytest.mark.parametrize("ext", ["ply", "obj", "off"])
def test_round_trip_is_bit_exact(tmp_path, nose, ext):
    # PLY holds the doubles themselves, OBJ and OFF "%.17g", which reads back as the same double
    V, F = nose
    write_mesh(tmp_path / f"m.{ext}", V, F)
    W, G = read_mesh(tmp_path / f"m.{ext}")
    assert W.dtype == np.float64 and G.dtype == np.int64
    assert np.array_equal(W.view(np.int64), V.view(np.int64)) and np.array_equal(G, F)


def test_ply_quality_is_a_plain_double_property(tmp_path, nose):
    V, F = nose
    q = np.linspace(-1.0, 1.0, len(V)) / 3
    write_mesh(tmp_path / "q.ply", V, F, quality=q)
    ply = plyfile.PlyData.read(str(tmp_path / "q.ply"))
    assert ply["vertex"].data.dtype["quality"] == np.float64 and not ply.text
    assert np.array_equal(read_mesh(tmp_path / "q.ply", fields=True)[2]["quality"], q)
    ms = pymeshlab.MeshSet()                      # MeshLab reads it as the vertex quality
    ms.load_new_mesh(str(tmp_path / "q.ply"))
    assert np.array_equal(ms.current_mesh().vertex_scalar_array(), q)


@pytest.mark.parametrize("binary", [True, False])
def test_a_meshlab_ply_reads_as_meshlab_reads_it(tmp_path, nose, binary):
    # MeshLab's PLY: flags, colours, quality beside the doubles; ASCII with "%.16g"
    V, F = nose
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32), v_scalar_array=V[:, 0]))
    ms.save_current_mesh(str(tmp_path / "m.ply"), binary=binary)
    ms.load_new_mesh(str(tmp_path / "m.ply"))
    W, G, fields = read_mesh(tmp_path / "m.ply", fields=True)
    assert np.array_equal(W, ms.current_mesh().vertex_matrix()) and np.array_equal(G, F)
    assert np.array_equal(fields["quality"], ms.current_mesh().vertex_scalar_array())


def test_meshlab_point_attributes_are_read_as_points(tmp_path, nose):
    # pymeshlab exports a custom point attribute as a list of three doubles per vertex
    V, F = nose
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32)))
    ms.current_mesh().add_vertex_custom_point_attribute(V * 2, "detail")
    ms.save_current_mesh(str(tmp_path / "a.ply"), __ca_vp__detail=True)
    W, G, fields = read_mesh(tmp_path / "a.ply", fields=True)
    assert np.array_equal(W, V) and np.array_equal(G, F) and np.array_equal(fields["detail"], V * 2)


def test_stl_goes_through_pymeshlab_in_single_precision(tmp_path, nose):
    V, F = nose
    write_mesh(tmp_path / "m.stl", V, F)
    W, G = read_mesh(tmp_path / "m.stl")
    assert G.shape == F.shape
    assert np.array_equal(W[G], V[F].astype(np.float32).astype(np.float64))


PENTAGON = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 0.5, 0]]      # convex in the order 0 1 4 3 2


def test_polygons_are_fanned_from_their_first_corner(tmp_path):
    (tmp_path / "p.obj").write_text("".join(f"v {x} {y} {z}\n" for x, y, z in PENTAGON) + "f 1 2 5 4 3\n")
    (tmp_path / "p.off").write_text("OFF\n5 1 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in PENTAGON) + "5 0 1 4 3 2\n")
    face = np.empty(1, dtype=[("vertex_indices", "O")])
    face[0] = (np.array([0, 1, 4, 3, 2], dtype=np.int32),)
    vertex = np.array([tuple(p) for p in PENTAGON], dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    plyfile.PlyData([plyfile.PlyElement.describe(vertex, "vertex"),
                     plyfile.PlyElement.describe(face, "face")]).write(str(tmp_path / "p.ply"))
    for ext in ("obj", "ply", "off"):
        V, F = read_mesh(tmp_path / f"p.{ext}")
        assert np.array_equal(V, PENTAGON) and F.tolist() == [[0, 1, 4], [0, 4, 3], [0, 3, 2]]


def _quad_grid(n):
    """An n x n grid of non-planar quads: ``(V, Q)``."""
    j, i = np.divmod(np.arange((n + 1) ** 2), n + 1)
    V = np.column_stack([i, j, 0.1 * ((7 * i + 3 * j) % 5)]).astype(np.float64)
    c = (np.arange(n)[:, None] * (n + 1) + np.arange(n)).ravel()
    return V, np.column_stack([c, c + 1, c + n + 2, c + n + 1])


def test_quads_are_split_the_same_way_by_every_reader(tmp_path):
    # pymeshlab's OFF loader cut them along the other diagonal (the grid remeshed to 400 vertices as
    # OBJ, 256 as OFF)
    V, Q = _quad_grid(4)
    (tmp_path / "g.obj").write_text("".join(f"v {x} {y} {z}\n" for x, y, z in V)
                                    + "".join(f"f {a} {b} {c} {d}\n" for a, b, c, d in Q + 1))
    (tmp_path / "g.off").write_text(f"OFF\n{len(V)} {len(Q)} 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in V)
                                    + "".join(f"4 {a} {b} {c} {d}\n" for a, b, c, d in Q))
    face = np.empty(len(Q), dtype=[("vertex_indices", "O")])
    face["vertex_indices"] = list(Q.astype(np.int32))
    vertex = np.array([tuple(p) for p in V], dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    plyfile.PlyData([plyfile.PlyElement.describe(vertex, "vertex"),
                     plyfile.PlyElement.describe(face, "face")]).write(str(tmp_path / "g.ply"))
    expected = np.column_stack([Q[:, [0, 1, 2]], Q[:, [0, 2, 3]]]).reshape(-1, 3)
    for ext in ("obj", "off", "ply"):
        W, F = read_mesh(tmp_path / f"g.{ext}")
        assert np.array_equal(W, V) and np.array_equal(F, expected), ext
    ms = pymeshlab.MeshSet()                  # a MeshSet layer (what the filters get) is the same
    mesh_io.load_new_mesh(ms, tmp_path / "g.obj")
    mesh_io.load_new_mesh(ms, tmp_path / "g.off")
    assert ms.current_mesh_id() == 1 and np.array_equal(ms.mesh(1).face_matrix(), expected)


def test_off_quads_and_larger_polygons_are_read(tmp_path):
    # pymeshlab's OFF loader cut a pentagon into triangles of vertices 0-4 wherever its corners were
    rows = "".join(f"{x} {y} {z}\n" for x, y, z in PENTAGON)
    (tmp_path / "q.off").write_text(f"OFF\n5 2 0\n{rows}4 0 1 3 2\n3 1 4 3\n")
    (tmp_path / "p.off").write_text(f"OFF\n6 2 0\n5 5 5\n{rows}3 0 1 2\n5 1 2 5 4 3\n")
    V, F = read_mesh(tmp_path / "q.off")
    twice_areas = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])[:, 2]
    assert F.shape == (3, 3) and (twice_areas > 0).all() and twice_areas.sum() == 3.0    # shoelace: 1.5
    assert read_mesh(tmp_path / "p.off")[1].tolist() == [[0, 1, 2], [1, 2, 5], [1, 5, 4], [1, 4, 3]]


def test_off_colours_and_normals_are_read_as_fields(tmp_path):
    (tmp_path / "c.off").write_text("COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n3 0 1 2\n")
    (tmp_path / "n.off").write_text("NOFF\n3 1 0\n0 0 0 0 0 -1\n1 0 0 0 0 -1\n0 1 0 0 0 -1\n3 0 1 2\n")
    (tmp_path / "a.off").write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    colours = read_mesh(tmp_path / "c.off", fields=True)[2]
    assert colours["red"].tolist() == [255, 0, 0] and colours["blue"].tolist() == [0, 0, 255]
    assert read_mesh(tmp_path / "n.off", fields=True)[2]["nz"].tolist() == [-1.0, -1.0, -1.0]
    assert read_mesh(tmp_path / "a.off", fields=True)[2] == {}


@pytest.mark.parametrize("name, text, declared, loaded", [
    ("nan.off", "OFF\n4 1 0\n0 0 0\nnan 0 0\n0 1 0\n1 1 0\n3 0 2 3\n", (4, 1), (3, 1)),
    ("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nv 1 1 0\nf 1 3 4\n", (4, 1), (3, 1)),
    ("far.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 9\n", (4, 2), (4, 1)),
])
def test_what_the_loader_dropped_is_refused_with_both_counts(tmp_path, name, text, declared, loaded):
    # pymeshlab drops a NaN vertex (renumbering the rest) and an OBJ face past the vertices
    (tmp_path / name).write_text(text)
    with pytest.raises(MeshFileError) as e:
        read_mesh(tmp_path / name)
    assert (e.value.declared, e.value.loaded) == (declared, loaded)
    assert e.value.parameter == "path" and e.value.value == str(tmp_path / name)


def test_an_index_out_of_range_is_refused_with_the_face(tmp_path):
    vertex = np.zeros(3, dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    vertex["x"], vertex["y"] = [0, 1, 0], [0, 0, 1]
    face = np.array([([0, 1, 2],), ([0, 2, 1],), ([0, 1, 7],)], dtype=[("vertex_indices", "i4", (3,))])
    path = tmp_path / "far.ply"
    plyfile.PlyData([plyfile.PlyElement.describe(vertex, "vertex"), plyfile.PlyElement.describe(face, "face")],
                    byte_order="<").write(str(path))
    with pytest.raises(MeshFileError) as e:
        read_mesh(path)
    assert e.value.value == str(path) and re.search(r"\bfirst: 2\b", str(e.value))


def _binary_ply(path):
    write_mesh(path.with_suffix(".ply"), [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    os.rename(path.with_suffix(".ply"), path)


@pytest.mark.parametrize("make", [
    lambda p: p.write_bytes(bytes(np.random.default_rng(3).integers(0, 256, 3000, dtype=np.uint8))),
    _binary_ply,
    lambda p: p.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", encoding="utf-16"),
], ids=["random bytes", "binary PLY", "UTF-16"])
def test_a_file_that_is_not_text_is_not_read_as_obj(tmp_path, make):
    # these were blamed on "a classic Mac OS line end" and "0 v lines above the face"
    path = tmp_path / "m.obj"
    make(path)
    with pytest.raises(MeshFileError) as e:
        read_mesh(path)
    assert e.value.value == str(path) and "text OBJ" in str(e.value)


def test_unreadable_files_name_the_file(tmp_path):
    (tmp_path / "bad.ply").write_text("not a ply")
    (tmp_path / "bad.off").write_text("garbage")
    (tmp_path / "bad.ply.ply").write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 9\n"
                                           b"property double x\nproperty double y\nproperty double z\n"
                                           b"end_header\n" + bytes(16))          # 9 vertices declared, 16 bytes
    for name in ("bad.ply", "bad.off", "bad.ply.ply"):
        with pytest.raises(MeshFileError) as e:
            read_mesh(tmp_path / name)
        assert e.value.parameter == "path" and e.value.value == str(tmp_path / name)
        assert str(tmp_path / name) in str(e.value)
    with pytest.raises(FileNotFoundError) as e:
        read_mesh(tmp_path / "none.obj")
    assert e.value.filename == str(tmp_path / "none.obj")
    with pytest.raises(MeshFileError) as e:
        read_mesh(tmp_path)
    assert e.value.value == str(tmp_path)


def test_a_failed_load_leaves_the_working_folder_alone(tmp_path):
    (tmp_path / "bad.off").write_text("garbage")
    before = os.getcwd()
    with pytest.raises(MeshFileError):
        read_mesh(tmp_path / "bad.off")
    assert os.getcwd() == before


def test_an_existing_file_is_kept_unless_overwrite(tmp_path, nose):
    V, F = nose
    path = tmp_path / "m.obj"
    path.write_text("keep me")
    with pytest.raises(FileExistsError):
        write_mesh(path, V, F)
    assert path.read_text() == "keep me"
    write_mesh(path, V, F, overwrite=True)
    assert np.array_equal(read_mesh(path)[0], V)


@pytest.mark.parametrize("ext, writer", [("ply", "write_ply"), ("obj", "_write_text"),
                                         ("stl", "_write_with_pymeshlab")])
def test_a_full_disk_names_the_file_and_leaves_nothing(tmp_path, monkeypatch, nose, ext, writer):
    def full(path, *args):
        with open(path, "wb") as f:
            f.write(b"half a mesh")
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), path)

    monkeypatch.setattr(mesh_io, writer, full)
    path = tmp_path / f"m.{ext}"
    with pytest.raises(MeshFileError) as e:
        write_mesh(path, *nose)
    assert e.value.value == str(path) and str(path) in str(e.value) and os.strerror(errno.ENOSPC) in str(e.value)
    assert isinstance(e.value.__cause__, OSError) and e.value.__cause__.errno == errno.ENOSPC
    assert os.listdir(tmp_path) == []


def test_a_full_disk_is_named_where_pymeshlab_says_only_that_it_failed(tmp_path, monkeypatch, nose):
    import shutil
    import types

    def exporter_error(path, *args):
        raise pymeshlab.PyMeshLabException(f"Error encountered while exportering file {path}: Output Stream error")

    monkeypatch.setattr(mesh_io, "_write_with_pymeshlab", exporter_error)
    monkeypatch.setattr(shutil, "disk_usage", lambda folder: types.SimpleNamespace(total=1 << 20, used=1 << 20, free=0))
    path = tmp_path / "m.stl"
    with pytest.raises(MeshFileError) as e:
        write_mesh(path, *nose)
    assert e.value.value == str(path) and os.strerror(errno.ENOSPC) in str(e.value)
    assert ".curvdetail-" not in str(e.value) and os.listdir(tmp_path) == []


def test_a_format_pymeshlab_does_not_write_names_the_file(tmp_path, nose):
    with pytest.raises(MeshFileError) as e:
        write_mesh(tmp_path / "m.nosuchformat", *nose)
    assert e.value.value == str(tmp_path / "m.nosuchformat") and os.listdir(tmp_path) == []


def test_bad_arrays_are_refused_before_writing(tmp_path, nose):
    V, F = nose
    with pytest.raises(MeshError) as e:
        write_mesh(tmp_path / "m.ply", V, F, quality=np.ones(3))
    assert e.value.parameter == "quality"
    with pytest.raises(MeshError):
        write_mesh(tmp_path / "m.ply", V, F + len(V))
    assert os.listdir(tmp_path) == []


def test_an_output_without_extension_is_refused_before_writing(tmp_path, nose):
    with pytest.raises(MeshFileError) as e:
        write_mesh(tmp_path / "m", *nose)
    assert e.value.parameter == "path" and e.value.value == str(tmp_path / "m") and os.listdir(tmp_path) == []
