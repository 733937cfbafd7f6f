"""Two-sided surface distances (curvdetail.remesh.evaluate)."""

import numpy as np
import pytest
from conftest import triangle_brute_force

from curvdetail.curvature.errors import CurvdetailError, MeshError
from curvdetail.curvature.testing import grid
from curvdetail.remesh import hausdorff, vertex_distance

ENGINES = ["exact", "meshlab"]


@pytest.mark.parametrize("engine", ENGINES)
def test_a_mesh_is_at_distance_zero_from_itself(load_mesh, engine):
    V, F = load_mesh("mannequin_nose.obj")
    h = hausdorff(V, F, V, F, engine=engine, samples=20000)
    # exact: rounding of coordinates of order 1 (1e-15); pymeshlab works in single precision
    tol = 1e-12 if engine == "exact" else 1e-6
    assert max(h["max"], h["rms"], h["mean"]) < tol * np.linalg.norm(np.ptp(V, axis=0))
    assert h["engine"] == engine and h["samples"] == 40000


@pytest.mark.parametrize("engine", ENGINES)
def test_a_translated_plane_is_the_translation_away(engine):
    V, F = grid(11, 11)
    W = V + [0.0, 0.0, 0.05]
    h = hausdorff(V, F, W, F, engine=engine, samples=20000)
    # every point of either square is exactly 0.05 from the other (same extent); meshlab: float32
    tol = 1e-12 if engine == "exact" else 1e-6
    for key in ("max", "rms", "mean", "a_to_b_max", "b_to_a_max"):
        assert h[key] == pytest.approx(0.05, rel=tol)


def test_vertex_distance_of_a_lifted_grid_is_the_lift():
    V, F = grid(6, 6)
    np.testing.assert_allclose(vertex_distance(V + [0.0, 0.0, 0.3], V, F), 0.3, rtol=1e-14)
    np.testing.assert_allclose(vertex_distance(V, V, F), 0.0, rtol=0, atol=1e-15)


def test_vertex_distance_of_planar_points_is_the_distance_in_the_plane():
    V, F = grid(3, 3)
    P = np.array([[0.5, 0.5], [2.0, 0.5], [-3.0, -4.0]])        # inside; 1 beside; 5 from the corner
    np.testing.assert_allclose(vertex_distance(P, V[:, :2], F), [0.0, 1.0, 5.0], rtol=1e-14, atol=1e-15)


def _two_squares():
    """A small square 0.05 above the middle of the large unit square: ``(W, G, V, F)``, the small
    one first. Every point of the small one is 0.05 from the large one, while the large one's
    points are from 0.05 to ~0.57 from the small one."""
    V, F = grid(11, 11)
    W, G = grid(3, 3)
    return W * 0.2 + [0.4, 0.4, 0.05], G, V, F


def _two_squares_rms():
    """The two-sided RMS of :func:`_two_squares`, ``sqrt((rms_ab^2 + rms_ba^2) / 2)``, in closed
    form: small to large is 0.05 everywhere; a point (x, y) of the large square is
    sqrt(dx^2 + dy^2 + 0.05^2) from the small one, dx its distance to [0.4, 0.6], and
    E[dx^2] = 2 * int_0^0.4 t^2 dt = 2 * 0.4^3 / 3 for x uniform on [0, 1] (likewise dy)."""
    rms_ba = np.sqrt(0.05 ** 2 + 2 * (2 * 0.4 ** 3 / 3))             # 0.29637
    return np.sqrt((0.05 ** 2 + rms_ba ** 2) / 2)                    # 0.21252


