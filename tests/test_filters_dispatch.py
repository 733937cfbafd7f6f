"""apply(ms, name, **params): validation at the boundary, defaults, layers, pymeshlab failures."""

import os

import numpy as np
import pymeshlab
import pytest

from curvdetail.filters import (FilterError, FilterParameterError, UnknownFilterError, apply)

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


def meshset(name="mannequin_nose.obj"):
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, name))
    return ms


def test_unknown_filter_error_lists_close_matches():
    with pytest.raises(UnknownFilterError, match=r"\bapply_curvature_reconstruction\b") as e:    # the close match
        apply(meshset(), "apply_curvature_reconstrution")
    assert e.value.value == "apply_curvature_reconstrution"


def test_unknown_parameter_error_lists_close_matches():
    with pytest.raises(FilterParameterError, match=r"\brows\b") as e:                # the close match
        apply(meshset(), "apply_curvature_reconstruction", row="free")
    assert e.value.value == "row"


def test_wrong_type_error_names_parameter_and_type():
    with pytest.raises(FilterParameterError, match=r"\bbool\b") as e:
        apply(meshset(), "apply_curvature_reconstruction", fix_boundary="yes")
    assert e.value.parameter == "fix_boundary"


def test_validation_happens_before_the_mesh_changes():
    ms = meshset()
    V = ms.current_mesh().vertex_matrix().copy()
    apply(ms, "compute_curvature_detail")
    with pytest.raises(FilterParameterError):
        apply(ms, "apply_curvature_reconstruction", rows="some")
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V)


def test_empty_meshset_is_refused_clearly():
    with pytest.raises(FilterError) as e:
        apply(pymeshlab.MeshSet(), "compute_curvature_detail")
    assert (e.value.parameter, e.value.count) == ("ms", 0)


def test_not_a_meshset_is_refused():
    with pytest.raises(FilterError, match=r"\bstr\b") as e:
        apply("mesh.obj", "compute_curvature_detail")
    assert e.value.parameter == "ms"



def test_left_out_parameters_take_defaults_not_earlier_values():
    # pymeshlab carries values over between calls; ours never do
    ms = meshset()
    apply(ms, "compute_curvature_detail")
    assert apply(ms, "apply_curvature_reconstruction", rows="free")["rows"] == "free"
    assert apply(ms, "apply_curvature_reconstruction")["rows"] == "all"


def test_returns_a_dict_of_figures():
    figures = apply(meshset(), "compute_curvature_detail")
    assert isinstance(figures, dict) and figures["interior_vertices"] == 640 - 72
