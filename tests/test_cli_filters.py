"""`curvdetail list / apply / run`: outputs, figures on stdout, and every error path."""

import importlib
import json
import os
import subprocess
import sys

import numpy as np
import pymeshlab
import pytest

from curvdetail.cli import main
from curvdetail.filters import list_filters
from curvdetail.filters.files import load_meshset
from curvdetail.filters.meshset import vertex_attribute

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")
NOSE = os.path.join(DATA, "mannequin_nose.obj")
SPOT = os.path.join(DATA, "spot.obj")


def run_cli(capsys, *argv):
    rc = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, err


def assert_failed(capsys, argv, message, output=None):
    rc, out, err = run_cli(capsys, *argv)
    assert rc != 0
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("curvdetail: error: "), err
    assert message in lines[0], lines[0]
    if output is not None:
        assert not os.path.exists(output)


# --- list ---------------------------------------------------------------------------------------

def test_list_shows_every_filter_with_its_parameters(capsys):
    rc, out, _ = run_cli(capsys, "list")
    assert rc == 0
    for spec in list_filters():
        assert spec.name in out
        for p in spec.parameters:
            assert f"    {p.name} : {p.type_label} = " in out


def test_list_one_filter(capsys):
    rc, out, _ = run_cli(capsys, "list", "apply_curvature_reconstruction")
    assert rc == 0 and out.startswith("apply_curvature_reconstruction  [")
    assert "rows : str = 'all'  (all | free)" in out and "generate_minimal_surface" not in out


def test_list_json_is_every_filter_with_typed_parameters(capsys):
    import json

    rc, out, _ = run_cli(capsys, "list", "--json")
    assert rc == 0
    found = json.loads(out)
    assert [f["name"] for f in found] == [spec.name for spec in list_filters()]
    remesh = {f["name"]: f for f in found}["generate_curvature_remeshing"]
    params = {p["name"]: p for p in remesh["parameters"]}
    assert params["target_edge"]["type"] == "PercentageValue" and params["target_edge"]["default"] == "1.0%"
    assert params["rows"]["default"] == "free" and params["rows"]["choices"] == ["all", "free"]
    assert "\n" not in remesh["description"] and "Fig. 3" in remesh["description"]
    rc, out, _ = run_cli(capsys, "list", "generate_minimal_surface", "--json")
    one = json.loads(out)
    assert one["name"] == "generate_minimal_surface"
    assert {"name": "max_iterations", "type": "int", "default": 200, "min": 1} == \
        {k: v for k, v in one["parameters"][0].items() if k != "description"}


def test_list_unknown_filter_fails(capsys):
    assert_failed(capsys, ["list", "generate_minimal_surfaces"], "generate_minimal_surface")


# --- apply --------------------------------------------------------------------------------------

def test_apply_writes_ply_with_attributes_and_prints_figures(capsys, tmp_path):
    out_path = tmp_path / "d.ply"
    rc, out, _ = run_cli(capsys, "apply", "compute_curvature_detail", NOSE, out_path)
    assert rc == 0 and json.loads(out)["interior_vertices"] == 568
    ms = load_meshset(out_path)
    assert vertex_attribute(ms, 0, "curvature_detail", "point").shape == (640, 3)
    assert ms.current_mesh().has_vertex_scalar()


def test_apply_to_a_format_without_attributes_says_what_is_left_out(capsys, tmp_path):
    rc, _, err = run_cli(capsys, "apply", "compute_curvature_detail", NOSE, tmp_path / "d.obj")
    assert rc == 0
    assert ("note: d.obj holds the geometry only; the vertex quality and the attributes curvature_area, "
            "curvature_detail, curvature_normal, curvature_vertex_id, curvature_vertex_ring are kept by PLY "
            "output.") in err
    rc, _, err = run_cli(capsys, "apply", "compute_curvature_detail", NOSE, tmp_path / "d.ply")
    assert rc == 0 and "note:" not in err


