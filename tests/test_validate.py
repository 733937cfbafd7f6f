"""Input checks (checks, topology): every bad-input class gets its error class and a message that names
the count and the first offending indices; good input comes back as float64 / int64."""

import re

import numpy as np
import pytest

from curvdetail import (ConstraintError, CurvatureEditor, MeshError, check_mesh, cotan_laplacian,
                        curvature_coefficients, curvature_detail, edit_boundary, mean_curvature_normal,
                        minimal_surface, mixed_voronoi_area, reconstruct, sine_displacement)
from curvdetail.curvature import boundary_edges, boundary_vertices
from curvdetail.curvature.checks import as_index_set, as_values
from curvdetail.curvature.errors import CurvdetailError

from curvdetail.curvature.topology import vertex_components
from curvdetail.curvature.testing import grid, icosphere

OPERATORS = [cotan_laplacian, mixed_voronoi_area, mean_curvature_normal, curvature_detail]


def _square():
    V, F = grid(3, 3)       # 9 vertices, 8 triangles
    return V, F


@pytest.mark.parametrize("op", OPERATORS)
def test_empty_vertices_are_refused(op):
    with pytest.raises(MeshError) as e:
        op(np.zeros((0, 3)), np.zeros((0, 3), dtype=int))
    assert (e.value.parameter, e.value.count) == ("V", 0)


def test_empty_faces_are_refused():
    V, _ = _square()
    with pytest.raises(MeshError, match=r"\(0 triangles\)") as e:
        cotan_laplacian(V, np.zeros((0, 3), dtype=int))
    assert e.value.parameter == "F"


@pytest.mark.parametrize("shape", [(9, 2), (9,), (9, 3, 1)])
def test_vertex_array_of_the_wrong_shape_is_refused(shape):
    _, F = _square()
    with pytest.raises(MeshError, match=re.escape(str(shape))) as e:
        cotan_laplacian(np.zeros(shape), F)
    assert e.value.parameter == "V"


def test_quad_faces_are_refused():
    V, _ = _square()
    with pytest.raises(MeshError, match=r"\(1, 4\)") as e:
        cotan_laplacian(V, np.array([[0, 1, 4, 3]]))
    assert e.value.parameter == "F"


@pytest.mark.parametrize("bad", [np.array([["a", "b", "c"]] * 9), np.ones((9, 3), dtype=complex)])
def test_non_real_vertices_are_refused(bad):
    _, F = _square()
    with pytest.raises(MeshError, match=str(bad.dtype)) as e:
        cotan_laplacian(bad, F)
    assert e.value.parameter == "V"


def test_ragged_input_is_refused():
    with pytest.raises(MeshError) as e:
        cotan_laplacian([[0, 0, 0], [1, 0]], [[0, 1, 2]])
    assert e.value.parameter == "V"


def test_fractional_face_indices_are_refused():
    V, F = _square()
    with pytest.raises(MeshError) as e:
        cotan_laplacian(V, F + 0.5)
    assert (e.value.parameter, e.value.count, e.value.first) == ("F", 8, [0, 1, 2])


def test_integral_float_faces_and_integer_vertices_are_accepted():
    V, F = _square()
    V2, F2 = check_mesh((2 * V).astype(np.int32), F.astype(np.float32))   # coordinates 0, 1, 2
    assert V2.dtype == np.float64 and F2.dtype == np.int64 and np.array_equal(F2, F)


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_non_finite_coordinates_are_refused_with_the_vertices(value):
    V, F = _square()
    V[[2, 7], 1] = value
    with pytest.raises(MeshError) as e:
        mean_curvature_normal(V, F)
    assert (e.value.parameter, e.value.count, e.value.first) == ("V", 2, [2, 7])


