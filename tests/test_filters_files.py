"""Loading into a MeshSet and saving the current mesh: PLY keeps what the filters stored, exactly."""

import errno
import os

import numpy as np
import plyfile
import pymeshlab
import pytest

import curvdetail.io.mesh as mesh_io
from curvdetail.filters import apply
from curvdetail.filters.files import attributes_lost_in, load_meshset, save_current_mesh, vertex_colours_kept_in
from curvdetail.filters.meshset import vertex_attribute
from curvdetail.io import MeshFileError, read_mesh

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")
NOSE = os.path.join(DATA, "mannequin_nose.obj")
ATTRIBUTES = (("curvature_normal", "point"), ("curvature_detail", "point"), ("curvature_area", "scalar"))


def test_ply_round_trip_keeps_positions_quality_and_attributes_exactly(tmp_path):
    ms = load_meshset(NOSE)
    apply(ms, "compute_curvature_detail")
    save_current_mesh(ms, tmp_path / "d.ply")
    back = load_meshset(tmp_path / "d.ply")
    assert np.array_equal(back.current_mesh().vertex_matrix(), ms.current_mesh().vertex_matrix())
    assert np.array_equal(back.current_mesh().face_matrix(), ms.current_mesh().face_matrix())
    assert np.array_equal(back.current_mesh().vertex_scalar_array(), ms.current_mesh().vertex_scalar_array())
    for name, kind in ATTRIBUTES:
        assert np.array_equal(vertex_attribute(back, 0, name, kind), vertex_attribute(ms, 0, name, kind))
    header = (tmp_path / "d.ply").read_bytes().split(b"end_header")[0]
    assert b"scratch" not in header            # the adapters' scratch attributes are not saved


def test_a_vertex_selection_is_kept_in_ply_and_serves_the_next_step(tmp_path):
    # the selection (MeshLab keeps it in the vertex flags) is what a later reconstruction keeps fixed
    ms = load_meshset(NOSE)
    V = ms.current_mesh().vertex_matrix()
    ms.compute_selection_by_condition_per_vertex(condselect="(x < 0)")
    selected = ms.current_mesh().vertex_selection_array().copy()
    assert 0 < selected.sum() < selected.size
    apply(ms, "compute_curvature_detail")
    save_current_mesh(ms, tmp_path / "d.ply")
    back = load_meshset(tmp_path / "d.ply")
    assert np.array_equal(back.current_mesh().vertex_selection_array(), selected)
    apply(back, "apply_curvature_reconstruction", fix_boundary=False)
    X = back.current_mesh().vertex_matrix()
    assert np.array_equal(X[selected], V[selected])
    assert np.abs(X - V).max() < 1e-9 * np.linalg.norm(np.ptp(V, axis=0))
    # MeshLab reads the flags as the selection too
    meshlab = pymeshlab.MeshSet()
    meshlab.load_new_mesh(str(tmp_path / "d.ply"))
    assert np.array_equal(meshlab.current_mesh().vertex_selection_array(), selected)


def test_a_layers_colours_are_kept_in_ply(tmp_path):
    V = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5]]
    (tmp_path / "c.off").write_text("COFF\n4 2 0\n" + "".join(f"{x} {y} {z} {10 * k} 20 30 255\n"
                                                              for k, (x, y, z) in enumerate(V))
                                    + "3 0 1 2\n3 1 3 2\n")
    ms = load_meshset(tmp_path / "c.off")
    assert vertex_colours_kept_in(ms, "c.ply") and not vertex_colours_kept_in(ms, "c.obj")
    save_current_mesh(ms, tmp_path / "c.ply")
    back = load_meshset(tmp_path / "c.ply")
    assert np.array_equal(np.rint(back.current_mesh().vertex_color_matrix() * 255),
                          [[10 * k, 20, 30, 255] for k in range(4)])
    plain = load_meshset(NOSE)                  # pymeshlab's white is not written
    save_current_mesh(plain, tmp_path / "p.ply")
    assert "red" not in plyfile.PlyData.read(str(tmp_path / "p.ply"))["vertex"].data.dtype.names


def test_a_layer_without_quality_comes_back_without(tmp_path):
    # a quality read as zeros would pass for a measured distance (a layer built from arrays has one)
    ms = load_meshset(NOSE)
    assert not ms.current_mesh().has_vertex_scalar()
    save_current_mesh(ms, tmp_path / "p.ply")
    assert "quality" not in plyfile.PlyData.read(str(tmp_path / "p.ply"))["vertex"].data.dtype.names
    assert not load_meshset(tmp_path / "p.ply").current_mesh().has_vertex_scalar()


