"""The filter registry: declarations complete, pymeshlab-style listing, lookup with close matches."""

import doctest
import importlib

import pytest

from curvdetail import filters
from curvdetail.filters import Parameter, UnknownFilterError, get_filter, list_filters
from curvdetail.filters.parameters import TYPES
from curvdetail.filters.registry import FAMILIES, filter as declare

CORE_FILTERS = {"compute_curvature_detail", "apply_curvature_reconstruction", "generate_minimal_surface",
                "transfer_curvature_detail", "generate_curvature_remeshing",
                "get_curvature_reconstruction_error", "apply_curvature_editing"}


def test_issue_filters_are_registered():
    assert CORE_FILTERS <= {spec.name for spec in list_filters()}


def test_list_is_sorted_by_name():
    names = [spec.name for spec in list_filters()]
    assert names == sorted(names)


def test_every_filter_is_named_categorized_and_described():
    for spec in list_filters():
        assert spec.name.startswith(FAMILIES) and spec.name == spec.name.lower(), spec.name
        assert spec.category.strip(), spec.name
        assert len(spec.description.split()) >= 20, spec.name


def test_every_filter_description_cites_the_paper():
    for spec in list_filters():
        assert "10.1631/jzus.2006.A1210" in spec.description, spec.name


def test_every_parameter_is_typed_described_and_has_a_valid_default():
    for spec in list_filters():
        for p in spec.parameters:
            assert p.type in TYPES, (spec.name, p.name)
            assert len(p.description.split()) >= 3, (spec.name, p.name)
            assert p.check(p.default) == p.default or (p.type == "mesh" and p.default is None)
            if p.choices is not None:
                assert p.type == "str" and p.default in p.choices, (spec.name, p.name)


def test_parameters_match_the_function_signature():
    import inspect

    for spec in list_filters():
        kw = [q.name for q in inspect.signature(spec.function).parameters.values()
              if q.kind is inspect.Parameter.KEYWORD_ONLY]
        assert sorted(kw) == sorted(spec.parameter_names), spec.name


def test_unknown_filter_lists_close_matches():
    with pytest.raises(UnknownFilterError, match=r"\bcompute_curvature_detail\b") as e:      # the close match
        get_filter("compute_curvature_details")
    assert e.value.value == "compute_curvature_details"


def test_unrelated_name_points_to_the_list():
    with pytest.raises(UnknownFilterError, match="`curvdetail list`") as e:                   # the command
        get_filter("zzzz")
    assert e.value.value == "zzzz"


def test_print_filter_list_prints_every_name(capsys):
    filters.print_filter_list()
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].endswith("list of filter names:")
    assert [line.strip() for line in lines[1:]] == [spec.name for spec in list_filters()]


def test_print_filter_parameter_list_prints_like_pymeshlab(capsys):
    filters.print_filter_parameter_list("apply_curvature_reconstruction")
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "apply_curvature_reconstruction filter - list of parameter names:"
    assert "\trows : str = 'all'" in out and "\tfix_boundary : bool = True" in out


def test_filter_without_parameters_prints_none(capsys, monkeypatch):
    from curvdetail.filters import registry

    monkeypatch.setattr(registry, "_REGISTRY", dict(registry._REGISTRY))     # forgotten after the test
    declare(name="get_nothing", category="c", description="d")(lambda ms: {})
    filters.print_filter_parameter_list("get_nothing")
    assert capsys.readouterr().out.splitlines()[1] == "\tNone."


def test_declaration_refuses_a_name_outside_the_verb_families():
    with pytest.raises(TypeError, match="'curvature_things'"):
        declare(name="curvature_things", category="c", description="d")(lambda ms: {})


def test_declaration_refuses_parameters_that_the_function_lacks():
    def f(ms, *, rows):
        return {}

    with pytest.raises(TypeError, match=r"\['rowz'\].*\['rows'\]"):

        declare(name="get_never_registered", category="c", description="d",
                parameters=[Parameter("rowz", "str", "all", "d")])(f)
    with pytest.raises(UnknownFilterError):
        get_filter("get_never_registered")


@pytest.mark.parametrize("module", ["registry", "dispatch", "mlx", "parameters"])
def test_docstring_examples_run(module):
    mod = importlib.import_module(f"curvdetail.filters.{module}")
    result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def test_filter_functions_get_a_docstring_from_their_declaration():
    for spec in list_filters():
        doc = spec.function.__doc__
        assert doc and spec.description.split()[0] in doc, spec.name
        for p in spec.parameters:
            assert f"{p.name} : {p.type_label}" in doc, (spec.name, p.name)


def test_a_choice_index_means_the_same_value_in_every_filter():
    # pymeshlab and .mlx scripts may give an enumeration by index: rows=1 was "all" in
    # generate_curvature_remeshing and "free" in apply_curvature_reconstruction
    from curvdetail.filters import list_filters

    seen = {}
    for spec in list_filters():
        for p in spec.parameters:
            if p.choices is not None:
                seen.setdefault(p.name, {}).setdefault(frozenset(p.choices), set()).add(p.choices)
    for name, by_set in seen.items():
        for orders in by_set.values():
            assert len(orders) == 1, f"parameter {name!r} lists the same choices in different orders: {orders}"
