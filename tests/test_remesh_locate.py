"""Closest points and point location (curvdetail.remesh.closest_point, curvdetail.remesh.locate)."""

import numpy as np
import pytest
from conftest import triangle_brute_force

from curvdetail.curvature.errors import MeshError
from curvdetail.curvature.testing import grid
from curvdetail.remesh import closest_points, interpolate, locate, spread

#: One right triangle A = (0, 0, 0), B = (2, 0, 0), C = (0, 2, 0) and points whose closest point
#: is worked out by hand: (point, closest point, distance, barycentrics of the closest point).
TRIANGLE = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]]), np.array([[0, 1, 2]])
HAND = [
    # above the interior: straight down, (0.5, 0.5, 0) = A/2 + B/4 + C/4
    ([0.5, 0.5, 3.0], [0.5, 0.5, 0.0], 3.0, [0.5, 0.25, 0.25]),
    # beside the edge BC (x + y = 2) and above: its foot on BC is (1, 1, 0), the edge's midpoint
    ([1.5, 1.5, 0.5], [1.0, 1.0, 0.0], np.sqrt(0.75), [0.0, 0.5, 0.5]),
    # beyond the corner B (past AB and past BC): B itself, at |(1, -1, 1)|
    ([3.0, -1.0, 1.0], [2.0, 0.0, 0.0], np.sqrt(3.0), [0.0, 1.0, 0.0]),
    # in the plane, beside the edge AC (x = 0): its foot (0, 0.5, 0)
    ([-0.7, 0.5, 0.0], [0.0, 0.5, 0.0], 0.7, [0.75, 0.0, 0.25]),
]


def _points_on_faces(V, F, rng, k=2000):
    face = rng.integers(0, F.shape[0], k)
    bary = rng.dirichlet([1.0, 1.0, 1.0], k)
    return face, bary, interpolate(V, F, face, bary)


