"""MeshLab filter scripts: save/run round trip, native pymeshlab steps mixed in, defaults, errors."""

import os
import re


import numpy as np
import pymeshlab
import pytest

from curvdetail import curvature_detail
from curvdetail.filters import (FilterParameterError, ScriptError, UnknownFilterError, apply,
                                run_script, save_script)
from curvdetail.filters.meshset import vertex_attribute

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")

NATIVE_BORDER = '<filter name="Select Border"/>'
NATIVE_SMOOTH = """<filter name="Laplacian Smooth">
  <Param name="stepSmoothNum" value="2" type="RichInt" description="Smoothing steps" tooltip=""/>
  <Param name="Boundary" value="false" type="RichBool" description="1D Boundary Smoothing" tooltip=""/>
  <Param name="cotangentWeight" value="true" type="RichBool" description="Cotangent weighting" tooltip=""/>
  <Param name="Selected" value="false" type="RichBool" description="Affect only selection" tooltip=""/>
 </filter>"""


def meshset(name="mannequin_nose.obj"):
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(DATA, name))
    return ms


def write(tmp_path, body, name="s.mlx"):
    path = tmp_path / name
    path.write_text(f"<!DOCTYPE FilterScript>\n<FilterScript>\n {body}\n</FilterScript>\n")
    return path


def test_saved_script_runs_to_the_same_mesh_as_direct_calls(tmp_path):
    steps = [("compute_curvature_detail", {}),
             ("apply_curvature_reconstruction", {"rows": "free", "fix_selected": False}),
             ("generate_minimal_surface", {"max_iterations": 3, "tol": 1.0 / 3.0 * 1e-5})]
    save_script(tmp_path / "p.mlx", steps)
    direct, scripted = meshset(), meshset()
    expected = [apply(direct, name, **params) for name, params in steps]
    results = run_script(scripted, tmp_path / "p.mlx")
    assert [r["figures"] for r in results] == expected
    assert scripted.mesh_number() == direct.mesh_number() == 2
    for k in range(2):
        assert np.array_equal(scripted.mesh(k).vertex_matrix(), direct.mesh(k).vertex_matrix())
        assert np.array_equal(scripted.mesh(k).vertex_scalar_array(), direct.mesh(k).vertex_scalar_array())


def test_saved_script_writes_every_parameter_in_meshlab_format(tmp_path):
    save_script(tmp_path / "p.mlx", [("apply_curvature_reconstruction", {"rows": "free"})])
    text = (tmp_path / "p.mlx").read_text()
    assert text.startswith("<!DOCTYPE FilterScript>\n<FilterScript>")
    assert 'name="rows" value="1" type="RichEnum"' in text and 'enum_val1="free"' in text
    for name in ("fix_boundary", "fix_selected", "backend"):
        assert f'name="{name}"' in text


def test_native_and_our_filters_mix_in_order(tmp_path):
    # Laplacian smoothing (pymeshlab) moves interior vertices, then our detail is computed on the
    # smoothed mesh: the stored detail must be that of the smoothed geometry, not the original
    path = write(tmp_path, NATIVE_SMOOTH + "\n " + NATIVE_BORDER +
                 '\n <filter name="compute_curvature_detail"/>')
    ms = meshset()
    V0 = ms.current_mesh().vertex_matrix().copy()
    results = run_script(ms, path)
    assert [r["filter"] for r in results] == ["Laplacian Smooth", "Select Border", "compute_curvature_detail"]
    V, F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    assert np.abs(V - V0).max() > 1e-4
    assert np.array_equal(vertex_attribute(ms, 0, "curvature_detail", "point"), curvature_detail(V, F))
    assert ms.current_mesh().selected_vertex_number() == 72      # the nose's boundary


def test_selection_made_by_a_native_step_is_used_by_ours(tmp_path):
    # Select Border + fix_boundary=false: the selection alone keeps the rim; rebuild is exact
    path = write(tmp_path, NATIVE_BORDER + """
 <filter name="compute_curvature_detail"/>
 <filter name="apply_curvature_reconstruction"><Param name="fix_boundary" value="false"/></filter>""")
    figures = run_script(meshset(), path)[-1]["figures"]
    assert figures["fixed_vertices"] == 72 and figures["max_displacement_percent_of_diagonal"] < 1e-7


