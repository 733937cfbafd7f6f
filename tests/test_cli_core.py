"""The reconstruct and minimal commands: results, --help, --example, exit codes, no output on failure."""

import os
import subprocess
import sys

import numpy as np
import pytest

from curvdetail import boundary_vertices, read_mesh
from curvdetail.cli import main
from curvdetail.curvature._validate import bbox_diagonal

from conftest import data_path

NOSE = data_path("mannequin_nose.obj")
SPOT = data_path("spot.obj")


def _error_line(capsys):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("curvdetail: error: ")
    return err[0]


def _spy_on_solve(monkeypatch):
    """Every ``Reconstructor.solve`` call as ``(detail, fixed_positions, result, reconstructor)``
    (a spy that still solves)."""
    from curvdetail import Reconstructor

    calls, real = [], Reconstructor.solve

    def spy(self, detail, fixed_positions):
        X = real(self, detail, fixed_positions)
        calls.append((np.array(detail), np.array(fixed_positions), np.array(X), self))
        return X

    monkeypatch.setattr(Reconstructor, "solve", spy)
    return calls


@pytest.mark.parametrize("rows", ["all", "free"])
def test_reconstruct_rebuilds_the_input(tmp_path, capsys, monkeypatch, rows):
    # the answer is the input itself, which a copy of it also gives: so the solver's run is
    # checked too, with the input's own detail and boundary, and the file holds what it returned
    from curvdetail import curvature_detail, reconstruct

    calls = _spy_on_solve(monkeypatch)
    out = tmp_path / "nose.ply"
    assert main(["reconstruct", NOSE, str(out), "--rows", rows]) == 0
    V, F = read_mesh(NOSE)
    X, G = read_mesh(out)
    assert np.array_equal(G, F)
    assert np.abs(X - V).max() <= 1e-9 * bbox_diagonal(V)
    (detail, positions, solved, rec), = calls
    b = boundary_vertices(F)
    assert np.array_equal(detail, curvature_detail(V, F)) and np.array_equal(rec.fixed, b)
    assert np.array_equal(positions, V[b]) and rec.rows == rows
    assert np.array_equal(X, solved)                  # binary PLY: doubles, exact
    expected = reconstruct(V, F, curvature_detail(V, F), b, V[b], rows=rows)
    assert np.abs(X - expected).max() <= 1e-12 * bbox_diagonal(V)
    printed = capsys.readouterr().out
    assert "max vertex error" in printed and f"rows={rows}" in printed
    assert float(printed.split("max vertex error ")[1].split()[0]) <= 1e-9


def test_reconstruct_shows_its_stages_on_a_terminal_only(tmp_path, capsys, monkeypatch):
    assert main(["reconstruct", NOSE, str(tmp_path / "a.ply")]) == 0
    assert capsys.readouterr().err == ""                       # not a terminal: quiet
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    assert main(["reconstruct", NOSE, str(tmp_path / "b.ply")]) == 0
    stages = [line.split(" ...")[0] for line in capsys.readouterr().err.splitlines()]
    assert stages == ["[1/4] read", "[2/4] factor", "[3/4] solve", "[4/4] write"]


def test_reconstruct_closed_mesh_with_fixed_vertices(tmp_path, monkeypatch):
    calls = _spy_on_solve(monkeypatch)
    out = tmp_path / "spot.off"
    assert main(["reconstruct", SPOT, str(out), "--fix", "0", "1000", "2000"]) == 0
    V, _ = read_mesh(SPOT)
    assert np.abs(read_mesh(out)[0] - V).max() <= 1e-9 * bbox_diagonal(V)
    (detail, positions, solved, rec), = calls            # solved with the three named vertices fixed
    assert np.array_equal(rec.fixed, [0, 1000, 2000]) and np.array_equal(positions, V[[0, 1000, 2000]])
    assert np.abs(read_mesh(out)[0] - solved).max() <= 1e-12 * bbox_diagonal(V)


def test_reconstruct_example(tmp_path, capsys):
    out = tmp_path / "terrain.obj"
    assert main(["reconstruct", "--example", str(out)]) == 0
    printed = capsys.readouterr().out
    # the default: E_Q over all rows
    assert out.exists() and "1089 vertices" in printed and "rows=all" in printed
    # the bundled terrain, rebuilt from its own detail: itself
    from curvdetail.data import example_path

    V, F = read_mesh(example_path())
    X, G = read_mesh(out)
    assert np.array_equal(G, F) and V.shape == (1089, 3)
    assert np.abs(X - V).max() <= 1e-9 * bbox_diagonal(V)


def test_minimal_example_converges(tmp_path, capsys):
    out = tmp_path / "minimal.ply"
    assert main(["minimal", "--example", str(out)]) == 0
    assert capsys.readouterr().out.startswith("converged after")
    V, F = read_mesh(out)
    V0, _ = read_mesh(data_path("terrainA_1k.obj"))
    b = boundary_vertices(F)
    assert np.abs(V[b] - V0[b]).max() < 1e-12 * bbox_diagonal(V0)


