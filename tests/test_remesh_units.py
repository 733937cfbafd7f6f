"""One unit convention: a plain length is in model units, a percentage is of the bbox diagonal."""

import numpy as np
import pymeshlab
import pytest

from curvdetail.curvature.errors import CurvdetailError
from curvdetail.curvature.geometry import bbox_diagonal
from curvdetail.data import example_path
from curvdetail.io import read_mesh
from curvdetail.remesh import remesh_experiment
from curvdetail.remesh.units import BBoxLength, as_bbox_length, as_length


@pytest.mark.parametrize("given, expected", [
    (0.3, 0.3), (3, 3.0), (np.float32(0.5), 0.5), (np.array(0.25), 0.25),         # model units
    ("2%", 0.3), ("2 %", 0.3), (" 2.0% ", 0.3), ("1e0%", 0.15),                     # of a diagonal of 15
    (pymeshlab.PercentageValue(2), 0.3), (pymeshlab.PureValue(0.5), 0.5), (BBoxLength(2.0, True), 0.3),
])
def test_lengths_in_model_units_or_percent_of_the_diagonal(given, expected):
    assert as_length(given, 15.0, "target_edge") == pytest.approx(expected, rel=1e-7)    # PureValue: float32


@pytest.mark.parametrize("given", ["0.3", "2 percent", "%", "-1%", "0%", 0, -0.1, float("inf"), float("nan"),
                                   True, None, [1.0], "nan%"])
def test_anything_else_is_refused_naming_the_parameter(given):
    with pytest.raises(CurvdetailError) as refused:
        as_length(given, 15.0, "maxsurfdist")
    assert refused.value.parameter == "maxsurfdist"


def test_a_percentage_is_exactly_its_fraction():
    # "3%" gives the fraction 0.03 to the last bit, as the remeshers were always given it
    assert as_bbox_length("3%").fraction(7.0) == 0.03 and as_bbox_length(0.75).fraction(3.0) == 0.25


def test_the_same_mesh_from_a_percentage_however_given():
    V, F = read_mesh(example_path())
    runs = [remesh_experiment(V, F, target_edge=edge, evaluate=False)
            for edge in ("5%", pymeshlab.PercentageValue(5), BBoxLength(5.0, True))]
    for (X, Ft), report in runs[1:]:
        assert np.array_equal(X, runs[0][0][0]) and np.array_equal(Ft, runs[0][0][1])
        assert report["options"]["target_edge_percent_of_diagonal"] == 5.0
    # and its value in model units: the same edge length (to the rounding of 5 % x diagonal / diagonal)
    (X, Ft), report = remesh_experiment(V, F, target_edge=0.05 * bbox_diagonal(V), evaluate=False)
    assert report["options"]["target_edge_model_units"] == runs[0][1]["options"]["target_edge_model_units"]
    assert abs(Ft.shape[0] - runs[0][0][1].shape[0]) <= 0.02 * Ft.shape[0]


def test_the_filter_takes_a_plain_number_as_model_units_and_reports_both():
    from curvdetail.filters import apply

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(example_path())
    d = bbox_diagonal(ms.current_mesh().vertex_matrix())
    report = apply(ms, "generate_curvature_remeshing", target_edge=0.05 * d, evaluate=False)
    assert report["options"]["target_edge_model_units"] == pytest.approx(0.05 * d, rel=1e-12)
    assert report["options"]["target_edge_percent_of_diagonal"] == pytest.approx(5.0, rel=1e-12)
