"""The remeshing experiment on whole models: closed surfaces, handles, holes and several pieces."""

import numpy as np
import pytest

from curvdetail.curvature.geometry import bbox_diagonal
from curvdetail.curvature.testing import cylinder
from curvdetail.curvature.topology import boundary_vertices, vertex_components
from curvdetail.remesh import check_surface, remesh_experiment, retriangulate
from curvdetail.remesh._disk import Polyline
from curvdetail.remesh.experiment import run_experiment

from test_anchors import torus, two_spheres


def wavy_tube():
    """An open tube with two boundary loops (two holes in a closed surface), radius waving along z."""
    V, F = cylinder(n_around=48, n_along=25)
    V[:, :2] *= 1 + 0.2 * np.sin(3 * np.pi * V[:, 2:3])
    return V, F


def test_closed_genus_0_model_is_rebuilt_near_its_floor(load_mesh):
    # spot (closed, genus 0) at 3 %: measured 0.96x the retriangulated floor (RMS); allowed 1.5x,
    # the target
    (X, Ft), report = remesh_experiment(*load_mesh("spot.obj"), target_edge="3%")
    assert report["anchors"] == 1 and report["target"]["boundary_loops"] == 0
    assert report["ratio_to_floor"] < 1.5
    assert report["baseline_zero_detail"] is None and report["improvement_over_zero_detail"] is None
    assert "improvement_over_zero_detail" in report["ratio_notes"]


def test_closed_genus_1_torus_is_rebuilt_near_its_floor():
    # a torus of 3,840 vertices at 3 %, one anchor: measured 1.70x the floor (RMS) and 1.75x its
    # maximum; allowed 2x both. The detail's error drifts further around a handle than over a
    # sphere (4 anchors: 1.38x)
    V, F = torus(n_major=96, n_minor=40)
    (X, Ft), report = remesh_experiment(V, F, target_edge="3%")
    _, _, loops = check_surface(X, Ft)
    assert report["anchors"] == 1 and loops == []
    assert report["ratio_to_floor"] < 2.0
    top = "hausdorff_max_percent_of_diagonal"
    assert report["error"][top] < 2.0 * report["floor_retriangulated"][top]


def test_two_holes_both_loops_are_kept_fixed_bit_for_bit():
    V, F = wavy_tube()
    d = bbox_diagonal(V)
    out = run_experiment(V, F, target_edge="3%")
    Vt, Ft, X = out["Vt"], out["Ft"], out["X"]
    b = boundary_vertices(Ft)
    assert out["report"]["anchors"] == 0 and out["report"]["target"]["boundary_loops"] == 2
    assert np.array_equal(X[b], Vt[b])                                   # fixed, bit for bit
    # on the source's two boundary polylines (z = -0.5 and 0.5), within rounding
    source_loops = check_surface(V, F)[2]
    dist = np.min([Polyline(V[loop]).project(Vt[b])[2] for loop in source_loops], axis=0)
    assert dist.max() < 1e-12 * d
    assert out["report"]["ratio_to_floor"] < 1.5                          # measured 0.9


def test_two_pieces_are_each_rebuilt():
    V, F = two_spheres()
    out = run_experiment(V, F, target_edge="3%")
    X, Ft = out["X"], out["Ft"]
    labels, count = vertex_components(Ft, X.shape[0])
    assert count == 2 and out["report"]["anchors"] == 2
    d = bbox_diagonal(V)
    for piece in range(2):                  # each piece stays on its sphere (radius 1, centres known)
        P = X[labels == piece]
        centre = np.array([3.0, 0.5, 0.0]) if P[:, 0].mean() > 1.5 else np.zeros(3)
        assert np.abs(np.linalg.norm(P - centre, axis=1) - 1.0).max() < 2e-3 * d
    assert out["report"]["ratio_to_floor"] < 1.5                          # measured 0.45


def test_retriangulation_keeps_every_boundary_loop_on_its_source_loop():
    V, F = wavy_tube()
    Vt, Ft = retriangulate(V, F, target_edge="3%")
    loops = check_surface(Vt, Ft)[2]
    assert len(loops) == 2
    ends = sorted(np.round(Vt[loop, 2].mean(), 12) for loop in loops)
    assert ends == [-0.5, 0.5]


