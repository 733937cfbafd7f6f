"""Two-sided surface distances (curvdetail.remesh.evaluate)."""

import numpy as np
import pytest

from curvdetail.curvature.errors import MeshError
from curvdetail.curvature.testing import grid
from curvdetail.remesh import hausdorff, vertex_distance


@pytest.mark.parametrize("engine", ["meshlab", "kdtree"])
def test_parallel_planes_are_their_offset_apart(engine):
    V, F = grid(11, 11)
    W = V.copy()
    W[:, 2] += 0.05
    h = hausdorff(V, F, W, F, engine=engine, samples=20000)
    assert h["engine"] == engine
    # every sample of either plane is exactly 0.05 from the other (same extent)
    assert h["max"] == pytest.approx(0.05, rel=1e-6)
    assert h["rms"] == pytest.approx(0.05, rel=1e-6)
    assert h["mean"] == pytest.approx(0.05, rel=1e-6)


def _two_squares():
    """A small square 0.05 above the middle of the large unit square: ``(W, G, V, F)``, the small
    one first. Every point of the small one is 0.05 from the large one, while the large one's
    points are from 0.05 to ~0.57 from the small one."""
    V, F = grid(11, 11)
    W, G = grid(3, 3)
    return W * 0.2 + [0.4, 0.4, 0.05], G, V, F


def _two_squares_rms():
    """The two-sided RMS of :func:`_two_squares` as hausdorff defines it (its docstring),
    ``sqrt((rms_ab^2 + rms_ba^2) / 2)``, both one-sided values in closed form: small to large is
    0.05 everywhere; a point (x, y) of the large square is sqrt(dx^2 + dy^2 + 0.05^2) from the
    small one, dx its distance to [0.4, 0.6], and E[dx^2] = 2 * int_0^0.4 t^2 dt = 2 * 0.4^3 / 3
    for x uniform on [0, 1] (likewise E[dy^2])."""
    rms_ab = 0.05
    rms_ba = np.sqrt(0.05 ** 2 + 2 * (2 * 0.4 ** 3 / 3))             # 0.29637
    return np.sqrt((rms_ab ** 2 + rms_ba ** 2) / 2)                  # 0.21252


@pytest.mark.parametrize("engine", ["meshlab", "kdtree"])
def test_one_sided_maxima_are_told_apart(engine):
    # a small square 0.05 above the middle of a large one: every point of the small one is 0.05
    # from the large one, while the large one's corners are ~0.4 of a diagonal away
    W, G, V, F = _two_squares()
    h = hausdorff(W, G, V, F, engine=engine, samples=20000)
    assert h["a_to_b_max"] == pytest.approx(0.05, rel=1e-6)
    corner = np.hypot(0.4, 0.4)
    assert h["b_to_a_max"] == pytest.approx(np.hypot(corner, 0.05), rel=0.02)
    assert h["max"] == h["b_to_a_max"]
    # the two-sided RMS, known in closed form; 20,000 samples per direction: 0.24 % sampling
    # noise (meshlab, measured over 100 runs); either one-sided RMS (0.05 or 0.296) is far outside
    assert h["rms"] == pytest.approx(_two_squares_rms(), rel=1e-2)