@pytest.mark.parametrize("name, colours", [("d.ctm", False), ("d.obj", False), ("d.stl", False), ("d.ply", True)])
def test_the_note_says_what_an_output_keeps_of_a_coloured_mesh(capsys, tmp_path, name, colours):
    # PLY keeps colours, quality and attributes; every other output the geometry alone, and says so
    ms = load_meshset(NOSE)
    mesh = ms.current_mesh()
    n = mesh.vertex_number()
    ms.add_mesh(pymeshlab.Mesh(mesh.vertex_matrix(), mesh.face_matrix(),
                               v_color_matrix=np.c_[np.linspace(0, 1, n), np.full((n, 2), 0.4), np.ones(n)]))
    ms.save_current_mesh(str(tmp_path / "coloured.ply"))
    rc, _, err = run_cli(capsys, "apply", "compute_curvature_detail", tmp_path / "coloured.ply", tmp_path / name)
    assert rc == 0
    assert ("note:" in err) != colours and (colours or "curvature_detail" in err)
    back = load_meshset(tmp_path / name)                               # what the file holds
    assert back.current_mesh().has_vertex_color() == colours
    assert back.current_mesh().has_vertex_scalar() == colours
    if colours:             # the filter's quality (H) coloured them, as it does the layer in Python
        from curvdetail.filters import apply

        apply(ms, "compute_curvature_detail")
        assert np.abs(back.current_mesh().vertex_color_matrix() - ms.current_mesh().vertex_color_matrix()).max() \
            <= 1 / 255 + 1e-9


def vertices(path):
    ms = load_meshset(path)          # keep the MeshSet alive while its mesh is read
    return ms.current_mesh().vertex_matrix().copy()


def quality(path):
    ms = load_meshset(path)
    return ms.current_mesh().vertex_scalar_array().copy()


def test_apply_chains_through_ply_attributes(capsys, tmp_path):
    # detail stored in d.ply by one command is read back and rebuilt by the next
    run_cli(capsys, "apply", "compute_curvature_detail", NOSE, tmp_path / "d.ply")
    rc, out, _ = run_cli(capsys, "apply", "apply_curvature_reconstruction", tmp_path / "d.ply",
                         tmp_path / "r.ply", "--param", "rows=free")
    assert rc == 0 and json.loads(out)["max_displacement_percent_of_diagonal"] < 1e-7
    assert np.abs(vertices(tmp_path / "r.ply") - vertices(NOSE)).max() < 1e-9


def test_apply_writes_the_new_current_layer(capsys, tmp_path):
    from curvdetail import boundary_vertices, minimal_surface, read_mesh

    rc, out, _ = run_cli(capsys, "apply", "generate_minimal_surface", NOSE, tmp_path / "m.obj",
                         "--param", "max_iterations=2")
    assert rc == 3 and json.loads(out)["iterations"] == 2         # 3: written, not converged
    assert np.abs(vertices(tmp_path / "m.obj") - vertices(NOSE)).max() > 1e-3
    # the file holds the core's two steps (MeshLab's OBJ keeps 16 digits: measured 5.6e-17)
    V, F = read_mesh(NOSE)
    expected = np.asarray(minimal_surface(V, F, boundary_vertices(F), max_iterations=2))
    assert np.abs(vertices(tmp_path / "m.obj") - expected).max() < 1e-12


