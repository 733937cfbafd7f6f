"""The reconstruct and minimal commands: results, --help, --example, exit codes, no output on failure."""

import os
import subprocess
import sys

import numpy as np
import pytest

from curvdetail import boundary_vertices, read_mesh
from curvdetail.cli import main
from curvdetail.curvature._validate import bbox_diagonal

from conftest import data_path, run_commit_interrupted_by

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
    assert "stopped (not converged) after 1 step, " in capsys.readouterr().out and out.exists()   # not "1 steps"
    # one step, as the library takes it with the same options
    from curvdetail import minimal_surface

    V, F = read_mesh(NOSE)
    expected = minimal_surface(V, F, boundary_vertices(F), max_iterations=1, tol=1e-12)
    assert expected.iterations == 1 and not expected.converged
    X, G = read_mesh(out)
    assert np.array_equal(G, F)
    assert np.abs(X - expected).max() <= 1e-12 * bbox_diagonal(V)


@pytest.mark.parametrize("command", ["reconstruct", "minimal"])
@pytest.mark.parametrize("name", ["out.obj", "out.OFF", "out.stl"])
def test_an_output_without_quality_says_it_is_left_out(tmp_path, capsys, command, name):
    # --help promises quality = distance; OBJ, OFF and STL cannot hold it: said, as apply/run say it
    assert main([command, NOSE, str(tmp_path / name)]) == 0
    assert capsys.readouterr().err == (f"curvdetail: note: {name} holds the geometry only; the vertex quality "
                                       "is kept by PLY output.\n")


@pytest.mark.parametrize("command", ["reconstruct", "minimal"])
def test_a_ctm_output_is_written_without_quality_and_reads_back(tmp_path, capsys, command):
    # a CTM "Quality" map without a "Color" one crashes pymeshlab's reader; write_mesh refuses a
    # quality for .ctm, so the command writes the geometry only, says so, and the file reads back
    import subprocess
    import sys

    out = tmp_path / "out.ctm"
    assert main([command, NOSE, str(out)]) == 0
    assert capsys.readouterr().err == ("curvdetail: note: out.ctm holds the geometry only; the vertex quality "
                                       "is kept by PLY output.\n")
    code = f"import curvdetail; V, F = curvdetail.read_mesh({str(out)!r}); print(V.shape[0], F.shape[0])"
    child = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    V, F = read_mesh(NOSE)
    assert child.returncode == 0, child.stderr
    assert child.stdout.split() == [str(V.shape[0]), str(F.shape[0])]


@pytest.mark.parametrize("command", ["reconstruct", "minimal"])
def test_a_ply_output_keeps_the_quality_without_a_note(tmp_path, capsys, command):
    assert main([command, NOSE, str(tmp_path / "out.ply")]) == 0
    assert capsys.readouterr().err == ""
    from curvdetail.filters.files import load_meshset

    ms = load_meshset(tmp_path / "out.ply")
    V, _ = read_mesh(NOSE)
    assert np.allclose(ms.current_mesh().vertex_scalar_array(),
                       np.linalg.norm(ms.current_mesh().vertex_matrix() - V, axis=1), rtol=0, atol=1e-15)


@pytest.mark.parametrize("command", ["reconstruct", "minimal"])
def test_help_describes_the_command(command, capsys):
    with pytest.raises(SystemExit) as info:
        main([command, "--help"])
    assert info.value.code == 0
    text = capsys.readouterr().out
    assert "INPUT" in text and "OUTPUT" in text and "--example" in text and "--overwrite" in text