def test_missing_parameters_take_their_defaults(tmp_path):
    path = write(tmp_path, '<filter name="compute_curvature_detail"/>\n'
                           ' <filter name="apply_curvature_reconstruction"/>')
    assert run_script(meshset(), path)[-1]["figures"]["rows"] == "all"


def test_enum_given_by_text_is_accepted(tmp_path):
    path = write(tmp_path, '<filter name="compute_curvature_detail"/>\n <filter '
                           'name="apply_curvature_reconstruction"><Param name="rows" value="free"/></filter>')
    assert run_script(meshset(), path)[-1]["figures"]["rows"] == "free"


@pytest.mark.parametrize("enum_values, index, rows", [
    ('enum_val0="free" enum_val1="all"', 0, "free"),        # the script's own order wins
    ('enum_val0="free" enum_val1="all"', 1, "all"),
    ("", 1, "free"),                                          # no list: our order (all, free)
])
def test_enum_index_is_read_through_the_script_s_own_values(tmp_path, enum_values, index, rows):
    path = write(tmp_path, '<filter name="compute_curvature_detail"/>\n <filter name='
                           f'"apply_curvature_reconstruction"><Param name="rows" value="{index}" '
                           f'type="RichEnum" enum_cardinality="2" {enum_values}/></filter>')
    assert run_script(meshset(), path)[-1]["figures"]["rows"] == rows


def test_unknown_parameter_in_script_names_step_and_close_match(tmp_path):
    path = write(tmp_path, '<filter name="generate_minimal_surface"><Param name="max_iteration" '
                           'value="3"/></filter>')
    with pytest.raises(ScriptError, match=r"s\.mlx step 1 .*max_iterations") as e:     # the close match
        run_script(meshset(), path)
    assert e.value.parameter is None           # no such parameter


def test_bad_value_in_script_names_step_and_parameter(tmp_path):
    path = write(tmp_path, NATIVE_BORDER + '\n <filter name="generate_minimal_surface">'
                                           '<Param name="tol" value="small"/></filter>')
    with pytest.raises(ScriptError, match=r"s\.mlx step 2 \(generate_minimal_surface\)") as e:
        run_script(meshset(), path)
    assert e.value.parameter == "tol"


def test_failing_native_step_names_the_step(tmp_path):
    path = write(tmp_path, '<filter name="No Such MeshLab Filter"/>')
    with pytest.raises(ScriptError, match=r"s\.mlx step 1 \(No Such MeshLab Filter\)"):
        run_script(meshset(), path)


@pytest.mark.parametrize("name", ["meshing_remove_duplicate_vertices", "remove duplicate vertices",
                                  "Remove Duplicated Vertex"])
def test_misnamed_meshlab_step_says_what_meshlab_calls_it(tmp_path, name):
    # pymeshlab answers each with "Something really bad happened. Please report this issue"
    path = write(tmp_path, f'<filter name="{name}"/>')
    with pytest.raises(ScriptError, match=r"s\.mlx step 1 .*'remove duplicate vertices'"):    # its words
        run_script(meshset(), path)
    # the name MeshLab writes runs, and does what it says: a grid whose vertex 5 is also stored
    # as vertex 16 (used by one triangle) gets its 16 distinct vertices back
    from curvdetail.curvature.testing import grid

    V, F = grid(4, 4)
    F = F.copy()
    row = int(np.flatnonzero((F == 5).any(axis=1))[0])
    F[row][F[row] == 5] = 16
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(np.vstack([V, V[5]]), F.astype(np.int32)))
    assert ms.current_mesh().vertex_number() == 17
    run_script(ms, write(tmp_path, '<filter name="Remove Duplicate Vertices"/>'))
    assert ms.current_mesh().vertex_number() == 16
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V)
    def triangles(T):
        return sorted(tuple(np.roll(t, -int(np.argmin(t)))) for t in T.tolist())
    assert triangles(ms.current_mesh().face_matrix()) == triangles(grid(4, 4)[1])


@pytest.mark.parametrize("body", [NATIVE_BORDER,
                                  '<filter name="Delete Current Mesh"/>\n ' + NATIVE_BORDER])
