"""apply_curvature_editing: handles land on the transform, the unselected part stays, errors."""

import os

import numpy as np
import pymeshlab
import pytest

from curvdetail import ConstraintError
from curvdetail.filters import BBoxLength, FilterParameterError, apply, get_filter

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


def _select(ms, mask):
    """Replace the current mesh by a copy whose quality is ``mask`` and select where it is 1."""
    m = ms.current_mesh()
    copy = pymeshlab.Mesh(vertex_matrix=m.vertex_matrix(), face_matrix=m.face_matrix(),
                          v_scalar_array=mask.astype(float))
    ms.clear()
    ms.add_mesh(copy)
    ms.compute_selection_by_condition_per_vertex(condselect="(q > 0.5)")


def _meshset_with_roi():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "mannequin_ear.obj"))
    V = ms.current_mesh().vertex_matrix().copy()
    d = np.linalg.norm(V - V[0], axis=1)
    _select(ms, d < np.quantile(d, 0.6))
    handles = np.flatnonzero(d < np.quantile(d, 0.05))
    return ms, V, d, handles


def test_handles_follow_the_transform_and_unselected_vertices_stay():
    ms, V, d, handles = _meshset_with_roi()
    T = np.eye(4)
    T[:3, 3] = [0.0, 0.0, 0.02]
    figures = apply(ms, "apply_curvature_editing", handles=" ".join(map(str, handles)),
                    transform=" ".join(map(str, T.ravel())))
    X = ms.current_mesh().vertex_matrix()
    outside = d >= np.quantile(d, 0.6)
    assert np.abs(X[handles] - (V[handles] + [0, 0, 0.02])).max() < 1e-12
    assert np.array_equal(X[outside], V[outside])
    assert np.allclose(ms.current_mesh().vertex_scalar_array(), np.linalg.norm(X - V, axis=1))
    assert figures["handle_vertices"] == handles.size and figures["roi_vertices"] > handles.size
    assert figures["amplification"] == pytest.approx(1.0, abs=0.05)   # nothing outruns a translation


def test_amplification_is_none_where_the_handles_do_not_move():
    # a pure detail edit moves the region but not the handles: the ratio was reported as 1.0, and
    # rounding noise with move_handles=false as 3.4 (above the CLI's warning threshold)
    ms, V, d, handles = _meshset_with_roi()
    figures = apply(ms, "apply_curvature_editing", handles=" ".join(map(str, handles)), detail_scale=0.5)
    assert figures["amplification"] is None and figures["max_displacement"] > 1e-3


def test_python_callers_may_pass_handles_and_transform_as_arrays():
    # as pymeshlab takes a matrix parameter: the same edit as from the texts, digit for digit
    T = np.eye(4)
    T[:3, :3] = [[np.cos(0.3), -np.sin(0.3), 0.0], [np.sin(0.3), np.cos(0.3), 0.0], [0.0, 0.0, 1.0]]
    T[:3, 3] = [0.01, 0.0, 0.02 / 3.0]
    ms_text, V, d, handles = _meshset_with_roi()
    apply(ms_text, "apply_curvature_editing", handles=" ".join(map(str, handles)),
          transform=" ".join(map(repr, T.ravel().tolist())))
    ms_array, *_ = _meshset_with_roi()
    apply(ms_array, "apply_curvature_editing", handles=handles, transform=T)
    ms_list, *_ = _meshset_with_roi()
    apply(ms_list, "apply_curvature_editing", handles=handles.tolist(), transform=T.tolist())
    X = ms_text.current_mesh().vertex_matrix()
    assert np.abs(X - V).max() > 1e-3                    # it did move
    assert np.array_equal(ms_array.current_mesh().vertex_matrix(), X)
    assert np.array_equal(ms_list.current_mesh().vertex_matrix(), X)