def test_out_of_range_face_indices_are_refused_with_the_faces():
    V, F = _square()
    F[5, 0] = 9
    F[6, 2] = -1
    with pytest.raises(MeshError, match=r"\[0, 9\)") as e:
        cotan_laplacian(V, F)
    assert (e.value.parameter, e.value.count, e.value.first) == ("F", 2, [5, 6])


def test_repeated_index_in_a_face_is_refused_with_the_face():
    V, F = _square()
    F[4] = [3, 4, 3]
    with pytest.raises(MeshError) as e:
        mixed_voronoi_area(V, F)
    assert (e.value.parameter, e.value.count, e.value.first) == ("F", 1, [4])


def test_the_advice_for_flat_slivers_works_where_removing_them_would_leave_slits():
    import pymeshlab

    from curvdetail import read_mesh
    from curvdetail.data import example_path

    V, F = read_mesh(example_path())
    for f in (17, 402, 931):                       # third corner onto the middle of the first edge
        a, b, c = F[f]
        V[c] = (V[a] + V[b]) / 2
    with pytest.raises(MeshError, match=r"meshing_remove_t_vertices\(method=1") as e:   # the advice's filter
        mean_curvature_normal(V, F)
    assert (e.value.parameter, e.value.count, e.value.first) == ("F", 3, [17, 402, 931])
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F))
    ms.meshing_remove_t_vertices(method=1, threshold=40, repeat=True)     # flips the slivers away
    V2, F2 = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    assert F2.shape == F.shape and boundary_vertices(F2).size == boundary_vertices(F).size    # no slit
    K, A = mean_curvature_normal(V2, F2)
    assert np.all(np.isfinite(K)) and np.all(A > 0)


def test_zero_area_faces_are_refused_with_the_faces():
    V, F = _square()
    V[4] = V[0] + 0.5 * (V[1] - V[0])         # centre vertex onto the bottom edge, between 0 and 1
    bad = np.flatnonzero(np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1) == 0)
    assert bad.size == 1
    with pytest.raises(MeshError) as e:
        cotan_laplacian(V, F)
    assert (e.value.parameter, e.value.count, e.value.first) == ("F", 1, [bad[0]])


def test_non_manifold_edge_is_refused_with_the_edge():
    V, F = _square()
    V = np.vstack([V, [0.25, 0.25, 1.0]])     # a fin on the interior diagonal (0, 4)
    F = np.vstack([F, [0, 4, 9]])
    with pytest.raises(MeshError) as e:
        cotan_laplacian(V, F)
    assert (e.value.parameter, e.value.count, e.value.first) == ("F", 1, [(0, 4)])


@pytest.mark.parametrize("entry", [check_mesh, cotan_laplacian, curvature_detail, mixed_voronoi_area,
                                   lambda V, F: reconstruct(V, F, np.zeros_like(V), [0], V[[0]])])
def test_non_manifold_edges_are_counted_and_listed_in_order_by_every_entry_point(entry):
    # check_mesh sorts the half-edges; the Laplacian's entry points count triangles per edge
    # during assembly instead: both must name the same edges in the same order
    V, F = _square()
    V = np.vstack([V, [[0.25, 0.25, 1.0], [0.75, 0.75, 1.0], [0.5, 0.0, 1.0]]])
    F = np.vstack([F, [[0, 4, 9], [4, 8, 10], [1, 4, 11]]])   # fins on (0, 4), (4, 8), (1, 4)
    with pytest.raises(MeshError, match=r"\(0, 4\), \(1, 4\), \(4, 8\)") as e:
        entry(V, F)
    assert (e.value.parameter, e.value.count, e.value.first) == ("F", 3, [(0, 4), (1, 4), (4, 8)])


