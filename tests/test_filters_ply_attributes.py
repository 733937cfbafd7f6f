"""Reading pymeshlab's custom vertex attributes back from PLY (binary and ASCII)."""

import os

import numpy as np
import pymeshlab
import pytest

from curvdetail import curvature_detail, mixed_voronoi_area, read_mesh
from curvdetail.filters.ply_attributes import read_ply_vertex_attributes

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


def saved(tmp_path, binary):
    V, F = read_mesh(os.path.join(DATA, "terrainA_1k.obj"))
    D, A = curvature_detail(V, F), mixed_voronoi_area(V, F)
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "terrainA_1k.obj"))
    ms.current_mesh().add_vertex_custom_point_attribute(D, "curvature_detail")
    ms.current_mesh().add_vertex_custom_scalar_attribute(A, "curvature_area")
    path = tmp_path / f"t{int(binary)}.ply"
    ms.save_current_mesh(str(path), binary=binary, save_vertex_quality=False,
                         __ca_vp__curvature_detail=True, __ca_vs__curvature_area=True)
    return read_ply_vertex_attributes(path), D, A


def test_binary_ply_attributes_are_read_exactly(tmp_path):
    attributes, D, A = saved(tmp_path, binary=True)
    assert np.array_equal(attributes["curvature_detail"], D)
    assert np.array_equal(attributes["curvature_area"], A)


def test_ascii_ply_attributes_are_read_to_six_digits(tmp_path):
    # pymeshlab writes ASCII attributes with 6 decimals ('%f'): absolute error <= 5e-7
    attributes, D, A = saved(tmp_path, binary=False)
    assert np.abs(attributes["curvature_detail"] - D).max() <= 5e-7 + 1e-12
    assert np.abs(attributes["curvature_area"] - A).max() <= 5e-7 + 1e-12


def test_files_without_custom_attributes_give_nothing(tmp_path):
    assert read_ply_vertex_attributes(os.path.join(DATA, "spot.obj")) == {}
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "spot.obj"))
    ms.save_current_mesh(str(tmp_path / "s.ply"))
    assert read_ply_vertex_attributes(tmp_path / "s.ply") == {}


_ASCII_HEAD = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty double mass\n"
               "property float y\nproperty list uchar double dir\nproperty float z\n"
               "element face 1\nproperty list uchar int vertex_indices\nend_header\n")


def test_ascii_columns_are_mapped_by_the_header_order(tmp_path):
    path = tmp_path / "a.ply"
    path.write_text(_ASCII_HEAD + "0 1.5 0 3 1 2 3 0\n1 2.5 0 3 4 5 6 0\n0 -3e2 1 3 7 8 9.5 0\n3 0 1 2\n")
    attributes = read_ply_vertex_attributes(path)
    assert np.array_equal(attributes["mass"], [1.5, 2.5, -300.0])
    assert np.array_equal(attributes["dir"], [[1, 2, 3], [4, 5, 6], [7, 8, 9.5]])


@pytest.mark.parametrize("body", [
    "0 1.5 0 3 1 2 3 0\n1 2.5 0 2 4 5 0 0\n0 3 1 3 7 8 9 0\n",     # list lengths vary
    "0 1.5 0 3 1 2 3 0\n1 2.5 0 3 4 5 6\n0 3 1 3 7 8 9 0\n",        # a value missing
    "0 1.5 0 3 1 2 3 0\n",                                          # vertices missing
    "0 x 0 3 1 2 3 0\n1 2.5 0 3 4 5 6 0\n0 3 1 3 7 8 9 0\n",        # not a number
])
def test_ascii_attributes_that_are_not_pymeshlab_s_give_nothing(tmp_path, body):
    path = tmp_path / "a.ply"
    path.write_text(_ASCII_HEAD + body)
    assert read_ply_vertex_attributes(path) == {}


@pytest.mark.parametrize("body", [
    "0 1.5 0 3 1 2 3 0\n\n1 2.5 0 3 4 5 6 0\n0 3 1 3 7 8 9 0\n",    # a blank line among them
    "0 1.5 0 3 1 2 3 0 # note\n1 2.5 0 3 4 5 6 0\n0 3 1 3 7 8 9 0\n",  # PLY has no comments here
])
def test_ascii_vertex_blocks_with_blank_lines_or_hashes_give_nothing(tmp_path, body):
    path = tmp_path / "a.ply"
    path.write_text(_ASCII_HEAD + body)
    assert read_ply_vertex_attributes(path) == {}


def test_element_counts_written_as_whole_decimals_are_read_as_read_mesh_reads_them(tmp_path):
    # "element vertex 3.0": read_mesh read it (as pymeshlab does), load_meshset failed in int()
    from curvdetail.filters.files import load_meshset
    path = tmp_path / "m.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 3.0\nproperty float x\nproperty float y\n"
                    "property float z\nproperty float quality_x\nelement face 1\n"
                    "property list uchar int vertex_indices\nend_header\n0 0 0 5\n1 0 0 6\n0 1 0 7\n3 0 1 2\n")
    assert read_mesh(path)[1].tolist() == [[0, 1, 2]]
    assert load_meshset(path).current_mesh().face_matrix().tolist() == [[0, 1, 2]]
    np.testing.assert_array_equal(read_ply_vertex_attributes(path)["quality_x"], [5, 6, 7])