def test_apply_with_added_layer_transfers_between_files(capsys, tmp_path):
    # INPUT = the source (layer 0), --add = its retriangulation (layer 1, current): transfer, then
    # rebuild the retriangulation from the stored detail in a second command
    ms = load_meshset(NOSE)
    ms.meshing_isotropic_explicit_remeshing(
        iterations=10, adaptive=False, selectedonly=False, targetlen=pymeshlab.PercentageValue(2.0),
        featuredeg=30, checksurfdist=True, maxsurfdist=pymeshlab.PercentageValue(1), splitflag=True,
        collapseflag=True, swapflag=True, smoothflag=True, reprojectflag=True)
    ms.save_current_mesh(str(tmp_path / "retri.ply"))
    rc, out, _ = run_cli(capsys, "apply", "transfer_curvature_detail", NOSE, tmp_path / "t.ply",
                         "--add", tmp_path / "retri.ply")
    assert rc == 0 and json.loads(out)["detail_total_gap"] < 1e-12
    rc, out, _ = run_cli(capsys, "apply", "apply_curvature_reconstruction", tmp_path / "t.ply",
                         tmp_path / "r.ply", "--param", "rows=free")
    assert rc == 0 and json.loads(out)["max_displacement_percent_of_diagonal"] < 1
    # r.ply is the core rebuild of t.ply's geometry from its stored detail (PLY keeps doubles;
    # measured equal), which the retriangulated surface alone is not; and it is far closer to
    # the source than the zero-detail (harmonic) surface of the same boundary (vertex distance
    # at most 0.11 % of the diagonal against 16.5 %)
    from curvdetail import boundary_vertices, read_mesh, reconstruct
    from curvdetail.curvature.geometry import bbox_diagonal
    from curvdetail.remesh import vertex_distance

    t = load_meshset(tmp_path / "t.ply")
    Vt, Ft = t.current_mesh().vertex_matrix().copy(), t.current_mesh().face_matrix().copy()
    Dt = vertex_attribute(t, 0, "curvature_detail", "point")
    b = boundary_vertices(Ft)
    X = vertices(tmp_path / "r.ply")
    assert np.abs(X - reconstruct(Vt, Ft, Dt, b, Vt[b], rows="free")).max() < 1e-9 * bbox_diagonal(Vt)
    V, F = read_mesh(NOSE)
    Z = reconstruct(Vt, Ft, np.zeros_like(Dt), b, Vt[b], rows="free")
    assert vertex_distance(X, V, F).max() < vertex_distance(Z, V, F).max() / 10


def test_apply_missing_added_layer(capsys, tmp_path):
    assert_failed(capsys, ["apply", "transfer_curvature_detail", NOSE, tmp_path / "o.ply", "--add",
                           tmp_path / "none.obj"], "none.obj", tmp_path / "o.ply")


def test_apply_overwrite_replaces_the_output(capsys, tmp_path):
    out_path = tmp_path / "d.ply"
    out_path.write_text("old")
    rc, _, _ = run_cli(capsys, "apply", "compute_curvature_detail", NOSE, out_path, "--overwrite")
    assert rc == 0 and out_path.read_bytes().startswith(b"ply")


def test_apply_refuses_an_existing_output(capsys, tmp_path):
    out_path = tmp_path / "d.ply"
    out_path.write_text("old")
    assert_failed(capsys, ["apply", "compute_curvature_detail", NOSE, out_path], "--overwrite")
    assert out_path.read_text() == "old"


def test_apply_missing_input(capsys, tmp_path):
    assert_failed(capsys, ["apply", "compute_curvature_detail", tmp_path / "none.obj", tmp_path / "o.ply"],
                  "none.obj", tmp_path / "o.ply")


def test_apply_unknown_filter(capsys, tmp_path):
    assert_failed(capsys, ["apply", "compute_curvature_detial", NOSE, tmp_path / "o.ply"],
                  "compute_curvature_detail", tmp_path / "o.ply")


def test_apply_unknown_parameter(capsys, tmp_path):
    assert_failed(capsys, ["apply", "generate_minimal_surface", NOSE, tmp_path / "o.ply", "--param",
                           "max_iteration=3"], "max_iterations", tmp_path / "o.ply")


def test_apply_bad_value(capsys, tmp_path):
    assert_failed(capsys, ["apply", "apply_curvature_reconstruction", NOSE, tmp_path / "o.ply",
                           "--param", "rows=some"], "'some'",
                  tmp_path / "o.ply")
    # an index out of range: the message says indices are taken too
    assert_failed(capsys, ["apply", "apply_curvature_reconstruction", NOSE, tmp_path / "o.ply",
                           "--param", "rows=2"], "'2'",
                  tmp_path / "o.ply")


def test_apply_bad_param_syntax(capsys, tmp_path):
    assert_failed(capsys, ["apply", "generate_minimal_surface", NOSE, tmp_path / "o.ply", "--param",
                           "max_iterations"], "max_iterations", tmp_path / "o.ply")