@pytest.mark.parametrize("op", OPERATORS + [check_mesh])
@pytest.mark.parametrize("second", [[0, 1, 2], [0, 2, 1], [1, 2, 0], [2, 1, 0]])
def test_an_isolated_pair_of_duplicate_triangles_is_refused(op, second):
    # same order, reversed, rotated: accepted before, with twice the area (each edge on exactly two
    # triangles passes the non-manifold check)
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    with pytest.raises(MeshError, match=r"\(0, 1\).*meshing_remove_duplicate_faces") as e:
        op(V, [[0, 1, 2], second])
    assert (e.value.parameter, e.value.count, e.value.first) == ("F", 1, [1])


@pytest.mark.parametrize("entry", [check_mesh, cotan_laplacian, curvature_detail, mixed_voronoi_area,
                                   lambda V, F: reconstruct(V, F, np.zeros_like(V), [0], V[[0]])])
def test_duplicates_inside_a_mesh_are_named_as_such_not_as_non_manifold_edges(entry):
    # a copy of an interior triangle puts three triangles on its edges: "not manifold, repair
    # the non-manifold edges" was the message
    V, F = grid(5, 5)
    F = np.vstack([F, F[[7]][:, ::-1], F[[3]], F[[7]][:, [1, 2, 0]]])     # 32 triangles before
    with pytest.raises(MeshError, match=r"\(7, 32\), \(3, 33\), \(7, 34\).*meshing_remove_duplicate_faces") as e:
        entry(V, F)
    assert (e.value.parameter, e.value.count, e.value.first) == ("F", 3, [32, 33, 34])


def test_repeated_triangles_finds_every_repeat_also_for_vertex_counts_beyond_its_key():
    from curvdetail.curvature.topology import repeated_triangles

    V, F = grid(6, 6)
    assert repeated_triangles(F, V.shape[0]) is None
    # triangles sharing two vertices with a third one elsewhere, the fan of vertex 0: no repeats
    assert repeated_triangles(np.array([[0, 1, 2], [0, 2, 3], [0, 1, 3], [1, 2, 3]]), 4) is None
    G = np.vstack([F, F[[9, 0, 9]][:, [2, 0, 1]]])
    expected = [[9, F.shape[0]], [0, F.shape[0] + 1], [9, F.shape[0] + 2]]
    assert repeated_triangles(G, V.shape[0]).tolist() == expected
    # beyond 3e9 vertices the (middle, highest) key would overflow: the fallback sorts the rows
    assert repeated_triangles(G, 4_000_000_000).tolist() == expected
    assert repeated_triangles(F, 4_000_000_000) is None


def test_unreferenced_vertices_are_refused_with_the_vertices():
    V, F = _square()
    V = np.vstack([V, [[5.0, 5, 5], [6.0, 6, 6]]])
    with pytest.raises(MeshError, match="meshing_remove_unreferenced_vertices") as e:
        curvature_detail(V, F)
    assert (e.value.parameter, e.value.count, e.value.first) == ("V", 2, [9, 10])
    with pytest.raises(MeshError) as e:
        curvature_detail(V[:10], F)
    assert (e.value.count, e.value.first) == (1, [9])


@pytest.mark.parametrize("count, words", [(0, "0 edges are"), (1, "1 edge is"), (2, "2 edges are")])
def test_counted_puts_noun_and_verb_in_the_number_of_the_count(count, words):
    from curvdetail.curvature.errors import counted, them

    assert counted(count, "edge", verb="are") == words
    assert counted(count, "vertex", "vertices").endswith("vertex" if count == 1 else "vertices")
    assert counted(count, "triangle", verb="repeat").endswith("repeats" if count == 1 else "repeat")
    assert them(count) == ("it" if count == 1 else "them")


def test_component_without_fixed_vertex_is_refused():
    V, F = _square()
    V2 = np.vstack([V, V + [3.0, 0, 0]])
    F2 = np.vstack([F, F + 9])
    with pytest.raises(ConstraintError) as e:
        reconstruct(V2, F2, np.zeros_like(V2), [0], V2[[0]])
    assert (e.value.parameter, e.value.count, e.value.first) == ("fixed", 1, [9])
    with pytest.raises(ConstraintError) as e:
        minimal_surface(V2, F2, [0, 1, 2])
    assert (e.value.count, e.value.first) == (1, [9])