def test_identity_edit_leaves_the_mesh_in_place():
    ms, V, d, handles = _meshset_with_roi()
    apply(ms, "apply_curvature_editing", handles=",".join(map(str, handles)))
    X = ms.current_mesh().vertex_matrix()
    assert np.abs(X - V).max() < 1e-8 * np.linalg.norm(np.ptp(V, axis=0))


def test_filter_is_declared_with_its_parameters():
    spec = get_filter("apply_curvature_editing")
    assert spec.category == "Curvature detail"
    expected = {"handles", "transform", "detail_scale", "move_handles", "handle_detail", "relations"}
    assert expected <= set(spec.parameter_names)


@pytest.mark.parametrize("params, error, message", [
    (dict(handles=""), FilterParameterError, "empty"),
    (dict(handles="1 2 999999"), FilterParameterError, "outside"),
    (dict(handles="1 99999999999999999999999"), FilterParameterError, r"1 index is outside \[0, \d+\) "
                                                                        r"\(first: 99999999999999999999999\)"),
    (dict(handles="1 2 2"), FilterParameterError, r"1 index is repeated \(first: 2\); list each vertex once"),
    (dict(handles="1 2", transform="1 0 0"), FilterParameterError, "16 finite numbers"),
    (dict(handles="1 2", detail_scale=-1.0), FilterParameterError, "greater than 0"),
    # transforms that collapse the handles: refused here as curvdetail edit's .def files are
    (dict(handles="1 2", transform="0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 1"), FilterParameterError, "singular"),
    (dict(handles="1 2", transform="1 0 0 0 0 1 0 0 0 0 0 0 0 0 0 1"), FilterParameterError, "singular"),
    (dict(handles="1 2", transform="1 0 0 1_0 0 1 0 0 0 0 1 0 0 0 0 1"), FilterParameterError, "16 numbers"),
])
def test_bad_parameters_are_refused(params, error, message):
    ms, V, d, handles = _meshset_with_roi()
    with pytest.raises(error, match=message):
        apply(ms, "apply_curvature_editing", **params)


@pytest.mark.parametrize("params, message", [
    (dict(detail_scale=1e300), "transform with detail_scale gives the handles values of"),
    (dict(transform="1e300 0 0 0 0 1e300 0 0 0 0 1e300 0 0 0 0 1"), "the transform gives the handles values of"),
])
def test_an_overflowing_edit_is_refused_before_the_mesh_is_touched(params, message):
    # before, the positions were written and only then the quality's infinities refused
    ms, V, d, handles = _meshset_with_roi()
    with pytest.raises(FilterParameterError, match=message):
        apply(ms, "apply_curvature_editing", handles=" ".join(map(str, handles)), **params)
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V)


def test_region_radius_makes_the_region_without_a_selection():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "mannequin_ear.obj"))
    V = ms.current_mesh().vertex_matrix().copy()
    d = np.linalg.norm(V - V[0], axis=1)
    handles = np.flatnonzero(d < np.quantile(d, 0.03))
    radius = np.quantile(d, 0.5)
    figures = apply(ms, "apply_curvature_editing", handles=" ".join(map(str, handles)),
                    region_radius=BBoxLength(radius, percent=False),
                    transform="1 0 0 0 0 1 0 0 0 0 1 0.01 0 0 0 1")
    X = ms.current_mesh().vertex_matrix()
    # the region is every vertex within the radius of a handle; everything beyond stays put
    from scipy.spatial import cKDTree
    dist = cKDTree(V[handles]).query(V)[0]
    assert figures["roi_vertices"] == int((dist <= radius).sum())
    assert np.array_equal(X[dist > radius], V[dist > radius])
    assert np.allclose(X[handles, 2], V[handles, 2] + 0.01)


def test_no_selection_is_refused():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "mannequin_ear.obj"))
    with pytest.raises(ConstraintError, match="no selected vertices"):
        apply(ms, "apply_curvature_editing", handles="1 2 3")


