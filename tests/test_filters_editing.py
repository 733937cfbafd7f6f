"""apply_curvature_editing: handles land on the transform, the unselected part stays, errors."""

import os
import warnings

import numpy as np
import pymeshlab
import pytest

from curvdetail import ConstraintError
from curvdetail.curvature.errors import FoldedTrianglesWarning
from curvdetail.filters import BBoxLength, FilterParameterError, apply, get_filter
from curvdetail.filters.editing import AMPLIFICATION_LIMIT, AmplifiedEditWarning

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


def test_the_default_rotation_aware_edit_turns_the_region_without_warning():
    # the handles turned by 60 degrees about their centre: the paper's one-ring edit of this
    # kind amplified or folded (see the status-4 test); the default runs silently, reports its
    # iterations, and leaves the coefficient counts it does not compute as None
    ms, V, d, handles = _meshset_with_roi()
    c = V[handles].mean(axis=0)
    T = np.eye(4)
    T[:2, :2] = [[np.cos(1.0), -np.sin(1.0)], [np.sin(1.0), np.cos(1.0)]]
    T[:3, 3] = c - T[:3, :3] @ c
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        figures = apply(ms, "apply_curvature_editing", handles=handles, transform=T)
    assert figures["folded_triangles"] == 0 and figures["iterations"] >= 1
    assert figures["amplification"] < AMPLIFICATION_LIMIT
    assert figures["rank_deficient_vertices"] is None and figures["detail_amplification"] is None


@pytest.mark.parametrize("params", [dict(detail_scale=0.5), dict(move_handles=False), dict(handle_detail="free"),
                                    dict(relations="one+two-ring"), dict(relations="one+two-ring", detail_scale=2.0)])
def test_paper_only_parameters_are_refused_with_the_rotation_aware_method(params):
    ms, V, d, handles = _meshset_with_roi()
    with pytest.raises(FilterParameterError, match="method='paper'") as e:      # the value that takes them
        apply(ms, "apply_curvature_editing", handles=handles, **params)
    assert e.value.parameter == "method" and sorted(e.value.value) == sorted(params)
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V)


def test_amplification_is_none_where_the_handles_do_not_move():
    # a pure detail edit moves the region but not the handles: the ratio was reported as 1.0, and
    # rounding noise with move_handles=false as 3.4 (above the CLI's warning threshold);
    # one+two-ring relations: the one-ring ones fold 6 triangles here (see the fold test below)
    ms, V, d, handles = _meshset_with_roi()
    figures = apply(ms, "apply_curvature_editing", method="paper", handles=" ".join(map(str, handles)), detail_scale=0.5,
                    relations="one+two-ring")
    assert figures["amplification"] is None and figures["max_displacement_percent_of_diagonal"] > 0.1


def test_a_detail_edit_reports_its_amplification_in_the_details():
    # amplification was None for every detail edit, blown up or not; detail_amplification is the
    # largest detail change over the largest the edit asks (the handles' change applied to every
    # region vertex): measured 0.19 here with one+two-ring, 0.97 with one-ring. With
    # move_handles=false the handles' motion is an outcome, not the edit: no ratio to it
    ms, V, d, handles = _meshset_with_roi()
    with warnings.catch_warnings():
        warnings.simplefilter("error")                      # nothing folds or is amplified
        figures = apply(ms, "apply_curvature_editing", method="paper", handles=handles, detail_scale=0.5,
                        move_handles=False, relations="one+two-ring")
    assert figures["amplification"] is None
    assert 0.05 < figures["detail_amplification"] < 1.0
    assert figures["folded_triangles"] == 0
    # a translation asks no detail change
    ms, *_ = _meshset_with_roi()
    figures = apply(ms, "apply_curvature_editing", method="paper", handles=handles, transform="1 0 0 0 0 1 0 0 0 0 1 0.02 0 0 0 1")
    assert figures["detail_amplification"] is None and figures["amplification"] == pytest.approx(1.0, abs=0.05)


def _folded(V, X, F):
    """Triangles whose normal in X points against the rest normal (an untransformed edit)."""
    def normals(Y):
        return np.cross(Y[F[:, 1]] - Y[F[:, 0]], Y[F[:, 2]] - Y[F[:, 0]])
    return int(np.count_nonzero(np.einsum("ij,ij->i", normals(V), normals(X)) < 0))


