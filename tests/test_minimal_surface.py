"""minimal_surface: catenoid, plane, fixed vertices, stopping rule, collapse, bad input."""

import doctest
import importlib
import re

import numpy as np
import pytest
from scipy.optimize import brentq

from curvdetail import (ConstraintError, MeshError, boundary_vertices, cotan_laplacian,
                        minimal_surface)
from curvdetail.curvature.errors import CurvdetailError
from curvdetail.curvature.geometry import bbox_diagonal, face_double_areas
from curvdetail.curvature.testing import cylinder, grid

from conftest import every_backend


def _catenoid_parameter():
    # a cosh(0.5 / a) = 1 has two roots; the stable (outer) catenoid is the larger, a ~ 0.848
    a = brentq(lambda a: a * np.cosh(0.5 / a) - 1.0, 0.6, 1.0)
    assert abs(a - 0.848) < 1e-3
    return a


def test_catenoid_radius_matches_cosh_profile():
    # Two unit circles at z = +-0.5 span the catenoid r(z) = a cosh(z / a). From the 64 x 33
    # cylinder grid the iteration's shape converges (normal step 1e-11) within 20 steps; the
    # remaining radial error, 4.4e-4, is the cotangent discretization's (O(h^2), h ~ 0.1).
    V, F = cylinder(radius=1.0, height=1.0, n_around=64, n_along=33)
    X = minimal_surface(V, F, boundary_vertices(F), tol=1e-9, max_iterations=60)
    assert X.converged
    a = _catenoid_parameter()
    radial_error = np.hypot(X[:, 0], X[:, 1]) - a * np.cosh(X[:, 2] / a)
    assert np.abs(radial_error).max() < 1e-3


def test_planar_boundary_spans_the_plane():
    V, F = grid(9, 9)
    V[:, 2] = V[:, 0] * (1 - V[:, 0]) * V[:, 1] * (1 - V[:, 1])
    X = minimal_surface(V, F, boundary_vertices(F), tol=1e-12)
    assert np.abs(X[:, 2]).max() < 1e-12


def test_fixed_vertices_keep_their_positions(load_mesh):
    V, F = load_mesh("mannequin_ear.obj")
    b = boundary_vertices(F)
    X = minimal_surface(V, F, b)
    assert np.array_equal(X[b], V[b])


def test_area_decreases(load_mesh):
    # each Pinkall-Polthier step minimizes the Dirichlet energy, an upper bound of the area
    V, F = load_mesh("mannequin_nose.obj")
    areas = []
    X = minimal_surface(V, F, boundary_vertices(F), max_iterations=5, tol=1e-12)
    for k in range(1, 6):
        Y = minimal_surface(V, F, boundary_vertices(F), max_iterations=k, tol=1e-12)
        areas.append(face_double_areas(Y, F).sum())
    assert np.all(np.diff([face_double_areas(V, F).sum()] + areas) < 0)
    assert np.array_equal(Y, X)


def test_nose_converges_with_the_default_tolerance(load_mesh):
    # Regression: with the full step as the criterion the nose never converged (2e-4 of the
    # diagonal after 200 steps, all of it tangential sliding); the normal step falls below the
    # default 1e-4 after ~45 steps while vertices still slide by ~7e-4 per step.
    V, F = load_mesh("mannequin_nose.obj")
    X = minimal_surface(V, F, boundary_vertices(F))
    assert X.converged and X.iterations < 200
    assert X.last_step < 1e-4 <= X.last_full_step


def test_callback_sees_every_step_and_the_stopping_quantity(load_mesh):
    V, F = load_mesh("terrainA_1k.obj")
    seen = []
    X = minimal_surface(V, F, boundary_vertices(F), callback=lambda i, s: seen.append((i, s)))
    assert [i for i, _ in seen] == list(range(1, X.iterations + 1))
    assert seen[-1][1] == X.last_step < 1e-4 <= seen[-2][1]


