"""Two-sided surface distances (curvdetail.remesh.evaluate)."""

import numpy as np
import pytest

from curvdetail.curvature.testing import grid
from curvdetail.remesh import hausdorff, vertex_distance


@pytest.mark.parametrize("engine", ["meshlab", "kdtree"])
def test_parallel_planes_are_their_offset_apart(engine):
    V, F = grid(11, 11)
    W = V.copy()
    W[:, 2] += 0.05
    h = hausdorff(V, F, W, F, engine=engine, samples=20000)
    # every sample of either plane is exactly 0.05 from the other (same extent)
    assert h["max"] == pytest.approx(0.05, rel=1e-6)
    assert h["rms"] == pytest.approx(0.05, rel=1e-6)
    assert h["mean"] == pytest.approx(0.05, rel=1e-6)


@pytest.mark.parametrize("engine", ["meshlab", "kdtree"])
def test_one_sided_maxima_are_told_apart(engine):
    # a small square 0.05 above the middle of a large one: every point of the small one is 0.05
    # from the large one, while the large one's corners are ~0.4 of a diagonal away
    V, F = grid(11, 11)
    W, G = grid(3, 3)
    W = W * 0.2 + [0.4, 0.4, 0.05]
    h = hausdorff(W, G, V, F, engine=engine, samples=20000)
    assert h["a_to_b_max"] == pytest.approx(0.05, rel=1e-6)
    corner = np.hypot(0.4, 0.4)
    assert h["b_to_a_max"] == pytest.approx(np.hypot(corner, 0.05), rel=0.02)
    assert h["max"] == h["b_to_a_max"]


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
    with pytest.raises(MeshError, match=r"points: 1 rows are NaN or infinite \(first: 1\)"):
        vertex_distance(P, V, F, far=far)
