"""MeshSet adapters: exact in-place writes of attributes, quality and positions; new layers."""

import os

import numpy as np
import pymeshlab
import pytest

from curvdetail.curvature.errors import MeshError
from curvdetail.curvature.testing import grid, icosphere
from curvdetail.filters import FilterError
from curvdetail.filters.meshset import (add_layer, layer_id, mesh_arrays, set_vertex_attribute,
                                        set_vertex_positions, set_vertex_quality, vertex_attribute,
                                        vertex_normals)

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


@pytest.fixture
def ms():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "mannequin_nose.obj"))
    return ms


def test_point_attribute_is_created_then_overwritten_exactly(ms, rng):
    first, second = rng.normal(size=(640, 3)), rng.normal(size=(640, 3)) * 1e-7
    set_vertex_attribute(ms, 0, "curvature_detail", first)
    set_vertex_attribute(ms, 0, "curvature_detail", second)
    assert np.array_equal(vertex_attribute(ms, 0, "curvature_detail", "point"), second)


def test_scalar_attribute_is_overwritten_exactly(ms, rng):
    set_vertex_attribute(ms, 0, "curvature_area", np.ones(640))
    values = rng.random(640) * np.pi
    set_vertex_attribute(ms, 0, "curvature_area", values)
    assert np.array_equal(vertex_attribute(ms, 0, "curvature_area", "scalar"), values)


def test_positions_are_set_exactly_in_place(ms, rng):
    X = rng.normal(size=(640, 3))
    F = ms.current_mesh().face_matrix().copy()
    set_vertex_positions(ms, 0, X)
    assert np.array_equal(ms.current_mesh().vertex_matrix(), X)
    assert np.array_equal(ms.current_mesh().face_matrix(), F) and ms.mesh_number() == 1


def test_quality_is_set_exactly(ms, rng):
    q = rng.normal(size=640)
    set_vertex_quality(ms, 0, q)
    assert np.array_equal(ms.current_mesh().vertex_scalar_array(), q)


def test_write_on_another_layer_keeps_the_current_one(ms, rng):
    ms.load_new_mesh(os.path.join(DATA, "terrainA_1k.obj"))
    terrain = ms.mesh(1)
    V1, F1, q1 = terrain.vertex_matrix().copy(), terrain.face_matrix().copy(), terrain.vertex_scalar_array().copy()
    V0 = ms.mesh(0).vertex_matrix().copy()
    q = rng.normal(size=640)
    set_vertex_quality(ms, 0, q)
    assert ms.current_mesh_id() == 1
    # layer 0 got the values (and kept its positions), layer 1 is as loaded
    assert np.array_equal(ms.mesh(0).vertex_scalar_array(), q)
    assert np.array_equal(ms.mesh(0).vertex_matrix(), V0)
    assert ms.current_mesh().vertex_number() == 1089
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V1)
    assert np.array_equal(ms.current_mesh().face_matrix(), F1)
    assert np.array_equal(ms.current_mesh().vertex_scalar_array(), q1)


def test_wrong_shape_and_nan_are_refused(ms):
    with pytest.raises(MeshError, match=r"\(640, 3\)") as e:
        set_vertex_positions(ms, 0, np.zeros((639, 3)))
    assert e.value.value == (639, 3)
    with pytest.raises(MeshError) as e:
        set_vertex_quality(ms, 0, np.full(640, np.nan))
    assert (e.value.count, e.value.first) == (640, [0, 1, 2])


def test_new_layer_becomes_current_with_quality_and_attributes(ms):
    V, F = mesh_arrays(ms, 0)
    mid = add_layer(ms, V * 2.0, F, "double", quality=np.arange(640.0),
                    attributes={"curvature_area": np.ones(640)})
    assert mid == ms.current_mesh_id() == 1 and ms.current_mesh().label() == "double"
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V * 2.0)
    assert np.array_equal(vertex_attribute(ms, 1, "curvature_area", "scalar"), np.ones(640))


def test_missing_layer_lists_the_existing_ones(ms):
    with pytest.raises(FilterError, match=r"layers 0\.") as e:                   # the ids there
        layer_id(ms, 4, role="sourcemesh")
    assert (e.value.parameter, e.value.value) == ("sourcemesh", 4)



def test_vertex_normals_point_outwards_on_a_sphere():
    V, F = icosphere(radius=2.0, subdivisions=3)
    N = vertex_normals(V, F)
    assert np.allclose(np.linalg.norm(N, axis=1), 1.0)
    assert np.einsum("ij,ij->i", N, V / 2.0).min() > 0.999


def test_a_quality_colours_the_layer_with_viridis_over_its_range_and_a_ply_keeps_it(tmp_path):
    # MeshLab shows vertex colours on open: a distance from viridis' first colour at 0 to its last
    # at the max; a signed quality symmetric about 0 (the middle colour)
    from curvdetail.filters.files import load_meshset, save_current_mesh
    from curvdetail.filters.meshset import set_vertex_quality
    from curvdetail.plot import vertex_colours

    V, F = grid(5, 5)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32)))
    q = np.linspace(0.0, 2.0, V.shape[0])
    assert set_vertex_quality(ms, 0, q) == (0.0, 2.0)
    save_current_mesh(ms, tmp_path / "q.ply")
    back = load_meshset(tmp_path / "q.ply")                  # kept alive while its mesh is read
    rgb = np.rint(back.current_mesh().vertex_color_matrix()[:, :3] * 255)
    expected = vertex_colours(q, 2.0)[:, :3]
    assert np.abs(rgb[[0, -1]] - expected[[0, -1]]).max() <= 1        # viridis' ends at 0 and at the max
    assert np.abs(rgb - expected).max() <= 20          # pymeshlab's viridis: a coarser table (19/255 measured)
    assert set_vertex_quality(ms, 0, q - 0.5) == (-1.5, 1.5)