def test_kdtree_engine_agrees_with_meshlab_on_far_surfaces(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    W = V.copy()
    W[:, 2] = V[:, 2].mean()                       # flattened: far from the nose tip
    a = hausdorff(W, F, V, F, engine="meshlab", samples=20000)
    b = hausdorff(W, F, V, F, engine="kdtree", samples=20000)
    # independent random samples of both: the figures agree to sampling noise (~1 %)
    assert b["rms"] == pytest.approx(a["rms"], rel=0.02)
    assert b["max"] == pytest.approx(a["max"], rel=0.02)


def test_vertex_distance_of_a_lifted_grid_is_the_lift():
    V, F = grid(6, 6)
    assert np.allclose(vertex_distance(V + [0.0, 0.0, 0.3], V, F), 0.3)


@pytest.mark.parametrize("samples", [0, -1, 0.5, "many"])
def test_sample_counts_below_one_are_refused_not_a_nan_rms(samples):
    # samples=-1 or 0.5 used to give {'rms': nan, 'samples': 0}
    V, F = grid(5, 5)
    with pytest.raises(ValueError, match="at least 1"):
        hausdorff(V, F, V, F, samples=samples)


@pytest.mark.parametrize("far", [False, True])
def test_vertex_distance_refuses_nan_points_naming_them(far):
    from curvdetail.curvature.errors import MeshError

    V, F = grid(5, 5)
    P = V[:3].copy()
    P[1, 2] = np.inf
    with pytest.raises(MeshError, match=r"V: 1 vertex has NaN or infinite coordinates \(first: 1\)"):
        vertex_distance(P, V, F, far=far)


@pytest.mark.parametrize("far", [False, True])
def test_vertex_distance_refuses_a_collapsed_or_overflowing_surface(far):
    # a surface collapsed to a point hung pymeshlab's grid; coordinates of 1e155 crashed it
    from curvdetail.curvature.errors import MeshError

    V, F = grid(5, 5)
    with pytest.raises(MeshError, match="Vs: all 25 vertices are at one point"):
        vertex_distance(V, np.zeros_like(V), F, far=far)
    with pytest.raises(MeshError, match=r"Vs: 24 rows reach 1e\+155"):
        vertex_distance(V, V * 1e155, F, far=far)


@pytest.mark.parametrize("far", [False, True])
def test_vertex_distance_refuses_unreferenced_source_vertices_as_hausdorff_does(far):
    # vertex_distance measured against a surface with stray vertices (hausdorff refused it): the
    # distances came out right, but relative to a bounding box the strays stretch, so a stray
    # 1e6 away made the clean triangles "zero area"
    V, F = grid(5, 5)
    P = V + [0.0, 0.0, 0.3]
    stray = np.vstack([[[0.5, 0.5, 2.0]], V, [[3.0, 0.0, 0.0]]])
    with pytest.raises(MeshError, match=r"2 vertices are not used by any triangle \(first: 0, 26\)"):
        hausdorff(P, F, stray, F + 1)
    with pytest.raises(MeshError, match=r"^Vs: 2 vertices are not used by any triangle \(first: 0, 26\); "
                                        r"remove them, e\.g\. with pymeshlab's meshing_remove_unreferenced"):
        vertex_distance(P, stray, F + 1, far=far)
    with pytest.raises(MeshError, match=r"^Vs: 1 vertex is not used by any triangle \(first: 25\); remove it"):
        vertex_distance(P, np.vstack([V, [[0.5, 0.5, 1.0]]]), F, far=far)
    assert np.allclose(vertex_distance(P, V, F, far=far), 0.3)      # the same surface without them


def test_surfaces_of_fewer_than_eight_triangles_are_measured():
    # the kd-tree engine asked for 8 neighbours and got missing-neighbour indices (IndexError)
    V, F = grid(2, 3)                               # 4 triangles
    assert hausdorff(V, F, V, F, engine="kdtree", samples=1000)["max"] < 1e-12
    assert np.allclose(vertex_distance(V + [0.0, 0.0, 0.5], V, F, far=True), 0.5)
    assert np.allclose(vertex_distance(V, V, F, far=True), 0.0)


def test_meshes_far_apart_are_measured_with_the_kdtree_engine_not_a_hang():
    # two unit squares 1e10 apart kept pymeshlab's grid search busy for minutes
    V, F = grid(5, 5)
    h = hausdorff(V, F, V + [0.0, 0.0, 1e10], F, samples=1000)
    assert h["max"] == pytest.approx(1e10, rel=1e-9)
    assert h["rms"] == pytest.approx(1e10, rel=1e-9)
    assert h["engine"] == "kdtree"                   # said, though "meshlab" was asked for


def test_huge_and_tiny_meshes_are_measured_in_a_unit_frame():
    # at 1e140 pymeshlab's figures overflowed to inf (silently); scale-free now
    V, F = grid(5, 5)
    for s in (1e140, 1e-100):
        h = hausdorff(V * s, F, (V + [0.0, 0.0, 0.1]) * s, F, samples=1000)
        assert h["rms"] == pytest.approx(0.1 * s, rel=1e-6)


@pytest.mark.parametrize("kwargs, words", [
    ({"samples": True}, "samples=True must be a whole number"),
    ({"samples": 2 ** 31}, "more than the limit of 10,000,000"),
    ({"seed": 2.5}, "seed=2.5 must be a whole number"),
    ({"seed": -1}, "seed=-1 must be at least 0"),
])
def test_bool_huge_or_fractional_counts_are_refused(kwargs, words):
    # samples=True was taken as 1, 2**31 raised pybind's RuntimeError, seed=2.5 numpy's TypeError
    V, F = grid(5, 5)
    with pytest.raises(ValueError, match=words):
        hausdorff(V, F, V, F, engine="kdtree", **kwargs)


@pytest.mark.parametrize("engine", ["octree", np.array(["kdtree"]), ["meshlab", "kdtree"]])
def test_an_engine_that_is_not_one_of_the_two_is_refused(engine):
    # an array was compared with ``in`` element-wise: np.array(["kdtree"]) passed as the engine
    V, F = grid(5, 5)
    shown = "'octree'" if isinstance(engine, str) else r".* \((ndarray|list), not a single str\)"
    with pytest.raises(ValueError, match=rf"engine={shown}; use 'meshlab' or 'kdtree'"):
        hausdorff(V, F, V, F, engine=engine)


def test_kdtree_seed_none_draws_fresh_samples():
    # surfaces whose distances vary over the samples: a new draw gives another RMS, while a
    # fixed seed repeats its figures bit for bit
    W, G, V, F = _two_squares()
    fresh = [hausdorff(W, G, V, F, engine="kdtree", samples=2000, seed=None) for _ in range(2)]
    assert fresh[0]["rms"] != fresh[1]["rms"]
    for h in fresh:                               # 2,000 samples: 0.84 % noise (measured)
        assert h["rms"] == pytest.approx(_two_squares_rms(), rel=0.05)
    seeded = [hausdorff(W, G, V, F, engine="kdtree", samples=2000, seed=3) for _ in range(2)]
    assert seeded[0] == seeded[1]
    assert seeded[0]["rms"] != fresh[0]["rms"]


@pytest.mark.parametrize("which, message", [("Fa", r"Fa: 2 triangles have vertex indices outside"),
                                            ("Va", r"Va has shape \(16, 2\); hausdorff measures surfaces in space")])
def test_hausdorff_names_each_argument_as_the_caller_does(which, message):
    V, F = grid(4, 4)
    args = {"Va": V, "Fa": F, "Vb": V, "Fb": F}
    args[which] = F - 1 if which == "Fa" else V[:, :2]
    if which == "Va":
        args["Vb"] = V[:, :2]
    with pytest.raises(MeshError, match=message):
        hausdorff(args["Va"], args["Fa"], args["Vb"], args["Fb"])


@pytest.mark.parametrize("engine", ["meshlab", "kdtree"])
def test_sample_counts_beyond_the_limit_are_refused_before_sampling(monkeypatch, engine):
    # samples=2e9 was taken and sampled for hours (pymeshlab takes up to 2**31 - 1)
    import curvdetail.remesh.evaluate as evaluate

    for name in ("_hausdorff_meshlab", "_hausdorff_kdtree"):
        monkeypatch.setattr(evaluate, name, lambda *a, **k: pytest.fail("sampled"))
    V, F = grid(5, 5)
    with pytest.raises(ValueError, match=r"samples=2,000,000,000 is more than the limit of 10,000,000 per "
                                         r"direction .*~1,000,000 is plenty"):
        hausdorff(V, F, V, F, samples=2_000_000_000, engine=engine)
    with pytest.raises(ValueError, match="more than the limit"):
        hausdorff(V, F, V, F, samples=evaluate.MAX_SAMPLE_COUNT + 1, engine=engine)


@pytest.mark.parametrize("far", ["no", 0, None])
def test_vertex_distance_far_must_be_a_bool(far):
    # far="no" was taken as True (the approximate engine)
    V, F = grid(5, 5)
    with pytest.raises(ValueError, match=r"far=.* must be True or False"):
        vertex_distance(V, V, F, far=far)


def _brute_force_distance(P, V, F):
    """Exact distance from each point of ``P`` to the surface ``(V, F)``, every triangle tried:
    the distance to the triangle's plane where the projection falls inside the triangle, else
    to the nearest of its three edges."""
    A, B, C = (V[F[:, i]][None] for i in range(3))                 # (1, m, 3)
    Q = P[:, None, :]                                              # (k, 1, 3)
    e0, e1, v = B - A, C - A, Q - A
    d00, d01, d11 = (e0 * e0).sum(-1), (e0 * e1).sum(-1), (e1 * e1).sum(-1)
    d20, d21 = (v * e0).sum(-1), (v * e1).sum(-1)
    den = d00 * d11 - d01 ** 2
    s, t = d11 * d20 - d01 * d21, d00 * d21 - d01 * d20            # barycentrics times den
    n = np.cross(e0, e1)
    plane = np.abs((v * n).sum(-1)) / np.linalg.norm(n, axis=-1)

    def segment(w, e):
        u = np.clip((w * e).sum(-1) / (e * e).sum(-1), 0.0, 1.0)
        return np.linalg.norm(w - u[..., None] * e, axis=-1)

    edge = np.minimum(np.minimum(segment(v, e0), segment(v, e1)), segment(Q - B, C - B))
    inside = (s >= 0) & (t >= 0) & (s + t <= den)
    return np.where(inside, np.minimum(plane, edge), edge).min(axis=1)


def test_brute_force_reference_is_right():
    # the tests' own reference, on points whose distances are known: above, beside, below a
    # corner, on the square
    V, F = grid(3, 3)
    P = np.array([[0.3, 0.6, 0.2], [1.5, 0.5, 0.0], [-0.3, -0.4, -1.2], [0.5, 0.5, 0.0]])
    assert np.allclose(_brute_force_distance(P, V, F), [0.2, 0.5, 1.3, 0.0], rtol=0, atol=1e-15)


@pytest.mark.parametrize("dim", [2, 3])
def test_triangle_distance_agrees_with_the_closest_point_of_locate(dim):
    # the tree search measures with its own distance formula: it must give Ericson's distances
    from curvdetail.remesh.evaluate import _triangle_distance
    from curvdetail.remesh.locate import _closest_barycentric

    rng = np.random.default_rng(7)
    T = rng.normal(size=(20000, 3, dim))
    P = np.concatenate([rng.normal(size=(10000, dim)) * 2,                       # all around
                        T[:10000].mean(axis=1) + rng.normal(size=(10000, dim)) * 1e-3])  # close by
    # (Ericson's point is rebuilt from its barycentric coordinates: inside a triangle in the
    # plane it comes out up to 3e-13 away, where this formula gives 0)
    assert np.allclose(_triangle_distance(P, T), _closest_barycentric(P, T)[1], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("engine", ["meshlab", "kdtree"])
def test_a_maximum_at_a_vertex_is_found_exactly(engine):
    # the flat unit square against itself with one interior vertex lifted by h: the two-sided
    # Hausdorff distance is h, attained at the lifted vertex alone. Face samples come near it
    # only by chance: before the vertices were measured, meshlab reported 0.0475-0.0488 (20,000
    # samples; the figure changes from call to call in one process) and kdtree 0.04858 for h = 0.05
    V, F = grid(11, 11)
    W = V.copy()
    lifted = 5 * 11 + 3                              # the vertex at (0.3, 0.5)
    h = 0.05
    W[lifted, 2] = h
    r = hausdorff(V, F, W, F, engine=engine, samples=20000)
    assert r["max"] == pytest.approx(h, rel=1e-12, abs=0)
    assert r["b_to_a_max"] == pytest.approx(h, rel=1e-12, abs=0)
    # the other way the largest distance is that of the flat square's vertex under the lifted one
    # (0.040825 from the tent of its six triangles; meshlab and kdtree found 0.04081 and 0.03913)
    assert r["a_to_b_max"] == pytest.approx(_brute_force_distance(V[[lifted]], W, F)[0], rel=1e-12, abs=0)
    assert r["a_to_b_max"] < h


def _coarse_and_fine():
    """A cylindrical patch z = (x - 0.5)^2 / 2 over the unit square, tessellated coarsely and
    unevenly (fine columns up to x = 0.3, then two columns 0.35 wide: long, flat triangles
    whose centroids lie 0.1-0.2 from most of their own points), and a fine regular tessellation
    of the same surface lifted by 0.002: ``(Vc, Fc, Vf, Ff)``."""
    def patch(xs, ys, lift):
        X, Y = np.meshgrid(xs, ys)
        V = np.column_stack([X.ravel(), Y.ravel(), 0.5 * (X.ravel() - 0.5) ** 2 + lift])
        _, F = grid(len(xs), len(ys))
        return V, F

    Vc, Fc = patch(np.r_[np.linspace(0.0, 0.3, 31), 0.65, 1.0], np.linspace(0.0, 1.0, 21), 0.0)
    Vf, Ff = patch(np.linspace(0.0, 1.0, 21), np.linspace(0.0, 1.0, 21), 0.002)
    return Vc, Fc, Vf, Ff


def test_vertex_distance_near_a_surface_of_uneven_triangles_is_exact():
    # points 0.002-0.013 from long triangles beside many small ones: the kd-tree candidates (the
    # 8 nearest centroids, all of small triangles) missed the triangle under the point and
    # overestimated 24 of these 741 distances, up to 0.0422 where the distance is 0.0044
    Vc, Fc, Vf, _ = _coarse_and_fine()
    rng = np.random.default_rng(1)
    xy = rng.random((300, 2))
    P = np.vstack([Vf, np.column_stack([xy, 0.5 * (xy[:, 0] - 0.5) ** 2 + 0.002])])
    exact = _brute_force_distance(P, Vc, Fc)
    for far in (True, False):
        assert np.allclose(vertex_distance(P, Vc, Fc, far=far), exact, rtol=1e-12, atol=1e-15)


def test_kdtree_figures_are_exact_at_its_own_samples(monkeypatch):
    # the same two surfaces; the engine's samples recorded: every figure it reports must be the
    # exact one over its samples (and, for the maxima, every vertex) as brute force finds it.
    # The 8-nearest-centroid candidates reported a fine-to-coarse maximum of 0.0421 here (the
    # exact one: 0.0130) and an RMS of 0.00863 (exact on the same samples: 0.00758)
    import curvdetail.remesh.evaluate as evaluate
    from curvdetail.remesh.locate import _unit_frame

    drawn = []
    area_samples = evaluate._area_samples

    def recording(V, F, n, rng):
        P, face = area_samples(V, F, n, rng)
        drawn.append(P)
        return P, face

    monkeypatch.setattr(evaluate, "_area_samples", recording)
    Vc, Fc, Vf, Ff = _coarse_and_fine()
    r = hausdorff(Vf, Ff, Vc, Fc, engine="kdtree", samples=300, seed=0)
    # the samples were drawn in hausdorff's frame, where the two meshes together have unit size
    both = np.vstack([Vf, Vc])
    _, _, scale = _unit_frame(both[:0], both)
    centre = 0.5 * (both.max(axis=0) + both.min(axis=0))
    ab, ba = (_brute_force_distance(P * scale + centre, V, F) for P, (V, F) in zip(drawn, ((Vc, Fc), (Vf, Ff))))
    assert r["samples"] == ab.size + ba.size == 600
    assert r["a_to_b_max"] == pytest.approx(max(ab.max(), _brute_force_distance(Vf, Vc, Fc).max()), rel=1e-12)
    assert r["b_to_a_max"] == pytest.approx(max(ba.max(), _brute_force_distance(Vc, Vf, Ff).max()), rel=1e-12)
    assert r["rms"] == pytest.approx(np.sqrt(0.5 * ((ab ** 2).mean() + (ba ** 2).mean())), rel=1e-12)
    assert r["mean"] == pytest.approx(0.5 * (ab.mean() + ba.mean()), rel=1e-12)


def test_tree_search_is_exact_where_every_triangle_is_about_as_close(monkeypatch):
    # points near the centre of a sphere are about as close to all of its triangles, which are
    # then all measured: with room for a few hundred point-box pairs at a time the points are
    # split again and again, down to one, and the distances must still be exact
    import curvdetail.remesh.evaluate as evaluate
    from curvdetail.curvature.testing import icosphere

    V, F = icosphere(1.0, 2)                                       # 320 triangles
    rng = np.random.default_rng(3)
    P = np.vstack([rng.normal(size=(40, 3)) * 1e-3, rng.normal(size=(40, 3)) * 0.5])
    monkeypatch.setattr(evaluate, "SEARCH_PAIRS", 300)
    monkeypatch.setattr(evaluate, "SEARCH_POINTS", 16)
    assert np.allclose(vertex_distance(P, V, F, far=True), _brute_force_distance(P, V, F), rtol=1e-12, atol=0)


def test_tree_search_far_from_a_surface_is_exact_and_quick():
    # a million diagonals above a wavy square the closest point is at the top of a wave, and
    # every triangle is within 0.1 (1e-7 of the distance) as close: the 8 nearest centroids gave
    # the triangle below the point (1,981 of 2,000 distances too large, by up to 0.099), and a
    # search that measured every triangle whose box comes that close would take all 20,000 of
    # them for every point (an exact nearest-centroid search alone took 8.7 s for 4,000 points
    # on a 40k-vertex square); this takes 0.2 s
    import time

    V, F = grid(101, 101)
    V[:, 2] = 0.05 * np.sin(6 * V[:, 0]) * np.cos(5 * V[:, 1])
    rng = np.random.default_rng(4)
    P = rng.normal(size=(20000, 3)) * [1.0, 1.0, 1e6]
    t = time.perf_counter()
    d = vertex_distance(P, V, F, far=True)
    assert time.perf_counter() - t < 20
    check = rng.choice(P.shape[0], 50, replace=False)
    assert np.allclose(d[check], _brute_force_distance(P[check], V, F), rtol=1e-12, atol=0)


def test_given_vertex_distances_give_the_figures_bit_for_bit():
    # vertex_distance(far=True) measures in hausdorff's frame (the two meshes together of unit
    # size): handing its distances over changes no figure, not even in the last bit. A noisy
    # copy off the origin, reaching out of the surface's bounding box: in the surface's own
    # frame 202 of the 225 distances, and the maximum, came out otherwise in the last bits
    from curvdetail.remesh.evaluate import _surface_distance
    from curvdetail.remesh.locate import _unit_frame

    Vb, F = grid(15, 15)
    Vb[:, 2] = 0.1 * np.sin(4 * Vb[:, 0])
    Vb += [3.1, -7.3, 1.7]
    Va = Vb + np.random.default_rng(5).normal(scale=0.02, size=Vb.shape)
    d = vertex_distance(Va, Vb, F, far=True)
    # the kd-tree engine's figures repeat exactly from call to call
    assert hausdorff(Va, F, Vb, F, engine="kdtree", samples=2000, a_vertex_distance=d) == \
        hausdorff(Va, F, Vb, F, engine="kdtree", samples=2000)
    P, S, scale = _unit_frame(Va, Vb)                          # the surface's own frame
    assert (scale * _surface_distance(P, S, F)).max() != d.max()    # the test can tell frames apart


def test_given_vertex_distances_give_pymeshlabs_maxima_bit_for_bit():
    # pymeshlab's samples change from call to call in one process: the maxima are compared where
    # they lie at vertices (a flat square and a copy with one interior vertex lifted by 0.05, as
    # in test_a_maximum_at_a_vertex_is_found_exactly), both ways round
    V, F = grid(11, 11)
    W = V.copy()
    W[5 * 11 + 3, 2] = 0.05
    for Va, Vb in ((W, V), (V, W)):
        given = hausdorff(Va, F, Vb, F, samples=2000, a_vertex_distance=vertex_distance(Va, Vb, F, far=True))
        measured = hausdorff(Va, F, Vb, F, samples=2000)
        keys = ("max", "a_to_b_max", "b_to_a_max", "engine")
        assert {k: given[k] for k in keys} == {k: measured[k] for k in keys}


@pytest.mark.parametrize("engine", ["meshlab", "kdtree"])
def test_given_vertex_distances_are_not_searched_again(monkeypatch, engine):
    # a's vertices are searched by the caller (vertex_distance) and not again in hausdorff: only
    # b's vertices (and the kd-tree engine's own samples) are searched there
    import curvdetail.remesh.evaluate as evaluate

    rows = []
    search = evaluate._surface_distance

    def spy(P, V, F):
        rows.append(P.shape[0])
        return search(P, V, F)

    Va, Fa = grid(9, 9)                                  # 81 vertices
    Vb, Fb = grid(12, 12)                                # 144 vertices
    Vb[:, 2] = 0.05 * np.sin(5 * Vb[:, 0])
    d = vertex_distance(Va, Vb, Fb, far=True)
    monkeypatch.setattr(evaluate, "_surface_distance", spy)
    hausdorff(Va, Fa, Vb, Fb, engine=engine, samples=500, a_vertex_distance=d)
    given, rows[:] = list(rows), []
    hausdorff(Va, Fa, Vb, Fb, engine=engine, samples=500)
    measured = list(rows)
    if engine == "meshlab":
        assert given == [144] and measured == [81, 144]
    else:
        assert given == [500, 500 + 144] and measured == [500 + 81, 500 + 144]


@pytest.mark.parametrize("value, words", [
    (np.zeros(24), r"shape \(24,\), but Va has 25 vertices.*shape \(25,\)"),
    (np.zeros((25, 1)), r"shape \(25, 1\)"),
    (np.r_[np.zeros(24), np.nan], r"1 of 25 entries are NaN, infinite or negative \(first: 24\)"),
    (np.r_[-1.0, np.zeros(23), np.inf], r"2 of 25 entries .* \(first: 0, 24\)"),
    (np.full(25, True), "dtype bool"),
    (["far"] * 25, "dtype <U3"),
])
def test_given_vertex_distances_that_are_not_distances_are_refused(value, words):
    V, F = grid(5, 5)
    with pytest.raises(ValueError, match=words) as info:
        hausdorff(V, F, V, F, a_vertex_distance=value)
    assert "vertex_distance(Va, Vb, Fb, far=True)" in str(info.value)          # what to pass