@pytest.mark.slow
def test_a_native_step_on_an_empty_meshset_is_refused_in_a_clean_process(tmp_path, body):
    # pymeshlab's script runner crashed the process (segmentation fault) on such a step
    import subprocess
    import sys

    path = write(tmp_path, body)
    script = ("import pymeshlab\nfrom curvdetail.filters import ScriptError, run_script\n"
              f"ms = pymeshlab.MeshSet()\nms.load_new_mesh({os.path.join(DATA, 'mannequin_nose.obj')!r})\n"
              f"if {body.startswith(NATIVE_BORDER)!r}:\n    ms = pymeshlab.MeshSet()\n"
              f"try:\n    run_script(ms, {str(path)!r})\nexcept ScriptError as exc:\n    print(exc)\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "the MeshSet holds no mesh, and this filter needs one" in done.stdout


def test_a_mesh_creating_native_step_runs_on_an_empty_meshset(tmp_path):
    path = write(tmp_path, '<filter name="Sphere"><Param name="subdiv" value="2" type="RichInt"/></filter>')
    ms = pymeshlab.MeshSet()
    run_script(ms, path)
    assert ms.current_mesh().vertex_number() == 162


def test_a_typo_of_one_of_our_filters_gets_the_close_match(tmp_path):
    path = write(tmp_path, '<filter name="compute_curvature_detial"/>')
    with pytest.raises(ScriptError, match=r"s\.mlx step 1 .*\bcompute_curvature_detail\b"):
        run_script(meshset(), path)


def test_a_parameter_given_twice_is_refused(tmp_path):
    path = write(tmp_path, '<filter name="compute_curvature_detail"/>\n <filter name='
                           '"apply_curvature_reconstruction"><Param name="rows" value="all"/>'
                           '<Param name="rows" value="free"/></filter>')
    with pytest.raises(ScriptError, match=r"s\.mlx step 2") as e:
        run_script(meshset(), path)
    assert e.value.parameter == "rows"


@pytest.mark.parametrize("ms, progress, message", [(None, None, "NoneType"), ("meshset", 3, "progress=3")])
def test_run_script_checks_its_arguments(tmp_path, ms, progress, message):
    path = write(tmp_path, '<filter name="compute_curvature_detail"/>')
    with pytest.raises(ScriptError, match=message):
        run_script(meshset() if ms == "meshset" else ms, path, progress=progress)


def test_an_unknown_encoding_is_a_script_error(tmp_path):
    path = tmp_path / "enc.mlx"
    path.write_text('<?xml version="1.0" encoding="foo"?>\n<FilterScript/>\n')
    with pytest.raises(ScriptError, match=r"enc\.mlx"):
        run_script(meshset(), path)


def test_malformed_xml_is_refused(tmp_path):
    path = tmp_path / "bad.mlx"
    path.write_text("<FilterScript><filter name='x'>")
    with pytest.raises(ScriptError, match=r"bad\.mlx"):
        run_script(meshset(), path)


def test_wrong_root_element_is_refused(tmp_path):
    path = tmp_path / "bad.mlx"
    path.write_text("<Script/>")
    with pytest.raises(ScriptError, match=r"bad\.mlx.*<Script>"):
        run_script(meshset(), path)


def test_missing_script_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"none\.mlx"):
        run_script(meshset(), tmp_path / "none.mlx")


@pytest.mark.parametrize("path, kind", [(None, "NoneType"), (3, "int")])
def test_a_script_path_that_is_not_a_path_is_a_script_error(path, kind):
    # os.fspath raised a TypeError
    with pytest.raises(ScriptError, match=kind):
        run_script(meshset(), path)


def test_a_folder_is_named_as_a_folder_not_as_missing(tmp_path):
    # it was "filter script not found" for a folder that exists
    with pytest.raises(ScriptError, match=re.escape(str(tmp_path))):
        run_script(meshset(), tmp_path)


@pytest.mark.parametrize("steps, message", [
    (None, "NoneType"), ("compute_curvature_detail", r"\bstr\b"),
    ([("compute_curvature_detail",)], r"step 1 is \('compute_curvature_detail',\)"),
])
def test_save_refuses_malformed_steps(tmp_path, steps, message):
    with pytest.raises(ScriptError, match=message):
        save_script(tmp_path / "s.mlx", steps)
    assert not (tmp_path / "s.mlx").exists()