def test_fixed_indices_out_of_range_and_repeated_are_named():
    with pytest.raises(ConstraintError, match=r"\[0, 9\)") as e:
        as_index_set([0, 9, -3], 9, "fixed")
    assert (e.value.parameter, e.value.count, e.value.first) == ("fixed", 2, [9, -3])
    with pytest.raises(ConstraintError) as e:
        as_index_set([4, 1, 4], 9, "fixed")
    assert (e.value.parameter, e.value.count, e.value.first) == ("fixed", 1, [4])
    # a non-whole value is named by its position, as the editing filter names it
    with pytest.raises(ConstraintError, match=r"0\.5") as e:
        as_index_set([3, 0.5, np.inf], 9, "fixed")
    assert (e.value.parameter, e.value.count, e.value.first) == ("fixed", 2, [1, 2])
    assert as_index_set([3.0, 0.0], 9, "fixed").tolist() == [3, 0]


def test_index_set_keeps_the_callers_order_and_reads_masks():
    assert as_index_set([5, 0, 3], 9, "fixed").tolist() == [5, 0, 3]
    mask = np.zeros(9, dtype=bool)
    mask[[7, 2]] = True
    assert as_index_set(mask, 9, "fixed").tolist() == [2, 7]


def test_values_of_the_wrong_shape_or_non_finite_are_named():
    with pytest.raises(ConstraintError, match=r"\(4, 2\).*\(4, 3\)") as e:
        as_values(np.zeros((4, 2)), 4, "detail")
    assert e.value.parameter == "detail"
    bad = np.zeros((4, 3))
    bad[3, 0] = np.nan
    with pytest.raises(ConstraintError) as e:
        as_values(bad, 4, "detail")
    assert (e.value.parameter, e.value.count, e.value.first) == ("detail", 1, [3])


def test_errors_are_value_errors():
    assert issubclass(MeshError, ValueError) and issubclass(ConstraintError, ValueError)


def test_boundary_of_a_grid_is_its_rim_oriented_as_in_the_faces():
    V, F = grid(5, 4)
    E = boundary_edges(F)
    assert E.shape == (2 * (5 - 1) + 2 * (4 - 1), 2)
    # each boundary edge appears in a face with the same orientation
    directed = {tuple(e) for f in F for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}
    assert all(tuple(e) in directed for e in E)
    rim = np.flatnonzero((V[:, 0] == 0) | (V[:, 0] == 1) | (V[:, 1] == 0) | (V[:, 1] == 1))
    assert np.array_equal(boundary_vertices(F), rim)


def test_closed_surface_has_no_boundary():
    _, F = icosphere(subdivisions=1)
    assert boundary_edges(F).shape == (0, 2) and boundary_vertices(F).size == 0


def test_boundary_vertices_are_the_ends_of_the_boundary_edges(load_mesh):
    # counted by a sparse pass, not derived from boundary_edges: the two must agree, also on a
    # mesh with a non-manifold edge (three triangles on (0, 1): not a boundary) and one unused index
    fan = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 5], [2, 1, 6]])
    for F in (load_mesh("mannequin_nose.obj")[1], load_mesh("terrainA_1k.obj")[1], fan,
              np.vstack([grid(4, 4)[1], grid(3, 3)[1] + 16])):
        assert np.array_equal(boundary_vertices(F), np.unique(boundary_edges(F)))


def test_components_are_labelled():
    V, F = _square()
    labels, count = vertex_components(np.vstack([F, F + 9]), 18)
    assert count == 2 and len(set(labels[:9])) == 1 and labels[0] != labels[9]