def test_max_iterations_stops_without_converging(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    X = minimal_surface(V, F, boundary_vertices(F), max_iterations=2, tol=1e-12)
    assert X.iterations == 2 and not X.converged and X.last_step > 1e-12


def test_circles_too_far_apart_collapse_with_a_clear_error():
    # no catenoid spans two unit circles more than 1.3255 apart: the neck pinches off
    V, F = cylinder(radius=1.0, height=2.0, n_around=32, n_along=21)
    with pytest.raises(MeshError) as e:
        minimal_surface(V, F, boundary_vertices(F), max_iterations=500)
    assert e.value.count > 0 and len(e.value.first) == 3        # the collapsed triangles


def test_no_fixed_vertex_is_refused():
    V, F = grid(4, 4)
    with pytest.raises(ConstraintError) as e:
        minimal_surface(V, F, [])
    assert (e.value.parameter, e.value.count) == ("fixed", 0)


def test_fixed_out_of_range_is_refused_with_the_index():
    V, F = grid(4, 4)
    with pytest.raises(ConstraintError, match=r"\[0, 16\)") as e:
        minimal_surface(V, F, [0, 99])
    assert (e.value.parameter, e.value.count, e.value.first) == ("fixed", 1, [99])


@pytest.mark.parametrize("kwargs, pattern", [
    ({"max_iterations": 0}, "max_iterations=0"), ({"max_iterations": 2.5}, r"max_iterations=2\.5"),
    ({"max_iterations": True}, "max_iterations=True"), ({"max_iterations": "5"}, "max_iterations='5'"),
    ({"max_iterations": float("inf")}, "max_iterations=inf"), ({"max_iterations": None}, "max_iterations=None"),
    ({"tol": 0.0}, "tol=0.0"), ({"tol": np.nan}, "tol=nan"), ({"tol": None}, "tol=None"),
    ({"tol": "5"}, "tol='5'"), ({"tol": 10 ** 400}, "tol=1000"), ({"callback": 3}, "callback=3"),
])
def test_bad_iteration_settings_are_refused(kwargs, pattern):
    V, F = grid(4, 4)
    with pytest.raises(CurvdetailError, match=pattern) as e:
        minimal_surface(V, F, boundary_vertices(F), **kwargs)
    assert e.value.parameter == next(iter(kwargs))


def test_result_is_scale_equivariant(load_mesh):
    V, F = load_mesh("mannequin_ear.obj")
    b = boundary_vertices(F)
    X0 = minimal_surface(V, F, b, max_iterations=3, tol=1e-12)
    X1 = minimal_surface(4.0 * V, F, b, max_iterations=3, tol=1e-12)
    assert np.abs(X1 - 4.0 * X0).max() < 1e-10 * 4.0 * bbox_diagonal(V)


def test_stopping_rule_is_relative_to_the_bbox_diagonal(load_mesh):
    # the same shape at ten times the size stops after the same steps, with the same relative step
    V, F = load_mesh("mannequin_nose.obj")
    b = boundary_vertices(F)
    X1 = minimal_surface(V, F, b, tol=1e-3)
    X10 = minimal_surface(10.0 * V, F, b, tol=1e-3)
    assert X1.converged and X10.converged
    assert X1.iterations == X10.iterations > 1
    assert X10.last_step == pytest.approx(X1.last_step, rel=1e-9)


def test_each_piece_settles_against_its_own_size(load_mesh):
    # nose and ear in one mesh, the ear 10 units away: against the whole mesh's diagonal the
    # nose counted as settled after 4 of its 44 steps; now the pair stops when the slower piece
    # does, and the nose part is the nose's own minimal surface
    Vn, Fn = load_mesh("mannequin_nose.obj")
    Ve, Fe = load_mesh("mannequin_ear.obj")
    V = np.vstack([Vn, Ve + [10.0, 0.0, 0.0]])
    F = np.vstack([Fn, Fe + Vn.shape[0]])
    both = minimal_surface(V, F, boundary_vertices(F))
    nose = minimal_surface(Vn, Fn, boundary_vertices(Fn))
    ear = minimal_surface(Ve, Fe, boundary_vertices(Fe))
    assert both.converged and both.iterations == max(nose.iterations, ear.iterations)
    assert np.abs(both[:Vn.shape[0]] - nose).max() < 1e-4 * bbox_diagonal(Vn)


@pytest.mark.parametrize("step", ["normal", "full"])
def test_a_settled_piece_stops_while_the_others_go_on(load_mesh, step):
    # the ear settles after 3 steps alone; beside the nose (44 steps) it went on sliding for 41
    # more and came back 1.2e-2 of its diagonal from its own result: each piece's result must not
    # depend on how long the others take (nor, past its own tol, on max_iterations)
    Vn, Fn = load_mesh("mannequin_nose.obj")
    Ve, Fe = load_mesh("mannequin_ear.obj")
    V = np.vstack([Vn, Ve + [10.0, 0.0, 0.0]])
    F = np.vstack([Fn, Fe + Vn.shape[0]])
    tol = 1e-4 if step == "normal" else 1e-3
    both = minimal_surface(V, F, boundary_vertices(F), step=step, tol=tol)
    nose = minimal_surface(Vn, Fn, boundary_vertices(Fn), step=step, tol=tol)
    ear = minimal_surface(Ve, Fe, boundary_vertices(Fe), step=step, tol=tol)
    assert both.converged and nose.converged and ear.converged
    assert ear.iterations < nose.iterations == both.iterations
    assert np.abs(both[:Vn.shape[0]] - nose).max() < 1e-10 * bbox_diagonal(Vn)
    assert np.abs(both[Vn.shape[0]:] - (ear + [10.0, 0.0, 0.0])).max() < 1e-10 * bbox_diagonal(Ve)


def test_order_of_the_fixed_vertices_does_not_matter(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    b = boundary_vertices(F)
    shuffled = np.random.default_rng(0).permutation(b)
    X = minimal_surface(V, F, b, max_iterations=3, tol=1e-12)
    Y = minimal_surface(V, F, shuffled, max_iterations=3, tol=1e-12)
    assert np.abs(X - Y).max() < 1e-12 * bbox_diagonal(V)
    assert np.array_equal(Y[b], V[b])


def test_docstring_example_runs():
    result = doctest.testmod(importlib.import_module("curvdetail.curvature.minimal_surface"))
    assert result.attempted > 0 and result.failed == 0, result


@pytest.mark.parametrize("backend", every_backend())
def test_steps_are_the_textbook_iteration_with_one_symbolic_analysis(load_mesh, backend):
    # three Pinkall-Polthier steps written out with scipy's spsolve, against minimal_surface,
    # which factors once and then only refactors the numeric values on the same pattern
    import scipy.sparse.linalg as spla

    from curvdetail.curvature import sparse_solver

    V, F = load_mesh("mannequin_nose.obj")
    fixed = boundary_vertices(F)
    free = np.setdiff1d(np.arange(V.shape[0]), fixed)
    X = V.copy()
    for _ in range(3):
        L = cotan_laplacian(X, F).tocsr()
        X = X.copy()
        X[free] = spla.spsolve(L[free][:, free].tocsc(), -(L[free][:, fixed] @ X[fixed]))
    before = sparse_solver.factorization_count
    got = minimal_surface(V, F, fixed, max_iterations=3, tol=1e-300, backend=backend)
    assert got.iterations == 3 and sparse_solver.factorization_count == before + 3
    assert np.abs(got - X).max() < 1e-10 * np.abs(V).max()


def test_far_from_the_origin_the_iteration_loses_no_digits():
    # UTM / ECEF: the right-hand side L_fc X_c is formed about the fixed vertices' centre
    V, F = grid(12, 12)
    V[:, 2] = 0.1 * np.sin(3 * V[:, 0]) * np.cos(2 * V[:, 1])
    shift = np.array([4e6, 5e5, 3e3])
    far = V + shift
    near = far - shift                        # the same triangles, exactly, near the origin
    b = boundary_vertices(F)
    X_near = minimal_surface(near, F, b, max_iterations=5)
    X_far = minimal_surface(far, F, b, max_iterations=5)
    # (5e-9 of the diagonal before, 4e-10 now: the coordinates' own spacing out there is 5e-10)
    assert np.abs((np.asarray(X_far) - shift) - np.asarray(X_near)).max() < 2e-9 * bbox_diagonal(V)


def test_reversed_triangles_stop_as_the_oriented_mesh_does(load_mesh):
    # the step is measured along vertex normals, which reversed triangles cancelled: the nose
    # ran all 200 steps and came back "not converged" (44 steps when oriented)
    V, F = load_mesh("mannequin_nose.obj")
    b = boundary_vertices(F)
    Fr = F.copy()
    Fr[::3] = Fr[::3, ::-1]
    X, Xr = minimal_surface(V, F, b), minimal_surface(V, Fr, b)
    assert X.converged and Xr.converged and Xr.iterations == X.iterations < 100
    assert np.abs(Xr - X).max() < 1e-12 * bbox_diagonal(V)


def _moebius_strip(n_around=60, n_across=6):
    u = np.linspace(0, 2 * np.pi, n_around, endpoint=False)
    w = np.linspace(-0.3, 0.3, n_across)
    U, W = np.meshgrid(u, w, indexing="ij")
    V = np.stack([(1 + W * np.cos(U / 2)) * np.cos(U), (1 + W * np.cos(U / 2)) * np.sin(U),
                  W * np.sin(U / 2)], -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n_around), np.arange(n_across - 1), indexing="ij")
    i, j = i.ravel(), j.ravel()
    last = i == n_around - 1                       # glued to the first column with a half turn
    a, d = i * n_across + j, i * n_across + j + 1
    b = np.where(last, n_across - 1 - j, (i + 1) * n_across + j)
    c = np.where(last, n_across - 2 - j, (i + 1) * n_across + j + 1)
    return V, np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])


