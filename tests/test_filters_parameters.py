"""Typed filter parameters: checking Python values, parsing text, bbox-diagonal lengths."""

import numpy as np
import pymeshlab
import pytest

from curvdetail.filters import BBoxLength, FilterParameterError, Parameter


def test_percentage_value_resolves_to_a_fraction_of_the_diagonal():
    p = Parameter("targetlen", "PercentageValue", pymeshlab.PercentageValue(1.0), "edge length")
    assert p.default == BBoxLength(1.0, True)
    assert p.check(pymeshlab.PercentageValue(2.5)).resolve(4.0) == pytest.approx(0.1, rel=1e-15)


def test_pure_value_and_plain_number_are_absolute_lengths():
    p = Parameter("targetlen", "PercentageValue", 0.5, "edge length")
    assert p.check(pymeshlab.PureValue(0.25)).resolve(1000.0) == 0.25  # 0.25 is exact in float32
    assert p.check(0.125).resolve(1000.0) == 0.125


def test_percentage_text_parses_as_percent_and_number_as_absolute():
    p = Parameter("targetlen", "PercentageValue", 0.5, "edge length")
    assert p.parse("1.5%") == BBoxLength(1.5, True)
    assert p.parse("0.02") == BBoxLength(0.02, False)


def test_formatted_values_parse_back_exactly():
    cases = [Parameter("a", "float", 1.0, "d"), Parameter("b", "bool", True, "d"),
             Parameter("c", "int", 3, "d"), Parameter("e", "PercentageValue", 1.0, "d"),
             Parameter("f", "str", "x", "d", choices=("x", "y"))]
    values = [0.1 + 1e-13, False, -7, BBoxLength(1.0 / 3.0, True), "y"]
    for p, v in zip(cases, values):
        assert p.parse(p.format(v)) == v


def _refused(p, value, parse=False):
    """The FilterParameterError of ``p.check(value)`` (``p.parse`` with ``parse``), which names ``p``."""
    with pytest.raises(FilterParameterError) as e:
        (p.parse if parse else p.check)(value)
    assert e.value.parameter == p.name
    return e.value


def test_wrong_type_error_names_parameter_and_expected_type():
    p = Parameter("max_iterations", "int", 200, "steps")
    assert "'200' (str)" in str(_refused(p, "200"))
    assert "2.5 (float)" in str(_refused(p, 2.5))


def test_bool_is_not_accepted_as_a_number():
    assert "True (bool)" in str(_refused(Parameter("tol", "float", 1e-6, "tolerance"), True))


def test_numpy_scalars_are_accepted():
    assert Parameter("n", "int", 1, "d").check(np.int32(4)) == 4
    assert Parameter("x", "float", 1.0, "d").check(np.float32(0.5)) == 0.5
    assert Parameter("b", "bool", False, "d").check(np.True_) is True        # numpy 2's bool
    _refused(Parameter("n", "int", 1, "d"), np.False_)


@pytest.mark.parametrize("kind, value, message", [
    ("mesh", 2 ** 31, "2147483648"), ("int", -(2 ** 40), "-1099511627776"), ("float", 10 ** 400, "inf"),
])
def test_numbers_beyond_what_pymeshlab_takes_are_refused(kind, value, message):
    # they reached pybind11 (TypeError) or float() (OverflowError) before
    p = Parameter("p", kind, None if kind == "mesh" else 1, "d")
    assert message in str(_refused(p, value))
    _refused(p, str(value), parse=True)


def test_an_enum_index_in_other_digits_is_named_not_a_key_error():
    p = Parameter("rows", "str", "all", "rows", choices=("all", "free"))
    assert "all, free" in str(_refused(p, "\u00b2", parse=True))       # the choices


def test_choice_is_case_insensitive_and_canonical():
    p = Parameter("rows", "str", "all", "rows", choices=("all", "free"))
    assert p.check("FREE") == "free"
    assert "all, free" in str(_refused(p, "some"))


def test_enum_index_parses_as_meshlab_writes_it():
    p = Parameter("method", "str", "pointwise", "m", choices=("pointwise", "conservative"))
    assert p.parse("1") == "conservative"


def test_range_is_enforced():
    p = Parameter("max_iterations", "int", 200, "steps", min=1)
    assert "at least 1" in str(_refused(p, 0))       # the bound


@pytest.mark.parametrize("value", [0.0, -1e-9, pymeshlab.PercentageValue(0.0)])
def test_positive_parameters_refuse_zero_and_below(value):
    p = Parameter("target_edge", "PercentageValue", BBoxLength(1.0, True), "edge", positive=True)
    assert "greater than 0" in str(_refused(p, value))       # the bound
    assert p.check(pymeshlab.PercentageValue(0.5)) == BBoxLength(0.5, True)


@pytest.mark.parametrize("name, parameter", [("generate_minimal_surface", "tol"),
                                             ("generate_curvature_remeshing", "target_edge"),
                                             ("apply_curvature_editing", "detail_scale")])