def test_save_refuses_to_overwrite_and_unknown_steps(tmp_path):
    path = tmp_path / "p.mlx"
    save_script(path, ["compute_curvature_detail"])
    with pytest.raises(FileExistsError):
        save_script(path, ["compute_curvature_detail"])
    with pytest.raises(UnknownFilterError):
        save_script(tmp_path / "q.mlx", ["compute_curvature_detial"])
    with pytest.raises(FilterParameterError):
        save_script(tmp_path / "q.mlx", [("generate_minimal_surface", {"tol": "x"})])
    assert not (tmp_path / "q.mlx").exists()


def test_progress_is_called_before_each_step(tmp_path):
    path = write(tmp_path, NATIVE_BORDER + '\n <filter name="compute_curvature_detail"/>')
    seen = []
    run_script(meshset(), path, progress=lambda k, n, name: seen.append((k, n, name)))
    assert seen == [(1, 2, "Select Border"), (2, 2, "compute_curvature_detail")]


# MeshLab misreads these without a word (measured): a bool other than "false" is true, an int
# that does not parse is 0, a RichAbsPerc without min and max is ignored, an unknown name too
@pytest.mark.parametrize("param, name, words", [
    ('name="Boundary" value="0" type="RichBool"', "Boundary", "'0'"),
    ('name="Boundary" value="False" type="RichBool"', "Boundary", "'False'"),
    ('name="Boundary" value="no" type="RichBool"', "Boundary", "'no'"),
    ('name="stepSmoothNum" value="3.7" type="RichInt"', "stepSmoothNum", r"'3\.7'"),
    ('name="stepSmoothNum" value="abc" type="RichInt"', "stepSmoothNum", "'abc'"),
    ('name="stepSmoothNum" type="RichInt"', "stepSmoothNum", "None"),
    ('name="Smoothing steps" value="2" type="RichInt"', "Smoothing steps", "stepsmoothnum"),   # the real names
])
def test_native_parameters_meshlab_would_misread_are_refused_before_any_step(tmp_path, param, name, words):
    body = NATIVE_SMOOTH + f'\n <filter name="Laplacian Smooth"><Param {param}/></filter>'
    ms = meshset()
    V0 = ms.current_mesh().vertex_matrix().copy()
    with pytest.raises(ScriptError, match=r"s\.mlx step 2 \(Laplacian Smooth\): .*" + words) as e:
        run_script(ms, write(tmp_path, body))
    assert e.value.parameter == name
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V0)     # step 1 did not run either


@pytest.mark.parametrize("attrs", ['', 'min="0"'])
def test_a_native_absolute_or_percentage_value_without_min_and_max_is_refused(tmp_path, attrs):
    body = ('<filter name="Remeshing: Isotropic Explicit Remeshing"><Param name="TargetLen" value="0.05" '
            'type="RichAbsPerc" {}/></filter>')
    with pytest.raises(ScriptError, match=r"\bmin\b.*\bmax\b") as e:
        run_script(meshset(), write(tmp_path, body.format(attrs)))
    assert e.value.parameter == "TargetLen"
    # with them (their values do not matter to MeshLab) the value is used: a coarser mesh
    ms = meshset()
    run_script(ms, write(tmp_path, body.format('min="0" max="1"')))
    assert ms.current_mesh().vertex_number() < 400


def test_a_native_parameter_name_with_other_capitals_is_reported_after_its_step(tmp_path):
    # MeshLab's own name check is case-sensitive; the step has run without the parameter
    body = '<filter name="Laplacian Smooth"><Param name="stepsmoothnum" value="2" type="RichInt"/></filter>'
    with pytest.raises(ScriptError, match=r"s\.mlx step 1 .*'stepsmoothnum'"):
        run_script(meshset(), write(tmp_path, body))


