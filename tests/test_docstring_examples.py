"""The Examples sections of the remeshing, filter and editing modules run as written (the core
modules' doctests run in their own test files)."""

import doctest
import importlib

import pytest

MODULES = [
    "curvdetail.remesh.closest_point", "curvdetail.remesh.evaluate", "curvdetail.remesh.experiment",
    "curvdetail.remesh.locate",
    "curvdetail.remesh.parameterize", "curvdetail.remesh.retriangulate", "curvdetail.remesh.transfer",
    "curvdetail.filters.dispatch", "curvdetail.filters.mlx", "curvdetail.filters.parameters",
    "curvdetail.io.deformation", "curvdetail.plot", "curvdetail.curvature.curvature_editor",
    "curvdetail.curvature.curvature_coefficients", "curvdetail.curvature.boundary_editing",
    "curvdetail.remesh._disk",
]


@pytest.mark.parametrize("name", MODULES)
def test_examples_run_as_written(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