def test_a_detail_edit_that_folds_triangles_warns_with_the_count_and_what_to_try():
    # the handles' details doubled on the ear with the paper's one-ring relations fold 201 of 2403
    # triangles; the filter said nothing (amplification None, "the handles do not move")
    ms, V, d, handles = _meshset_with_roi()
    F = ms.current_mesh().face_matrix()
    # the relations used, the triangle count, the relations to try
    with pytest.warns(FoldedTrianglesWarning,
                      match=r"relations='one-ring'.* 2403\b.*relations='one\+two-ring'") as record:
        figures = apply(ms, "apply_curvature_editing", method="paper", handles=handles, detail_scale=2.0)
    X = ms.current_mesh().vertex_matrix()
    assert figures["folded_triangles"] == _folded(V, X, F) > 100
    assert f"{figures['folded_triangles']} triangles of 2403" in str(record[0].message)
    assert record[0].filename == __file__                   # the caller's line, not the package's
    # the advice works: one+two-ring folds nothing and says nothing
    ms, *_ = _meshset_with_roi()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        figures = apply(ms, "apply_curvature_editing", method="paper", handles=handles, detail_scale=2.0, relations="one+two-ring")
    assert figures["folded_triangles"] == _folded(V, ms.current_mesh().vertex_matrix(), F) == 0


def test_a_region_turned_with_the_handles_counts_no_folded_triangle():
    # the end of a strip turned by 2 rad (115 degrees) about y: 378 of its triangles face away from
    # their rest normals, every one of them between the rest and the handles' turn; a fold is a
    # normal against both
    from curvdetail.curvature.testing import grid

    V, F = grid(30, 10, size=(3.0, 1.0))
    V[:, 2] = 0.05 * np.sin(4 * V[:, 0]) * np.cos(3 * V[:, 1])
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F))
    T = np.eye(4)
    T[:3, :3] = [[np.cos(2.0), 0, -np.sin(2.0)], [0, 1, 0], [np.sin(2.0), 0, np.cos(2.0)]]
    T[:3, 3] = [0.2, 0.0, 0.4]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        figures = apply(ms, "apply_curvature_editing", handles=np.flatnonzero(V[:, 0] > 2.4), transform=T,
                        region_radius=BBoxLength(1.85, percent=False))     # x > 0.55 or so
    assert _folded(V, ms.current_mesh().vertex_matrix(), F) > 300
    assert figures["folded_triangles"] == 0 and figures["amplification"] == pytest.approx(1.0)