def test_a_moebius_strip_which_no_orientation_fits_converges():
    from curvdetail.curvature.topology import misoriented_edges

    V, F = _moebius_strip()
    assert misoriented_edges(F).shape[0] > 0              # not orientable
    b = boundary_vertices(F)
    X = minimal_surface(V, F, b)
    assert X.converged and X.iterations < 50
    assert np.array_equal(X[b], V[b])
    full = minimal_surface(V, F, b, step="full", max_iterations=X.iterations)
    assert np.abs(full - X).max() < 1e-12                 # the same steps, another stopping measure


def test_full_step_measure_needs_no_orientation_and_gives_the_same_surface(load_mesh):
    # the geometry of a step does not depend on orientation: with step="full" a mesh with
    # reversed triangles gives the oriented mesh's surface, step by step
    V, F = load_mesh("mannequin_nose.obj")
    b = boundary_vertices(F)
    Fr = F.copy()
    Fr[::3] = Fr[::3, ::-1]
    X = minimal_surface(V, F, b, max_iterations=6, step="full")
    Xr = minimal_surface(V, Fr, b, max_iterations=6, step="full")
    assert X.iterations == Xr.iterations == 6 and not Xr.converged
    assert np.abs(X - Xr).max() < 1e-12 * bbox_diagonal(V)
    assert X.last_step == X.last_full_step > minimal_surface(V, F, b, max_iterations=6).last_step


