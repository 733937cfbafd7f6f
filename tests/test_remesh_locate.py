"""Point location with barycentric coordinates (curvdetail.remesh.locate)."""

import numpy as np
import pytest

from curvdetail.curvature.errors import MeshError
from curvdetail.curvature.testing import grid
from curvdetail.remesh import interpolate, locate, spread


def _points_on_faces(V, F, rng, k=2000):
    face = rng.integers(0, F.shape[0], k)
    bary = rng.dirichlet([1.0, 1.0, 1.0], k)
    return face, bary, interpolate(V, F, face, bary)


@pytest.mark.parametrize("engine", [np.array(["numpy"]), np.array(["auto", "numpy"]), ("auto",)])
def test_an_engine_that_is_not_one_str_is_refused_as_such(flat_disk, engine):
    # ``in`` compared an array element-wise: one entry passed, two raised numpy's "truth value"
    V, F = flat_disk
    with pytest.raises(ValueError, match=r"engine=.* \((ndarray|tuple), not a single str\); use 'auto' or 'numpy'"):
        locate(V[:3], V, F, engine=engine)


@pytest.mark.parametrize("engine", ["auto", "numpy"])
def test_located_barycentrics_reproduce_points_on_the_surface(load_mesh, rng, engine):
    V, F = load_mesh("mannequin_nose.obj")
    _, _, P = _points_on_faces(V, F, rng)
    face, bary, dist = locate(P, V, F, engine=engine)
    # a point on the surface is found at distance 0 and rebuilt from its face to rounding
    assert np.abs(interpolate(V, F, face, bary) - P).max() < 1e-12
    assert dist.max() < 1e-12
    assert np.all(bary >= 0) and np.allclose(bary.sum(1), 1.0)


@pytest.mark.parametrize("engine", ["auto", "numpy"])
def test_planar_location_finds_the_containing_triangle(flat_disk, rng, engine):
    V, F = flat_disk
    face0, bary0, P = _points_on_faces(V[:, :2], F, rng)
    face, bary, dist = locate(P, V[:, :2], F, engine=engine)
    assert np.abs(interpolate(V[:, :2], F, face, bary) - P).max() < 1e-12
    assert np.all(dist < 1e-12)


def test_points_off_the_surface_get_the_exact_closest_point(load_mesh, rng):
    V, F = load_mesh("mannequin_nose.obj")
    _, _, P = _points_on_faces(V, F, rng, k=200)
    P = P + rng.normal(scale=0.01, size=P.shape)
    _, _, dist = locate(P, V, F)
    # brute force over every triangle (Ericson's closest point, same code path, all candidates)
    from curvdetail.remesh.locate import _closest_barycentric

    _, d_all = _closest_barycentric(P[:, None, :], V[F][None])
    assert np.allclose(dist, d_all.min(axis=1), atol=1e-14)


def test_point_outside_a_planar_domain_falls_back_to_the_nearest_triangle():
    V = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    F = np.array([[0, 1, 2]])
    face, bary, dist = locate(np.array([[1.0, 1.0]]), V, F)
    # nearest point of the hypotenuse to (1, 1) is its midpoint, at distance sqrt(2)/2
    assert face.tolist() == [0]
    assert np.allclose(bary, [[0.0, 0.5, 0.5]])
    assert np.allclose(dist, [np.sqrt(0.5)])


def test_spread_is_the_adjoint_of_interpolate_and_conserves_the_total(load_mesh, rng):
    V, F = load_mesh("mannequin_nose.obj")
    face, bary, _ = _points_on_faces(V, F, rng)
    f = rng.normal(size=V.shape[0])
    g = rng.normal(size=face.size)
    assert np.dot(interpolate(f, F, face, bary), g) == pytest.approx(np.dot(f, spread(g, F, face, bary, V.shape[0])))
    assert spread(g, F, face, bary, V.shape[0]).sum() == pytest.approx(g.sum(), abs=1e-12)


@pytest.mark.parametrize("engine", ["auto", "numpy"])
@pytest.mark.parametrize("dim", [2, 3])
def test_nan_points_are_refused_naming_them_not_a_crash(flat_disk, engine, dim):
    # pymeshlab's nearest-face grid used to die with a segmentation fault on a NaN point
    V, F = flat_disk
    P = V[:4, :dim].copy()
    P[2, 0] = np.nan
    with pytest.raises(MeshError, match=r"points: 1 vertex has NaN or infinite coordinates \(first: 2\)"):
        locate(P, V[:, :dim], F, engine=engine)