def test_an_edit_the_handles_do_not_determine_is_refused_with_the_filter_s_options():
    import pymeshlab

    from curvdetail.curvature.errors import UndeterminedEditError
    from curvdetail.curvature.testing import grid
    from curvdetail.filters import apply

    V, F = grid(30, 30)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F))
    # free handle details on a flat grid: nothing ties the in-plane rings of the region down
    with pytest.raises(UndeterminedEditError, match="do not determine the edit.*more handles, handle_detail") as exc:
        apply(ms, "apply_curvature_editing", handles="450 451 480", handle_detail="free",
              region_radius=pymeshlab.PercentageValue(45.0))
    assert "roi" not in str(exc.value)              # the filter's terms, not the library's
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V)      # untouched
    # the advice works: the handles' details given
    report = apply(ms, "apply_curvature_editing", handles="450 451 480", handle_detail="transform",
                   region_radius=pymeshlab.PercentageValue(45.0))
    assert report["max_displacement"] < 1e-12


@pytest.mark.parametrize("shape", [(2, 8), (16, 1), (1, 16)])
def test_a_transform_array_of_another_shape_than_4x4_is_refused(shape):
    # every array was flattened: a 2x8 array (or 16x1, 1x16) passed and was read as a 4x4 matrix
    ms, V, d, handles = _meshset_with_roi()
    T = np.eye(4)
    T[:3, 3] = [0.0, 0.0, 0.02]
    dims = "x".join(map(str, shape))
    with pytest.raises(FilterParameterError, match=rf"parameter 'transform' is a {dims} array; it must be a "
                                                   r"4x4 matrix"):
        apply(ms, "apply_curvature_editing", handles=handles, transform=T.reshape(shape))
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V)
    # the documented forms stay: 16 numbers as a flat list, as in the text
    apply(ms, "apply_curvature_editing", handles=handles, transform=T.ravel().tolist())
    assert np.abs(ms.current_mesh().vertex_matrix()[handles] - (V[handles] + [0, 0, 0.02])).max() < 1e-12


@pytest.mark.parametrize("handles", [[], np.array([], dtype=np.int64)])
def test_handles_given_as_an_empty_list_are_named_as_no_handle(handles):
    # it was "parameter 'handles' expects a str; got [] (list)", about the type
    ms, *_ = _meshset_with_roi()
    with pytest.raises(FilterParameterError, match=r"parameter 'handles' is empty; name the handle vertices"):
        apply(ms, "apply_curvature_editing", handles=handles)


def test_handles_given_as_a_boolean_mask_are_refused_with_the_conversion():
    ms, V, d, handles = _meshset_with_roi()
    mask = np.zeros(V.shape[0], dtype=bool)
    mask[handles] = True
    with pytest.raises(FilterParameterError, match=rf"parameter 'handles' is a boolean mask \({V.shape[0]} "
                                                   r"True/False values\); .*np\.flatnonzero\(mask\)"):
        apply(ms, "apply_curvature_editing", handles=mask)
    apply(ms, "apply_curvature_editing", handles=np.flatnonzero(mask))      # the conversion it names


@pytest.mark.parametrize("radius, given", [(BBoxLength(1e-300, percent=False), r"region_radius=1e-300 of"),
                                           (BBoxLength(1e-300, percent=True), r"region_radius=1e-300% of a "
                                                                              r"handle \(\d.*e-30\d on this mesh\)"),
                                           (BBoxLength(1e-9, percent=False), r"region_radius=1e-09 of")])