def test_apply_filter_error(capsys, tmp_path):
    assert_failed(capsys, ["apply", "apply_curvature_reconstruction", NOSE, tmp_path / "o.ply"],
                  "'curvature_detail'", tmp_path / "o.ply")


def test_apply_constraint_error_on_closed_mesh(capsys, tmp_path):
    assert_failed(capsys, ["apply", "generate_minimal_surface", SPOT, tmp_path / "o.ply"],
                  "closed: a minimal surface needs a boundary", tmp_path / "o.ply")


def test_apply_missing_output_folder(capsys, tmp_path):
    assert_failed(capsys, ["apply", "compute_curvature_detail", NOSE, tmp_path / "no" / "o.ply"],
                  "(OUTPUT: ", tmp_path / "no" / "o.ply")


def test_apply_unreadable_input(capsys, tmp_path):
    bad = tmp_path / "bad.off"
    bad.write_text("garbage")
    assert_failed(capsys, ["apply", "compute_curvature_detail", bad, tmp_path / "o.ply"],
                  "bad.off", tmp_path / "o.ply")


# --- run ----------------------------------------------------------------------------------------

SCRIPT = """<!DOCTYPE FilterScript>
<FilterScript>
 <filter name="Select Border"/>
 <filter name="compute_curvature_detail"/>
 <filter name="generate_minimal_surface"><Param name="max_iterations" value="2"/></filter>
</FilterScript>
"""


def test_run_writes_the_current_mesh_after_the_script(capsys, tmp_path):
    (tmp_path / "s.mlx").write_text(SCRIPT)
    rc, out, _ = run_cli(capsys, "run", tmp_path / "s.mlx", NOSE, tmp_path / "o.ply")
    assert rc == 3                              # written, but two minimal-surface steps do not converge
    steps = json.loads(out)
    assert [s["filter"] for s in steps] == ["Select Border", "compute_curvature_detail",
                                            "generate_minimal_surface"]
    moved = np.linalg.norm(vertices(tmp_path / "o.ply") - vertices(NOSE), axis=1)
    assert np.allclose(quality(tmp_path / "o.ply"), moved)   # the minimal-surface layer's quality


def test_run_missing_script(capsys, tmp_path):
    assert_failed(capsys, ["run", tmp_path / "none.mlx", NOSE, tmp_path / "o.ply"],
                  "none.mlx", tmp_path / "o.ply")


def test_run_malformed_script(capsys, tmp_path):
    (tmp_path / "s.mlx").write_text("<FilterScript><filter")
    assert_failed(capsys, ["run", tmp_path / "s.mlx", NOSE, tmp_path / "o.ply"],
                  "s.mlx", tmp_path / "o.ply")


def test_run_refuses_a_script_with_no_steps(capsys, tmp_path):
    # it printed [], exited 0 and wrote a copy of INPUT
    (tmp_path / "s.mlx").write_text("<!DOCTYPE FilterScript>\n<FilterScript>\n</FilterScript>\n")
    assert_failed(capsys, ["run", tmp_path / "s.mlx", NOSE, tmp_path / "o.ply"],
                  "s.mlx", tmp_path / "o.ply")


def test_run_failing_step(capsys, tmp_path):
    (tmp_path / "s.mlx").write_text(SCRIPT.replace("Select Border", "Select Nothing Like This"))
    assert_failed(capsys, ["run", tmp_path / "s.mlx", NOSE, tmp_path / "o.ply"],
                  "s.mlx step 1 (Select Nothing Like This)", tmp_path / "o.ply")


def test_run_bad_value_in_script(capsys, tmp_path):
    (tmp_path / "s.mlx").write_text(SCRIPT.replace('value="2"', 'value="two"'))
    assert_failed(capsys, ["run", tmp_path / "s.mlx", NOSE, tmp_path / "o.ply"],
                  "step 3 (generate_minimal_surface): parameter 'max_iterations'",
                  tmp_path / "o.ply")


def test_run_missing_input(capsys, tmp_path):
    (tmp_path / "s.mlx").write_text(SCRIPT)
    assert_failed(capsys, ["run", tmp_path / "s.mlx", tmp_path / "none.obj", tmp_path / "o.ply"],
                  "none.obj", tmp_path / "o.ply")