@pytest.mark.parametrize("F, message, count", [
    ([[0, 1]], r"\(1, 2\)", None), (None, r"\(\)", None), (np.zeros((0, 3), int), r"\(0, 3\)|0 triangles", None),
    ([[0, 1, -2]], None, 1), ([[0, 1, 1]], None, 1), ([[0, 1, 2.5]], None, 1), (np.ones((1, 3), bool), "bool", None),
])
def test_boundary_functions_check_their_triangles(F, message, count):
    for function in (boundary_edges, boundary_vertices):
        with pytest.raises(MeshError, match=message) as e:
            function(F)
        assert (e.value.parameter, e.value.count) == ("F", count)
        assert e.value.first == (None if count is None else [0])


def test_indices_out_of_range_are_counted_by_position_not_wrapped():
    # 1e20 and 2**64 - 1 must not wrap around to an index in range on the cast to int64
    for given, first in (([1e20], [1e20]), (np.array([2 ** 64 - 1], dtype=np.uint64), [2 ** 64 - 1]),
                         ([-1, 7, 2], [-1, 7])):
        with pytest.raises(ConstraintError) as info:
            as_index_set(given, 5, "fixed")
        assert info.value.parameter == "fixed" and info.value.first == first
        assert info.value.count == len(first)
    with pytest.raises(MeshError) as info:
        check_mesh(np.eye(3), [[0, 1, 1e20]])
    assert info.value.parameter == "F"


@pytest.mark.parametrize("values", [np.ones((2, 3)) + 1j, np.ones((2, 3), bool), np.full((2, 3), "1")])
def test_values_must_be_real_numbers(values):
    # complex would silently lose its imaginary part, bool would mean 0/1
    with pytest.raises(ConstraintError, match=str(values.dtype)) as e:
        as_values(values, 2, "detail")
    assert e.value.parameter == "detail"
    assert as_values(np.ones((2, 3), np.int32), 2, "detail").dtype == np.float64


@pytest.mark.parametrize("scale", [1e80, 1e155])
def test_coordinates_whose_products_overflow_are_named(scale):
    # before: "16 triangles have zero area" at 1e155, and at 1e80 mean_curvature_normal returned
    # inf / NaN without a word (the areas square the cross products)
    V, F = grid(3, 3)
    with pytest.raises(MeshError, match=re.escape(f"{scale:.0e}")) as e:       # the largest coordinate
        check_mesh(V * scale, F)
    assert (e.value.parameter, e.value.count, e.value.first) == ("V", 8, [1, 2, 3])
    with pytest.raises(MeshError) as e:
        mean_curvature_normal(V * scale, F)
    assert (e.value.parameter, e.value.count) == ("V", 8)
    with pytest.raises(ConstraintError, match=r"1e\+200") as e:
        as_values([[1e200, 0, 0]], 1, "positions")
    assert (e.value.parameter, e.value.count, e.value.first) == ("positions", 1, [0])


def test_a_mesh_too_small_for_its_areas_is_named_by_its_size():
    V, F = grid(3, 3)
    V[:, 2] = V[:, 0] ** 2                                    # 1.73 across
    check_mesh(V * 1e-60, F)                                  # still fine
    for scale in (1e-61, 1e-100, 1e-200):                    # 1e-200: its squared extent underflows
        with pytest.raises(MeshError, match=rf"1.73e-{-np.log10(scale):.0f}.*1e-60") as e:   # size, limit
            check_mesh(V * scale, F)
        assert e.value.parameter == "V" and e.value.value == pytest.approx(1.73 * scale, rel=1e-2)
    with pytest.raises(MeshError) as e:
        check_mesh(V * 0.0, F)
    assert (e.value.parameter, e.value.value) == ("V", 0.0)


