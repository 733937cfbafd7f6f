"""Shape editing of a boundary: the loop lands on its displaced positions, the rest follows."""

import warnings

import numpy as np
import pytest

from curvdetail import edit_boundary, sine_displacement
from curvdetail.curvature.boundary_editing import boundary_loop, loop_of_boundary_edges
from curvdetail.curvature.errors import ConstraintError, CurvdetailError, FoldedTrianglesWarning, MeshError
from curvdetail.curvature.testing import cylinder, grid


# 5 % of the extent in three periods folds a triangle with the one-ring stage and warns; where
# the boundary lands is what is tested here
@pytest.mark.filterwarnings("ignore::curvdetail.curvature.errors.FoldedTrianglesWarning")
def test_boundary_lands_exactly_on_the_sine_displacement(load_mesh):
    V, F = load_mesh("terrainA_1k.obj")
    amp = 0.05 * np.ptp(V[:, 0])
    X, info = edit_boundary(V, F, sine_displacement(amp, periods=3, axis=2), return_info=True)
    b, s = info["boundary"], info["arc_length"]
    assert np.array_equal(X[b, :2], V[b, :2])
    assert np.allclose(X[b, 2] - V[b, 2], amp * np.sin(2 * np.pi * 3 * s), atol=1e-12)
    assert np.all(np.isfinite(X))


def test_zero_displacement_reproduces_the_patch(load_mesh):
    V, F = load_mesh("terrainA_1k.obj")
    X = edit_boundary(V, F, lambda s, P: np.zeros_like(P))
    assert np.abs(X - V).max() < 1e-8 * np.linalg.norm(np.ptp(V, axis=0))