@pytest.mark.parametrize("engine", ENGINES)
def test_one_sided_maxima_are_told_apart(engine):
    W, G, V, F = _two_squares()
    h = hausdorff(W, G, V, F, engine=engine, samples=20000)
    assert h["a_to_b_max"] == pytest.approx(0.05, rel=1e-6)
    # the large square's corners: (0.4, 0.4) from the small one's and 0.05 below (a vertex: exact)
    assert h["b_to_a_max"] == pytest.approx(np.hypot(np.hypot(0.4, 0.4), 0.05), rel=1e-6)
    assert h["max"] == h["b_to_a_max"]
    # 20,000 samples per direction: 0.24 % sampling noise (meshlab, measured over 100 runs);
    # either one-sided RMS (0.05 or 0.296) is far outside
    assert h["rms"] == pytest.approx(_two_squares_rms(), rel=1e-2)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_maximum_at_a_vertex_is_found_exactly(engine):
    # the flat unit square against itself with one interior vertex lifted by h: the two-sided
    # Hausdorff distance is h, attained at the lifted vertex alone (face samples come near it
    # only by chance)
    V, F = grid(11, 11)
    W = V.copy()
    lifted = 5 * 11 + 3                              # the vertex at (0.3, 0.5)
    W[lifted, 2] = 0.05
    r = hausdorff(V, F, W, F, engine=engine, samples=20000)
    assert r["max"] == r["b_to_a_max"] == pytest.approx(0.05, rel=1e-12, abs=0)
    # the other way the largest distance is that of the flat vertex under the lifted one
    assert r["a_to_b_max"] == pytest.approx(triangle_brute_force(V[[lifted]], W, F)[0], rel=1e-12, abs=0)