def test_a_positive_region_radius_that_reaches_no_vertex_is_named_as_given(radius, given):
    # 1e-300 was called "region_radius is 0"; 1e-9 made a region of the handles alone, moved them
    # and rebuilt nothing around them
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "mannequin_ear.obj"))
    V = ms.current_mesh().vertex_matrix().copy()
    with pytest.raises(ConstraintError, match=r"no selected vertices and no vertex but the handles lies within "
                                              + given) as error:
        apply(ms, "apply_curvature_editing", handles="1 2 3", region_radius=radius,
              transform="1 0 0 0 0 1 0 0 0 0 1 0.01 0 0 0 1")
    assert "is 0" not in str(error.value)
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V)
    with pytest.raises(ConstraintError, match="no selected vertices and region_radius is 0: the region"):
        apply(ms, "apply_curvature_editing", handles="1 2 3", region_radius=0.0)


def _edited(handles, transform="1 0 0 0 0 1 0 0 0 0 1 0.02 0 0 0 1"):
    """Positions after the filter with these handles (and a lift by 0.02) on a fresh MeshSet."""
    ms, *_ = _meshset_with_roi()
    apply(ms, "apply_curvature_editing", handles=handles, transform=transform)
    return ms.current_mesh().vertex_matrix()


@pytest.mark.parametrize("as_floats", [lambda h: h.astype(float), lambda h: h.astype(np.float32),
                                       lambda h: [float(i) for i in h], lambda h: " ".join(f"{i}.0" for i in h)])
def test_handles_given_as_whole_number_floats_make_the_edit_of_the_ints(as_floats):
    # [3.0, 7.0] was refused ("must be vertex indices separated by spaces or commas; got '3.0 7.0'")
    # while CurvatureEditor took it: float index arrays are common from pymeshlab / libigl
    ms, V, d, handles = _meshset_with_roi()
    assert np.array_equal(_edited(as_floats(handles)), _edited(handles))       # the same path: bit for bit


@pytest.mark.parametrize("handles, how_many", [
    ([3.5, 7.0], r"1 value is not a whole number \(first: 3\.5, at position 0\)"),
    (np.array([3.0, 7.25, 9.5]), r"2 values are not whole numbers \(first: 7\.25, at position 1\)"),
    ("3 7.5", r"1 value is not a whole number \(first: 7\.5, at position 1\)"),
    ([2, np.nan], r"1 value is not a whole number \(first: nan, at position 1\)"),
])
def test_handles_that_are_not_whole_numbers_are_refused_naming_the_first(handles, how_many):
    # [3.5, 7.0] was "must be vertex indices separated by spaces or commas; got '3.5 7.0'", naming no value
    ms, V, d, _ = _meshset_with_roi()
    with pytest.raises(FilterParameterError, match=rf"parameter 'handles': {how_many}; vertex indices are whole "
                                                   r"numbers: pass integers \(or whole floats such as 3\.0\)"):
        apply(ms, "apply_curvature_editing", handles=handles, transform="1 0 0 0 0 1 0 0 0 0 1 0.02 0 0 0 1")
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V)


def test_a_single_handle_is_taken_as_one_index():
    # 12 was refused with "expects a str (from Python also a list or array of numbers); got 12 (int)"
    X = _edited([12])
    for single in (12, np.int64(12), 12.0, np.array(12)):
        assert np.array_equal(_edited(single), X)


def test_a_range_of_handles_is_taken_as_its_indices():
    # vertices 0 ... 14 are handles of _meshset_with_roi; range(15) was refused as "got range(0, 15) (range)"
    assert np.array_equal(_edited(range(15)), _edited(list(range(15))))


def test_a_set_of_handles_is_taken_since_one_transform_moves_them_all():
    # the filter gives every handle the same transform, so their order does not matter (unlike the
    # rows of CurvatureEditor.solve's positions): a set was refused as "got {...} (set)"
    ms, V, d, handles = _meshset_with_roi()
    X = _edited(handles)
    assert np.array_equal(_edited(set(handles.tolist())), X)          # sorted: the same order as handles
    assert np.array_equal(_edited(frozenset(handles.tolist())), X)
    # another order gives the same edit up to the solvers' rounding
    assert np.abs(_edited(handles[::-1]) - X).max() < 1e-12 * np.linalg.norm(np.ptp(V, axis=0))