def test_minimal_not_converged_exits_3_and_says_so(tmp_path, capsys):
    out = tmp_path / "minimal.ply"
    assert main(["minimal", NOSE, str(out), "--max-iterations", "1", "--tol", "1e-12"]) == 3
    assert "not converged" in capsys.readouterr().out and out.exists()
    # one step, as the library takes it with the same options
    from curvdetail import minimal_surface

    V, F = read_mesh(NOSE)
    expected = minimal_surface(V, F, boundary_vertices(F), max_iterations=1, tol=1e-12)
    assert expected.iterations == 1 and not expected.converged
    X, G = read_mesh(out)
    assert np.array_equal(G, F)
    assert np.abs(X - expected).max() <= 1e-12 * bbox_diagonal(V)


@pytest.mark.parametrize("command", ["reconstruct", "minimal"])
def test_help_describes_the_command(command, capsys):
    with pytest.raises(SystemExit) as info:
        main([command, "--help"])
    assert info.value.code == 0
    text = capsys.readouterr().out
    assert "INPUT" in text and "OUTPUT" in text and "--example" in text and "--overwrite" in text


def test_console_script_help_runs():
    result = subprocess.run([sys.executable, "-m", "curvdetail.cli", "reconstruct", "--help"],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0 and "--rows" in result.stdout


def test_missing_input_fails_cleanly(tmp_path, capsys):
    out = tmp_path / "x.ply"
    assert main(["reconstruct", str(tmp_path / "absent.obj"), str(out)]) == 1
    assert "mesh file not found" in _error_line(capsys)
    assert not out.exists()


def test_closed_mesh_without_fix_fails_cleanly(tmp_path, capsys):
    out = tmp_path / "x.ply"
    assert main(["reconstruct", SPOT, str(out)]) == 1
    assert "closed (no boundary); name vertices to fix with --fix" in _error_line(capsys)
    assert os.listdir(tmp_path) == []


def test_fix_out_of_range_names_the_index(tmp_path, capsys):
    out = tmp_path / "x.ply"
    assert main(["reconstruct", NOSE, str(out), "--fix", "3", "640"]) == 1
    assert "first: 640" in _error_line(capsys)
    assert os.listdir(tmp_path) == []


def test_fix_without_indices_is_refused_not_taken_as_the_boundary(tmp_path, capsys):
    out = tmp_path / "x.ply"
    assert main(["reconstruct", NOSE, str(out), "--fix"]) == 1
    assert "--fix needs vertex indices" in _error_line(capsys)
    assert os.listdir(tmp_path) == []


def test_existing_output_is_refused_and_kept(tmp_path, capsys):
    out = tmp_path / "keep.ply"
    out.write_text("precious")
    assert main(["minimal", NOSE, str(out)]) == 1
    assert "exists; pass --overwrite" in _error_line(capsys)
    assert out.read_text() == "precious"


def test_overwrite_replaces_output(tmp_path):
    out = tmp_path / "keep.ply"
    out.write_text("old")
    assert main(["reconstruct", NOSE, str(out), "--overwrite"]) == 0
    V, F = read_mesh(NOSE)
    X, G = read_mesh(out)
    assert X.shape == (640, 3) and np.array_equal(G, F)
    assert np.abs(X - V).max() <= 1e-9 * bbox_diagonal(V)


def test_minimal_on_a_closed_mesh_fails_cleanly(tmp_path, capsys):
    out = tmp_path / "x.ply"
    assert main(["minimal", SPOT, str(out)]) == 1
    assert "needs a boundary" in _error_line(capsys)
    assert not out.exists()


def test_unknown_backend_fails_cleanly(tmp_path, capsys):
    out = tmp_path / "x.ply"
    assert main(["reconstruct", NOSE, str(out), "--backend", "magic"]) == 1
    assert "unknown solver backend 'magic'" in _error_line(capsys)
    assert not out.exists()


def test_example_with_two_paths_is_refused(tmp_path, capsys):
    assert main(["reconstruct", "--example", str(tmp_path / "a.ply"), str(tmp_path / "b.ply")]) == 1
    assert "with --example give only OUTPUT" in _error_line(capsys)


def _existing_output_message(tmp_path, capsys, argv):
    out = tmp_path / "keep.ply"
    out.write_text("precious")
    assert main(argv(str(out))) == 1
    assert out.read_text() == "precious"
    return _error_line(capsys).replace(str(out), "OUTPUT")


def test_every_command_refuses_an_existing_output_with_one_message(tmp_path, capsys):
    commands = {
        "reconstruct": lambda out: ["reconstruct", NOSE, out],
        "minimal": lambda out: ["minimal", NOSE, out],
        "remesh": lambda out: ["remesh", NOSE, out, "--quiet"],
        "apply": lambda out: ["apply", "compute_curvature_detail", NOSE, out],
        "edit": lambda out: ["edit", NOSE, out, "--sel", "absent.sel", "--def", "absent.def"],
    }
    messages = {name: _existing_output_message(tmp_path, capsys, argv) for name, argv in commands.items()}
    assert set(messages.values()) == {
        "curvdetail: error: OUTPUT exists; pass --overwrite (overwrite=True) to replace it."}, messages


@pytest.mark.parametrize("command", ["reconstruct", "minimal"])
@pytest.mark.parametrize("output, problem", [("nose", "no file extension"),
                                              ("nowhere/nose.ply", "does not exist")])
def test_unwritable_output_is_refused_before_reading_the_input(tmp_path, capsys, command, output, problem):
    # the input does not exist either: the output is checked first, before any work
    assert main([command, str(tmp_path / "absent.obj"), str(tmp_path / output)]) == 1
    assert problem in _error_line(capsys)
    assert os.listdir(tmp_path) == []


def test_minimal_tol_default_is_the_core_default():
    from curvdetail.cli import build_parser
    from curvdetail.curvature.minimal_surface import DEFAULT_TOL

    args = build_parser().parse_args(["minimal", "in.obj", "out.ply"])
    assert args.tol == DEFAULT_TOL


def test_fix_before_the_file_names_says_where_to_put_it(tmp_path, capsys):
    # nargs="*" takes the file names as indices; argparse alone said "invalid int value"
    with pytest.raises(SystemExit) as exc:
        main(["reconstruct", "--fix", "5", NOSE, str(tmp_path / "x.ply")])
    assert exc.value.code == 2
    assert "is not a vertex index (put --fix after INPUT OUTPUT, or end its list with --)" in capsys.readouterr().err
    assert main(["reconstruct", "--fix", "5", "--fix-boundary", "--", NOSE, str(tmp_path / "x.ply")]) == 0


def test_fix_takes_commas_and_adds_the_boundary_when_asked(tmp_path, capsys):
    from curvdetail import boundary_vertices, read_mesh

    V, F = read_mesh(NOSE)
    nb = boundary_vertices(F).size
    assert main(["reconstruct", NOSE, str(tmp_path / "a.ply"), "--fix", "0,5", "9"]) == 0
    assert "3 fixed" in capsys.readouterr().out
    assert main(["reconstruct", NOSE, str(tmp_path / "r.ply"), "--fix", "0", "--fix", "5,9"]) == 0
    assert "3 fixed" in capsys.readouterr().out            # a repeated --fix adds, not replaces
    assert main(["reconstruct", NOSE, str(tmp_path / "b.ply"), "--fix", "300", "--fix-boundary"]) == 0
    assert f"{nb + 1} fixed" in capsys.readouterr().out      # vertex 300 is inside


def test_minimal_surface_with_a_pinned_inner_vertex(tmp_path, capsys):
    # the closed-mesh message names --fix, which minimal now takes as reconstruct does
    assert main(["minimal", SPOT, str(tmp_path / "m.ply")]) == 1
    assert "needs a boundary to span (or vertices named with --fix)" in _error_line(capsys)
    # a pinned inner point is a cone tip that the flow pulls into a spike: three steps (status 3,
    # not converged, output written) show the constraint without running into the collapse
    steps = ["--max-iterations", "3"]
    assert main(["minimal", NOSE, str(tmp_path / "m.ply"), "--fix", "300", "--fix-boundary"] + steps) == 3
    assert main(["minimal", NOSE, str(tmp_path / "f.ply")] + steps) == 3
    V, F = read_mesh(NOSE)
    pinned, free = read_mesh(str(tmp_path / "m.ply"))[0], read_mesh(str(tmp_path / "f.ply"))[0]
    b = boundary_vertices(F)
    assert np.array_equal(pinned[b], V[b]) and np.array_equal(pinned[300], V[300])
    assert np.linalg.norm(free[300] - V[300]) > 1e-3 * bbox_diagonal(V)    # it would have moved


def test_minimal_full_step_says_what_it_measured(tmp_path, capsys):
    # the line said "normal to the surface" for --step full too, with the full step twice
    assert main(["minimal", NOSE, str(tmp_path / "m.ply"), "--step", "full", "--max-iterations", "3"]) == 3
    printed = capsys.readouterr().out
    assert "tangential sliding included" in printed and "normal to the surface" not in printed


@pytest.mark.parametrize("option, value, words", [
    ("--max-iterations", "0", "argument --max-iterations: '0' is not a whole number of at least 1"),
    ("--max-iterations", "2.5", "argument --max-iterations: '2.5' is not a whole number"),
    ("--tol", "-1e-4", "argument --tol: '-1e-4' is not a positive number"),
    ("--tol", "nan", "argument --tol: 'nan' is not a positive number"),
])
def test_minimal_options_out_of_range_are_named_as_options(tmp_path, capsys, option, value, words):
    # the library's words were "max_iterations=0 must be at least 1": a Python name, not the option
    with pytest.raises(SystemExit) as exit_:
        main(["minimal", NOSE, str(tmp_path / "m.ply"), f"{option}={value}"])
    assert exit_.value.code == 2 and words in capsys.readouterr().err
    assert not os.listdir(tmp_path)