def test_triangle_indices_outside_v_are_refused(flat_disk):
    V, F = flat_disk
    G = F.copy()
    G[5, 1] = V.shape[0]
    with pytest.raises(MeshError, match=r"1 triangle has vertex indices outside .*first: 5"):
        locate(V[:3], V, G)


def test_interpolate_and_spread_refuse_located_points_that_do_not_fit(flat_disk):
    # they used to fail with numpy's IndexError from deep inside the indexing
    V, F = flat_disk
    face, bary, _ = locate(V[:5], V, F)
    with pytest.raises(MeshError, match=r"spread: 1 face indices are outside"):
        spread(np.ones(5), F, np.r_[face[:4], F.shape[0]], bary, V.shape[0])
    with pytest.raises(MeshError, match="vertex indices outside"):
        spread(np.ones(5), F, face, bary, 3)
    with pytest.raises(MeshError, match="values has 4 rows for 5 located points"):
        spread(np.ones(4), F, face, bary, V.shape[0])
    with pytest.raises(MeshError, match=r"values has 3 rows but F references vertex \d+"):
        interpolate(np.ones(3), F, face, bary)


def test_a_mesh_collapsed_to_a_point_is_refused_not_a_hang():
    # pymeshlab's nearest-face grid never returned on a mesh whose vertices all coincide
    V, F = grid(5, 5)
    with pytest.raises(MeshError, match="V: all 25 vertices are at one point"):
        locate(V[:3], np.zeros_like(V), F)


def test_coordinates_whose_squares_overflow_are_refused_not_a_segfault():
    # pymeshlab's grid died with a segmentation fault on coordinates of 1e155
    V, F = grid(5, 5)
    with pytest.raises(MeshError, match=r"V: 24 rows reach 1e\+155.*beyond 1e\+150"):
        locate(V[:3], V * 1e155, F)


def test_zero_area_triangles_are_refused_by_name():
    V, F = grid(5, 5)
    V[F[7, 0]] = V[F[7, 1]]                        # triangle 7 (and its neighbours) collapse
    with pytest.raises(MeshError, match=r"F: \d+ triangles have zero area \(first: .*7"):
        locate(V[:3], V, F)