def test_rigid_translation_of_the_boundary_translates_the_patch(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    shift = np.array([0.1, -0.2, 0.3])
    X = edit_boundary(V, F, lambda s, P: np.tile(shift, (P.shape[0], 1)))
    # L annihilates translations: the boundary detail is unchanged and the patch just moves
    assert np.abs(X - (V + shift)).max() < 1e-8 * np.linalg.norm(np.ptp(V, axis=0))


@pytest.mark.parametrize("name", ["mannequin_ear.obj", "mannequin_nose.obj"])
@pytest.mark.parametrize("degrees, scale", [(30.0, 1.0), (90.0, 1.0), (0.0, 2.0), (30.0, 1.5)])
def test_a_boundary_turned_or_scaled_as_a_whole_moves_the_patch_with_it(load_mesh, name, degrees, scale):
    # SPEC: a similarity of every constraint moves the result by it. Spreading the whole move
    # harmonically gave the trunk turned by 30 degrees 1.8 diagonals off, scaled by 2 7.9
    V, F = load_mesh(name)
    c, a = V.mean(0), np.radians(degrees)
    R = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    X = edit_boundary(V, F, lambda s, P: scale * (P - c) @ R.T + c - P)
    expected = scale * (V - c) @ R.T + c
    assert np.abs(X - expected).max() < 1e-8 * scale * np.linalg.norm(V.max(0) - V.min(0))


def test_boundary_loop_follows_the_triangles_and_covers_the_boundary():
    V, F = grid(6, 5)
    loop = boundary_loop(F)
    assert loop.size == 2 * (6 + 5) - 4 and loop[0] == loop.min()
    # consecutive loop vertices form boundary edges oriented as in their triangle
    directed = {(int(f[a]), int(f[(a + 1) % 3])) for f in F for a in range(3)}
    assert all((int(p), int(q)) in directed for p, q in zip(loop, np.roll(loop, -1)))


def test_the_loop_of_a_long_strip_is_every_vertex_in_order():
    # a 2 x 100,000 strip: every vertex is on the boundary (the walk is no Python step per vertex)
    V, F = grid(100_000, 2)
    loop = boundary_loop(F)
    assert loop.size == V.shape[0] and np.array_equal(np.sort(loop), np.arange(V.shape[0]))
    edges = np.column_stack([loop, np.roll(loop, -1)])
    # the loop's edges are the mesh's boundary edges, as its triangles orient them
    assert np.array_equal(loop_of_boundary_edges(edges[np.random.default_rng(0).permutation(loop.size)]), loop)


@pytest.mark.parametrize("edges, count, first", [
    ([[0, 1], [1, 2], [2, 1]], None, [0, 1]),           # the walk from 0 runs into 1, which ends two edges
    ([[0, 1], [1, 0], [0, 2]], 1, [0]),                 # vertex 0 starts two edges
    ([[0, 1], [1, 2]], None, [2]),                      # nothing leaves vertex 2
    ([[0, 1], [1, 2], [2, 0], [3, 4], [4, 3]], 5, [0]),  # 5 edges, the loop through 0 has 3
])
def test_boundary_edges_that_make_no_simple_loop_are_named(edges, count, first):
    with pytest.raises(MeshError) as e:
        loop_of_boundary_edges(np.array(edges))
    assert (e.value.parameter, e.value.count, e.value.first) == ("F", count, first)


def test_a_mesh_with_two_boundary_loops_is_refused():
    V, F = cylinder(n_around=16, n_along=5)
    with pytest.raises(MeshError) as e:
        edit_boundary(V, F, sine_displacement(0.1))
    assert (e.value.parameter, e.value.count) == ("F", 32)      # 32 boundary edges, 16 in the loop


def test_displacement_array_of_the_wrong_shape_is_refused(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    # given or returned by a callable alike; complex or bool values are refused, not cast
    for displacement in (np.zeros((3, 3)), lambda s, P: np.zeros(3), lambda s, P: np.zeros((s.size, 3)) + 1j,
                         lambda s, P: np.ones((s.size, 3), dtype=bool)):
        with pytest.raises(ConstraintError) as e:
            edit_boundary(V, F, displacement)
        assert e.value.parameter == "displacement"


def test_rest_boundary_detail_keeps_the_inside_detail(load_mesh):
    V, F = load_mesh("terrainA_1k.obj")
    X, info = edit_boundary(V, F, sine_displacement(0.3, periods=2, axis=2), method="paper",
                            boundary_detail="rest", return_info=True)
    b, ed = info["boundary"], info["editor"]
    assert np.array_equal(info["boundary_detail"], ed.detail[b])
    # consistent detail constraints: the curvature stage gives back the rest detail everywhere
    X2, D = ed.solve(positions=X[b], details=ed.detail[b], return_details=True)
    assert np.abs(D - ed.detail).max() < 1e-9 * np.abs(ed.detail).max()
    assert np.array_equal(X2, X)


def test_the_sine_runs_along_the_arc_length_of_an_uneven_boundary():
    # uneven spacing along x: arc length and vertex count along the loop disagree
    V, F = grid(9, 9)
    V[:, 0] **= 2
    X, info = edit_boundary(V, F, sine_displacement(0.1, periods=1, axis=2), return_info=True)
    loop = info["boundary"]
    P = V[loop]
    edges = np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1)
    s = np.concatenate([[0.0], np.cumsum(edges)[:-1]]) / edges.sum()
    assert np.allclose(info["arc_length"], s, atol=1e-15)
    assert np.allclose(X[loop, 2] - V[loop, 2], 0.1 * np.sin(2 * np.pi * s), atol=1e-12)


def test_unknown_boundary_detail_mode_is_refused(load_mesh):
    V, F = load_mesh("terrainA_1k.obj")
    with pytest.raises(CurvdetailError) as e:
        edit_boundary(V, F, sine_displacement(0.1), boundary_detail="rotate")
    assert (e.value.parameter, e.value.value) == ("boundary_detail", "rotate")


def test_stacked_relations_keep_a_large_boundary_sine_free_of_folds(load_mesh):
    # a sine in z of 8 % of the patch's extent: the paper's one-ring curvature stage amplifies
    # the updated boundary detail and folds triangles (6 measured); one+two-ring folds none
    V, F = load_mesh("terrainA_1k.obj")
    f = sine_displacement(0.08 * np.ptp(V[:, :2], axis=0).max(), periods=2, axis=2)

    def folded(X):
        nz = np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]])[:, 2]
        return int((nz < 0).sum())

    assert folded(V) == 0
    with pytest.warns(FoldedTrianglesWarning):
        assert folded(edit_boundary(V, F, f, method="paper", relations="one-ring")) > 0
    assert folded(edit_boundary(V, F, f, method="paper", relations="one+two-ring")) == 0
    assert folded(edit_boundary(V, F, f)) == 0          # the rotation-aware default