def test_installed_command_exits_non_zero_with_one_line(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "curvdetail.cli", "apply", "nope", NOSE,
                           str(tmp_path / "o.ply")], capture_output=True, text=True)
    assert proc.returncode == 1 and proc.stderr.count("\n") == 1
    assert proc.stderr.startswith("curvdetail: error: unknown filter 'nope'")


def test_list_into_a_closed_pipe_exits_quietly():
    # `curvdetail list | head -1`: the reader is gone before the listing is written
    import subprocess
    import sys

    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        done = subprocess.run([sys.executable, "-m", "curvdetail", "list"], stdout=write_end,
                              stderr=subprocess.PIPE, timeout=120)
    finally:
        os.close(write_end)
    assert done.returncode == 0
    assert done.stderr == b""


def test_a_closed_stderr_does_not_stop_the_work(tmp_path):
    # `curvdetail remesh ... 2>&1 | head -c 10`: the progress line met the closed pipe and the
    # run ended with status 0 and no output file; progress and notes now give up quietly
    import subprocess
    import sys

    read_end, write_end = os.pipe()
    os.close(read_end)
    out = tmp_path / "o.ply"
    try:
        done = subprocess.run([sys.executable, "-m", "curvdetail", "remesh", NOSE, str(out), "--target-edge", "6%",
                               "--method", "decimate", "--no-evaluate"],
                              stdout=subprocess.PIPE, stderr=write_end, timeout=300)
    finally:
        os.close(write_end)
    assert done.returncode == 0 and out.exists()
    assert b"vertices; not measured" in done.stdout


def test_a_script_step_with_a_big_target_is_announced_as_a_note(capsys, tmp_path, monkeypatch):
    from curvdetail import read_mesh
    from curvdetail.curvature.geometry import bbox_diagonal
    from curvdetail.filters import save_script

    monkeypatch.setattr(importlib.import_module("curvdetail.remesh.retriangulate"), "BIG_TARGET", 500)
    length = round(0.03 * bbox_diagonal(read_mesh(NOSE)[0]), 6)
    save_script(tmp_path / "s.mlx", [("generate_curvature_remeshing", {"target_edge": length, "evaluate": False})])
    rc, out, err = run_cli(capsys, "run", tmp_path / "s.mlx", NOSE, tmp_path / "o.ply")
    assert rc == 0
    notes = [line for line in err.splitlines() if line.startswith("note: target_edge=")]
    assert len(notes) == 1 and "target vertices; this takes minutes." in notes[0], err
    assert "LongRunWarning" not in err


def test_apply_refuses_to_write_over_an_added_layer_even_with_overwrite(capsys, tmp_path):
    added = tmp_path / "b.obj"
    added.write_bytes(open(NOSE, "rb").read())
    before = added.read_bytes()
    rc, out, err = run_cli(capsys, "apply", "compute_curvature_detail", NOSE, added, "--add", added, "--overwrite")
    assert rc == 1 and "b.obj is an input of this run" in err
    assert added.read_bytes() == before


def test_apply_remeshing_says_a_rebuild_worse_than_zero_detail_as_a_note(capsys, tmp_path):
    from curvdetail import boundary_vertices, write_mesh
    from curvdetail.curvature.testing import disk

    V, F = disk(n_rings=8)                      # noise on a flat disk, see test_remesh_experiment.noisy_disk
    z = 0.02 * np.random.default_rng(1).standard_normal(V.shape[0])
    z[boundary_vertices(F)] = 0.0
    V[:, 2] = z
    write_mesh(tmp_path / "noisy.ply", V, F)
    rc, out, err = run_cli(capsys, "apply", "generate_curvature_remeshing", tmp_path / "noisy.ply", tmp_path / "o.ply",
                           "--param", "transfer=pointwise", "--param", "target_edge=8%")
    assert rc == 0 and json.loads(out)["improvement_over_zero_detail"] < 0.5
    notes = [line for line in err.splitlines() if line.startswith("note: ")]
    assert len(notes) == 1 and "farther from the source than the zero-detail surface" in notes[0], err
    assert "WorseThanZeroDetailWarning" not in err


