"""Disk-topology checks and the boundary polyline (curvdetail.remesh._disk)."""

import numpy as np
import pytest

from curvdetail.curvature.errors import MeshError
from curvdetail.curvature.testing import disk, grid, icosphere
from curvdetail.remesh import NotADiskError
from curvdetail.remesh._disk import Polyline, check_disk


def test_flat_disk_is_accepted_with_its_boundary_loop_in_face_order(flat_disk):
    V, F = flat_disk
    _, _, loop = check_disk(V, F)
    # the outer ring of 20 rings has 6 * 20 vertices, all at radius 1, walked counter-clockwise
    # (normals +z: the mesh lies to the left)
    assert loop.size == 120
    assert np.allclose(np.linalg.norm(V[loop, :2], axis=1), 1.0)
    angle = np.unwrap(np.arctan2(V[loop, 1], V[loop, 0]))
    assert np.all(np.diff(angle) > 0)


def test_closed_mesh_is_refused_saying_it_is_closed():
    with pytest.raises(NotADiskError) as e:
        check_disk(*icosphere(subdivisions=1))
    assert (e.value.parameter, e.value.count) == ("F", 0)            # boundary loops


def test_open_cylinder_is_refused_with_its_two_boundary_loops(open_cylinder):
    with pytest.raises(NotADiskError) as e:
        check_disk(*open_cylinder)
    assert (e.value.parameter, e.value.count) == ("F", 2)


def test_two_pieces_are_refused_with_the_count():
    V, F = disk(n_rings=3)
    V2 = np.vstack([V, V + [3.0, 0.0, 0.0]])
    F2 = np.vstack([F, F + V.shape[0]])
    with pytest.raises(NotADiskError) as e:
        check_disk(V2, F2)
    assert (e.value.parameter, e.value.count) == ("F", 2)


def test_non_manifold_edge_is_refused_as_not_manifold():
    V, F = disk(n_rings=3)
    a, b = F[0, 0], F[0, 1]
    V2 = np.vstack([V, [[0.0, 0.0, 1.0]]])
    F2 = np.vstack([F, [[a, b, V.shape[0]]]])
    with pytest.raises(NotADiskError) as e:
        check_disk(V2, F2)
    assert (e.value.parameter, e.value.count, e.value.first) == ("F", 1, [sorted([a, b])])


def test_polyline_projection_gives_arc_length_and_distance():
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    poly = Polyline(square)
    Y, s, d = poly.project(np.array([[0.25, -0.5, 0.0], [1.2, 0.5, 0.0], [0.0, 0.5, 0.0]]))
    assert np.allclose(Y, [[0.25, 0, 0], [1, 0.5, 0], [0, 0.5, 0]])
    assert np.allclose(s, [0.25, 1.5, 3.5])          # hand-computed arc lengths from the first corner
    assert np.allclose(d, [0.5, 0.2, 0.0])
    assert np.allclose(poly.point_at(s), Y)


def test_polyline_projection_is_exact_beside_one_long_segment_among_short_ones():
    # a unit square whose bottom side is one segment and the other sides 30 each: the 8 nearest
    # midpoints of a point on the bottom near a corner are all on the short side (it came back
    # projected onto the corner, 0.1 away)
    t = np.linspace(0.0, 1.0, 31)[:-1]
    right = np.column_stack([np.ones(30), t, np.zeros(30)])
    top = np.column_stack([1 - t, np.ones(30), np.zeros(30)])
    left = np.column_stack([np.zeros(30), 1 - t, np.zeros(30)])
    poly = Polyline(np.vstack([right, top, left, [[0.0, 0.0, 0.0]]]))
    X = np.array([[0.9, 0.0, 0.0], [0.97, -0.01, 0.0], [0.5, 0.2, 0.0]])
    Y, s, d = poly.project(X)
    # hand-computed: straight down onto the bottom side, which runs from (0, 0) (arc length
    # 3, after the right, top and left sides) back to (1, 0) at arc length 4
    assert np.allclose(Y, [[0.9, 0, 0], [0.97, 0, 0], [0.5, 0, 0]], atol=1e-15)
    assert np.allclose(d, [0.0, 0.01, 0.2], atol=1e-15)
    assert np.allclose(s, [3.9, 3.97, 3.5], atol=1e-12)


def test_patch_with_a_handle_is_refused_with_the_handle_count():
    # a torus (8 x 6 periodic grid) with one triangle removed: one boundary loop, but a handle
    n, m = 8, 6
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    u, v = 2 * np.pi * i.ravel() / n, 2 * np.pi * j.ravel() / m
    V = np.column_stack([(2 + np.cos(v)) * np.cos(u), (2 + np.cos(v)) * np.sin(u), np.sin(v)])
    a = (i * m + j).ravel()
    b = (((i + 1) % n) * m + j).ravel()
    c = (i * m + (j + 1) % m).ravel()
    d = (((i + 1) % n) * m + (j + 1) % m).ravel()
    F = np.concatenate([np.column_stack([a, b, d]), np.column_stack([a, d, c])])[1:]
    with pytest.raises(NotADiskError) as e:
        check_disk(V, F)
    assert (e.value.parameter, e.value.value) == ("F", -1)           # the Euler characteristic: 1 handle


def test_a_reversed_boundary_triangle_is_named_as_an_orientation_problem(flat_disk):
    # it looked like a pinched boundary ("cut one out"); the fix is to orient the triangles
    from curvdetail.curvature.topology import boundary_edges

    V, F = flat_disk
    F = F.copy()
    B = boundary_edges(F)
    on_boundary = np.isin(F, B).sum(axis=1)
    k = int(np.flatnonzero(on_boundary == 2)[0])
    F[k] = F[k, ::-1]
    with pytest.raises(NotADiskError, match="meshing_re_orient_faces_coherently") as e:      # the repair
        check_disk(V, F)
    assert (e.value.parameter, e.value.count) == ("F", 2)            # interior edges run both ways alike


def test_fractional_indices_are_named_not_read_as_a_non_manifold_edge():
    # the non-manifold look-up cast F to int64: 5.5 became 5, a third triangle on edge (5, 6)
    V, F = grid(4, 4)
    a, b = 5, 6                                         # an interior edge: two triangles have it
    assert sum(set((a, b)) <= set(t) for t in F.tolist()) == 2
    F = np.vstack([F.astype(float), [a + 0.5, b, 15.0]])
    with pytest.raises(MeshError) as error:
        check_disk(V, F)
    assert (error.value.parameter, error.value.first) == ("F", [F.shape[0] - 1])

    assert not isinstance(error.value, NotADiskError)


def test_check_disk_returns_arrays_of_its_own_not_the_inputs():
    # float64 / int64 C inputs came back as the very objects given (writing to the checked V
    # changed the caller's patch; a read-only input came back unwritable)
    V, F = grid(4, 4)
    V.setflags(write=False)
    V0, F0 = V.copy(), F.copy()
    W, G, loop = check_disk(V, F)
    assert not np.shares_memory(W, V) and not np.shares_memory(G, F)
    assert W.flags.writeable and G.flags.writeable
    W[0] += 1.0
    G[0] = G[0, ::-1]
    assert np.array_equal(V, V0) and np.array_equal(F, F0)