def test_the_mesh_is_checked_and_its_laplacian_assembled_once(monkeypatch):
    import importlib

    module = importlib.import_module("curvdetail.curvature.cotan_laplacian")
    calls = []
    real = module._assemble_upper

    def counting(V, F, cot, check_manifold):
        calls.append(check_manifold)
        return real(V, F, cot, check_manifold)

    monkeypatch.setattr(module, "_assemble_upper", counting)
    V, F = grid(10, 10)
    V[:, 2] = 0.05 * np.sin(4 * V[:, 0])
    X, info = edit_boundary(V, F, sine_displacement(0.1, axis=2), method="paper", return_info=True)
    assert calls.count(True) == 1               # the checked rest-shape L (the editor's)
    from curvdetail import cotan_laplacian
    monkeypatch.setattr(module, "_assemble_upper", real)
    assert (info["editor"].laplacian != cotan_laplacian(V, F)).nnz == 0


@pytest.mark.parametrize("damage, first", [
    (lambda V, F: (V, np.vstack([F, F[:1]])), [162]),                                   # a doubled triangle
    (lambda V, F: (np.vstack([V, [0.5, 0.5, 1.0]]), np.vstack([F, [[F[40, 0], F[40, 1], V.shape[0]]]])),
     [(44, 45)]),                                                # a fin on edge F[40, :2] = (44, 45)
])
def test_a_malformed_mesh_is_named_before_its_boundary(damage, first):
    V, F = grid(10, 10)
    V, F = damage(V, F)
    with pytest.raises(MeshError) as e:
        edit_boundary(V, F, sine_displacement(0.1, axis=2))
    assert (e.value.parameter, e.value.count, e.value.first) == ("F", 1, first)


def test_a_doubled_triangle_is_named_not_the_broken_boundary_it_makes():
    # a doubled triangle takes its edges off the boundary: the loop breaks off (was a KeyError,
    # then "the boundary does not close")
    V, F = grid(10, 10)
    with pytest.raises(MeshError, match="meshing_remove_duplicate_faces") as e:        # the repair filter
        boundary_loop(np.vstack([F, F[:1, ::-1]]))
    assert (e.value.parameter, e.value.count, e.value.first) == ("F", 1, [0])


def test_a_boundary_that_does_not_close_is_a_mesh_error():
    from curvdetail.curvature.boundary_editing import loop_of_boundary_edges

    with pytest.raises(MeshError) as e:
        loop_of_boundary_edges(np.array([[0, 1], [1, 2], [3, 0]]))
    assert e.value.first == [2]                 # the vertex nothing leaves


@pytest.mark.parametrize("kwargs, message", [
    (dict(amplitude=0.1, axis=3), "axis=3"),
    (dict(amplitude=0.1, axis=True), "axis=True"),
    (dict(amplitude=0.1, axis=np.True_), "True"),
    (dict(amplitude=0.1, axis=2.0), r"axis=2\.0"),     # would index columns with a float
    (dict(amplitude=float("nan")), "amplitude=nan"),
    (dict(amplitude=0.1, periods=float("inf")), "periods=inf"),
    (dict(amplitude=0.1, phase="0"), "phase='0'"),
])
def test_sine_displacement_refuses_what_would_give_no_displacement(kwargs, message):
    with pytest.raises(CurvdetailError, match=message) as e:
        sine_displacement(**kwargs)
    assert e.value.parameter == next(iter(k for k in kwargs if k != "amplitude"), "amplitude")


def test_sine_displacement_takes_numpy_scalars():
    f = sine_displacement(np.float32(2.0), periods=np.int64(1), axis=np.int64(2))
    assert np.allclose(f(np.array([0.25]), np.zeros((1, 3))), [[0.0, 0.0, 2.0]])


@pytest.mark.parametrize("flag", ["no", 0, None])
def test_return_info_must_be_a_bool(flag):
    V, F = grid(6, 6)
    with pytest.raises(CurvdetailError) as e:
        edit_boundary(V, F, sine_displacement(0.05, axis=2), return_info=flag)
    assert e.value.parameter == "return_info"


def test_return_info_takes_a_numpy_bool():
    V, F = grid(6, 6)
    X, info = edit_boundary(V, F, sine_displacement(0.05, axis=2), return_info=np.True_)
    assert info["boundary"].size == 20


def test_two_separate_disks_are_named_as_two_pieces_not_as_holes():
    V, F = grid(6, 6)
    V2 = np.vstack([V, V + [3.0, 0.0, 0.0]])
    F2 = np.vstack([F, F + V.shape[0]])
    for call in (lambda: boundary_loop(F2), lambda: edit_boundary(V2, F2, sine_displacement(0.1))):
        with pytest.raises(MeshError) as e:
            call()
        assert (e.value.parameter, e.value.count) == ("F", 2)