def test_exact_engine_agrees_with_meshlab_on_far_surfaces(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    W = V.copy()
    W[:, 2] = V[:, 2].mean()                       # flattened: far from the nose tip
    a = hausdorff(W, F, V, F, engine="meshlab", samples=20000)
    b = hausdorff(W, F, V, F, engine="exact", samples=20000)
    # independent random samples of both: the figures agree to sampling noise (~1 %)
    assert b["rms"] == pytest.approx(a["rms"], rel=0.02)
    assert b["max"] == pytest.approx(a["max"], rel=0.02)


def test_meshes_far_apart_are_measured_with_the_exact_engine():
    # two unit squares 1e10 apart kept pymeshlab's grid search busy for minutes
    V, F = grid(5, 5)
    h = hausdorff(V, F, V + [0.0, 0.0, 1e10], F, samples=1000, engine="meshlab")
    assert h["max"] == pytest.approx(1e10, rel=1e-9)
    assert h["rms"] == pytest.approx(1e10, rel=1e-9)
    assert h["engine"] == "exact"                    # said, though "meshlab" was asked for


@pytest.mark.parametrize("scale", [1e140, 1e-100])
def test_huge_and_tiny_meshes_are_measured_in_a_unit_frame(scale):
    V, F = grid(5, 5)
    h = hausdorff(V * scale, F, (V + [0.0, 0.0, 0.1]) * scale, F, samples=1000)
    assert h["rms"] == pytest.approx(0.1 * scale, rel=1e-12)


def test_surfaces_of_few_triangles_are_measured():
    V, F = grid(2, 3)                               # 4 triangles
    assert hausdorff(V, F, V, F, samples=1000)["max"] < 1e-12
    np.testing.assert_allclose(vertex_distance(V + [0.0, 0.0, 0.5], V, F), 0.5, rtol=1e-14)


def test_exact_seed_none_draws_fresh_samples_and_a_seed_repeats_them():
    W, G, V, F = _two_squares()
    fresh = [hausdorff(W, G, V, F, samples=2000, seed=None) for _ in range(2)]
    assert fresh[0]["rms"] != fresh[1]["rms"]
    for h in fresh:                               # 2,000 samples: 0.84 % noise (measured)
        assert h["rms"] == pytest.approx(_two_squares_rms(), rel=0.05)
    seeded = [hausdorff(W, G, V, F, samples=2000, seed=3) for _ in range(2)]
    assert seeded[0] == seeded[1]
    assert seeded[0]["rms"] != fresh[0]["rms"]


def _coarse_and_fine():
    """A cylindrical patch z = (x - 0.5)^2 / 2 over the unit square, tessellated coarsely and
    unevenly (fine columns up to x = 0.3, then two columns 0.35 wide: long, flat triangles beside
    small ones), and a fine regular tessellation of the same surface lifted by 0.002."""
    def patch(xs, ys, lift):
        X, Y = np.meshgrid(xs, ys)
        V = np.column_stack([X.ravel(), Y.ravel(), 0.5 * (X.ravel() - 0.5) ** 2 + lift])
        _, F = grid(len(xs), len(ys))
        return V, F

    Vc, Fc = patch(np.r_[np.linspace(0.0, 0.3, 31), 0.65, 1.0], np.linspace(0.0, 1.0, 21), 0.0)
    Vf, Ff = patch(np.linspace(0.0, 1.0, 21), np.linspace(0.0, 1.0, 21), 0.002)
    return Vc, Fc, Vf, Ff


def test_vertex_distance_near_a_surface_of_uneven_triangles_is_exact():
    Vc, Fc, Vf, _ = _coarse_and_fine()
    rng = np.random.default_rng(1)
    xy = rng.random((300, 2))
    P = np.vstack([Vf, np.column_stack([xy, 0.5 * (xy[:, 0] - 0.5) ** 2 + 0.002])])
    np.testing.assert_allclose(vertex_distance(P, Vc, Fc), triangle_brute_force(P, Vc, Fc), rtol=1e-12, atol=1e-15)


def test_vertex_distance_far_above_a_wavy_surface_is_exact():
    # a million diagonals above a wavy square the closest point is at the top of a wave
    V, F = grid(41, 41)
    V[:, 2] = 0.05 * np.sin(6 * V[:, 0]) * np.cos(5 * V[:, 1])
    rng = np.random.default_rng(4)
    P = rng.normal(size=(200, 3)) * [1.0, 1.0, 1e6]
    np.testing.assert_allclose(vertex_distance(P, V, F), triangle_brute_force(P, V, F), rtol=1e-12, atol=0)


def test_exact_figures_are_those_of_its_own_samples(monkeypatch):
    # the engine's samples recorded: every figure it reports must be the exact one over its
    # samples (and, for the maxima, every vertex) as brute force finds it
    import curvdetail.remesh.evaluate as evaluate
    from curvdetail.remesh.closest_point import unit_frame

    drawn = []
    area_samples = evaluate._area_samples

    def recording(V, F, n, rng):
        P, face = area_samples(V, F, n, rng)
        drawn.append(P)
        return P, face

    monkeypatch.setattr(evaluate, "_area_samples", recording)
    Vc, Fc, Vf, Ff = _coarse_and_fine()
    r = hausdorff(Vf, Ff, Vc, Fc, samples=300, seed=0)
    # each mesh's samples were drawn in its own unit frame (its closest-point tree's)
    def placed(P, V):
        _, _, scale = unit_frame(V[:0], V)
        return P * scale + 0.5 * (V.max(axis=0) + V.min(axis=0))

    ab = triangle_brute_force(placed(drawn[0], Vf), Vc, Fc)
    ba = triangle_brute_force(placed(drawn[1], Vc), Vf, Ff)
    assert r["samples"] == ab.size + ba.size == 600
    assert r["a_to_b_max"] == pytest.approx(max(ab.max(), triangle_brute_force(Vf, Vc, Fc).max()), rel=1e-12)
    assert r["b_to_a_max"] == pytest.approx(max(ba.max(), triangle_brute_force(Vc, Vf, Ff).max()), rel=1e-12)
    assert r["rms"] == pytest.approx(np.sqrt(0.5 * ((ab ** 2).mean() + (ba ** 2).mean())), rel=1e-12)
    assert r["mean"] == pytest.approx(0.5 * (ab.mean() + ba.mean()), rel=1e-12)


def test_one_surface_measured_against_many_gives_the_one_off_figures_bit_for_bit():
    # the experiment's way: the source checked and its tree built once, then the rebuilt, the
    # zero-detail and the retriangulated surfaces measured against it, each as a call of its own
    from curvdetail.remesh.evaluate import Surface

    Vc, Fc, Vf, Ff = _coarse_and_fine()
    source = Surface(Vc, Fc)
    for lift in (0.0, 0.002, 0.3):
        Va = Vf + [0.0, 0.0, lift]
        d = source.vertex_distance(Va)
        np.testing.assert_array_equal(d, vertex_distance(Va, Vc, Fc))
        assert source.hausdorff(Va, Ff, samples=500, a_vertex_distance=d) == hausdorff(Va, Ff, Vc, Fc, samples=500)


def test_brute_force_reference_is_right():
    # the tests' own reference, on points whose distances are known: above, beside, below a
    # corner, on the square
    V, F = grid(3, 3)
    P = np.array([[0.3, 0.6, 0.2], [1.5, 0.5, 0.0], [-0.3, -0.4, -1.2], [0.5, 0.5, 0.0]])
    np.testing.assert_allclose(triangle_brute_force(P, V, F), [0.2, 0.5, 1.3, 0.0], rtol=0, atol=1e-15)


def test_given_vertex_distances_give_the_figures_bit_for_bit():
    # vertex_distance measures in hausdorff's frame (the two meshes together of unit size):
    # handing its distances over changes no figure, not even in the last bit. A noisy copy off
    # the origin, reaching out of the surface's bounding box
    Vb, F = grid(15, 15)
    Vb[:, 2] = 0.1 * np.sin(4 * Vb[:, 0])
    Vb += [3.1, -7.3, 1.7]
    Va = Vb + np.random.default_rng(5).normal(scale=0.02, size=Vb.shape)
    d = vertex_distance(Va, Vb, F)
    assert hausdorff(Va, F, Vb, F, samples=2000, a_vertex_distance=d) == hausdorff(Va, F, Vb, F, samples=2000)


def test_given_vertex_distances_give_pymeshlabs_maxima_bit_for_bit():
    # pymeshlab's samples change from call to call in one process: the maxima are compared where
    # they lie at vertices (one interior vertex lifted), both ways round
    V, F = grid(11, 11)
    W = V.copy()
    W[5 * 11 + 3, 2] = 0.05
    for Va, Vb in ((W, V), (V, W)):
        given = hausdorff(Va, F, Vb, F, samples=2000, engine="meshlab", a_vertex_distance=vertex_distance(Va, Vb, F))
        measured = hausdorff(Va, F, Vb, F, samples=2000, engine="meshlab")
        keys = ("max", "a_to_b_max", "b_to_a_max", "engine")
        assert {k: given[k] for k in keys} == {k: measured[k] for k in keys}


@pytest.mark.parametrize("engine", ENGINES)
def test_given_vertex_distances_are_not_searched_again(monkeypatch, engine):
    # a's vertices are searched by the caller (vertex_distance), not again in hausdorff: only b's
    # vertices (and the exact engine's own samples) are searched there
    import curvdetail.remesh.evaluate as evaluate

    rows = []
    search = evaluate.SurfaceTree.distance

    def spy(tree, P):
        rows.append(P.shape[0])
        return search(tree, P)

    Va, Fa = grid(9, 9)                                  # 81 vertices
    Vb, Fb = grid(12, 12)                                # 144 vertices
    Vb[:, 2] = 0.05 * np.sin(5 * Vb[:, 0])
    d = vertex_distance(Va, Vb, Fb)
    monkeypatch.setattr(evaluate.SurfaceTree, "distance", spy)
    hausdorff(Va, Fa, Vb, Fb, engine=engine, samples=500, a_vertex_distance=d)
    given, rows[:] = list(rows), []
    hausdorff(Va, Fa, Vb, Fb, engine=engine, samples=500)
    if engine == "meshlab":
        assert given == [144] and rows == [81, 144]
    else:                                                # a's samples, b's samples, b's vertices
        assert given == [500, 500, 144] and rows == [81, 500, 500, 144]


# ---- refusals: the type and the facts a user acts on ----

@pytest.mark.parametrize("samples", [0, -1, 0.5, "many", True, 2 ** 31])
def test_sample_counts_outside_one_to_the_limit_are_refused(monkeypatch, samples):
    import curvdetail.remesh.evaluate as evaluate

    for name in ("_hausdorff_meshlab", "_hausdorff_exact"):             # refused before sampling
        monkeypatch.setattr(evaluate, name, lambda *a, **k: pytest.fail("sampled"))
    V, F = grid(5, 5)
    with pytest.raises(CurvdetailError) as e:
        hausdorff(V, F, V, F, samples=samples)
    assert (e.value.parameter, e.value.value) == ("samples", samples)
    assert isinstance(e.value, ValueError)


@pytest.mark.parametrize("seed, words", [(2.5, r"^seed=2\.5"), (-1, "^seed=-1")])
def test_a_seed_that_is_not_a_whole_number_from_zero_is_refused(seed, words):
    V, F = grid(5, 5)
    with pytest.raises(ValueError, match=words):
        hausdorff(V, F, V, F, seed=seed)


@pytest.mark.parametrize("engine", ["octree", "kdtree", np.array(["exact"]), ["meshlab", "exact"]])
def test_an_engine_that_is_not_one_of_the_two_is_refused(engine):
    V, F = grid(5, 5)
    with pytest.raises(ValueError, match="^engine="):
        hausdorff(V, F, V, F, engine=engine)


@pytest.mark.parametrize("which, words", [("Fa", None), ("Va", r"\(16, 2\)")])
def test_hausdorff_names_each_argument_as_the_caller_does(which, words):
    V, F = grid(4, 4)
    args = {"Va": V, "Fa": F, "Vb": V, "Fb": F}
    args[which] = F - 1 if which == "Fa" else V[:, :2]
    if which == "Va":
        args["Vb"] = V[:, :2]
    with pytest.raises(MeshError, match=words) as e:
        hausdorff(args["Va"], args["Fa"], args["Vb"], args["Fb"])
    assert e.value.parameter == which
    if which == "Fa":
        assert (e.value.count, e.value.first) == (2, [0, 9])      # the triangles of vertex 0


def test_vertex_distance_refuses_nan_points_naming_them():
    V, F = grid(5, 5)
    P = V[:3].copy()
    P[1, 2] = np.inf
    with pytest.raises(MeshError) as e:
        vertex_distance(P, V, F)
    assert (e.value.parameter, e.value.count, e.value.first) == ("V", 1, [1])


def test_vertex_distance_refuses_a_collapsed_or_overflowing_surface():
    V, F = grid(5, 5)
    with pytest.raises(MeshError) as e:
        vertex_distance(V, np.zeros_like(V), F)
    assert (e.value.parameter, e.value.count) == ("Vs", 25)
    with pytest.raises(MeshError, match=r"1e\+155") as e:
        vertex_distance(V, V * 1e155, F)
    assert (e.value.parameter, e.value.count) == ("Vs", 24)


def test_vertex_distance_refuses_unreferenced_source_vertices_as_hausdorff_does():
    # they measure nothing but stretch the bounding box the checks are relative to
    V, F = grid(5, 5)
    P = V + [0.0, 0.0, 0.3]
    stray = np.vstack([[[0.5, 0.5, 2.0]], V, [[3.0, 0.0, 0.0]]])
    with pytest.raises(MeshError) as e:
        hausdorff(P, F, stray, F + 1)
    assert (e.value.count, e.value.first) == (2, [0, 26])
    with pytest.raises(MeshError) as e:
        vertex_distance(P, stray, F + 1)
    assert (e.value.parameter, e.value.count, e.value.first) == ("Vs", 2, [0, 26])

    np.testing.assert_allclose(vertex_distance(P, V, F), 0.3, rtol=1e-14)      # the same surface without them


@pytest.mark.parametrize("value, facts", [
    (np.zeros(24), {"value": (24,)}),
    (np.zeros((25, 1)), {"value": (25, 1)}),
    (np.full(25, True), {"value": (25,)}),
    (["far"] * 25, {"value": (25,)}),
    (np.r_[np.zeros(24), np.nan], {"count": 1, "first": [24]}),
    (np.r_[-1.0, np.zeros(23), np.inf], {"count": 2, "first": [0, 24]}),
])
def test_given_vertex_distances_that_are_not_distances_are_refused(value, facts):
    V, F = grid(5, 5)
    with pytest.raises(CurvdetailError) as e:
        hausdorff(V, F, V, F, a_vertex_distance=value)
    assert e.value.parameter == "a_vertex_distance"
    assert {k: getattr(e.value, k) for k in facts} == facts
    assert "vertex_distance(Va, Vb, Fb)" in e.value.hint                       # what to pass
