"""The scan-like model of scripts/reproduce_scan.py: its cracks, and the experiment on them."""

import numpy as np
import pytest
from conftest import load_script

from curvdetail.curvature.robust_laplacian import degenerate_triangles, flip_caps
from curvdetail.curvature.topology import boundary_vertices
from curvdetail.remesh._disk import Polyline, check_surface
from curvdetail.remesh.experiment import run_experiment

scan = load_script("reproduce_scan")


@pytest.fixture(scope="module")
def cracked():
    """2,000 points, one hole, two caps and two cracks of 6 edges."""
    return scan.scan_like(2000, holes=1, caps=2, cracks=2, crack_edges=6)


def test_each_crack_is_a_boundary_loop_of_twice_its_edges(cracked):
    V, F = cracked
    _, _, loops = check_surface(V, flip_caps(V, F), "the scan")        # manifold and oriented
    sizes = sorted(len(loop) for loop in loops)
    # the hole: the ring of one removed vertex (5 to 7 on this hull); the cracks: 2 x 6 each
    assert len(loops) == 3 and sizes[1:] == [12, 12] and 4 <= sizes[0] <= 8
    assert degenerate_triangles(V, F).size == 2                          # the caps alone


def test_a_crack_is_thin_and_folds_no_triangle(cracked):
    V, F = cracked
    _, _, loops = check_surface(V, flip_caps(V, F), "the scan")
    for loop in (loop for loop in loops if len(loop) == 12):
        # the copies (the loop's second half, appended last) face their originals across the crack
        ends = loop[np.isin(loop, np.arange(V.shape[0] - 10, V.shape[0]))]
        assert ends.size == 5
        apart = np.linalg.norm(V[loop][:, None] - V[ends][None], axis=2)
        apart[loop[:, None] == ends[None]] = np.inf
        gap = apart.min(axis=0)                                          # to its original
        original = loop[apart.argmin(axis=0)]
        for c, o, g in zip(ends, original, gap):
            fan = F[(F == c).any(axis=1)]
            # open, but thin: moved a fifth of its smallest height beside the crack, so under a
            # quarter of its shortest edge there (each edge, before the move, at least that height)
            assert 0 < g <= 0.25 * np.linalg.norm(V[fan[fan != c]] - V[c], axis=1).min()
            # and no triangle beside it turned over by the move
            W = V.copy()
            W[c] = V[o]
            assert (np.sum(_normals(V, fan) * _normals(W, fan), axis=1) > 0).all()


def _normals(V, F):
    return np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])


def test_the_experiment_keeps_every_crack_and_hole_loop_fixed(cracked):
    V, F = cracked
    r = run_experiment(V, F, target_edge="4%", evaluate=False)
    assert r["report"]["target"]["boundary_loops"] == 3
    _, _, loops = check_surface(V, flip_caps(V, F), "the scan")
    b = boundary_vertices(r["Ft"])
    np.testing.assert_array_equal(r["X"][b], r["Vt"][b])                 # the rebuild moves none
    lines = [Polyline(V[loop]) for loop in loops]
    off = np.min([line.project(r["Vt"][b])[2] for line in lines], axis=0)
    assert off.max() < 1e-12 * np.linalg.norm(np.ptp(V, axis=0))         # each on a source loop