def test_a_reversed_boundary_triangle_is_named_as_an_orientation_problem():
    V, F = grid(6, 6)
    F = F.copy()
    F[0] = F[0, ::-1]                                   # a corner triangle
    with pytest.raises(MeshError, match="meshing_re_orient_faces_coherently") as e:      # the repair filter
        edit_boundary(V, F, sine_displacement(0.1))
    assert e.value.parameter == "F"


def test_two_closed_pieces_are_named_as_closed_not_as_pieces_with_boundaries():
    from curvdetail.curvature.testing import icosphere

    V, F = icosphere(subdivisions=1)
    with pytest.raises(MeshError) as e:
        boundary_loop(np.vstack([F, F + V.shape[0]]))
    assert (e.value.parameter, e.value.count) == ("F", 0)


def _onto_first_neighbour(s, P):
    d = np.zeros_like(P)
    d[1] = P[0] - P[1]                       # the loop's second vertex onto its first
    return d


@pytest.mark.filterwarnings("error")        # the refusal comes without numpy's RuntimeWarnings
@pytest.mark.parametrize("displacement, message", [
    (lambda s, P: -P, r"\b36\b"),                       # all 36 boundary vertices onto one point
    (lambda s, P: P.mean(axis=0) - P, r"\b36\b"),
    (lambda s, P: -P * [1.0, 1.0, 0.0], ""),            # onto a line
    (_onto_first_neighbour, ""),                        # a vertex onto its neighbour
])
def test_a_displacement_that_collapses_the_boundary_is_refused_without_warnings(displacement, message):
    # divide-by-zero and invalid-value warnings from the provisional surface's cotangents came
    # first, then "details: 36 rows are NaN or infinite", naming values the caller never passed
    V, F = grid(10, 10)
    V[:, 2] = 0.1 * np.sin(3 * V[:, 0])
    with pytest.raises(ConstraintError, match=message or None) as e:
        edit_boundary(V, F, displacement, method="paper")
    assert e.value.parameter == "displacement" and e.value.count >= 1
    # the advice: defined, no numpy warnings (a loop collapsed onto a point or a line does fold
    # the inside, and the fold warning says so)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        X = edit_boundary(V, F, displacement, method="paper", boundary_detail="rest")
        Y = None if message else edit_boundary(V, F, displacement)      # the rotation-aware default
    assert np.all(np.isfinite(X)) and (Y is None or np.all(np.isfinite(Y)))
    assert [w.category for w in caught if w.category is not FoldedTrianglesWarning] == []


@pytest.mark.filterwarnings("error")
def test_the_rotation_aware_default_refuses_a_boundary_moved_onto_one_point():
    V, F = grid(10, 10)
    V[:, 2] = 0.1 * np.sin(3 * V[:, 0])
    with pytest.raises(ConstraintError) as e:
        edit_boundary(V, F, lambda s, P: P.mean(axis=0) - P)
    assert (e.value.parameter, e.value.count) == ("displacement", 36)


@pytest.mark.filterwarnings("error")
def test_a_displaced_boundary_beyond_1e75_is_refused_before_any_algebra():
    # the callable's result was only checked for NaN: overflow warnings, then the editor's "positions"
    V, F = grid(10, 10)
    with pytest.raises(ConstraintError) as e:
        edit_boundary(V, F, lambda s, P: np.full(P.shape, 1e80))
    assert (e.value.parameter, e.value.count, e.value.first) == ("displacement", 36, [0, 1, 2])


@pytest.mark.filterwarnings("error")
def test_a_boundary_of_one_point_is_a_mesh_error_without_warnings():
    # the arc length divided by a loop length of 0 first (invalid-value warning)
    V, F = grid(6, 6)
    with pytest.raises(MeshError) as e:
        edit_boundary(np.zeros_like(V), F, sine_displacement(0.1))
    assert (e.value.parameter, e.value.value) == ("V", 0.0)


def test_a_displacement_callable_with_non_finite_values_is_named_as_such():
    V, F = grid(6, 6)

    def nan_at_the_start(s, P):
        d = np.zeros_like(P)
        d[0, 2] = np.nan
        return d

    with pytest.raises(ConstraintError) as e:
        edit_boundary(V, F, nan_at_the_start)
    assert (e.value.parameter, e.value.count, e.value.first) == ("displacement", 1, [0])


@pytest.mark.parametrize("kwargs", [dict(boundary_detail=np.array(["rest", "deformed"])),
                                    dict(relations=np.array(["one-ring", "one+two-ring"])),
                                    dict(backend=np.array(["auto", "splu"]))])