def test_full_step_measure_stops_on_the_whole_displacement():
    V, F = grid(9, 9)
    V[:, 2] = V[:, 0] * (1 - V[:, 0]) * V[:, 1] * (1 - V[:, 1])
    seen = []
    X = minimal_surface(V, F, boundary_vertices(F), step="full", tol=1e-6,
                        callback=lambda i, s: seen.append(s))
    assert X.converged and X.last_full_step < 1e-6 and seen[-1] == X.last_full_step
    assert all(s >= 1e-6 for s in seen[:-1])
    with pytest.raises(ValueError, match="step='sideways'"):
        minimal_surface(V, F, boundary_vertices(F), step="sideways")


def test_aligned_normals_take_the_largest_triangle_as_reference():
    # a flat fan around vertex 0 with two triangles reversed, and a small triangle standing
    # perpendicular to it: taken as the reference, the small one flipped the fan's normals
    # into its own plane ([0, 1, 0] instead of the fan's -z)
    from curvdetail.curvature.geometry import vertex_normals as _vertex_normals

    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0], [0.05, 0, 0.05]], dtype=float)
    fan = [[0, 1, 2], [0, 3, 2], [0, 3, 4], [0, 1, 4]]          # the second and fourth reversed
    for F in (np.array(fan + [[0, 1, 5]]), np.array([[0, 1, 5]] + fan)):
        n0 = _vertex_normals(V, F, aligned=True)[0]
        assert abs(abs(n0[2]) - 1.0) < 0.05, F.tolist()


@pytest.mark.parametrize("step", ["half", np.array(["full"]), ["normal", "full"]])
def test_a_step_that_is_not_normal_or_full_is_refused(step):
    # an array was compared with ``in`` element-wise: np.array(["full"]) passed as the step
    V, F = grid(4, 4)
    with pytest.raises(CurvdetailError, match="'half'" if isinstance(step, str) else "ndarray|list") as e:
        minimal_surface(V, F, boundary_vertices(F), step=step)
    assert e.value.parameter == "step"


