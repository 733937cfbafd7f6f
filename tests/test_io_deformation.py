"""The Botsch-Sorkine .sel/.def format (curvdetail.io.deformation) and edit_with_selection's exact
constraint placement."""

import numpy as np
import pytest

from curvdetail import CurvatureEditor
from curvdetail.curvature.rotation_editor import RotationAwareEditor
from curvdetail.curvature.errors import ConstraintError, MeshError
from curvdetail.curvature.testing import grid
from curvdetail.io.deformation import (DeformationFileError, apply_transform, edit_with_selection,
                                       read_selection, read_transform, write_selection, write_transform)


def _strip(n=14):
    """A flat strip along x: left fifth fixed, right fifth the handle."""
    V, F = grid(3 * n, n, size=(3.0, 1.0))
    status = np.where(V[:, 0] < 0.6, 0, np.where(V[:, 0] > 2.4, 2, 1)).astype(np.int8)
    return V, F, status


def _similarity(angle, scale, shift):
    c, s = np.cos(angle), np.sin(angle)
    T = np.eye(4)
    T[:3, :3] = scale * np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    T[:3, 3] = shift
    return T


def test_selection_file_round_trip_keeps_comments_out(tmp_path):
    p = tmp_path / "a.sel"
    p.write_text("# per vertex status\n# 5 vertices\n0\n1\n\n2\n  1 \n0\n")
    assert read_selection(p, 5).tolist() == [0, 1, 2, 1, 0]
    q = tmp_path / "b.sel"
    write_selection(q, [2, 1, 0])
    assert q.read_text() == ("# per vertex status: 0=fixed, 1=deformable-region, 2=handle\n"
                             "# 3 vertices\n2\n1\n0\n")
    assert read_selection(q).tolist() == [2, 1, 0] and read_selection(q).dtype == np.int8


def test_transform_file_is_read_as_a_homogeneous_matrix(tmp_path):
    T = _similarity(0.3, 1.5, [1.0, -2.0, 0.5])
    p = tmp_path / "a.def"
    write_transform(p, T)
    got = read_transform(p)
    assert np.allclose(got, T, atol=1e-9)
    P = np.array([[1.0, 2.0, 3.0]])
    assert np.allclose(apply_transform(got, P), (np.c_[P, [1.0]] @ T.T)[:, :3])


@pytest.mark.parametrize("text, count, first", [
    ("# c\n0\n1\n3\n", 1, [4]),
    ("# c\n0\nx\n1\n7\n", 2, [3, 5]),
    ("# only comments\n\n", 0, None),
])
def test_malformed_selection_is_refused_with_its_lines(tmp_path, text, count, first):
    p = tmp_path / "bad.sel"
    p.write_text(text)
    with pytest.raises(DeformationFileError) as e:
        read_selection(p)
    assert (e.value.count, e.value.first, e.value.value) == (count, first, str(p))


def test_selection_of_the_wrong_length_is_refused(tmp_path):
    p = tmp_path / "a.sel"
    write_selection(p, [0, 1, 2])
    with pytest.raises(DeformationFileError) as e:
        read_selection(p, 4)
    assert e.value.count == 3 and e.value.value == str(p)


@pytest.mark.parametrize("text, count, first", [
    ("# c\n1 0 0 0\n0 1 0 0\n0 0 1 0\n", 3, None),                  # 3 rows
    ("1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0\n", 1, [4]),
    ("1 0 0 0\n0 1 0 0\n0 0 1 a\n0 0 0 1\n", 1, [3]),
    ("1 0 0 0\n0 1 0 0\n0 0 1 nan\n0 0 0 1\n", 1, [3]),
    ("1 0 0 1_0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", 1, [1]),            # Python would read 10
])
def test_a_transform_file_that_is_not_four_rows_of_four_numbers_is_refused(tmp_path, text, count, first):
    p = tmp_path / "bad.def"
    p.write_text(text)
    with pytest.raises(DeformationFileError) as e:
        read_transform(p)
    assert (e.value.count, e.value.first, e.value.value) == (count, first, str(p))


@pytest.mark.parametrize("text", [
    "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0.5 1\n",                       # projective
    "0 0 0 1\n0 1 0 0\n0 0 1 0\n0 0 0 1\n",                         # singular
    "1e6 0 0 0\n0 1e6 0 0\n0 0 1e-12 0\n0 0 0 1\n",                 # collapses z, determinant 1
])
def test_a_transform_that_is_not_an_invertible_affine_map_is_refused(tmp_path, text):
    p = tmp_path / "bad.def"
    p.write_text(text)
    with pytest.raises(DeformationFileError) as e:
        read_transform(p)
    assert e.value.value == str(p)


def test_missing_files_raise_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError):
        read_selection(tmp_path / "none.sel")
    with pytest.raises(FileNotFoundError):
        read_transform(tmp_path / "none.def")


