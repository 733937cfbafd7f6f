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
    with pytest.raises(UnknownFilterError, match="did you mean apply_curvature_reconstruction"):
        apply(meshset(), "apply_curvature_reconstrution")


def test_unknown_parameter_error_lists_close_matches():
    with pytest.raises(FilterParameterError, match="no parameter 'row'; did you mean rows"):
        apply(meshset(), "apply_curvature_reconstruction", row="free")


def test_wrong_type_error_names_parameter_and_type():
    with pytest.raises(FilterParameterError, match="'fix_boundary' expects a bool"):
        apply(meshset(), "apply_curvature_reconstruction", fix_boundary="yes")


def test_validation_happens_before_the_mesh_changes():
    ms = meshset()
    V = ms.current_mesh().vertex_matrix().copy()
    apply(ms, "compute_curvature_detail")
    with pytest.raises(FilterParameterError):
        apply(ms, "apply_curvature_reconstruction", rows="some")
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V)


def test_empty_meshset_is_refused_clearly():
    with pytest.raises(FilterError, match="holds no mesh"):
        apply(pymeshlab.MeshSet(), "compute_curvature_detail")


def test_not_a_meshset_is_refused():
    with pytest.raises(FilterError, match="needs a pymeshlab.MeshSet"):
        apply("mesh.obj", "compute_curvature_detail")


def test_left_out_parameters_take_defaults_not_earlier_values():
    # pymeshlab carries values over between calls; ours never do
    ms = meshset()
    apply(ms, "compute_curvature_detail")
    assert apply(ms, "apply_curvature_reconstruction", rows="free")["rows"] == "free"
    assert apply(ms, "apply_curvature_reconstruction")["rows"] == "all"


def test_returns_a_dict_of_figures():
    figures = apply(meshset(), "compute_curvature_detail")
    assert isinstance(figures, dict) and figures["interior_vertices"] == 640 - 72