def test_options_given_as_arrays_are_refused_before_the_displacement_runs(kwargs):
    # numpy's "truth value of an array ... is ambiguous" before
    V, F = grid(6, 6)
    with pytest.raises(CurvdetailError, match="ndarray") as e:
        edit_boundary(V, F, lambda s, P: pytest.fail("the displacement ran"), **kwargs)
    assert e.value.parameter == next(iter(kwargs))


@pytest.mark.parametrize("raised", [IndexError("index 99 is out of bounds"), ValueError("my own check failed"),
                                    TypeError("unsupported operand"), KeyError("axis")])
def test_an_error_inside_the_displacement_callable_reaches_the_caller_unchanged(raised):
    # a ValueError or TypeError of the user's own was re-labelled "the displacement callable failed
    # (...); it must map (s, P) to a (b, 3) float array" and its traceback dropped (from None)
    V, F = grid(6, 6)

    def user_displacement(s, P):
        raise raised

    with pytest.raises(type(raised)) as caught:
        edit_boundary(V, F, user_displacement)
    assert caught.value is raised
    assert any(entry.name == "user_displacement" for entry in caught.traceback)     # where it went wrong


@pytest.mark.parametrize("displacement", [lambda s: np.zeros((s.size, 3)), lambda s, P, scale: P * scale])
def test_a_displacement_callable_that_does_not_take_s_and_p_is_named_before_it_runs(displacement):
    V, F = grid(6, 6)
    with pytest.raises(CurvdetailError, match=r"\(20, 3\)") as e:       # the shapes it must take and give
        edit_boundary(V, F, displacement)
    assert (e.value.parameter, e.value.count) == ("displacement", 20)



def test_a_displacement_callable_with_a_ragged_result_is_named_as_such():
    V, F = grid(6, 6)
    with pytest.raises(ConstraintError) as e:
        edit_boundary(V, F, lambda s, P: [[0.0, 0.0, 0.0], [0.0]])
    assert e.value.parameter == "displacement"


def _folded_against_rest(V, F, X):
    """Triangles whose normal in X points against their rest normal (dot < 0)."""
    def normals(Y):
        return np.cross(Y[F[:, 1]] - Y[F[:, 0]], Y[F[:, 2]] - Y[F[:, 0]])

    return int((np.einsum("ij,ij->i", normals(V), normals(X)) < 0).sum())


def _loop_extent(V, F):
    return np.linalg.norm(np.ptp(V[boundary_loop(F)], axis=0))


def test_a_small_boundary_move_that_folds_the_inside_warns_with_the_count_and_the_amplification(load_mesh):
    # the boundary moves 1.9 % of the diagonal; the one-ring stage amplifies its detail change
    # and folds triangles
    V, F = load_mesh("mannequin_nose.obj")
    f = sine_displacement(0.02 * _loop_extent(V, F), periods=2, axis=1)
    with pytest.warns(FoldedTrianglesWarning) as caught:
        X, info = edit_boundary(V, F, f, method="paper", return_info=True)
    message = str(caught[-1].message)
    folds = info["folded_triangles"]
    # the boundary does not turn as a whole here (best-fitting rotation ~0): the count is the
    # plain one against the rest normals
    assert folds == _folded_against_rest(V, F, X) and folds > 20
    diag = np.linalg.norm(np.ptp(V, axis=0))
    moved = np.linalg.norm(X - V, axis=1)
    assert info["max_displacement"] == pytest.approx(moved.max() / diag, rel=1e-12)
    assert info["boundary_displacement"] == pytest.approx(moved[info["boundary"]].max() / diag, rel=1e-12)
    assert info["amplification"] == pytest.approx(info["max_displacement"] / info["boundary_displacement"],
                                                  rel=1e-12)
    assert info["amplification"] > 3
    assert f"{folds} triangles of {F.shape[0]} folded over (normal against the rest shape's; first: " in message
    assert f"{info['amplification']:.1f} times as far as the boundary" in message
    assert "relations='one+two-ring'" in message and "smaller displacement" in message
    # the advice names the other relations from the other side too
    with pytest.warns(FoldedTrianglesWarning, match="Try relations='one-ring'"):
        edit_boundary(V, F, f, method="paper", relations="one+two-ring")
    # the rotation-aware default folds nothing and does not amplify the move here
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        X, info = edit_boundary(V, F, f, return_info=True)
    assert info["folded_triangles"] == 0 == _folded_against_rest(V, F, X)
    assert info["amplification"] == pytest.approx(1.0)