def test_filters_declare_the_strictly_positive_ranges_their_code_demands(name, parameter):
    # the declared range is what `curvdetail list` shows and what apply checks before running
    from curvdetail.filters.registry import describe_filter, get_filter

    spec = get_filter(name)
    p = next(q for q in spec.parameters if q.name == parameter)
    assert p.positive
    line = next(text for text in describe_filter(spec).splitlines() if text.strip().startswith(parameter))
    assert "> 0" in line and ">= 0" not in line
    _refused(p, "0", parse=True)


def test_non_finite_float_is_refused():
    assert "nan" in str(_refused(Parameter("tol", "float", 1e-6, "tolerance"), "nan", parse=True))


def test_unparsable_text_names_parameter():
    assert "'maybe'" in str(_refused(Parameter("fix_boundary", "bool", True, "d"), "maybe", parse=True))


def test_mesh_parameter_defaults_to_current_mesh():
    p = Parameter("sourcemesh", "mesh", None, "source layer")
    assert p.check(None) is None and p.parse("2") == 2 and p.type_label == "int"


def test_negative_layer_id_is_refused():
    assert "-1" in str(_refused(Parameter("targetmesh", "mesh", 0, "target layer"), -1))


def test_declaration_needs_known_type_and_description():
    with pytest.raises(TypeError, match="'double'"):
        Parameter("x", "double", 1.0, "d")
    with pytest.raises(TypeError, match="'x'"):
        Parameter("x", "float", 1.0, " ")


def test_enum_takes_its_index_from_python_as_pymeshlab_does():
    p = Parameter("rows", "str", "all", "rows", choices=("all", "free"))
    assert p.check(1) == "free" and p.check(np.int64(0)) == "all"
    for bad in (2, -1, True):
        assert "all, free" in str(_refused(p, bad))


def test_text_parameter_takes_a_sequence_of_numbers_digit_for_digit():
    p = Parameter("transform", "str", "", "numbers")
    assert p.check([1, 2, 3]) == "1 2 3"
    assert p.check(np.array([[0.1, 1 / 3], [2.0, 5.0]])) == "0.1 0.3333333333333333 2.0 5.0"
    assert [float(t) for t in p.check(np.array([np.pi])).split()] == [np.pi]
    # a list of numpy scalars (numpy 2 writes np.float64(1.0) as "np.float64(1.0)")
    assert p.check(list(np.eye(2).ravel())) == "1.0 0.0 0.0 1.0"
    assert p.check([np.int64(3), np.int32(4), np.float32(0.5)]) == "3 4 0.5"
    for bad in ([[1, 2], [3]], ["1", 2], object()):
        _refused(p, bad)
    # True/False among numbers are named with the position of the first
    assert "position 0" in str(_refused(p, [True, 2]))
    assert "position 1" in str(_refused(p, (2, np.True_)))


@pytest.mark.parametrize("shape", [(2, 8), (16, 1), (1, 16), (4, 4, 1)])
def test_a_matrix_parameter_refuses_arrays_of_another_shape(shape):
    # every array was flattened: a 2x8 array passed and was read row by row as a 4x4 matrix
    p = Parameter("transform", "str", "", "4x4 matrix", shape=(4, 4))
    dims = "x".join(map(str, shape))
    assert f"a {dims} array" in str(_refused(p, np.arange(16.0).reshape(shape)))
    text = " ".join(repr(float(x)) for x in range(16))
    for good in (np.arange(16.0).reshape(4, 4), np.arange(16.0), np.arange(16.0).reshape(4, 4).tolist()):
        assert p.check(good) == text                  # the matrix, or its 16 numbers row by row


def test_a_shape_is_declared_for_a_str_of_numbers_only():
    with pytest.raises(TypeError, match="'rows'"):
        Parameter("rows", "str", "all", "d", choices=("all", "free"), shape=(2,))


def test_an_index_parameter_takes_any_array_of_indices():
    # no shape declared: an index set, whose order does not matter (np.argwhere gives (k, 1))
    p = Parameter("handles", "str", "", "indices")
    assert p.check(np.argwhere(np.array([0, 1, 1, 0]))) == "1 2"


@pytest.mark.parametrize("value, text", [(3, "3"), (np.int64(3), "3"), (3.0, "3.0"), (range(2, 5), "2 3 4"),
                                         ({7, 2, 5}, "2 5 7"), (frozenset({1.0, 0.0}), "0.0 1.0")])
def test_an_index_parameter_takes_a_single_number_a_range_and_a_set(value, text):
    # each was "expects a str (from Python also a list or array of numbers); got 3 (int)": an index
    # set's order does not matter (a set comes sorted), and one number is one index
    assert Parameter("handles", "str", "", "indices").check(value) == text