def test_other_formats_hold_the_geometry_exactly(tmp_path):
    ms = load_meshset(NOSE)
    apply(ms, "compute_curvature_detail")
    lost = attributes_lost_in(ms, "d.obj")
    assert lost == sorted(lost) and {name for name, _ in ATTRIBUTES} <= set(lost)
    assert attributes_lost_in(ms, "d.ply") == []
    for ext in ("obj", "off"):
        save_current_mesh(ms, tmp_path / f"d.{ext}")
        V, F = read_mesh(tmp_path / f"d.{ext}")
        assert np.array_equal(V, ms.current_mesh().vertex_matrix())
        assert np.array_equal(F, ms.current_mesh().face_matrix())


def test_meshlab_exports_of_custom_attributes_are_read(tmp_path):
    # what pymeshlab (and so earlier curvdetail saves) writes: lists of three doubles, a double
    ms = load_meshset(NOSE)
    D = ms.current_mesh().vertex_matrix() * 1e-3
    ms.current_mesh().add_vertex_custom_point_attribute(D, "curvature_detail")
    ms.current_mesh().add_vertex_custom_scalar_attribute(D[:, 0], "curvature_area")
    ms.save_current_mesh(str(tmp_path / "old.ply"), __ca_vp__curvature_detail=True, __ca_vs__curvature_area=True)
    back = load_meshset(tmp_path / "old.ply")
    assert np.array_equal(vertex_attribute(back, 0, "curvature_detail", "point"), D)
    assert np.array_equal(vertex_attribute(back, 0, "curvature_area", "scalar"), D[:, 0])


def test_layers_come_in_order_the_last_current_with_their_source(tmp_path):
    from curvdetail.filters.files import loaded_from

    ms = load_meshset(NOSE, os.path.join(DATA, "spot.obj"))
    assert ms.mesh_number() == 2 and ms.current_mesh_id() == 1
    assert loaded_from(ms, 0) == NOSE and loaded_from(ms, 1) == os.path.join(DATA, "spot.obj")


def test_an_existing_output_is_kept_unless_overwrite(tmp_path):
    out = tmp_path / "d.ply"
    out.write_text("keep me")
    ms = load_meshset(NOSE)
    with pytest.raises(FileExistsError):
        save_current_mesh(ms, out)
    assert out.read_text() == "keep me"
    save_current_mesh(ms, out, overwrite=True)
    assert np.array_equal(read_mesh(out)[0], ms.current_mesh().vertex_matrix())


def test_a_full_disk_names_the_file_and_leaves_nothing(tmp_path, monkeypatch):
    def full(path, *args):
        with open(path, "wb") as f:
            f.write(b"half a mesh")
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), path)

    monkeypatch.setattr(mesh_io, "write_ply", full)
    ms = load_meshset(NOSE)
    with pytest.raises(MeshFileError) as e:
        save_current_mesh(ms, tmp_path / "d.ply")
    assert e.value.value == str(tmp_path / "d.ply") and str(tmp_path / "d.ply") in str(e.value)
    assert os.listdir(tmp_path) == []


def test_inputs_that_cannot_be_read_are_named(tmp_path):
    with pytest.raises(FileNotFoundError) as e:
        load_meshset(NOSE, tmp_path / "none.obj")
    assert e.value.filename == str(tmp_path / "none.obj")
    (tmp_path / "bad.ply").write_text("not a ply")
    (tmp_path / "nan.obj").write_text("v 0 0 0\nv nan 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 3 4\nf 3 5 4\n")
    for name in ("bad.ply", "nan.obj"):
        with pytest.raises(MeshFileError) as e:
            load_meshset(tmp_path / name)
        assert e.value.value == str(tmp_path / name)
    assert e.value.declared == (5, 2) and e.value.loaded == (4, 2)


def test_a_ply_loaded_by_pymeshlab_itself_lacks_the_attributes_and_the_error_says_how_to_keep_them(tmp_path):
    # pymeshlab's load_new_mesh reads no custom attribute: the next filter's error points to
    # load_meshset, and that load serves it
    from curvdetail.filters import FilterError

    ms = load_meshset(NOSE)
    apply(ms, "compute_curvature_detail")
    save_current_mesh(ms, tmp_path / "d.ply")
    own = pymeshlab.MeshSet()
    own.load_new_mesh(str(tmp_path / "d.ply"))
    with pytest.raises(FilterError) as e:
        apply(own, "apply_curvature_reconstruction")
    assert e.value.value == "curvature_detail"
    assert "curvdetail.filters.files.load_meshset" in e.value.hint
    assert "curvdetail.filters.files.save_current_mesh" in e.value.hint
    back = load_meshset(tmp_path / "d.ply")
    apply(back, "apply_curvature_reconstruction")
    V = ms.current_mesh().vertex_matrix()
    assert np.abs(back.current_mesh().vertex_matrix() - V).max() < 1e-9 * np.linalg.norm(np.ptp(V, axis=0))