def test_writers_refuse_to_overwrite(tmp_path):
    p = tmp_path / "a.sel"
    write_selection(p, [0, 1])
    with pytest.raises(FileExistsError):
        write_selection(p, [1, 1])
    write_selection(p, [1, 2], overwrite=True)
    assert read_selection(p).tolist() == [1, 2]


@pytest.mark.parametrize("relations", ["one-ring", "one+two-ring"])
@pytest.mark.parametrize("mode", ["transform", "free"])
def test_fixed_vertices_stay_and_handles_land_on_their_transformed_positions(mode, relations):
    V, F, status = _strip()
    T = _similarity(0.4, 1.0, [0.0, 0.3, 0.5])
    X = edit_with_selection(V, F, status, T, method="paper", handle_detail=mode, relations=relations)
    fixed, handles = status == 0, status == 2
    assert np.array_equal(X[fixed], V[fixed])
    assert np.array_equal(X[handles], apply_transform(T, V[handles]))
    assert np.all(np.isfinite(X))


@pytest.mark.parametrize("mode", ["transform", "free"])
def test_free_vertices_are_the_editors_solution_for_the_prescribed_constraints(mode):
    # the benchmark's status and transform mean: region = status 1 and 2, handles at T V, handle
    # details T_3x3 D ("transform") or unknown ("free"); the free vertices are the editor's answer
    V, F, status = _strip()
    T = _similarity(0.4, 1.0, [0.0, 0.3, 0.5])
    X = edit_with_selection(V, F, status, T, method="paper", handle_detail=mode)
    handles = np.flatnonzero(status == 2)
    ed = CurvatureEditor(V, F, handles, handles if mode == "transform" else [], roi=np.flatnonzero(status != 0))
    Y = ed.solve(positions=apply_transform(T, V[handles]),
                 details=ed.detail[handles] @ T[:3, :3].T if mode == "transform" else None)
    free = status == 1
    assert np.abs(X - Y).max() < 1e-12
    # and they did follow the handles: lifted part of the way, between the fixed end and the handle
    assert 0.0 < X[free, 2].min() and X[free, 2].max() < 0.5 + 1e-9


def test_the_default_is_the_rotation_aware_editor_and_paper_options_are_refused_with_it():
    V, F, status = _strip()
    T = _similarity(0.4, 1.0, [0.0, 0.3, 0.5])
    X, ed = edit_with_selection(V, F, status, T, return_editor=True)
    handles = np.flatnonzero(status == 2)
    alone = RotationAwareEditor(V, F, handles, roi=np.flatnonzero(status != 0))
    assert np.abs(X - alone.solve(apply_transform(T, V[handles]))).max() < 1e-12
    assert ed.converged and ed.iterations >= 1
    for option in ({"handle_detail": "free"}, {"relations": "one+two-ring"}):
        with pytest.raises(ValueError) as e:
            edit_with_selection(V, F, status, T, **option)
        assert e.value.parameter == next(iter(option))


def test_a_transform_beyond_double_precision_is_named():
    V, F, status = _strip()
    with pytest.raises(ConstraintError, match="3e\\+300"):
        edit_with_selection(V, F, status, np.diag([1e300, 1e300, 1e300, 1.0]))


def test_identity_transform_leaves_the_mesh_in_place(load_mesh):
    V, F = load_mesh("mannequin_ear.obj")
    d = np.linalg.norm(V - V[0], axis=1)
    status = np.where(d > np.quantile(d, 0.7), 0, np.where(d < np.quantile(d, 0.1), 2, 1))
    X = edit_with_selection(V, F, status, np.eye(4))
    assert np.abs(X - V).max() < 1e-8 * np.linalg.norm(np.ptp(V, axis=0))


def test_rigid_motion_of_a_fully_handled_piece_is_reproduced():
    # every non-fixed vertex a handle with a rigid transform: the handle piece moves rigidly
    V, F, status = _strip()
    status[status == 1] = 2
    T = _similarity(0.25, 1.0, [0.1, 0.2, 0.3])
    X = edit_with_selection(V, F, status, T)
    assert np.array_equal(X[status == 2], apply_transform(T, V[status == 2]))


def test_bad_selections_are_refused_with_their_counts():
    V, F, status = _strip()
    n, free = V.shape[0], np.flatnonzero(status == 1)
    for change, count, first in [(lambda s: s[:-1], n - 1, None), (lambda s: np.where(s == 2, 1, s), 0, None),
                                 (lambda s: np.where(s == 0, 1, s), 0, None),
                                 (lambda s: np.where(s == 1, 5, s), free.size, free[:3].tolist())]:
        with pytest.raises(ConstraintError) as e:
            edit_with_selection(V, F, change(status), np.eye(4))
        assert (e.value.parameter, e.value.count, e.value.first) == ("status", count, first)