@pytest.mark.parametrize("method", ["isotropic", "decimate"])
def test_retriangulation_of_a_torus_keeps_its_genus(method):
    V, F = torus(n_major=96, n_minor=40)
    Vt, Ft = retriangulate(V, F, method=method, target_edge="3%")
    n, m = Vt.shape[0], Ft.shape[0]
    assert n - 3 * m // 2 + m == 0 and vertex_components(Ft, n)[1] == 1     # Euler characteristic 0


def test_non_manifold_input_names_its_edges():
    from curvdetail import MeshError

    V, F = torus()
    V2 = np.vstack([V, [[0.0, 0.0, 2.0]]])
    F2 = np.vstack([F, [[F[0, 0], F[0, 1], V.shape[0]]]])               # a fin on edge F[0, :2]
    with pytest.raises(MeshError) as refused:
        remesh_experiment(V2, F2, target_edge="3%")
    assert refused.value.count == 1 and refused.value.first == [sorted(F[0, :2].tolist())]


@pytest.mark.parametrize("apart", [True, False])
def test_two_spheres_touching_at_a_vertex_stay_two_pieces(apart, monkeypatch):
    # two vertices at one position (cow.off has a pair): pymeshlab's remeshing merges them, which
    # glued the pieces there; they are moved apart first (by APART of their one-ring)
    from curvdetail.curvature.testing import icosphere
    from curvdetail.remesh import RemeshError

    V, F = icosphere(subdivisions=3)
    v = V[0]
    B = V + 2 * v                        # B's vertex -v lands on A's vertex v
    assert np.flatnonzero(np.all(np.isclose(B, v, atol=1e-15), axis=1)).size == 1
    W = np.vstack([V, B])
    W[V.shape[0] + np.flatnonzero(np.all(np.isclose(B, v, atol=1e-15), axis=1))] = v    # exactly
    T = np.vstack([F, F + V.shape[0]])
    if not apart:
        import importlib

        monkeypatch.setattr(importlib.import_module("curvdetail.remesh.retriangulate"), "APART", 0.0)
        with pytest.raises(RemeshError):
            retriangulate(W, T, target_edge="3%")
        return
    Vt, Ft = retriangulate(W, T, target_edge="3%")
    assert vertex_components(Ft, Vt.shape[0])[1] == 2


@pytest.mark.parametrize("relocate", [True, False])
def test_detail_stays_on_its_own_sheet_where_two_lie_close(relocate, monkeypatch):
    # two spheres 0.001 apart; the target's first one is 2 % smaller, so near the gap the source's
    # first sphere is closer to the target's second. Known answer: a closed piece's detail sums
    # to zero, and the measure carried on the edges keeps each piece's total where its samples land
    import importlib

    from curvdetail.curvature.testing import icosphere
    from curvdetail.remesh import transfer_curvature

    V, F = icosphere(subdivisions=3)
    n = V.shape[0]
    Vs = np.vstack([V, V + [2.001, 0.0, 0.0]])
    Vt = np.vstack([0.98 * V, V + [2.001, 0.0, 0.0]])
    Fs = np.vstack([F, F + n])
    if not relocate:
        monkeypatch.setattr(importlib.import_module("curvdetail.remesh.transfer"), "_facing_side",
                            lambda *args: None)
    Dt = transfer_curvature(Vs, Fs, Vt, Fs, metric="target")
    first = np.abs(Dt[:n].sum(axis=0)).max() / np.abs(Dt).sum()
    assert (first < 1e-12) == relocate           # moved to the other sphere without the check
    # in the source's metric each piece's detail is integrated on its own triangles: zero
    Dt = transfer_curvature(Vs, Fs, Vt, Fs)
    assert np.abs(Dt[:n].sum(axis=0)).max() < 1e-12 * np.abs(Dt).sum()


def test_a_closed_surface_with_a_reversed_triangle_is_refused():
    from curvdetail import MeshError
    from curvdetail.curvature.testing import icosphere

    V, F = icosphere(subdivisions=2)
    F[7] = F[7, ::-1]
    with pytest.raises(MeshError):         # a closed surface has no boundary to show it otherwise
        remesh_experiment(V, F, target_edge="5%")