@pytest.mark.parametrize("op", OPERATORS)
def test_a_mesh_whose_areas_lose_digits_to_subnormals_is_refused_not_answered_inexactly(load_mesh, op):
    # the nose (0.91 across) scaled by 1e-78: its squared cross products fall into the subnormals,
    # and K came back 9.7e-5 off without a word (reconstruct 4.9e-7); at 1e-75 np.errstate(all="raise")
    # met an underflow inside the cotangents instead of a MeshError
    V, F = load_mesh("mannequin_nose.obj")
    exact = op(V, F)
    exact = exact[0] if isinstance(exact, tuple) else exact
    for scale in (1e-75, 1e-78):
        with np.errstate(all="raise"), pytest.raises(MeshError, match=r"9.08e-\d+") as e:
            op(V * scale, F)
        assert e.value.parameter == "V"
    # just above the limit the answer is exact: K scales as 1 / length, A as length^2, L as 1
    scaled = op(V * 1e-59, F)
    scaled = scaled[0] if isinstance(scaled, tuple) else scaled
    power = {cotan_laplacian: 0, mixed_voronoi_area: 2, mean_curvature_normal: -1, curvature_detail: 1}[op]
    if op is cotan_laplacian:
        exact, scaled = exact.toarray(), scaled.toarray()
    assert np.abs(scaled / 1e-59 ** power - exact).max() <= 1e-12 * np.abs(exact).max()


def test_a_cross_product_component_that_underflows_is_no_error():
    # a triangle almost in a coordinate plane squares a component of 1e-170: numpy's underflow,
    # negligible next to the other components, raised FloatingPointError under np.errstate(all="raise")
    V, F = grid(4, 4)
    V[5, 2] = 1e-170
    b = boundary_vertices(F)
    with np.errstate(all="raise"):
        check_mesh(V, F)
        L = cotan_laplacian(V, F)
        X = reconstruct(V, F, curvature_detail(V, F), b, V[b])
    inner = np.setdiff1d(np.arange(V.shape[0]), b)
    assert np.abs((L @ V[:, :2])[inner]).max() < 1e-14         # flat: x and y are harmonic inside
    assert np.abs(X - V).max() < 1e-14


def _nearly_flat_grid():
    """A flat 10 x 10 grid whose z coordinates are 0, 1e-170 and 2e-170: squares of them
    underflow, the surface is the plane to every digit."""
    V, F = grid(10, 10)
    V[:, 2] = 1e-170 * (np.arange(V.shape[0]) % 3)
    return V, F


_CORE_CALLS = {
    "mean_curvature_normal": lambda V, F, b: mean_curvature_normal(V, F)[0],
    "mixed_voronoi_area": lambda V, F, b: mixed_voronoi_area(V, F),
    "curvature_coefficients": lambda V, F, b: curvature_coefficients(V, F).toarray(),
    "minimal_surface": lambda V, F, b: minimal_surface(V, F, b),
    "CurvatureEditor": lambda V, F, b: CurvatureEditor(V, F, b, [44, 45, 55]).solve(
        V[b], V[[44, 45, 55]] + [0.0, 0.0, 0.1]),
    "edit_boundary": lambda V, F, b: edit_boundary(V, F, sine_displacement(0.1, axis=2)),
}


@pytest.mark.parametrize("name", sorted(_CORE_CALLS))
def test_underflow_in_a_nearly_flat_mesh_is_no_error_under_the_callers_seterr(name):
    # np.seterr(all="raise") turned the underflow of such squares into FloatingPointError from
    # inside numpy in every one of these; the answers are those of the exactly flat grid
    V, F = _nearly_flat_grid()
    b = boundary_vertices(F)
    flat = V.copy()
    flat[:, 2] = 0.0
    expected = _CORE_CALLS[name](flat, F, b)
    with np.errstate(all="raise"):
        got = _CORE_CALLS[name](V, F, b)
    assert np.abs(np.asarray(got) - np.asarray(expected)).max() < 1e-12