@pytest.mark.parametrize("scale, turn", [(1.0, False), (2.0, True)])
def test_the_figures_of_a_boundary_moved_as_a_whole_are_those_of_the_similarity(scale, turn):
    # flat unit grid, centre c = (0.5, 0.5, 0): x -> scale R (x - c) + c + t, R = turned by 180
    # degrees about the x axis (normals now -z, but nothing folded: the patch turned as a whole).
    # A vertex moves by |(scale R - I)(x - c) + t|; the farthest are the corners, on the boundary,
    # so the amplification is 1
    V, F = grid(9, 9)
    c, t = np.array([0.5, 0.5, 0.0]), np.array([0.3, 0.0, 0.4])
    R = np.diag([1.0, -1.0, -1.0]) if turn else np.eye(3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        X, info = edit_boundary(V, F, lambda s, P: scale * (P - c) @ R.T + c + t - P, return_info=True)
    corner = np.array([0.5, 0.5, 0.0])
    expected = np.linalg.norm(scale * R @ corner - corner + t) / np.sqrt(2.0)    # diagonal sqrt(2)
    assert np.abs(X - (scale * (V - c) @ R.T + c + t)).max() < 1e-10
    assert info["folded_triangles"] == 0
    assert info["max_displacement"] == pytest.approx(expected, rel=1e-10)
    assert info["boundary_displacement"] == pytest.approx(expected, rel=1e-10)
    assert info["amplification"] == pytest.approx(1.0, rel=1e-10)


def test_a_boundary_that_does_not_move_has_no_amplification(load_mesh):
    V, F = load_mesh("mannequin_nose.obj")
    _, info = edit_boundary(V, F, lambda s, P: np.zeros_like(P), return_info=True)
    assert info["amplification"] is None and info["boundary_displacement"] == 0.0
    assert info["folded_triangles"] == 0 and info["max_displacement"] < 1e-8


@pytest.mark.filterwarnings("error")
def test_a_small_smooth_edit_neither_folds_nor_warns(load_mesh):
    # the same sine on the nose at a quarter of the folding amplitude: amplified ~7 times, but
    # nothing folds, and amplification alone does not warn (a boundary moved near a long patch's
    # base moves its far end further by leverage, with either relations, folded or not)
    V, F = load_mesh("mannequin_nose.obj")
    f = sine_displacement(0.005 * _loop_extent(V, F), periods=2, axis=1)
    X, info = edit_boundary(V, F, f, method="paper", return_info=True)
    assert info["folded_triangles"] == 0 == _folded_against_rest(V, F, X)
    assert info["amplification"] > 3
    # the docstring's example and the one of docs/guide/editing.md (the package's terrain)
    V, F = grid(12, 12)
    V[:, 2] = 0.05 * np.sin(6 * V[:, 0]) * np.sin(6 * V[:, 1])
    _, info = edit_boundary(V, F, sine_displacement(0.1, periods=2, axis=2), return_info=True)
    assert info["folded_triangles"] == 0
    V, F = load_mesh("terrainA_1k.obj")
    _, info = edit_boundary(V, F, sine_displacement(0.5, periods=2, axis=2), return_info=True)
    assert info["folded_triangles"] == 0


def test_the_rotation_aware_editor_returned_for_re_solves_rests_on_the_moved_patch():
    # its rest is the patch moved by the boundary's similarity (here a halving about the centre):
    # a re-solve at that boundary gives the halved patch, at the edit's boundary the edit itself
    V, F = grid(9, 9)
    V[:, 2] = 0.2 * np.sin(3 * V[:, 0])
    c = V.mean(axis=0)
    X, info = edit_boundary(V, F, lambda s, P: -0.5 * (P - c), return_info=True)
    b, ed = info["boundary"], info["editor"]
    halved = c + 0.5 * (V - c)
    assert np.abs(ed.solve(halved[b]) - halved).max() < 1e-6
    assert np.abs(ed.solve(X[b]) - X).max() < 1e-6


@pytest.mark.parametrize("option", [dict(boundary_detail="rest"), dict(relations="one+two-ring"), dict(rcond=1e-3)])
def test_the_paper_s_options_are_refused_with_the_rotation_aware_default(option):
    V, F = grid(6, 6)
    with pytest.raises(ConstraintError) as e:
        edit_boundary(V, F, lambda s, P: pytest.fail("the displacement ran"), **option)
    assert e.value.parameter == next(iter(option))
    edit_boundary(V, F, sine_displacement(0.1, axis=2), method="paper", **option)      # taken there