# --- exit status 3 and the script as an input ----------------------------------------------------

def test_apply_not_converged_exits_3_and_writes_what_minimal_writes(capsys, tmp_path):
    # the rule of `curvdetail minimal`: stopped at max_iterations -> OUTPUT written, a line saying
    # so, exit status 3; the same mesh as minimal's (both run the core's one step; PLY doubles)
    rc, out, err = run_cli(capsys, "apply", "generate_minimal_surface", NOSE, tmp_path / "a.ply",
                           "--param", "max_iterations=1")
    figures = json.loads(out)                       # stdout stays the figures, JSON only
    assert rc == 3 and figures["converged"] is False and figures["iterations"] == 1
    notes = [line for line in err.splitlines() if "not converged" in line]
    assert len(notes) == 1 and "after 1 step," in notes[0] and f"{figures['last_step']:.2e}" in notes[0], err
    assert main(["minimal", NOSE, str(tmp_path / "m.ply"), "--max-iterations", "1"]) == 3
    capsys.readouterr()
    assert np.array_equal(vertices(tmp_path / "a.ply"), vertices(tmp_path / "m.ply"))


def test_apply_converged_exits_0_without_a_note(capsys, tmp_path):
    rc, out, err = run_cli(capsys, "apply", "generate_minimal_surface", NOSE, tmp_path / "a.ply")
    assert rc == 0 and json.loads(out)["converged"] is True and err == ""


def test_every_filter_reporting_convergence_is_covered_by_the_rule():
    # the filters whose figures carry "converged" (grep): if another one appears, give it a test
    # like test_apply_not_converged_exits_3_and_writes_what_minimal_writes
    import inspect

    carrying = sorted(spec.name for spec in list_filters()
                      if '"converged"' in inspect.getsource(inspect.getmodule(spec.function)))
    assert carrying == ["generate_minimal_surface"]


def test_run_not_converged_step_exits_3_and_names_the_step(capsys, tmp_path):
    (tmp_path / "s.mlx").write_text(SCRIPT)
    rc, out, err = run_cli(capsys, "run", tmp_path / "s.mlx", NOSE, tmp_path / "o.ply")
    assert rc == 3 and json.loads(out)[2]["figures"]["converged"] is False
    notes = [line for line in err.splitlines() if "not converged" in line]
    assert len(notes) == 1 and notes[0].startswith(
        "curvdetail: note: s.mlx step 3 (generate_minimal_surface) stopped (not converged) after 2 steps, "), err
    assert (tmp_path / "o.ply").exists()
    (tmp_path / "c.mlx").write_text(SCRIPT.replace('value="2"', 'value="200"'))
    rc, _, err = run_cli(capsys, "run", tmp_path / "c.mlx", NOSE, tmp_path / "c.ply")
    assert rc == 0 and "not converged" not in err


def test_a_minimal_surface_in_obj_says_its_quality_is_left_out(capsys, tmp_path):
    rc, _, err = run_cli(capsys, "apply", "generate_minimal_surface", NOSE, tmp_path / "m.obj")
    assert rc == 0
    assert err == "curvdetail: note: m.obj holds the geometry only; the vertex quality is kept by PLY output.\n"


def test_run_names_a_folder_given_as_script(capsys, tmp_path):
    # the command's own check called an existing folder "not found"
    assert_failed(capsys, ["run", tmp_path, NOSE, tmp_path / "o.ply"],
                  "is a folder; pass the path of a .mlx filter script", tmp_path / "o.ply")


def test_run_checks_the_script_before_reading_input(capsys, tmp_path):
    # a bad step was reported only after INPUT (and the --add meshes) had been read: here the
    # missing input was reported, not the script's mistake
    (tmp_path / "s.mlx").write_text(SCRIPT.replace('value="2"', 'value="two"'))
    assert_failed(capsys, ["run", tmp_path / "s.mlx", tmp_path / "none.obj", tmp_path / "o.ply"],
                  "step 3 (generate_minimal_surface): parameter 'max_iterations'",
                  tmp_path / "o.ply")