@pytest.mark.parametrize("engine", ["auto", "numpy"])
def test_points_far_from_the_mesh_get_their_exact_distance_without_a_hang(engine):
    # points 1e10 mesh sizes away kept pymeshlab's grid search busy for minutes; they go to the
    # numpy engine. The closest point of (x, y, 1) with x, y in [0, 1] is right below it.
    V, F = grid(5, 5)
    P = np.array([[0.5, 0.5, 1.0], [2e10, 0.5, 0.0], [0.25, 0.75, -3e10]])
    face, bary, dist = locate(P, V, F, engine=engine)
    # (which point is closest is not resolved in float64 that far away: only the distance is)
    assert dist == pytest.approx([1.0, 2e10 - 1.0, 3e10], rel=1e-12)
    assert np.allclose(interpolate(V, F, face[:1], bary[:1]), [[0.5, 0.5, 0.0]], atol=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_scale_and_position_of_the_input_do_not_change_the_answer(flat_disk, rng, dim):
    # locate works in a frame where the mesh has unit size: a mesh of size 1e100 far from the
    # origin gets the same faces and barycentrics and its distances scaled (to rounding)
    V, F = flat_disk
    V = V[:, :dim]
    P = V[rng.integers(0, V.shape[0], 50)] + rng.normal(scale=0.01, size=(50, dim))
    face, bary, dist = locate(P, V, F)
    s, t = 1e100, 3e100
    face2, bary2, dist2 = locate(P * s + t, V * s + t, F)
    assert np.array_equal(face, face2)
    assert np.allclose(bary, bary2, atol=1e-9)
    assert np.allclose(dist2 / s, dist, atol=1e-12)


@pytest.mark.parametrize("what, value, words", [
    ("F", "fractional", "F has non-integer entries"),
    ("F", "bool", "F has dtype bool"),
    ("points", "str", "points has dtype <U"),
    ("points", "object", "points has dtype object"),
    ("points", "datetime64", "points has dtype datetime64"),
    ("V", "complex", "V has dtype complex128"),
])
def test_inputs_that_are_not_real_numbers_or_integers_are_refused(what, value, words):
    # they were coerced: 0.5 face indices truncated, bools read as 0/1, strings parsed
    V, F = grid(5, 5)
    args = {"points": V[:3], "V": V, "F": F}
    x = args[what]
    args[what] = {"fractional": x + 0.5, "bool": x.astype(bool), "str": x.astype(str),
                  "object": x.astype(object), "datetime64": x.astype("datetime64[s]"),
                  "complex": x.astype(complex)}[value]
    with pytest.raises(MeshError, match=words):
        locate(args["points"], args["V"], args["F"])


@pytest.mark.parametrize("name", ["candidates", "chunk"])
@pytest.mark.parametrize("value, words", [(0, "at least 1"), (-5, "at least 1"), (True, "whole number"),
                                          (2.5, "whole number")])
def test_candidates_and_chunk_must_be_whole_numbers_of_at_least_one(name, value, words):
    # chunk=-5 returned garbage, candidates=0 / chunk=0 raised numpy errors
    V, F = grid(5, 5)
    with pytest.raises(ValueError, match=f"{name}={value!r} must .*{words}"):
        locate(V[:3], V, F, engine="numpy", **{name: value})


def test_interpolate_names_the_offending_face_index_not_its_position():
    V, F = grid(5, 5)
    with pytest.raises(MeshError, match=r"1 face indices are outside \[0, 32\) \(first: 99, at positions 1\)"):
        interpolate(V, F, np.array([3, 99]), np.full((2, 3), 1 / 3))
    with pytest.raises(MeshError, match="face has dtype float64"):
        interpolate(V, F, np.array([3.0, 9.5]), np.full((2, 3), 1 / 3))


def test_a_mesh_too_small_to_square_its_extent_is_located_not_called_a_point():
    # its bbox diagonal underflows when squared: it was reported as "all vertices at one point"
    V, F = grid(6, 6)
    V[:, 2] = 0.1 * V[:, 0] ** 2
    P = V[[3, 17]] + [0.01, 0.02, 0.05]
    _, _, d = locate(P, V, F)
    _, _, d_tiny = locate(P * 1e-170, V * 1e-170, F)
    assert np.allclose(d_tiny / 1e-170, d, rtol=1e-12)


def test_blocks_of_the_exact_step_give_the_one_block_answer(load_mesh, rng, monkeypatch):
    # the exact closest-point step runs in blocks to bound its memory; block edges change nothing
    import importlib

    locate_module = importlib.import_module("curvdetail.remesh.locate")

    V, F = load_mesh("mannequin_nose.obj")
    _, _, P = _points_on_faces(V, F, rng, k=1000)
    P = P + rng.normal(scale=0.01, size=P.shape)
    whole = locate(P, V, F)
    monkeypatch.setattr(locate_module, "EXACT_BLOCK", 77)
    blocks = locate(P, V, F)
    for a, b in zip(whole, blocks):
        assert np.array_equal(a, b)


def _fine_patch_beside_a_large_triangle(dim):
    """An 8 x 8 grid of the unit square (98 triangles of area 0.01) and one triangle of area
    ~200 beside it, its edge x = -1 (y in [-10, 10]) nearer to points far out along -x than
    the patch, its centroid (6, 0) much further: the nearest centroids, and the nearest vertex
    (of the patch) and its triangles, are all the patch's."""
    V, F = grid(8, 8)
    n = V.shape[0]
    big = [[-1.0, -10.0, 0.0], [-1.0, 10.0, 0.0], [20.0, 0.0, 1.0]] if dim == 3 else \
        [[-1.0, -10.0, 0.0], [-1.0, 10.0, 0.0], [-3.0, 0.0, 0.0]]     # planar: beside the patch, not over it
    return np.vstack([V, big])[:, :dim], np.vstack([F, [[n, n + 1, n + 2]]])


def test_a_far_point_nearest_a_large_triangle_s_edge_gets_that_edge_not_a_small_triangle():
    # points more than a diagonal (here 29) from the mesh's box skip pymeshlab's grid; they
    # went to the nearest centroids and the nearest vertex's triangles, all of the patch here,
    # and got (0, 0.5, 0) at 40 for the edge's (-1, 0.5, 0) at 39
    V, F = _fine_patch_beside_a_large_triangle(3)
    face, bary, dist = locate(np.array([[-40.0, 0.5, 0.0]]), V, F)
    assert face.tolist() == [F.shape[0] - 1]
    # the known answer, to rounding (distance and coordinates of order 10-40: ~1e-14)
    assert np.allclose(interpolate(V, F, face, bary), [[-1.0, 0.5, 0.0]], rtol=0, atol=1e-12)
    assert dist == pytest.approx([39.0], rel=1e-14)


@pytest.mark.parametrize("dim", [2, 3])
def test_far_points_get_the_closest_point_of_every_triangle_where_sizes_vary(rng, dim):
    # 300 points 1.7 to 40 diagonals from the box's centre (at least 1.2 from the box) in every
    # direction: the old fallback got ~40 % of them (both dimensions) at a triangle up to 13 %
    # (3D) and 28 % (2D) further than the closest
    V, F = _fine_patch_beside_a_large_triangle(dim)
    from curvdetail.remesh.locate import _closest_barycentric

    u = rng.normal(size=(300, dim))
    u /= np.linalg.norm(u, axis=1)[:, None]
    diagonal = np.linalg.norm(np.ptp(V, axis=0))
    P = 0.5 * (V.max(0) + V.min(0)) + u * diagonal * rng.uniform(1.7, 40.0, 300)[:, None]
    face, bary, dist = locate(P, V, F)
    # brute force over every triangle (Ericson's closest point); the closest point of a random
    # point is unique, so it must be found, not only its distance: both to rounding (relative
    # 1e-12 of distances up to ~1200; 1e-9 for coordinates of that size)
    b, d = _closest_barycentric(P[:, None, :], V[F][None])
    best = d.argmin(axis=1)
    X = np.einsum("kj,kjd->kd", b[np.arange(P.shape[0]), best], V[F[best]])
    assert dist == pytest.approx(d.min(axis=1), rel=1e-12)
    assert np.abs(interpolate(V, F, face, bary) - X).max() < 1e-9


def test_one_point_in_space_is_located_as_exactly_as_in_a_batch():
    # a square patch whose bottom side is one long edge: the triangles along it are large beside
    # small ones. pymeshlab's search radius was a percentage of the points' bounding box, 0 for a
    # single point, so a lone point found no face and went to the numpy engine, which misses the
    # large triangle here (distance 0.059 against 0.0055)
    from conftest import square_with_one_long_side, triangle_brute_force

    X, F = square_with_one_long_side(60)
    V = np.column_stack([X, 0.05 * X[:, 0] * X[:, 1]])
    P = np.array([[0.774408151263812, 0.00300842016378447, -0.005450218387754509]])
    exact = triangle_brute_force(P, V, F)                     # every triangle measured
    _, _, numpy_engine = locate(P, V, F, engine="numpy")
    assert numpy_engine[0] > 10 * exact[0]                    # the case the grid must answer
    face, bary, dist = locate(P, V, F)
    assert dist[0] == pytest.approx(exact[0], rel=1e-12)
    assert np.linalg.norm(bary[0] @ V[F[face[0]]] - P[0]) == pytest.approx(exact[0], rel=1e-12)


def test_planar_points_outside_the_domain_get_the_nearest_triangle():
    # the unit square with its bottom side one edge and the others 40 each: points just below the
    # bottom are outside the domain, and the numpy engine they went to took triangles along the
    # short sides (up to 0.069 too far); now the tree search measures them. Hand-computed: the
    # closest point of the domain to (x, -y) is (x, 0), at distance y
    from conftest import square_with_one_long_side

    U, F = square_with_one_long_side(40)
    rng = np.random.default_rng(0)
    P = np.column_stack([rng.random(2000), -0.02 * rng.random(2000)])
    face, bary, dist = locate(P, U, F)
    assert np.abs(dist + P[:, 1]).max() < 1e-14
    closest = np.einsum("ki,kid->kd", bary, U[F[face]])
    assert np.abs(closest - np.column_stack([P[:, 0], np.zeros(len(P))])).max() < 1e-14