def test_the_core_is_exact_across_its_range_of_scales():
    V, F = grid(4, 4)
    V[:, 2] = V[:, 0] ** 2
    b = boundary_vertices(F)
    for scale in (1e-60, 1e70):
        X = reconstruct(V * scale, F, curvature_detail(V * scale, F), b, V[b] * scale)
        assert np.abs(X / scale - V).max() < 1e-12


def test_counts_and_positive_numbers_take_what_numpy_hands_out():
    # float32 scalars (no overflow warning in the range check), 0-d arrays, whole floats
    import warnings

    from curvdetail.curvature.checks import as_count, as_positive_number

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert as_positive_number(np.float32(0.25), "tol") == 0.25
        assert as_positive_number(np.array(0.05), "tol") == 0.05
        assert as_count(3.0, "n") == 3 and as_count(np.array(2000), "n") == 2000
        assert as_count(np.uint8(7), "n") == 7 and as_count(2 ** 70, "n") == 2 ** 70
    for bad in (True, np.True_, 2.5, "5", None, float("nan"), np.array([1, 2])):
        with pytest.raises(CurvdetailError, match=">= 1") as e:
            as_count(bad, "n")
        assert e.value.parameter == "n"
    with pytest.raises(CurvdetailError) as e:       # inf, not an OverflowError
        as_positive_number(10 ** 400, "tol")
    assert e.value.parameter == "tol"


