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