def test_help_lists_the_exit_statuses(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "Exit status: 0 done; 1 an error" in text
    assert "3 OUTPUT written, but an iteration stopped before it converged (minimal, or a filter of " \
           "apply/run whose figures say converged: false)" in text
    assert "4 OUTPUT written, but edit folded triangles or amplified the handles' motion (or an editing filter of " \
           "apply/run folded triangles or amplified its constraints)" in text and "130 Ctrl-C, 143 SIGTERM" in text


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


def test_minimal_with_fix_that_leaves_the_boundary_free_names_fix_boundary(tmp_path, capsys):
    # a free boundary has no minimal surface (it shrinks towards nothing): the library refuses it
    # by naming a Python call; the command names its own option
    out = tmp_path / "m.ply"
    assert main(["minimal", NOSE, str(out), "--fix", "300"]) == 1
    line = _error_line(capsys)
    nb = boundary_vertices(read_mesh(NOSE)[1]).size
    assert f"--fix leaves {nb} boundary vertices free" in line and line.endswith("add --fix-boundary.")
    assert not out.exists()


def test_unknown_backend_fails_cleanly(tmp_path, capsys):
    out = tmp_path / "x.ply"
    assert main(["reconstruct", NOSE, str(out), "--backend", "magic"]) == 1
    assert "unknown solver backend 'magic'" in _error_line(capsys)
    assert not out.exists()


def test_example_with_two_paths_is_refused(tmp_path, capsys):
    assert main(["reconstruct", "--example", str(tmp_path / "a.ply"), str(tmp_path / "b.ply")]) == 1
    assert "with --example give only OUTPUT" in _error_line(capsys)


@pytest.mark.parametrize("command", ["reconstruct", "minimal", "remesh"])
def test_example_output_over_the_bundled_example_is_refused_even_with_overwrite(tmp_path, capsys,
                                                                                  monkeypatch, command):
    # --example OUTPUT naming the bundled mesh, with --overwrite, rewrote the package's own data
    # file (its coordinates as read back, quality dropped); a copy stands in for it here
    import shutil

    import curvdetail.data
    from curvdetail.data import example_path

    example = tmp_path / "data" / "terrainA_1k.obj"
    example.parent.mkdir()
    shutil.copyfile(example_path(), example)
    before = example.read_bytes()
    monkeypatch.setattr(curvdetail.data, "example_path", lambda: str(example))
    (tmp_path / "sub").mkdir()
    spelled = tmp_path / "sub" / ".." / "data" / "terrainA_1k.obj"
    assert main([command, "--example", str(spelled), "--overwrite"]) == 1
    assert "is the bundled example mesh that --example reads" in _error_line(capsys)
    assert example.read_bytes() == before


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
    # the command line's option only: "(overwrite=True)" is Python's, no use in a shell
    assert set(messages.values()) == {"curvdetail: error: OUTPUT exists; pass --overwrite to replace it."}, messages


def test_an_output_made_during_the_run_is_refused_in_the_command_lines_words(tmp_path, capsys, monkeypatch):
    # the check before the work says --overwrite; a file made meanwhile was refused by write_mesh
    # in Python's words, "--overwrite (overwrite=True)", now "overwrite=True", which the CLI says
    # as its option
    from curvdetail import Reconstructor

    out = tmp_path / "o.ply"
    solve = Reconstructor.solve

    def solve_while_another_process_writes(self, *args, **kwargs):
        out.write_text("another process's")
        return solve(self, *args, **kwargs)

    monkeypatch.setattr(Reconstructor, "solve", solve_while_another_process_writes)
    assert main(["reconstruct", NOSE, str(out)]) == 1
    assert _error_line(capsys) == f"curvdetail: error: {out} exists; pass --overwrite to replace it."
    assert out.read_text() == "another process's" and os.listdir(tmp_path) == ["o.ply"]


@pytest.mark.parametrize("option", ["--report", "--image"])
def test_an_existing_report_or_picture_is_refused_in_the_command_lines_words(tmp_path, capsys, option):
    extra = tmp_path / ("keep.json" if option == "--report" else "keep.png")
    extra.write_text("precious")
    assert main(["remesh", NOSE, str(tmp_path / "o.ply"), option, str(extra), "--quiet"]) == 1
    assert _error_line(capsys) == f"curvdetail: error: {extra} exists; pass --overwrite to replace it."
    assert extra.read_text() == "precious" and sorted(os.listdir(tmp_path)) == [extra.name]


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


# --- Ctrl-C (SIGINT) ------------------------------------------------------------------------

#: bytes the blocking call writes into a pipe at once: far more than a pipe holds (64 KiB), so the
#: write blocks until the test has read them all
_BLOCKING_WRITE = 4 << 20

_BLOCKING_CALL = (
    "import os, signal, sys\n"
    "# a suite started in the background by a shell (cmd &) hands its children SIGINT ignored,\n"
    "# which the CLI rightly leaves ignored: this run is one a terminal's Ctrl-C reaches\n"
    "signal.signal(signal.SIGINT, signal.SIG_DFL)\n"
    "import curvdetail.io, curvdetail.remesh.experiment\n"
    "from curvdetail.cli import main\n"
    "busy = int(os.environ['CURVDETAIL_TEST_FD'])\n"
    "def long_native_call():\n"
    "    # like pymeshlab's remeshing: native code that goes on when a signal comes. SIGINT is\n"
    "    # blocked in this (the main) thread, so the write is not interrupted, and the signal goes\n"
    "    # to another thread, whose C-level handler runs as it would during the native call. One\n"
    "    # write of more than the pipe holds: the test reads its first bytes while it is blocked\n"
    "    # in it (no Python line runs in between), and it ends only once the test reads the rest\n"
    "    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})\n"
    f"    os.write(busy, bytes({_BLOCKING_WRITE}))\n"
    "    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})\n"
    "def during(function):\n"
    "    def run(*args, **kwargs):\n"
    "        result = function(*args, **kwargs)      # a written mesh leaves its temporary file\n"
    "        long_native_call()\n"
    "        return result\n"
    "    return run\n"
    "stage = sys.argv.pop(1)\n"
    "if stage == 'retriangulate':\n"
    "    module = curvdetail.remesh.experiment\n"
    "    module.retriangulate = during(module.retriangulate)\n"
    "else:\n"
    "    curvdetail.io.write_mesh = during(curvdetail.io.write_mesh)\n"
    "sys.exit(main(sys.argv[1:]))\n")


@pytest.mark.parametrize("stage", ["retriangulate", "write"])
def test_ctrl_c_ends_a_run_at_once_during_a_native_call(tmp_path, stage):
    # SIGINT waited for pymeshlab's retriangulation to end (70 s for a 0.15 % target edge on the
    # nose), as Python raises KeyboardInterrupt only between bytecodes; SIGTERM ended the run at
    # once. Handshakes, no sleeps: the SIGINT is sent once the call is known to be under way (its
    # first bytes have come), and the call ends only if the test reads the rest, which it does
    # only if the run did not end first
    import select
    import signal

    script = tmp_path / "interrupted.py"
    script.write_text(_BLOCKING_CALL)
    out = tmp_path / "out"
    out.mkdir()
    busy_r, busy_w = os.pipe()
    child, released = None, False
    try:
        with open(tmp_path / "stderr", "w") as stderr:
            child = subprocess.Popen(
                [sys.executable, str(script), stage, "remesh", NOSE, str(out / "o.ply"), "--report",
                 str(out / "r.json"), "--no-evaluate"],
                stdout=subprocess.DEVNULL, stderr=stderr, pass_fds=(busy_w,),
                env={**os.environ, "CURVDETAIL_TEST_FD": str(busy_w)})
        os.close(busy_w)
        busy_w = None
        # readable once the call is under way (or at EOF: the child ended before)
        assert select.select([busy_r], [], [], 300)[0], "the run did not reach the call"
        assert os.read(busy_r, 1) == b"\0", (tmp_path / "stderr").read_text()
        if stage == "write":
            assert any(name.startswith(".curvdetail-") for name in os.listdir(out))   # its temporary files
        child.send_signal(signal.SIGINT)
        try:
            # the watcher ends the run in milliseconds; the bound only keeps a broken one from
            # hanging the test: the call is then let end, and the test fails below
            child.wait(timeout=60)
        except subprocess.TimeoutExpired:
            released = True
            while os.read(busy_r, 1 << 16):                # to EOF: the child closes it as it ends
                pass
            child.wait(timeout=60)
    finally:
        if child is not None and child.poll() is None:
            child.kill()
            child.wait()
        for fd in (busy_r, busy_w):
            if fd is not None:
                os.close(fd)
    stderr = (tmp_path / "stderr").read_text()
    assert not released, "the run waited for the native call to end"
    assert child.returncode == 130, stderr
    # one line of its own, after the open progress line ("[1/3] retriangulate ...")
    assert stderr.splitlines().count("curvdetail: interrupted") == 1, stderr
    assert "Traceback" not in stderr and "KeyboardInterrupt" not in stderr
    assert os.listdir(out) == []                        # no output, no temporary file


def test_ctrl_c_during_a_commit_lets_it_finish(tmp_path):
    # as with SIGTERM: the outputs are all written (exit status 130 all the same) or none, and
    # no old file is left in a hidden folder. The commit goes on only once the watcher has asked
    # for the commit lock; the main thread then waits for the watcher, which only its exit ends
    done, out = run_commit_interrupted_by(tmp_path, "SIGINT")
    assert done.returncode == 130 and done.stdout == "", (done.returncode, done.stdout, done.stderr)
    assert done.stderr == "curvdetail: interrupted\n"
    assert ((out / "a.txt").read_text(), (out / "b.txt").read_text()) == ("new a", "new b")
    assert sorted(os.listdir(out)) == ["a.txt", "b.txt"]


def test_main_puts_the_sigint_handling_back_afterwards(tmp_path):
    import signal

    before = signal.getsignal(signal.SIGINT)
    assert main(["reconstruct", NOSE, str(tmp_path / "o.ply")]) == 0
    assert signal.getsignal(signal.SIGINT) is before


# --- a remeshing that failed ----------------------------------------------------------------

def _noisy_disk_file(folder):
    """A flat unit disk (8 rings) with noise of 0.02 on its interior heights (seed 1), as a PLY:
    the pointwise transfer at 8 % rebuilds it ~5x farther from the source than zero detail
    (see tests/test_remesh_experiment.py)."""
    from curvdetail import write_mesh
    from curvdetail.curvature.testing import disk

    V, F = disk(n_rings=8)
    z = 0.02 * np.random.default_rng(1).standard_normal(V.shape[0])
    z[boundary_vertices(F)] = 0.0
    V[:, 2] = z
    path = folder / "noisy.ply"
    write_mesh(path, V, F)
    return str(path)


def test_remesh_says_when_the_rebuild_is_worse_than_zero_detail(tmp_path, capsys):
    # `curvdetail remesh camelhead.off out.ply --transfer pointwise` printed "RMS 35.9508 % ...
    # (zero detail 20.981 % ...)" and exited 0 without a word on what that means
    import json

    source = _noisy_disk_file(tmp_path)
    rc = main(["remesh", source, str(tmp_path / "o.ply"), "--target-edge", "8", "--transfer", "pointwise",
               "--report", str(tmp_path / "r.json")])
    captured = capsys.readouterr()
    assert rc == 0 and (tmp_path / "o.ply").exists()          # the run did what was asked
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["improvement_over_zero_detail"] < 0.5
    notes = [line for line in captured.err.splitlines() if line.startswith("note: ")]
    assert len(notes) == 1, captured.err
    assert notes[0].startswith("note: the rebuilt surface is farther from the source than the zero-detail surface")
    assert "worse than no detail at all" in notes[0] and "--transfer conservative" in notes[0]
    assert "transfer='" not in notes[0]                       # the command line's options, not Python's
    assert "WorseThanZeroDetailWarning" not in captured.err and "warn" not in captured.err
    assert captured.out.startswith("217 -> ")                 # the figures as before, on stdout


def test_remesh_says_nothing_of_the_sort_when_the_rebuild_is_better(tmp_path, capsys):
    source = _noisy_disk_file(tmp_path)
    assert main(["remesh", source, str(tmp_path / "o.ply"), "--target-edge", "4", "--quiet"]) == 0
    assert "note:" not in capsys.readouterr().err


# --- the note before a long run -------------------------------------------------------------

@pytest.mark.parametrize("argv, says", [
    # a decimation finer than the source: refused at once, so no "this takes minutes" before it
    (["--method", "decimate", "--target-edge", "2"], None),
    (["--method", "decimate", "--target-edge", "6", "--no-evaluate"], None),      # seconds, not minutes
    (["--method", "decimate", "--target-edge", "6"],
     "this takes minutes. Most of it is the measurements (--no-evaluate skips them)"),
    # the isotropic remeshing, not the measurements, takes most of a big run's time
    (["--target-edge", "3", "--no-evaluate"],
     "this takes minutes. Most of it is pymeshlab's isotropic remeshing (--no-surface-check makes it 25-50 % "
     "faster)."),
])
def test_the_note_before_a_long_run_fits_the_method(tmp_path, capsys, monkeypatch, argv, says):
    import importlib

    monkeypatch.setattr(importlib.import_module("curvdetail.remesh.retriangulate"), "BIG_TARGET", 50)
    rc = main(["remesh", NOSE, str(tmp_path / "o.ply"), *argv])
    err = capsys.readouterr().err
    notes = [line for line in err.splitlines() if line.startswith("note: ")]
    if says is None:
        assert notes == [], err
    else:
        assert rc == 0 and len(notes) == 1 and says in notes[0], err
    if "2" in argv:
        assert rc == 1 and "decimation can only coarsen" in err and os.listdir(tmp_path) == []


def test_a_line_said_during_a_stage_gets_a_line_of_its_own():
    # "[1/3] retriangulate ...curvdetail: interrupted" on one line before
    import io

    from curvdetail import cli

    stream = io.StringIO()
    progress = cli.Progress(2, stream=stream)
    progress.stage("retriangulate")
    cli._say("note: something", stream)
    progress.stage("transfer")
    progress.close()
    lines = stream.getvalue().splitlines()
    assert lines[0] == "[1/2] retriangulate ..." and lines[1] == "note: something"
    assert lines[2].startswith("[1/2] retriangulate ... ") and lines[2].endswith(" s")
    assert lines[3].startswith("[2/2] transfer ... ") and len(lines) == 4


@pytest.mark.parametrize("command, says", [
    ("minimal", "Pinkall-Polthier steps at most (default: 200)"),
    ("reconstruct", "all vertices (the paper) or free ones only (default: all)"),
])
def test_help_gives_the_defaults(command, capsys, says):
    # remesh rebuilds over the free rows by default, reconstruct over all: --help said neither
    # reconstruct's --rows nor minimal's --max-iterations default
    with pytest.raises(SystemExit):
        main([command, "--help"])
    assert says in " ".join(capsys.readouterr().out.split())


def _choice_options():
    """(command, option, choices) of every option of every command that takes one of a few words."""
    import argparse

    from curvdetail.cli import build_parser

    commands = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return [(name, action.option_strings[0], action.choices)
            for name, sub in commands.choices.items() for action in sub._actions
            if action.choices and action.option_strings]


def test_every_choice_option_takes_its_words_in_any_case():
    # the filters take 'FREE' for rows=free; the command line refused --rows FREE ("invalid choice")
    from curvdetail.cli import build_parser

    options = _choice_options()
    assert {(c, o) for c, o, _ in options} >= {("reconstruct", "--rows"), ("remesh", "--method"),
                                               ("edit", "--relations"), ("minimal", "--step")}
    for command, option, choices in options:
        for choice in choices:
            given = choice.upper() if choice.lower() == choice else choice.lower()
            args = build_parser().parse_args([command, "a.obj", "b.ply", option, given]
                                             + (["--sel", "s", "--def", "d"] if command == "edit" else []))
            assert getattr(args, option[2:].replace("-", "_")) == choice, (command, option, given)


def test_reconstruct_with_rows_in_capitals_is_the_free_rows_reconstruction(tmp_path, capsys):
    assert main(["reconstruct", NOSE, str(tmp_path / "o.ply"), "--rows", "Free"]) == 0
    out = capsys.readouterr().out
    assert "rows=free" in out and float(out.split()[3]) < 1e-9     # "max vertex error E of the bbox diagonal"


def test_a_collapsing_minimal_surface_is_told_what_to_change_in_options(tmp_path, capsys):
    # the library's advice came through in its parameters' names ("a larger tol, or max_iterations
    # below 18"), which `curvdetail minimal` does not take: its options are --tol and --max-iterations
    out = tmp_path / "m.ply"
    assert main(["minimal", NOSE, str(out), "--fix", "300", "--fix-boundary"]) == 1
    line = _error_line(capsys)
    assert "1 fixed vertex lies inside the surface (first: 300)" in line, line
    assert "a larger --tol" in line and "--max-iterations below " in line, line
    assert "max_iterations" not in line and "larger tol" not in line, line
    assert not out.exists()


@pytest.mark.parametrize("command", ["reconstruct", "minimal", "remesh"])
def test_a_backend_that_is_not_installed_is_told_in_options(tmp_path, capsys, monkeypatch, command):
    # "or use backend='auto'" is Python; the command line option is --backend auto
    import curvdetail.curvature.sparse_solver as solver

    monkeypatch.setattr(solver, "available_backends", lambda: ("splu", "banded"))
    out = tmp_path / "o.ply"
    quiet = ["--quiet"] if command == "remesh" else []
    assert main([command, NOSE, str(out), "--backend", "pardiso"] + quiet) == 1
    line = _error_line(capsys)
    assert "solver backend 'pardiso' is not installed" in line, line
    assert line.endswith("or use --backend auto."), line
    assert not out.exists()