def test_docstring_examples_run():
    import doctest
    import importlib

    result = doctest.testmod(importlib.import_module("curvdetail.curvature.checks"), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0, result


def test_boundary_functions_take_sparse_huge_indices_without_allocating_or_overflowing():
    # 2**32 - 1 is a common "no vertex" sentinel: boundary_vertices allocated 32 GiB for it, and
    # boundary_edges' key min * n + max overflowed for indices near 2**33, losing two edges
    X = 2 ** 33 - 1
    F = np.array([[0, X, 5], [2 ** 31, X, 7]])
    expected = {(5, 0), (0, X), (X, 5), (7, 2 ** 31), (X, 7), (2 ** 31, X)}
    assert set(map(tuple, boundary_edges(F).tolist())) == expected
    G = np.array([[0, 1, 2], [0, 2, 0xFFFFFFFF]], dtype=np.uint32)
    assert boundary_vertices(G).tolist() == [0, 1, 2, 0xFFFFFFFF]
    assert set(map(tuple, boundary_edges(G).tolist())) == {(0, 1), (1, 2), (2, 0xFFFFFFFF), (0xFFFFFFFF, 0)}


def test_misoriented_edges_finds_the_three_edges_of_a_reversed_interior_triangle():
    from curvdetail.curvature.topology import misoriented_edges

    V, F = grid(6, 6)
    assert misoriented_edges(F).shape == (0, 2)
    F = F.copy()
    interior = np.flatnonzero(~np.isin(F, boundary_vertices(F)).any(axis=1))[0]
    F[interior] = F[interior, ::-1]
    E = misoriented_edges(F)
    # each of its edges now runs as in the neighbour across it, i.e. as in the reversed triangle
    reversed_edges = {(F[interior, k], F[interior, (k + 1) % 3]) for k in range(3)}
    assert set(map(tuple, E.tolist())) == reversed_edges


def test_repeated_indices_are_counted_and_named():
    mask = np.zeros(25, dtype=int)          # a 0/1 mask of ints: 23 repeats of 0, 4 of 1
    mask[:5] = 1
    with pytest.raises(ConstraintError) as info:
        as_index_set(mask, 25, "fixed")
    assert (info.value.parameter, info.value.count, info.value.first) == ("fixed", 23, [0, 1])
    with pytest.raises(ConstraintError) as info:
        as_index_set([3, 3], 25, "fixed")
    assert (info.value.count, info.value.first) == (1, [3])
    assert as_index_set(mask.astype(bool), 25, "fixed").tolist() == [0, 1, 2, 3, 4]


def test_check_choice_takes_one_str_of_the_choices_and_names_anything_else():
    from curvdetail.curvature.checks import check_choice

    assert check_choice("free", "rows", ("all", "free"), "; use 'all' or 'free'.") == "free"
    assert type(check_choice(np.str_("all"), "rows", ("all", "free"), ".")) is str
    with pytest.raises(CurvdetailError, match="'some'") as e:
        check_choice("some", "rows", ("all", "free"), "; use 'all' or 'free'.")
    assert (e.value.parameter, e.value.value) == ("rows", "some")
    # ``value in choices`` compares an array element-wise: one entry passed, two raised numpy's
    # "truth value ... is ambiguous"; neither is an option value
    for value, kind in ((np.array(["all"]), "ndarray"), (np.array(["all", "free"]), "ndarray"),
                        (["all"], "list"), (None, "NoneType")):
        with pytest.raises(ConstraintError, match=kind) as e:
            check_choice(value, "rows", ("all", "free"), "; use 'all' or 'free'.", ConstraintError)
        assert e.value.parameter == "rows"


def test_index_values_that_are_not_whole_numbers_are_named_with_the_first_and_its_position():
    from curvdetail.curvature.checks import non_whole_index_error      # here: new in this module

    assert non_whole_index_error([3.0, 7.0, -0.0], "handles") is None         # whole floats are indices
    assert non_whole_index_error(np.arange(5), "handles") is None
    error = non_whole_index_error(np.array([3.0, 7.5, np.nan, np.inf]), "handles")
    assert isinstance(error, ConstraintError)
    assert (error.parameter, error.count, error.first) == ("handles", 3, [1, 2, 3])
    error = non_whole_index_error([np.inf], "fixed", MeshError)
    assert isinstance(error, MeshError) and (error.count, error.first) == (1, [0])


def test_an_index_set_of_more_than_one_dimension_is_refused_by_shape():
    # boundary edges (k, 2) passed as fixed: flattened, every vertex appeared twice and the
    # refusal spoke of repeated indices
    E = np.array([[0, 1], [1, 2], [2, 0]])
    with pytest.raises(ConstraintError, match=r"\(3, 2\)") as info:
        as_index_set(E, 9, "fixed")
    assert info.value.parameter == "fixed"
    # a column or a row of indices is one list
    assert as_index_set(np.array([[4], [1]]), 9, "fixed").tolist() == [4, 1]
    assert as_index_set(np.array([[4, 1]]), 9, "fixed").tolist() == [4, 1]
    assert as_index_set(np.int64(3), 9, "fixed").tolist() == [3]


def _read_only(a):
    a = np.array(a)
    a.setflags(write=False)
    return a


@pytest.mark.parametrize("form", ["plain", "read-only", "memmap"])
def test_check_mesh_returns_arrays_of_its_own_not_the_inputs(form, tmp_path):
    # float64 / int64 C arrays were returned as the very objects given: writing to the checked
    # V changed the caller's mesh, and a read-only or memmapped input came back unwritable
    V, F = grid(4, 4)
    if form == "read-only":
        V, F = _read_only(V), _read_only(F)
    elif form == "memmap":
        m = np.memmap(tmp_path / "F.bin", dtype=np.int64, mode="w+", shape=F.shape)
        m[:] = F
        m.flush()
        F = np.memmap(tmp_path / "F.bin", dtype=np.int64, mode="r", shape=F.shape)
    V0, F0 = np.array(V), np.array(F)
    W, G = check_mesh(V, F)
    assert not np.shares_memory(W, V) and not np.shares_memory(G, F)
    assert type(W) is np.ndarray and type(G) is np.ndarray
    assert W.flags.writeable and G.flags.writeable and W.flags.c_contiguous and G.flags.c_contiguous
    assert np.array_equal(W, V0) and np.array_equal(G, F0)
    W[0] += 1.0
    G[0] = G[0, ::-1]
    assert np.array_equal(V, V0) and np.array_equal(F, F0)