def test_a_script_pymeshlab_saved_runs_through_the_checks(tmp_path):
    # keyword names ('lambda' is pymeshlab's lambda_) and x/y/z parameters without a value
    ms = meshset()
    ms.apply_coord_taubin_smoothing(lambda_=0.5, mu=-0.53, stepsmoothnum=3, selected=False)
    ms.compute_matrix_from_translation(traslmethod="XYZ translation", axisx=1.0, axisy=0.0, axisz=0.0,
                                       freeze=True, alllayers=False)
    ms.save_filter_script(str(tmp_path / "saved.mlx"))
    scripted = meshset()
    run_script(scripted, tmp_path / "saved.mlx")
    assert np.array_equal(scripted.current_mesh().vertex_matrix(), ms.current_mesh().vertex_matrix())


@pytest.mark.parametrize("value", ["True", "TRUE", "1", "true"])
def test_native_bools_meshlab_reads_as_written_pass(tmp_path, value):
    # MeshLab reads any text but "false" as true: these mean what it reads
    def smoothed(text):
        body = f'<filter name="Laplacian Smooth"><Param name="Boundary" value="{text}" type="RichBool"/></filter>'
        ms = meshset()
        run_script(ms, write(tmp_path, body, name=f"{text}.mlx"))
        return ms.current_mesh().vertex_matrix()

    # the mesh MeshLab's own "true" gives, which differs from "false" (the boundary is smoothed)
    assert np.array_equal(smoothed(value), smoothed("true"))
    assert np.abs(smoothed(value) - smoothed("false")).max() > 1e-6


def test_a_native_float_with_an_underscore_is_refused(tmp_path):
    # Python reads 3_0 as 30, MeshLab as 0
    body = '<filter name="Taubin Smooth"><Param name="lambda" value="0_5" type="RichFloat"/></filter>'
    with pytest.raises(ScriptError, match="'0_5'") as e:
        run_script(meshset(), write(tmp_path, body))
    assert e.value.parameter == "lambda"


DUPLICATE = '<filter name="Duplicate Current layer"/>'


@pytest.mark.parametrize("step, parameter, message", [
    ('<filter name="generate_minimal_surface"><Param name="tol" value="small"/></filter>', "tol", "'small'"),
    ('<filter name="generate_minimal_surface"><Param name="max_iteration" value="3"/></filter>', None,
     r"\bmax_iterations\b"),
    ('<filter name="generate_minimal_surface"><Param name="max_iterations" value="0"/></filter>',
     "max_iterations", r"\b1\b"),
    ('<filter name="generate_minimal_surfaces"/>', None, r"\bgenerate_minimal_surface\b"),
])
def test_a_bad_later_step_of_ours_is_refused_before_the_first_step_runs(tmp_path, step, parameter, message):
    # it was found only when its turn came, after the steps before it (minutes of remeshing)
    # had changed the MeshSet: here the duplicate layer of step 1
    ms = meshset()
    with pytest.raises(ScriptError, match=r"s\.mlx step 2 .*" + message) as e:
        run_script(ms, write(tmp_path, DUPLICATE + "\n " + step))
    assert e.value.parameter == parameter
    assert ms.mesh_number() == 1


def test_a_step_with_another_tag_is_named_by_its_tag_not_as_nameless(tmp_path):
    # "<Filter name='x'>" was called "without a name"
    path = write(tmp_path, '<Filter name="Select Border"/>')
    with pytest.raises(ScriptError, match=r"s\.mlx: step 1 is <Filter name='Select Border'>"):
        run_script(meshset(), path)


def test_a_layer_set_to_the_current_mesh_is_saved_as_such_not_as_its_default(tmp_path):
    # targetmesh=None (current) was left out of the saved script, so the run took its default,
    # layer 0: "sampledmesh and targetmesh are both layer 0", or, with other layers, another
    # layer than the one meant, without a word
    ms = meshset()
    ms.generate_copy_of_current_mesh()                       # layer 1, current
    params = {"sampledmesh": 0, "targetmesh": None, "samplenum": 1000, "set_quality": False}
    save_script(tmp_path / "e.mlx", [("get_curvature_reconstruction_error", params)])
    assert 'name="targetmesh" value=""' in (tmp_path / "e.mlx").read_text()
    assert 'name="sampledmesh" value="0"' in (tmp_path / "e.mlx").read_text()
    figures = run_script(ms, tmp_path / "e.mlx")[0]["figures"]
    assert (figures["sampledmesh"], figures["targetmesh"]) == (0, 1) == \
        tuple(apply(ms, "get_curvature_reconstruction_error", **params)[k] for k in ("sampledmesh", "targetmesh"))
    assert figures["hausdorff_max_percent_of_diagonal"] < 1e-10                 # a copy: on it to rounding