def test_figures_print_numpy_values_as_numbers_and_nan_as_null(capsys, tmp_path, monkeypatch):
    # json.dumps(default=str) printed numpy integers, float32 and arrays as strings ("3",
    # "[1. 2.]") and NaN as NaN, which strict JSON readers refuse
    import curvdetail.filters

    figures = {"count": np.int64(3), "ratio": np.float32(0.5), "flag": np.bool_(True), "nan": float("nan"),
               "inf": np.float64(np.inf), "centre": np.array([1.0, 2.0, np.nan]), "scalar": np.array(2.5),
               "pair": (np.int32(1), 2.0), "converged": np.bool_(False), "iterations": np.int64(7)}
    monkeypatch.setattr(curvdetail.filters, "apply", lambda ms, name, **params: dict(figures))

    def refuse(constant):
        raise ValueError(f"{constant} is not JSON")

    rc, out, err = run_cli(capsys, "apply", "compute_curvature_detail", NOSE, tmp_path / "o.ply")
    got = json.loads(out, parse_constant=refuse)
    assert got == {"count": 3, "ratio": 0.5, "flag": True, "nan": None, "inf": None, "centre": [1.0, 2.0, None],
                   "scalar": 2.5, "pair": [1, 2.0], "converged": False, "iterations": 7}
    assert type(got["count"]) is int and type(got["ratio"]) is float
    assert rc == 3 and "after 7 steps" in err          # the not-converged note reads the plain figures




def test_a_big_remeshing_target_is_announced_once_before_the_work(capsys, tmp_path, monkeypatch):
    from curvdetail import read_mesh

    V = read_mesh(NOSE)[0]
    monkeypatch.setattr(importlib.import_module("curvdetail.remesh.retriangulate"), "BIG_TARGET", 500)
    length = round(0.03 * np.linalg.norm(np.ptp(V, axis=0)), 6)
    rc, out, err = run_cli(capsys, "apply", "generate_curvature_remeshing", NOSE, tmp_path / "o.ply",
                           "--param", f"target_edge={length}", "--param", "evaluate=false")
    notes = [line for line in err.splitlines() if line.startswith("note: ")]
    assert rc == 0 and len(notes) == 1 and f"target_edge={length}" in notes[0], err
    assert "LongRunWarning" not in err
    monkeypatch.setattr(importlib.import_module("curvdetail.remesh.retriangulate"), "BIG_TARGET", 1_000_000)
    rc, out, err = run_cli(capsys, "apply", "generate_curvature_remeshing", NOSE, tmp_path / "p.ply",
                           "--param", f"target_edge={length}", "--param", "evaluate=false")
    assert rc == 0 and "note:" not in err


@pytest.mark.parametrize("link", ["same", "dot-slash", "symlink", "hardlink"])
def test_run_never_writes_over_its_script_even_with_overwrite(capsys, tmp_path, monkeypatch, link):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.ply").write_text(SCRIPT)              # a script under any name runs
    output = {"same": "s.ply", "dot-slash": "./s.ply", "symlink": "sym.ply", "hardlink": "hard.ply"}[link]
    if link == "symlink":
        os.symlink("s.ply", "sym.ply")
    elif link == "hardlink":
        os.link("s.ply", "hard.ply")
    rc, out, err = run_cli(capsys, "run", "s.ply", NOSE, output, "--overwrite")
    assert rc == 1 and out == "" and "(SCRIPT s.ply)" in err
    assert (tmp_path / "s.ply").read_text() == SCRIPT


@pytest.mark.parametrize("link", ["symlink", "hardlink"])
@pytest.mark.parametrize("command", ["apply", "run"])
def test_an_added_mesh_reached_through_another_path_is_never_overwritten(capsys, tmp_path, command, link):
    mesh = tmp_path / "b.obj"
    mesh.write_bytes(open(NOSE, "rb").read())
    before = mesh.read_bytes()
    other = tmp_path / "other.obj"
    (os.symlink if link == "symlink" else os.link)(mesh, other)
    (tmp_path / "s.mlx").write_text(SCRIPT)
    first = ["apply", "compute_curvature_detail"] if command == "apply" else ["run", tmp_path / "s.mlx"]
    for argv in ([NOSE, other, "--add", mesh], [mesh, other, "--add", mesh], [NOSE, mesh, "--add", other]):
        rc, out, err = run_cli(capsys, *first, *argv, "--overwrite")
        assert rc == 1 and out == "" and "(--add " in err, err
        assert mesh.read_bytes() == before
    # OUTPUT over INPUT alone is taken with --overwrite: the name given is replaced
    rc, out, err = run_cli(capsys, *first, mesh, other, "--overwrite")
    assert rc in (0, 3) and other.read_bytes() != before