def test_unknown_handle_detail_mode_is_refused():
    V, F, status = _strip()
    with pytest.raises(ValueError, match="handle_detail"):
        edit_with_selection(V, F, status, np.eye(4), method="paper", handle_detail="rotate")
    # an array was compared element-wise: numpy's "truth value ... is ambiguous" for two entries
    with pytest.raises(ValueError, match="handle_detail"):
        edit_with_selection(V, F, status, np.eye(4), method="paper",
                            handle_detail=np.array(["transform", "free"]))


def test_a_small_uniform_scaling_is_no_singular_transform(tmp_path):
    # its determinant, 1e-15, was below the absolute threshold 1e-12
    p = tmp_path / "small.def"
    p.write_text("1e-5 0 0 0\n0 1e-5 0 0\n0 0 1e-5 0\n0 0 0 1\n")
    assert np.allclose(read_transform(p)[:3, :3], 1e-5 * np.eye(3))


def test_files_with_a_byte_order_mark_are_read(tmp_path):
    # "1 lines are not a vertex status (line 1: '\ufeff# per vertex status')" before
    sel, d = tmp_path / "a.sel", tmp_path / "a.def"
    sel.write_bytes("\ufeff# per vertex status\n0\n1\n2\n".encode("utf-8"))
    d.write_bytes("\ufeff# transform\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n".encode("utf-8"))
    assert read_selection(sel, 3).tolist() == [0, 1, 2]
    assert np.array_equal(read_transform(d), np.eye(4))


def test_a_folder_or_latin1_text_is_named_as_such(tmp_path):
    with pytest.raises(DeformationFileError) as e:
        read_selection(tmp_path, 3)
    assert e.value.value == str(tmp_path)
    p = tmp_path / "b.sel"
    p.write_bytes("# caf\xe9\n0\n".encode("latin-1"))
    with pytest.raises(DeformationFileError) as e:
        read_selection(p, 1)
    assert e.value.value == str(p) and e.value.first == [5]           # the byte offset


@pytest.mark.parametrize("T", [np.array([[1.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0.5, 0, 0, 1]]),
                               np.diag([1.0, 1.0, 0.0, 1.0]), np.zeros((4, 4)), [[1.0, 0.0], [0.0]], "eye", None,
                               np.full((4, 4), np.nan)])
def test_a_transform_the_reader_refuses_is_refused_when_passed_directly(T):
    # read_transform refuses a projective or collapsing matrix; given as an array, the last row was
    # ignored (the handles moved by the top 3 rows alone) and a singular map flattened the handles;
    # a ragged list or a string raised numpy's own errors
    V, F, status = _strip()
    with pytest.raises(ConstraintError) as e:
        edit_with_selection(V, F, status, T)
    assert e.value.parameter == "T"


@pytest.mark.parametrize("V", [3.0, [[0.0, 1.0], [1.0]], np.zeros(3 * 588)])
def test_vertices_that_are_no_position_array_are_refused_as_a_mesh_error(V):
    # a scalar raised IndexError ("tuple index out of range"); flat coordinates were reported as a
    # status of the wrong length ("588 entries for 1764 vertices")
    _, F, status = _strip()
    with pytest.raises(MeshError, match="V"):
        edit_with_selection(V, F, status, np.eye(4))


def test_return_editor_must_be_a_bool():
    # "no" is truthy: the call returned (X, editor) where X was asked for
    V, F, status = _strip()
    with pytest.raises(ValueError, match="return_editor"):
        edit_with_selection(V, F, status, np.eye(4), return_editor="no")


@pytest.mark.parametrize("T", [np.diag([1e-10, 1e-10, 1e-10, 1.0]), _similarity(0.3, 1.5, [1e-11, 2.0 / 3.0, 1e8])])
def test_written_transforms_read_back_exactly(tmp_path, T):
    # 9 decimals: a uniform scale of 1e-10 was written as zeros (the reader then refused it as
    # singular), a rotation came back 5e-10 off (no longer orthogonal), a tiny shift as 0
    p = tmp_path / "t.def"
    write_transform(p, T)
    assert np.array_equal(read_transform(p), T)


@pytest.mark.parametrize("T", [np.diag([1.0, 1.0, 0.0, 1.0]), np.ones((4, 4)), [[1, 0], [0]]])
def test_a_transform_the_reader_would_refuse_is_not_written(tmp_path, T):
    p = tmp_path / "t.def"
    with pytest.raises(DeformationFileError) as e:
        write_transform(p, T)
    assert e.value.parameter == "T" and not p.exists()


def test_a_selection_with_other_values_is_not_written(tmp_path):
    p = tmp_path / "a.sel"
    for status in ([0, 3], []):
        with pytest.raises(DeformationFileError) as e:
            write_selection(p, status)
        assert e.value.parameter == "status" and not p.exists()