def _terrain_handles():
    """terrainA_1k in a MeshSet and 20 scattered handles (the review's case, on the small terrain)."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "terrainA_1k.obj"))
    V = ms.current_mesh().vertex_matrix().copy()
    return ms, V, np.random.default_rng(1).choice(V.shape[0], 20, replace=False)


def test_a_detail_edit_amplified_without_folds_warns_with_the_ratio():
    # 20 scattered handles on terrainA_1k, details x1.2, one-ring: the details changed 14 times
    # as much as the edit asks and the vertices moved 10 times as far as with one+two-ring
    # (6.0 % against 0.58 % of the diagonal), without a fold; nothing was said
    ms, V, handles = _terrain_handles()
    edit = dict(handles=handles, region_radius=pymeshlab.PercentageValue(10.0), detail_scale=1.2)
    with pytest.warns(AmplifiedEditWarning, match=r"\b\d+\.\d times.*\(vertex \d+\).*relations='one\+two-ring'"):
        amplified = apply(ms, "apply_curvature_editing", method="paper", **edit)
    assert amplified["folded_triangles"] == 0 and amplified["amplification"] is None
    assert amplified["detail_amplification"] > 3.0 * AMPLIFICATION_LIMIT          # 14.2
    ms, *_ = _terrain_handles()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        steady = apply(ms, "apply_curvature_editing", method="paper", relations="one+two-ring", **edit)
    assert steady["detail_amplification"] < 1.05                                   # 0.80
    assert amplified["max_displacement_percent_of_diagonal"] > 5.0 * steady["max_displacement_percent_of_diagonal"]


def test_the_filter_warns_where_curvdetail_edit_exits_with_status_4(tmp_path, capsys):
    # the same edit through curvdetail edit (.sel/.def) and the filter: the CLI exited 4 ("vertices
    # moved up to 4.3 times as far as the handles") and the filter returned the same ratio silently
    from curvdetail import read_mesh, write_mesh
    from curvdetail.cli import main
    from curvdetail.io.deformation import write_selection, write_transform

    V, F = read_mesh(os.path.join(DATA, "mannequin_nose.obj"))
    diagonal = np.linalg.norm(np.ptp(V, axis=0))
    centre = int(np.argmin(np.linalg.norm(V - V.mean(axis=0), axis=1)))
    handles = np.flatnonzero(np.linalg.norm(V - V[centre], axis=1) < 0.06 * diagonal)
    radius = 0.3 * diagonal
    from scipy.spatial import cKDTree
    status = np.where(cKDTree(V[handles]).query(V)[0] <= radius, 1, 0)
    status[handles] = 2
    T = np.eye(4)
    T[1:3, 1:3] = [[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]]
    T[:3, 3] = V[handles].mean(axis=0) - T[:3, :3] @ V[handles].mean(axis=0)
    write_mesh(tmp_path / "nose.off", V, F)
    write_selection(tmp_path / "nose.sel", status)
    write_transform(tmp_path / "nose.def", T)
    for relations, rc in (("one-ring", 4), ("one+two-ring", 0)):
        out = tmp_path / f"{relations}.ply"
        assert main(["edit", str(tmp_path / "nose.off"), "--sel", str(tmp_path / "nose.sel"), "--def",
                     str(tmp_path / "nose.def"), str(out), "--method", "paper", "--relations", relations]) == rc
        err = capsys.readouterr().err
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F))
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            figures = apply(ms, "apply_curvature_editing", method="paper", handles=handles, transform=T,
                            relations=relations, region_radius=BBoxLength(radius, percent=False))
        assert figures["roi_vertices"] == int(np.count_nonzero(status))
        if rc == 4:
            assert figures["amplification"] > AMPLIFICATION_LIMIT                  # 4.26
            assert f"moved up to {figures['amplification']:.1f} times as far as the handles" in err
            assert [type(w.message) for w in said] == [AmplifiedEditWarning]
            assert f"{figures['amplification']:.1f} times as far as the handles" in str(said[0].message)
        else:
            assert figures["amplification"] < AMPLIFICATION_LIMIT and "warning" not in err   # 1.66
            assert said == []
        # and `curvdetail apply` with the filter exits as `edit` does, the warning on stderr
        params = [f"handles={' '.join(map(str, handles))}", f"transform={' '.join(map(repr, T.ravel().tolist()))}",
                  "method=paper", f"relations={relations}", f"region_radius={float(radius)!r}"]
        assert main(["apply", "apply_curvature_editing", str(tmp_path / "nose.off"), str(tmp_path / f"a-{relations}.ply"),
                     *[a for p in params for a in ("--param", p)]]) == rc
        err = capsys.readouterr().err
        assert ("curvdetail: warning: " in err) == (rc == 4)


def test_detail_scale_below_1_shortens_a_protrusion_and_the_description_says_so():
    # the description said "a factor below 1 shortens them, which lengthens a protrusion"; the
    # detail D = K A is constrained, and the nose's tip details x0.5 shorten the nose (x0.80), x2
    # lengthen it (x1.42), as a horn of mannequin_devil (x0.48 / x2.04, scripts/reproduce_fig1.py)
    from curvdetail.curvature import boundary_vertices

    description = get_filter("apply_curvature_editing").parameter("detail_scale").description
    assert "below 1 flattens what the handles sit on, above 1 sharpens it" in description
    assert "lengthens a protrusion" not in description
    lengths = {}
    for scale in (0.5, 2.0):
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(os.path.join(DATA, "mannequin_nose.obj"))
        V, F = ms.current_mesh().vertex_matrix().copy(), ms.current_mesh().face_matrix()
        base = V[boundary_vertices(F)].mean(axis=0)
        tip = int(np.argmax(np.linalg.norm(V - base, axis=1)))
        handles = np.flatnonzero(np.linalg.norm(V - V[tip], axis=1) < 0.05 * np.linalg.norm(np.ptp(V, axis=0)))
        apply(ms, "apply_curvature_editing", method="paper", handles=handles, region_radius=pymeshlab.PercentageValue(40.0),
              detail_scale=scale, move_handles=False)
        X = ms.current_mesh().vertex_matrix()
        lengths[scale] = np.linalg.norm(X[tip] - base) / np.linalg.norm(V[tip] - base)
    assert lengths[0.5] < 0.9 and lengths[2.0] > 1.3


def _bump_on_a_plane():
    """A 30 x 30 grid, a bump for x < 0.5 and flat beyond (417 rank-deficient rings there, the
    bump none); the corner (0, 1), vertex 870, has a widened ring."""
    from curvdetail.curvature.testing import grid

    V, F = grid(30, 30)
    V[:, 2] = np.where(V[:, 0] < 0.5, 0.05 * np.sin(12 * V[:, 0]) * np.cos(9 * V[:, 1]), 0.0)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F))
    return ms, V, F


@pytest.mark.parametrize("centre, radius", [((0.15, 0.85), 0.2), ((0.3, 0.5), 0.4)])
def test_ring_figures_count_the_region_not_the_whole_mesh(centre, radius):
    # rank_deficient_vertices was the editor's count over the whole mesh: 417 for an edit of the
    # bump that reaches no flat ring; widened_ring_vertices (the editor's widened_rings) is new
    from scipy.spatial import cKDTree

    from curvdetail.curvature import curvature_coefficients

    ms, V, F = _bump_on_a_plane()
    handles = np.flatnonzero(np.linalg.norm(V[:, :2] - centre, axis=1) < 0.05)
    figures = apply(ms, "apply_curvature_editing", method="paper", handles=handles, region_radius=BBoxLength(radius, percent=False),
                    transform="1 0 0 0 0 1 0 0 0 0 1 0.01 0 0 0 1", relations="one+two-ring")
    roi = np.flatnonzero(cKDTree(V[handles]).query(V)[0] <= radius)
    assert figures["roi_vertices"] == roi.size
    _, info = curvature_coefficients(V, F, return_info=True)
    assert info.rank_deficient == 417 and info.widened_vertices.tolist() == [870]
    assert figures["rank_deficient_vertices"] == np.isin(info.rank_deficient_vertices, roi).sum()
    assert figures["widened_ring_vertices"] == np.isin(info.widened_vertices, roi).sum()
    if radius == 0.2:                       # on the bump, at the corner: no flat ring, the widened one
        assert figures["rank_deficient_vertices"] == 0 and figures["widened_ring_vertices"] == 1
    else:                                   # into the flat part, away from the corner
        assert 0 < figures["rank_deficient_vertices"] < 417 and figures["widened_ring_vertices"] == 0


def test_python_callers_may_pass_handles_and_transform_as_arrays():
    # as pymeshlab takes a matrix parameter: the same edit as from the texts, digit for digit
    ms_text, V, d, handles = _meshset_with_roi()
    # a 0.3 rad turn about the handles' centre (about a distant origin it slides the handles
    # along the surface and the region buckles: the ARAP energy's own minimum folds there)
    T = np.eye(4)
    T[:3, :3] = [[np.cos(0.3), -np.sin(0.3), 0.0], [np.sin(0.3), np.cos(0.3), 0.0], [0.0, 0.0, 1.0]]
    c = V[handles].mean(axis=0)
    T[:3, 3] = c - T[:3, :3] @ c + [0.01, 0.0, 0.02 / 3.0]
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
    expected = {"handles", "transform", "method", "detail_scale", "move_handles", "handle_detail", "relations"}
    assert expected <= set(spec.parameter_names)


@pytest.mark.parametrize("params, fields", [
    (dict(handles=""), ("handles", 0, None)),
    (dict(handles="1 2 999999"), ("handles", 1, [999999])),
    (dict(handles="1 99999999999999999999999"), ("handles", 1, [99999999999999999999999])),
    (dict(handles="1 2 2"), ("handles", 1, [2])),
    (dict(handles="1 2", transform="1 0 0"), ("transform", 3, None)),
    (dict(handles="1 2", detail_scale=-1.0), ("detail_scale", None, None)),
    # transforms that collapse the handles: refused here as curvdetail edit's .def files are
    (dict(handles="1 2", transform="0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 1"), ("transform", None, None)),
    (dict(handles="1 2", transform="1 0 0 0 0 1 0 0 0 0 0 0 0 0 0 1"), ("transform", None, None)),
    (dict(handles="1 2", transform="1 0 0 1_0 0 1 0 0 0 0 1 0 0 0 0 1"), ("transform", None, None)),
])
def test_bad_parameters_are_refused(params, fields):
    ms, V, d, handles = _meshset_with_roi()
    with pytest.raises(FilterParameterError) as e:
        apply(ms, "apply_curvature_editing", **params)
    assert (e.value.parameter, e.value.count, e.value.first) == fields


@pytest.mark.parametrize("params, message", [
    (dict(detail_scale=1e300), r"detail_scale .*e\+29\d.*\b1e\+75"),          # the value, the limit
    (dict(transform="1e300 0 0 0 0 1e300 0 0 0 0 1e300 0 0 0 0 1"), r"e\+29\d.*\b1e\+75"),
])
def test_an_overflowing_edit_is_refused_before_the_mesh_is_touched(params, message):
    # before, the positions were written and only then the quality's infinities refused
    ms, V, d, handles = _meshset_with_roi()
    with pytest.raises(FilterParameterError, match=message):
        apply(ms, "apply_curvature_editing", method="paper", handles=" ".join(map(str, handles)), **params)
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
    with pytest.raises(ConstraintError, match=r"layer 0 \('mannequin_ear\.obj'\)") as e:
        apply(ms, "apply_curvature_editing", handles="1 2 3")
    assert (e.value.parameter, e.value.value) == ("region_radius", 0.0)


def test_an_edit_the_handles_do_not_determine_is_refused_with_the_filter_s_options():
    import pymeshlab

    from curvdetail.curvature.errors import UndeterminedEditError
    from curvdetail.curvature.testing import grid
    from curvdetail.filters import apply

    V, F = grid(30, 30)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F))
    # free handle details on a flat grid: nothing ties the in-plane rings of the region down
    with pytest.raises(UndeterminedEditError, match="handle_detail='transform'") as exc:      # the advice
        apply(ms, "apply_curvature_editing", method="paper", handles="450 451 480", handle_detail="free",
              region_radius=pymeshlab.PercentageValue(45.0))
    assert "roi" not in str(exc.value)              # the filter's terms, not the library's
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V)      # untouched
    # the advice works: the handles' details given
    report = apply(ms, "apply_curvature_editing", method="paper", handles="450 451 480", handle_detail="transform",
                   region_radius=pymeshlab.PercentageValue(45.0))
    assert report["max_displacement_percent_of_diagonal"] < 1e-10


def test_a_selected_piece_with_one_handle_is_refused_in_the_filter_s_terms():
    # a second piece wholly selected, one handle on it: its details are fixed only up to a linear
    # map; the filter moved it (its rest shape off by rounding of a singular system) and said nothing
    from curvdetail.curvature.errors import UndeterminedEditError

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, "mannequin_nose.obj"))
    V = ms.current_mesh().vertex_matrix().copy()
    F = ms.current_mesh().face_matrix().copy()
    n = V.shape[0]
    V2, F2 = np.vstack([V, V + [3 * np.ptp(V, axis=0).max(), 0.0, 0.0]]), np.vstack([F, F + n])
    ms.clear()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V2, face_matrix=F2))
    _select(ms, np.arange(2 * n) >= n)
    T = np.eye(4)
    T[2, 3] = 1.0
    with pytest.raises(UndeterminedEditError, match=r"\b1 detail") as exc:
        apply(ms, "apply_curvature_editing", method="paper", handles=[n + 5], transform=T)
    assert (exc.value.count, exc.value.first) == (1, [n])
    assert "roi" not in str(exc.value)
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V2)      # untouched
    # three handles determine it: the translation moves the piece as a whole
    apply(ms, "apply_curvature_editing", method="paper", handles=[n + 5, n + 200, n + 400], transform=T)
    X = ms.current_mesh().vertex_matrix()
    assert np.array_equal(X[:n], V)
    assert np.abs(X[n:] - (V2[n:] + [0.0, 0.0, 1.0])).max() < 1e-8 * np.linalg.norm(np.ptp(V, axis=0))


@pytest.mark.parametrize("shape", [(2, 8), (16, 1), (1, 16)])
def test_a_transform_array_of_another_shape_than_4x4_is_refused(shape):
    # every array was flattened: a 2x8 array (or 16x1, 1x16) passed and was read as a 4x4 matrix
    ms, V, d, handles = _meshset_with_roi()
    T = np.eye(4)
    T[:3, 3] = [0.0, 0.0, 0.02]
    dims = "x".join(map(str, shape))
    with pytest.raises(FilterParameterError, match=rf"\b{dims}\b") as e:
        apply(ms, "apply_curvature_editing", handles=handles, transform=T.reshape(shape))
    assert e.value.parameter == "transform"
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V)
    # the documented forms stay: 16 numbers as a flat list, as in the text
    apply(ms, "apply_curvature_editing", handles=handles, transform=T.ravel().tolist())
    assert np.abs(ms.current_mesh().vertex_matrix()[handles] - (V[handles] + [0, 0, 0.02])).max() < 1e-12


@pytest.mark.parametrize("handles", [[], np.array([], dtype=np.int64)])
def test_handles_given_as_an_empty_list_are_named_as_no_handle(handles):
    # it was "parameter 'handles' expects a str; got [] (list)", about the type
    ms, *_ = _meshset_with_roi()
    with pytest.raises(FilterParameterError) as e:
        apply(ms, "apply_curvature_editing", handles=handles)
    assert (e.value.parameter, e.value.count) == ("handles", 0)


def test_handles_given_as_a_boolean_mask_are_refused_with_the_conversion():
    ms, V, d, handles = _meshset_with_roi()
    mask = np.zeros(V.shape[0], dtype=bool)
    mask[handles] = True
    with pytest.raises(FilterParameterError, match=r"np\.flatnonzero\(mask\)") as e:     # the fix
        apply(ms, "apply_curvature_editing", handles=mask)
    assert e.value.parameter == "handles"
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
    with pytest.raises(ConstraintError, match=given) as error:
        apply(ms, "apply_curvature_editing", handles="1 2 3", region_radius=radius,
              transform="1 0 0 0 0 1 0 0 0 0 1 0.01 0 0 0 1")
    assert error.value.parameter == "region_radius" and error.value.value > 0
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V)
    with pytest.raises(ConstraintError) as error:
        apply(ms, "apply_curvature_editing", handles="1 2 3", region_radius=0.0)
    assert (error.value.parameter, error.value.value) == ("region_radius", 0.0)


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


@pytest.mark.parametrize("handles, value, count, first", [
    ([3.5, 7.0], r"3\.5", 1, [0]), (np.array([3.0, 7.25, 9.5]), r"7\.25", 2, [1, 2]), ("3 7.5", r"7\.5", 1, [1]),
    ([2, np.nan], "nan", 1, [1]),
])
def test_handles_that_are_not_whole_numbers_are_refused_naming_the_first(handles, value, count, first):
    # [3.5, 7.0] was "must be vertex indices separated by spaces or commas; got '3.5 7.0'", naming no value
    ms, V, d, _ = _meshset_with_roi()
    with pytest.raises(FilterParameterError, match=value) as e:
        apply(ms, "apply_curvature_editing", handles=handles, transform="1 0 0 0 0 1 0 0 0 0 1 0.02 0 0 0 1")
    assert (e.value.parameter, e.value.count, e.value.first) == ("handles", count, first)
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


def test_a_translation_with_move_handles_false_is_refused_as_doing_nothing():
    # the details take the transform's linear part alone: the translation was dropped and the
    # mesh came back unchanged, without a word
    ms, V, d, handles = _meshset_with_roi()
    shift = "1 0 0 0.1 0 1 0 0 0 0 1 0 0 0 0 1"
    with pytest.raises(FilterParameterError) as e:
        apply(ms, "apply_curvature_editing", method="paper", handles=" ".join(map(str, handles)), transform=shift,
              move_handles=False)
    assert e.value.parameter == "move_handles"
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V)
    # what the advice names works: the handles move by the translation
    apply(ms, "apply_curvature_editing", method="paper", handles=" ".join(map(str, handles)), transform=shift,
          move_handles=True)
    X = ms.current_mesh().vertex_matrix()
    assert np.allclose(X[handles] - V[handles], [0.1, 0.0, 0.0], atol=1e-12)
    # and so does a detail_scale with the handles left free to move (the details change)
    ms2, V2, _, _ = _meshset_with_roi()
    apply(ms2, "apply_curvature_editing", method="paper", handles=" ".join(map(str, handles)), transform=shift,
          move_handles=False, detail_scale=1.1)
    assert np.abs(ms2.current_mesh().vertex_matrix() - V2).max() > 1e-4 * np.linalg.norm(np.ptp(V2, axis=0))


def test_a_region_of_every_vertex_is_refused_naming_what_made_it():
    # a region_radius beyond the mesh took in every vertex, and the refusal named only the selection
    ms, V, d, handles = _meshset_with_roi()
    h = " ".join(map(str, handles))
    with pytest.raises(ConstraintError, match=r"region_radius=1000") as e:       # what made it
        apply(ms, "apply_curvature_editing", handles=h, region_radius=1000.0)
    assert (e.value.parameter, e.value.value, e.value.count) == ("region_radius", 1000.0, V.shape[0])

    assert np.array_equal(ms.current_mesh().vertex_matrix(), V)
    _select(ms, np.ones(V.shape[0]))
    with pytest.raises(ConstraintError) as e:                                    # the selection alone
        apply(ms, "apply_curvature_editing", handles=h, region_radius=pymeshlab.PercentageValue(0.0))
    assert (e.value.value, e.value.count) == (0.0, V.shape[0]) and "region_radius=" not in str(e.value)