def test_a_refused_decimation_exits_1_and_writes_nothing(capsys, tmp_path):
    rc, out, err = run_cli(capsys, "apply", "generate_curvature_remeshing", NOSE, tmp_path / "o.ply",
                           "--param", "method=decimate", "--param", "target_edge=0.5%")
    assert rc == 1 and err.startswith("curvdetail: error: ") and "isotropic" in err
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("name, parameter", [("transfer_curvature_detail", "targetmesh"),
                                             ("get_curvature_reconstruction_error", "sampledmesh")])
def test_a_second_layer_missing_from_apply_names_add_and_the_param(capsys, tmp_path, name, parameter):
    rc, out, err = run_cli(capsys, "apply", name, NOSE, tmp_path / "o.ply")
    assert rc == 1 and out == "" and f"(--add MESH / --param {parameter}: " in err, err
    assert not os.path.exists(tmp_path / "o.ply")


def test_an_editing_warning_from_apply_exits_4_with_the_output_written(capsys, tmp_path):
    rc, out, err = run_cli(capsys, "apply", "apply_curvature_editing", NOSE, tmp_path / "o.ply",
                           "--param", "handles=300 301 302", "--param", "region_radius=30%",
                           "--param", "transform=1 0 0 0 0 1 0 0 0 0 1 0.5 0 0 0 1")
    folded = json.loads(out)["folded_triangles"]
    assert rc == 4 and folded > 0 and (tmp_path / "o.ply").exists()
    assert "curvdetail: warning: apply_curvature_editing" in err and str(folded) in err, err


@pytest.mark.parametrize("params", [["backend=pardiso"], ["handles=0 1 2", "region_radius=20%", "method=paper", "backend=cholmod"]])
def test_a_backend_error_names_the_backend_param(capsys, tmp_path, monkeypatch, params):
    import curvdetail.curvature.sparse_solver as solver

    monkeypatch.setattr(solver, "available_backends", lambda: ["cholmod", "splu"])
    name = "generate_minimal_surface" if len(params) == 1 else "apply_curvature_editing"
    argv = [a for p in params for a in ("--param", p)]
    assert_failed(capsys, ["apply", name, NOSE, tmp_path / "o.ply", *argv], "(--param backend: ", tmp_path / "o.ply")


def test_a_closed_mesh_rebuilt_by_apply_gets_one_anchor(capsys, tmp_path):
    detail = tmp_path / "d.ply"
    assert run_cli(capsys, "apply", "compute_curvature_detail", SPOT, detail)[0] == 0
    rc, out, _ = run_cli(capsys, "apply", "apply_curvature_reconstruction", detail, tmp_path / "r.ply")
    figures = json.loads(out)
    assert rc == 0 and figures["anchors"] == 1 and figures["max_displacement_percent_of_diagonal"] < 1e-10


def test_a_required_parameter_left_out_of_apply_names_it(capsys, tmp_path):
    assert_failed(capsys, ["apply", "apply_curvature_editing", NOSE, tmp_path / "o.ply"],
                  "(--param handles: ", tmp_path / "o.ply")


def test_a_script_whose_step_deletes_the_last_mesh_names_the_step(capsys, tmp_path):
    (tmp_path / "d.mlx").write_text('<!DOCTYPE FilterScript>\n<FilterScript>\n <filter name="Delete Current Mesh"/>\n'
                                    '</FilterScript>\n')
    assert_failed(capsys, ["run", tmp_path / "d.mlx", NOSE, tmp_path / "o.ply"], "d.mlx step 1 (Delete Current Mesh)",
                  tmp_path / "o.ply")