def test_a_neck_pinching_into_needles_is_refused_not_converged():
    # two unit circles 2 apart span no catenoid. On this coarse grid the neck's triangles shrank
    # into needles (largest |cot| 3.4e7, area 1.4e-7 of their start) without reaching the
    # absolute zero-area threshold, and the result came back converged after 10 steps with a
    # neck of radius 2e-7
    V, F = cylinder(radius=1.0, height=2.0, n_around=24, n_along=8)
    with pytest.raises(MeshError) as e:
        minimal_surface(V, F, boundary_vertices(F))
    assert (e.value.count, e.value.first) == (48, [72, 73, 74])


def test_healthy_results_keep_their_angles_clear_of_the_needle_threshold(load_mesh):
    # the needle check (|cot| above 1e6 and 100 times the input's) must not touch real results:
    # they stay below ~100 (the nose's after its 44 steps: under 20)
    from curvdetail.curvature.geometry import corner_cotangents
    from curvdetail.curvature.minimal_surface import DEGENERATE_COTANGENT

    V, F = load_mesh("mannequin_nose.obj")
    X = minimal_surface(V, F, boundary_vertices(F))
    largest = np.abs(corner_cotangents(np.asarray(X), F, lengths=False)[0]).max()
    assert X.converged and largest < 20 and DEGENERATE_COTANGENT == 1e6


def test_an_input_sliver_is_not_taken_for_a_collapse():
    # a bump with a flat rim, and a flap 1e-8 high on a rim edge: its |cot| is 1.25e7 in the
    # input already (its vertices are fixed, it stays so). Only a growth past the input's counts
    from curvdetail.curvature import boundary_edges
    from curvdetail.curvature.geometry import corner_cotangents

    V, F = grid(5, 5)
    V[:, 2] = V[:, 0] * (1 - V[:, 0]) * V[:, 1] * (1 - V[:, 1])
    a, b = next(e for e in boundary_edges(F) if set(e) == {1, 2})      # (0.25, 0) and (0.5, 0)
    V = np.vstack([V, [0.375, -1e-8, 0.0]])
    F = np.vstack([F, [b, a, 25]])                                       # wound as its neighbour
    assert np.abs(corner_cotangents(V, F[-1:], lengths=False)[0]).max() > 1e7
    X = minimal_surface(V, F, boundary_vertices(F), tol=1e-12)
    assert X.converged and np.abs(X[:, 2]).max() < 1e-12


def test_free_boundary_vertices_are_refused():
    # a cylinder held at its middle ring only: the free rims shrank onto it, every vertex ended
    # at z = 0 (area 0.10 of 6.27) and the result came back converged after 2 steps
    V, F = cylinder(radius=1.0, height=1.0, n_around=32, n_along=17)
    ring = np.flatnonzero(np.isclose(V[:, 2], 0.0))
    with pytest.raises(ConstraintError) as e:
        minimal_surface(V, F, ring)
    assert (e.value.parameter, e.value.count, e.value.first) == ("fixed", 64, [0, 1, 2])
    b = boundary_vertices(F)
    with pytest.raises(ConstraintError) as e:
        minimal_surface(V, F, np.union1d(ring, np.delete(b, 7)))
    assert (e.value.parameter, e.value.count, e.value.first) == ("fixed", 1, [7])
    # the ring and both rims: three curves, a valid constraint
    X = minimal_surface(V, F, np.union1d(ring, b))
    assert X.converged and np.array_equal(X[ring], V[ring])


def test_a_degenerating_disk_blames_the_iteration_not_the_boundary(load_mesh):
    # a disk's boundary always spans a minimal surface; at tol=1e-6 the nose's vertices slide
    # until a triangle degenerates. The message said the fixed vertices "span no minimal surface
    # of this topology"; it now says where the run got to and what to change
    V, F = load_mesh("mannequin_nose.obj")
    with pytest.raises(MeshError) as error:
        minimal_surface(V, F, boundary_vertices(F), tol=1e-6, max_iterations=2000)
    message = str(error.value)
    assert re.match(r"minimal surface iteration (\d+): 1 triangle collapsed into needles", message)
    iteration = int(re.match(r"minimal surface iteration (\d+)", message).group(1))
    assert 600 < iteration < 866                              # 866: the zero-area threshold
    assert re.search(r"the step before moved the shape by \d\.\d\de-06 of the bbox diagonal \(normal to "
                     r"the surface; tol 1e-06\)\. This piece is a disk, whose boundary always spans a "
                     r"minimal surface: the iteration itself degraded the triangles", message)
    assert f"max_iterations below {iteration}" in message and "no minimal surface of this" not in message