@pytest.mark.parametrize("param, value, message", [
    ("transform", "1 0 0 0 0 1 0 0 0 0 1 0", r"\b12\b"),
    ("transform", "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 nan", "NaN"),
    ("transform", "1 0 0 0 0 1 0 0 0 0 1 0 1 0 0 1", r"\[1.0, 0.0, 0.0, 1.0\]"),      # the last row
    ("handles", "5 x", "'5 x'"),
    ("handles", "5 5", r"\b5\b"),
    ("handles", "2.5", r"2\.5"),
    ("handles", "3 -1", "-1"),
])
def test_a_malformed_edit_is_refused_before_the_first_step_runs(tmp_path, param, value, message):
    # a transform of 12 numbers or repeated handles were found only when the editing step ran,
    # after the steps before it had changed the MeshSet (here: curvature detail stored)
    path = write(tmp_path, '<filter name="compute_curvature_detail"/>\n <filter name="apply_curvature_editing">'
                           f'<Param name="{param}" value="{value}"/></filter>')
    ms = meshset()
    with pytest.raises(ScriptError, match=r"s\.mlx step 2 \(apply_curvature_editing\): .*" + message) as e:
        run_script(ms, path)
    assert e.value.parameter == param
    assert vertex_attribute(ms, 0, "curvature_detail", "point") is None
    with pytest.raises(FilterParameterError, match=message) as e:          # and save_script writes no such step
        save_script(tmp_path / "other.mlx", [("apply_curvature_editing", {param: value})])
    assert e.value.parameter == param


def test_a_step_that_leaves_out_a_required_parameter_is_refused_before_the_first_step_runs(tmp_path):
    # an editing step without handles failed only when it ran, after the steps before it had
    # changed the MeshSet (its default, no handles, never works)
    path = write(tmp_path, '<filter name="compute_curvature_detail"/>\n <filter name="apply_curvature_editing">'
                           '<Param name="region_radius" value="10%"/></filter>')
    ms = meshset()
    with pytest.raises(ScriptError, match=r"s\.mlx step 2 \(apply_curvature_editing\)") as e:
        run_script(ms, path)
    assert e.value.parameter == "handles"
    assert vertex_attribute(ms, 0, "curvature_detail", "point") is None
    with pytest.raises(FilterParameterError) as e:
        save_script(tmp_path / "other.mlx", ["apply_curvature_editing"])
    assert e.value.parameter == "handles"
    assert not (tmp_path / "other.mlx").exists()
    # and apply, before the mesh is read; given, the step runs
    V = ms.current_mesh().vertex_matrix().copy()
    with pytest.raises(FilterParameterError) as e:
        apply(ms, "apply_curvature_editing", region_radius=pymeshlab.PercentageValue(10.0))
    assert e.value.parameter == "handles"
    assert np.array_equal(ms.current_mesh().vertex_matrix(), V)
    apply(ms, "apply_curvature_editing", handles="0 1 2", region_radius=pymeshlab.PercentageValue(10.0))
    from curvdetail.filters import get_filter
    assert [p.name for p in get_filter("apply_curvature_editing").parameters if p.to_dict().get("required")] \
        == ["handles"]


def test_a_last_step_that_deletes_the_last_mesh_is_a_script_error_naming_it(tmp_path):
    # pymeshlab's "MeshSet has no current Mesh" came out of the save afterwards, as a traceback
    script = tmp_path / "d.mlx"
    script.write_text('<!DOCTYPE FilterScript>\n<FilterScript>\n <filter name="compute_curvature_detail"/>\n'
                      ' <filter name="Delete Current Mesh"/>\n</FilterScript>\n')
    with pytest.raises(ScriptError) as e:
        run_script(meshset(), script)
    assert "d.mlx step 2 (Delete Current Mesh)" in str(e.value) and e.value.parameter == "script"