@pytest.mark.parametrize("value, what", [(3, "(3)"), (set(range(16)), "set of 16")])
def test_a_matrix_parameter_refuses_a_single_number_and_a_set_with_the_fix(value, what):
    # a matrix is read row by row: one number is no matrix, and a set has no order to read
    p = Parameter("transform", "str", "", "4x4 matrix", shape=(4, 4))
    message = str(_refused(p, value))
    assert what in message and "(4, 4)" in message
    assert p.check(range(16)) == " ".join(map(str, range(16)))      # a range has an order


@pytest.mark.parametrize("empty", [[], (), np.array([], dtype=np.int64), np.zeros((0, 2))])
def test_an_empty_sequence_of_numbers_is_the_empty_text(empty):
    # it was "expects a str; got [] (list)": the filter now names the empty value as empty
    assert Parameter("handles", "str", "", "indices").check(empty) == ""


@pytest.mark.parametrize("mask", [np.array([False, True, True, False]), [False, True, True, False]])
def test_a_boolean_mask_is_refused_with_the_indices_it_means(mask):
    # it was "expects a str; got array([False, True, ...]) (ndarray)", about the type
    p = Parameter("handles", "str", "", "indices")
    assert "np.flatnonzero(mask)" in str(_refused(p, mask))        # the fix


def test_masked_entries_are_refused_not_read_as_numbers():
    # np.ma.array([1, 2], mask=[0, 1]) was read as "1 2", the masked entry included
    p = Parameter("handles", "str", "", "indices")
    _refused(p, np.ma.array([1, 2], mask=[False, True]))
    assert p.check(np.ma.array([1, 2], mask=[False, False])) == "1 2"


@pytest.mark.parametrize("value", [np.array(["all"]), np.array(["all", "free"]), ["all"], ("free",),
                                   np.array("all")])
def test_an_enum_given_as_an_array_or_a_list_names_the_parameter_and_the_choices(value):
    # not numpy's "truth value of an array ... is ambiguous", and not the first element taken
    p = Parameter("rows", "str", "all", "rows", choices=("all", "free"))
    assert "all, free" in str(_refused(p, value))


def test_an_enum_index_outside_the_choices_says_the_range_of_indices():
    # it was "expects a str (one of all, free, or its index); got 2 (int)": the type was right,
    # the index was not (pymeshlab: "Enum 2 not valid. Must be a value between 0 and 1")
    p = Parameter("rows", "str", "all", "rows", choices=("all", "free"))
    for bad in (2, np.int64(-1)):
        assert "0 to 1" in str(_refused(p, bad))


@pytest.mark.parametrize("kind, value, expected", [
    ("int", np.array(5), 5), ("float", np.array(0.25), 0.25), ("bool", np.array(False), False),
    ("mesh", np.array(2, dtype=np.int32), 2), ("PercentageValue", np.array(0.5), BBoxLength(0.5, False)),
])
def test_a_zero_dimensional_array_is_taken_as_its_number_as_pymeshlab_takes_it(kind, value, expected):
    # pymeshlab's iterations=np.array(5) runs; it was "expects an int; got array(5) (ndarray)"
    default = {"int": 1, "float": 1.0, "bool": True, "mesh": None, "PercentageValue": 1.0}[kind]
    out = Parameter("x", kind, default, "d").check(value)
    assert out == expected and type(out) is type(expected)


@pytest.mark.parametrize("text", ["", "current", " Current "])
def test_a_layer_id_written_empty_or_current_reads_back_as_the_current_mesh(text):
    # format(None) writes "", which parse refused ("expects a layer id (integer); got ''")
    p = Parameter("targetmesh", "mesh", 0, "layer")
    assert p.format(None) == "" and p.parse(text) is None and p.parse("3") == 3


@pytest.mark.parametrize("value, expected", [(np.array(1), "free"), (np.array(0, dtype=np.int32), "all"),
                                             (np.array(np.uint8(1)), "free")])
def test_an_enum_index_given_as_a_zero_dimensional_array_is_taken(value, expected):
    # docs/guide/filters.md: "numpy scalars and 0-d arrays are taken as the numbers they hold", and an
    # enumeration takes its index; np.array(1) was refused as "expects a str (... or its index)"
    # while np.int64(1) was taken
    p = Parameter("rows", "str", "all", "rows", choices=("all", "free"))
    out = p.check(value)
    assert out == expected and type(out) is str
    assert "0 to 1" in str(_refused(p, np.array(2)))



def test_curvdetail_list_says_which_parameters_are_required():
    # `curvdetail list` is the full reference: a parameter whose default is refused (the editing
    # filter's handles) is marked there as in the JSON listing, and only that one
    from curvdetail.filters.registry import describe_filter, list_filters

    for spec in list_filters():
        for p in spec.parameters:
            line = next(text for text in describe_filter(spec).splitlines()
                        if text.startswith(f"    {p.name} : "))
            assert ("(required" in line) == bool(p.to_dict().get("required")), line
    text = describe_filter(next(s for s in list_filters() if s.name == "apply_curvature_editing"))
    assert "    handles : str = ''  (required)" in text.splitlines()