def test_a_pinned_inner_vertex_is_named_as_the_cause(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    with pytest.raises(MeshError, match=r"\(first: 300\)") as e:          # the pinned vertex
        minimal_surface(V, F, np.union1d(boundary_vertices(F), [300]))
    assert e.value.count > 0                                             # collapsed triangles around it



def test_a_collapse_in_the_first_step_is_not_told_to_stop_earlier():
    # the first step itself collapsed: "or stop earlier (a larger tol, or max_iterations below 1)"
    # named what nothing accepts (max_iterations >= 1) and no tol can do (it is checked after a step)
    from curvdetail.curvature.testing import icosphere

    V, F = icosphere(2)
    with pytest.raises(MeshError) as error:
        minimal_surface(V, F, [0, 1, 2, 3])
    message = str(error.value)
    assert message.startswith("minimal surface iteration 1: ")
    assert message.endswith("into spikes. Fix whole curves (e.g. the boundary only)."), message
    assert "max_iterations" not in message and "tol" not in message


def test_remaining_estimate_bounds_the_distance_to_the_limit_near_the_critical_height():
    # two unit circles 1.32 apart, just below the largest height a catenoid spans (1.3255): the
    # steps contract by only ~0.92, and the default tol stops 1.2e-3 of the diagonal (normal to
    # the surface) from where the iteration converges, twelve times tol; the estimate says so
    from curvdetail.curvature.geometry import vertex_normals as _vertex_normals

    V, F = cylinder(radius=1.0, height=1.32, n_around=64, n_along=33)
    b = boundary_vertices(F)
    steps = []
    X = minimal_surface(V, F, b, callback=lambda i, s: steps.append(s))
    limit = minimal_surface(V, F, b, tol=1e-7, max_iterations=300)
    assert X.converged and limit.converged and limit.iterations > 3 * X.iterations
    distance = np.abs(np.einsum("ij,ij->i", X - limit, _vertex_normals(np.asarray(limit), F))).max()
    distance /= bbox_diagonal(V)
    assert X.contraction == steps[-1] / steps[-2] and 0.9 < X.contraction < 0.95
    assert distance > 10 * 1e-4 and 0.8 * distance < X.remaining_estimate < 1.2 * distance


def test_remaining_estimate_on_the_regular_catenoid_is_below_tol():
    # away from the critical height the steps contract by 0.38: the last step bounds the rest
    V, F = cylinder(radius=1.0, height=1.0, n_around=64, n_along=33)
    steps = []
    X = minimal_surface(V, F, boundary_vertices(F), callback=lambda i, s: steps.append(s))
    rho = steps[-1] / steps[-2]
    assert X.iterations == 7 and X.contraction == rho and 0.35 < rho < 0.42
    assert X.remaining_estimate == pytest.approx(X.last_step * rho / (1 - rho), rel=1e-12)
    assert X.remaining_estimate < 1e-4


def test_figures_survive_copy_slicing_arithmetic_and_pickling(load_mesh):
    # a MinimalSurfaceResult lost its figures on .copy(), arithmetic and pickling (the results of
    # a ProcessPoolExecutor)
    import copy
    import pickle

    V, F = load_mesh("mannequin_nose.obj")
    X = minimal_surface(V, F, boundary_vertices(F), max_iterations=3, tol=1e-12)
    figures = {name: getattr(X, name) for name in ("iterations", "converged", "last_step", "last_full_step",
                                                   "contraction", "remaining_estimate")}
    assert figures["iterations"] == 3 and figures["converged"] is False
    copies = [X.copy(), copy.deepcopy(X), X[:10], 2.0 * X] + [pickle.loads(pickle.dumps(X, protocol=p))
                                                              for p in range(2, pickle.HIGHEST_PROTOCOL + 1)]
    for Y in copies:
        assert {name: getattr(Y, name) for name in figures} == figures
    for Y in copies[:2] + copies[4:]:
        assert np.array_equal(Y, X) and Y.flags.writeable