def test_closest_points_of_one_triangle_are_the_hand_computed_ones():
    V, F = TRIANGLE
    P = np.array([p for p, *_ in HAND])
    sqrD, face, C, bary = closest_points(P, V, F)
    # coordinates of order 1: rounding ~1e-15
    assert face.tolist() == [0] * len(HAND)
    np.testing.assert_allclose(C, [c for _, c, *_ in HAND], rtol=0, atol=1e-14)
    np.testing.assert_allclose(sqrD, [d ** 2 for _, _, d, _ in HAND], rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(bary, [b for *_, b in HAND], rtol=0, atol=1e-14)


def test_locate_gives_the_hand_computed_barycentrics_and_distances():
    V, F = TRIANGLE
    face, bary, dist = locate(np.array([p for p, *_ in HAND]), V, F)
    np.testing.assert_allclose(dist, [d for _, _, d, _ in HAND], rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(bary, [b for *_, b in HAND], rtol=0, atol=1e-14)


def test_planar_points_inside_get_distance_zero_and_outside_the_closest_boundary_point():
    V, F = TRIANGLE
    # (0.5, 0.5) lies inside; (1, 1) is on the hypotenuse; (2, 2) is sqrt(2) from its midpoint
    face, bary, dist = locate(np.array([[0.5, 0.5], [1.0, 1.0], [2.0, 2.0]]), V[:, :2], F)
    np.testing.assert_allclose(dist, [0.0, 0.0, np.sqrt(2.0)], rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(bary, [[0.5, 0.25, 0.25], [0.0, 0.5, 0.5], [0.0, 0.5, 0.5]], atol=1e-14)


def test_points_on_the_surface_are_rebuilt_from_their_barycentrics(load_mesh, rng):
    V, F = load_mesh("mannequin_nose.obj")
    _, _, P = _points_on_faces(V, F, rng)
    face, bary, dist = locate(P, V, F)
    # a point on the surface is found at distance 0 and rebuilt from its face, to rounding
    assert np.abs(interpolate(V, F, face, bary) - P).max() < 1e-12
    assert dist.max() < 1e-12
    assert np.all(bary >= 0) and np.allclose(bary.sum(1), 1.0, rtol=0, atol=1e-15)


def test_planar_location_finds_the_containing_triangle(flat_disk, rng):
    V, F = flat_disk
    _, _, P = _points_on_faces(V[:, :2], F, rng)
    face, bary, dist = locate(P, V[:, :2], F)
    assert np.abs(interpolate(V[:, :2], F, face, bary) - P).max() < 1e-12
    assert dist.max() < 1e-12


def test_points_off_the_surface_get_the_brute_force_distance(load_mesh, rng):
    V, F = load_mesh("mannequin_nose.obj")
    _, _, P = _points_on_faces(V, F, rng, k=300)
    P = P + rng.normal(scale=0.01, size=P.shape)
    face, bary, dist = locate(P, V, F)
    # every triangle measured; distances of order 0.01 in a mesh of size ~1: rounding 1e-14
    np.testing.assert_allclose(dist, triangle_brute_force(P, V, F), rtol=1e-12, atol=1e-14)
    # and the returned face and barycentrics give a point at that distance
    np.testing.assert_allclose(np.linalg.norm(interpolate(V, F, face, bary) - P, axis=1), dist,
                               rtol=1e-12, atol=1e-14)


def _fine_patch_beside_a_large_triangle(dim):
    """An 8 x 8 grid of the unit square (98 triangles of area 0.01) and one triangle of area
    ~200 beside it, whose edge x = -1 is nearer to points far out along -x than the patch."""
    V, F = grid(8, 8)
    n = V.shape[0]
    big = [[-1.0, -10.0, 0.0], [-1.0, 10.0, 0.0], [20.0, 0.0, 1.0]] if dim == 3 else \
        [[-1.0, -10.0, 0.0], [-1.0, 10.0, 0.0], [-3.0, 0.0, 0.0]]     # planar: beside the patch, not over it
    return np.vstack([V, big])[:, :dim], np.vstack([F, [[n, n + 1, n + 2]]])


@pytest.mark.parametrize("dim", [2, 3])
def test_far_points_get_the_closest_point_where_triangle_sizes_vary(rng, dim):
    # 300 points 1.7 to 40 diagonals from the mesh in every direction, beside one large
    # triangle and many small ones (where candidate searches by nearest centroid go wrong)
    V, F = _fine_patch_beside_a_large_triangle(dim)
    u = rng.normal(size=(300, dim))
    u /= np.linalg.norm(u, axis=1)[:, None]
    diagonal = np.linalg.norm(np.ptp(V, axis=0))
    P = 0.5 * (V.max(0) + V.min(0)) + u * diagonal * rng.uniform(1.7, 40.0, 300)[:, None]
    face, bary, dist = locate(P, V, F)
    # distances up to ~1200: relative 1e-12
    np.testing.assert_allclose(dist, triangle_brute_force(P, V, F), rtol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(interpolate(V, F, face, bary) - P, axis=1), dist, rtol=1e-12)


def test_a_far_point_nearest_a_large_triangles_edge_gets_that_edge():
    V, F = _fine_patch_beside_a_large_triangle(3)
    face, bary, dist = locate(np.array([[-40.0, 0.5, 0.0]]), V, F)
    # the closest point is (-1, 0.5, 0) on the large triangle's edge x = -1, at 39
    assert face.tolist() == [F.shape[0] - 1]
    np.testing.assert_allclose(interpolate(V, F, face, bary), [[-1.0, 0.5, 0.0]], rtol=0, atol=1e-12)
    assert dist == pytest.approx([39.0], rel=1e-14)


def test_points_very_far_from_the_mesh_get_their_exact_distance():
    # the closest point of (x, y, 1) with x, y in [0, 1] is right below it; the others lie 2e10
    # beside and 3e10 below the unit square
    V, F = grid(5, 5)
    P = np.array([[0.5, 0.5, 1.0], [2e10, 0.5, 0.0], [0.25, 0.75, -3e10]])
    face, bary, dist = locate(P, V, F)
    assert dist == pytest.approx([1.0, 2e10 - 1.0, 3e10], rel=1e-12)
    np.testing.assert_allclose(interpolate(V, F, face[:1], bary[:1]), [[0.5, 0.5, 0.0]], atol=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_scale_and_position_of_the_input_do_not_change_the_answer(flat_disk, rng, dim):
    # a mesh of size 1e100 far from the origin: the same faces and barycentrics, distances
    # scaled (to rounding)
    V, F = flat_disk
    V = V[:, :dim]
    P = V[rng.integers(0, V.shape[0], 50)] + rng.normal(scale=0.01, size=(50, dim))
    face, bary, dist = locate(P, V, F)
    s, t = 1e100, 3e100
    face2, bary2, dist2 = locate(P * s + t, V * s + t, F)
    assert np.array_equal(face, face2)
    np.testing.assert_allclose(bary, bary2, rtol=0, atol=1e-9)
    np.testing.assert_allclose(dist2 / s, dist, rtol=0, atol=1e-12)
    sqrD, _, C, _ = closest_points(P * s + t, V * s + t, F)
    np.testing.assert_allclose(np.sqrt(sqrD) / s, dist, rtol=0, atol=1e-12)
    np.testing.assert_allclose((C - t) / s, interpolate(V, F, face, bary), rtol=0, atol=1e-9)


def test_a_mesh_too_small_to_square_its_extent_is_located():
    # its bbox diagonal underflows when squared
    V, F = grid(6, 6)
    V[:, 2] = 0.1 * V[:, 0] ** 2
    P = V[[3, 17]] + [0.01, 0.02, 0.05]
    _, _, d = locate(P, V, F)
    _, _, d_tiny = locate(P * 1e-170, V * 1e-170, F)
    np.testing.assert_allclose(d_tiny / 1e-170, d, rtol=1e-12)


def test_no_points_give_empty_results():
    V, F = grid(3, 3)
    sqrD, face, C, bary = closest_points(np.empty((0, 3)), V, F)
    assert (sqrD.shape, face.shape, C.shape, bary.shape) == ((0,), (0,), (0, 3), (0, 3))
    assert [x.shape for x in locate(np.empty((0, 3)), V, F)] == [(0,), (0, 3), (0,)]


def test_spread_is_the_adjoint_of_interpolate_and_conserves_the_total(load_mesh, rng):
    V, F = load_mesh("mannequin_nose.obj")
    face, bary, _ = _points_on_faces(V, F, rng)
    f = rng.normal(size=V.shape[0])
    g = rng.normal(size=face.size)
    assert np.dot(interpolate(f, F, face, bary), g) == pytest.approx(np.dot(f, spread(g, F, face, bary, V.shape[0])))
    assert spread(g, F, face, bary, V.shape[0]).sum() == pytest.approx(g.sum(), abs=1e-12)


# ---- refusals: the type and the facts a user acts on ----

@pytest.mark.parametrize("dim", [2, 3])
def test_nan_points_are_refused_naming_them(flat_disk, dim):
    V, F = flat_disk
    P = V[:4, :dim].copy()
    P[2, 0] = np.nan
    with pytest.raises(MeshError) as e:
        locate(P, V[:, :dim], F)
    assert (e.value.parameter, e.value.count, e.value.first) == ("points", 1, [2])


def test_triangle_indices_outside_v_are_refused(flat_disk):
    V, F = flat_disk
    G = F.copy()
    G[5, 1] = V.shape[0]
    with pytest.raises(MeshError) as e:
        locate(V[:3], V, G)
    assert (e.value.parameter, e.value.count, e.value.first) == ("F", 1, [5])


def test_a_mesh_collapsed_to_a_point_is_refused():
    V, F = grid(5, 5)
    with pytest.raises(MeshError) as e:
        locate(V[:3], np.zeros_like(V), F)
    assert (e.value.parameter, e.value.count) == ("V", 25)


def test_coordinates_whose_squares_overflow_are_refused():
    V, F = grid(5, 5)
    with pytest.raises(MeshError, match=r"1e\+155.*1e\+150") as e:          # the largest, the limit
        locate(V[:3], V * 1e155, F)
    assert (e.value.parameter, e.value.count) == ("V", 24)


def test_zero_area_triangles_are_refused_by_index():
    V, F = grid(5, 5)
    V[F[7, 0]] = V[F[7, 1]]                        # triangle 7 (and its neighbours) collapse
    with pytest.raises(MeshError) as e:
        locate(V[:3], V, F)
    assert e.value.parameter == "F" and 7 in e.value.first and e.value.count == len(e.value.first)


def test_points_beyond_the_overflow_distance_are_refused_by_index():
    # more than 1e100 diagonals away (libigl's squared distances overflow from ~1e154)
    V, F = grid(5, 5)
    P = np.array([[0.5, 0.5, 1.0], [0.0, 0.0, 1e110], [0.0, 0.0, -1e140]])
    with pytest.raises(MeshError) as e:
        locate(P, V, F)
    assert (e.value.parameter, e.value.count, e.value.first) == ("points", 2, [1, 2])


def test_points_and_mesh_of_other_dimensions_are_refused():
    V, F = grid(5, 5)
    with pytest.raises(MeshError) as e:
        closest_points(V[:3, :2], V, F)
    assert (e.value.parameter, e.value.value) == ("P", (3, 2))


@pytest.mark.parametrize("what, value, words", [
    ("F", "fractional", None), ("F", "bool", "bool"), ("points", "str", "<U"), ("points", "object", "object"),
    ("V", "complex", "complex128"),
])
def test_inputs_that_are_not_real_numbers_or_integers_are_refused(what, value, words):
    V, F = grid(5, 5)
    args = {"points": V[:3], "V": V, "F": F}
    x = args[what]
    args[what] = {"fractional": x + 0.5, "bool": x.astype(bool), "str": x.astype(str),
                  "object": x.astype(object), "complex": x.astype(complex)}[value]
    with pytest.raises(MeshError, match=words) as e:               # the dtype given
        locate(args["points"], args["V"], args["F"])
    assert e.value.parameter == what


def test_interpolate_and_spread_refuse_faces_that_are_not_located_ones(flat_disk):
    V, F = flat_disk
    face, bary, _ = locate(V[:5], V, F)
    with pytest.raises(MeshError) as e:
        spread(np.ones(5), F, np.r_[face[:4], F.shape[0]], bary, V.shape[0])
    assert (e.value.parameter, e.value.count, e.value.first) == ("face", 1, [4])
    with pytest.raises(MeshError) as e:
        interpolate(V, F, face.astype(float), bary)
    assert e.value.parameter == "face"
    with pytest.raises(MeshError) as e:
        spread(np.ones(4), F, face, bary, V.shape[0])
    assert (e.value.parameter, e.value.value) == ("values", 4)


def test_closest_points_on_paired_triangles_match_libigl():
    # own_side's relocation: each point against its own triangle (inside, beyond an edge, beyond
    # a corner), checked against libigl's exact closest point on that one triangle
    import igl

    from curvdetail.remesh.locate import _closest_on_triangles

    V, F = TRIANGLE
    for point, closest, distance, _ in HAND:
        sq, C = _closest_on_triangles(np.array([point]), V[F])
        assert np.sqrt(sq[0]) == pytest.approx(distance, abs=1e-12)
        np.testing.assert_allclose(C[0], closest, atol=1e-12)
    rng = np.random.default_rng(3)
    T = rng.normal(size=(300, 3, 3))
    P = T.mean(axis=1) + 2.0 * rng.normal(size=(300, 3))
    sq, C = _closest_on_triangles(P, T)
    for i in range(0, 300, 7):
        ref_sq, _, ref_C = igl.point_mesh_squared_distance(P[i:i + 1], T[i], np.array([[0, 1, 2]]))
        assert sq[i] == pytest.approx(ref_sq[0], rel=1e-10, abs=1e-12)
        np.testing.assert_allclose(C[i], ref_C[0], atol=1e-10)
