"""The command line's core: reconstruct and minimal, errors said with option names, exit
statuses, outputs written atomically, inputs never overwritten, and streams that cannot decide
a run's outcome (stdout or stderr full, SIGTERM)."""

import glob
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from curvdetail import boundary_vertices, curvature_detail, minimal_surface, read_mesh, reconstruct
from curvdetail.cli import main

from conftest import data_path

NOSE = data_path("mannequin_nose.obj")
SPOT = data_path("spot.obj")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def diagonal(V):
    return np.linalg.norm(np.ptp(V, axis=0))


def error_line(capsys):
    """The one stderr line of a failed run."""
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("curvdetail: error: "), err
    return err[0]


@pytest.mark.parametrize("rows", ["all", "FREE"])
def test_reconstruct_rebuilds_the_input_from_its_own_detail(tmp_path, capsys, rows):
    out = tmp_path / "nose.ply"
    assert main(["reconstruct", NOSE, str(out), "--rows", rows]) == 0
    V, F = read_mesh(NOSE)
    X, G = read_mesh(out)
    b = boundary_vertices(F)
    expected = reconstruct(V, F, curvature_detail(V, F), b, V[b], rows=rows.lower())
    assert np.array_equal(G, F)
    assert np.abs(X - expected).max() <= 1e-12 * diagonal(V)       # binary PLY keeps doubles
    assert np.abs(X - V).max() <= 1e-9 * diagonal(V)                # the input itself
    assert f"rows={rows.lower()}" in capsys.readouterr().out


def test_reconstruct_a_closed_mesh_with_named_fixed_vertices(tmp_path):
    out = tmp_path / "spot.off"
    assert main(["reconstruct", SPOT, str(out), "--fix", "0,1000", "2000"]) == 0
    V, _ = read_mesh(SPOT)
    X, _ = read_mesh(out)
    assert np.abs(X - V).max() <= 1e-6 * diagonal(V)                # OFF: decimal text
    assert np.array_equal(X[[0, 1000, 2000]], V[[0, 1000, 2000]])


def test_reconstruct_a_closed_mesh_without_fix_uses_one_anchor(tmp_path, capsys):
    out = tmp_path / "spot.ply"
    assert main(["reconstruct", SPOT, str(out)]) == 0
    V, _ = read_mesh(SPOT)
    X, _ = read_mesh(out)
    assert np.abs(X - V).max() <= 1e-9 * diagonal(V)
    assert "2930 vertices, 1 fixed," in capsys.readouterr().out


def test_reconstruct_example_prints_the_readme_line(tmp_path, capsys):
    assert main(["reconstruct", "--example", str(tmp_path / "t.ply")]) == 0
    out = capsys.readouterr().out
    assert out.startswith("max vertex error ") and "(1089 vertices, 128 fixed, rows=all," in out


def test_minimal_not_converged_writes_the_output_and_exits_3(tmp_path, capsys):
    out = tmp_path / "minimal.ply"
    assert main(["minimal", NOSE, str(out), "--max-iterations", "1", "--tol", "1e-12"]) == 3
    V, F = read_mesh(NOSE)
    expected = minimal_surface(V, F, boundary_vertices(F), max_iterations=1, tol=1e-12)
    X, _ = read_mesh(out)
    assert np.abs(X - expected).max() <= 1e-12 * diagonal(V)
    assert capsys.readouterr().out.startswith("stopped (not converged) after 1 step,")


def test_minimal_example_converges_with_the_boundary_kept(tmp_path, capsys):
    out = tmp_path / "minimal.ply"
    assert main(["minimal", "--example", str(out)]) == 0
    X, F = read_mesh(out)
    V, _ = read_mesh(data_path("terrainA_1k.obj"))
    b = boundary_vertices(F)
    assert np.array_equal(X[b], V[b])
    assert capsys.readouterr().out.startswith("converged after 3 steps")


@pytest.mark.parametrize("command", ["reconstruct", "minimal"])
def test_an_obj_output_gets_a_note_that_the_quality_is_dropped(tmp_path, capsys, command):
    assert main([command, NOSE, str(tmp_path / "out.obj")]) == 0
    err = capsys.readouterr().err
    assert err.startswith("curvdetail: note: out.obj") and "PLY" in err


@pytest.mark.parametrize("argv, option", [
    (["reconstruct", NOSE, "--fix"], "--fix"),                  # --fix without indices
    (["minimal", NOSE, "--fix", "300"], "--fix-boundary"),      # a free boundary
    (["reconstruct", NOSE, "--fix", "3", "640"], "--fix"),      # out of range
])
def test_a_constraint_error_names_the_option(tmp_path, capsys, argv, option):
    out = tmp_path / "x.ply"
    assert main([*argv[:2], str(out), *argv[2:]]) == 1
    assert f"({option}: " in error_line(capsys)
    assert os.listdir(tmp_path) == []


def test_an_index_out_of_range_is_named(tmp_path, capsys):
    assert main(["reconstruct", NOSE, str(tmp_path / "x.ply"), "--fix", "3", "640", "700"]) == 1
    line = error_line(capsys)
    assert "640" in line and "(2 " in line and "0..639" in line


def test_a_missing_input_names_the_file(tmp_path, capsys):
    assert main(["reconstruct", str(tmp_path / "absent.obj"), str(tmp_path / "x.ply")]) == 1
    assert "absent.obj" in error_line(capsys)
    assert os.listdir(tmp_path) == []


def test_an_existing_output_is_refused_and_kept_then_replaced_with_overwrite(tmp_path, capsys):
    out = tmp_path / "keep.ply"
    out.write_text("precious")
    assert main(["minimal", NOSE, str(out)]) == 1
    assert "(--overwrite: " in error_line(capsys) and out.read_text() == "precious"
    assert main(["reconstruct", NOSE, str(out), "--overwrite"]) == 0
    assert read_mesh(out)[0].shape == (640, 3)


def test_the_bundled_example_is_never_overwritten(tmp_path, capsys):
    from curvdetail.data import example_path

    before = open(example_path(), "rb").read()
    link = tmp_path / "example.obj"
    os.symlink(example_path(), link)
    assert main(["reconstruct", "--example", str(link), "--overwrite"]) == 1
    assert "--example" in error_line(capsys)
    assert open(example_path(), "rb").read() == before


def test_example_with_two_paths_is_refused(tmp_path, capsys):
    assert main(["reconstruct", "--example", NOSE, str(tmp_path / "x.ply")]) == 1
    assert "(--example: " in error_line(capsys)


def test_an_unknown_backend_fails_with_status_1(tmp_path, capsys):
    assert main(["reconstruct", NOSE, str(tmp_path / "x.ply"), "--backend", "magic"]) == 1
    assert "'magic'" in error_line(capsys)
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("argv", [["minimal", NOSE, "o.ply", "--max-iterations", "0"],
                                  ["minimal", NOSE, "o.ply", "--tol", "-1"],
                                  ["reconstruct", NOSE, "o.ply", "--rows", "some"],
                                  ["reconstruct", "--fix", "a", NOSE, "o.ply"]])
def test_an_option_value_argparse_refuses_exits_2(argv, capsys):
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 2


def test_help_lists_every_command_and_the_exit_statuses(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--help"])
    out = capsys.readouterr().out
    assert e.value.code == 0
    for word in ("reconstruct", "minimal", "remesh", "edit", "list", "apply", "run", "130", "143"):
        assert word in out


# --- broken streams -------------------------------------------------------------------------

class FullStream:
    """A stream on a full device: every write fails with ENOSPC."""

    def write(self, text):
        raise OSError(28, "No space left on device")

    def flush(self):
        pass

    def isatty(self):
        return False


def test_a_full_stderr_does_not_stop_the_run(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(sys, "stderr", FullStream())        # the note on .obj goes to stderr
    assert main(["reconstruct", NOSE, str(tmp_path / "out.obj")]) == 0
    assert read_mesh(tmp_path / "out.obj")[0].shape == (640, 3)


def test_a_full_stderr_does_not_stop_the_progress_of_remesh(tmp_path, monkeypatch):
    monkeypatch.setattr(sys, "stderr", FullStream())
    out = tmp_path / "out.ply"
    assert main(["remesh", "--example", str(out), "--method", "decimate", "--target-edge", "5%",
                 "--no-evaluate"]) == 0
    assert out.exists()


@pytest.mark.slow
def test_stdout_on_a_full_device_still_exits_0_with_the_output_written(tmp_path):
    out = tmp_path / "out.ply"
    with open("/dev/full", "w") as full:
        done = subprocess.run([sys.executable, "-m", "curvdetail", "reconstruct", NOSE, str(out)],
                              stdout=full, stderr=subprocess.PIPE, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert read_mesh(out)[0].shape == (640, 3)
    assert "curvdetail: note:" in done.stderr and "Traceback" not in done.stderr


# --- signals --------------------------------------------------------------------------------

#: A run of ``reconstruct`` whose mesh writer stalls inside atomic_write, its temporary file made.
_SLOW_WRITE = r"""
import sys, time
import curvdetail.io.mesh
from curvdetail.io import atomic_write

def slow_write(path, X, F, fields=None, overwrite=False):
    with atomic_write(path, overwrite=overwrite) as tmp:
        with open(tmp, "w") as fh:
            fh.write("partial")
            fh.flush()
            time.sleep(60)

curvdetail.io.mesh.write_mesh_fields = slow_write
from curvdetail.cli import main
sys.exit(main(["reconstruct", "--example", sys.argv[1]]))
"""


@pytest.mark.slow
@pytest.mark.parametrize("signum, status", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_a_signal_during_the_write_leaves_no_file_and_exits_128_plus_it(tmp_path, signum, status):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([ROOT, os.environ.get("PYTHONPATH", "")])}
    child = subprocess.Popen([sys.executable, "-c", _SLOW_WRITE, str(tmp_path / "out.ply")], env=env,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        while not glob.glob(str(tmp_path / ".curvdetail-*")):
            assert child.poll() is None, child.communicate()
            time.sleep(0.002)
        child.send_signal(signum)
        _, err = child.communicate(timeout=60)
    finally:
        child.kill()
    assert child.returncode == status, err
    assert os.listdir(tmp_path) == []


def test_main_puts_the_sigterm_handler_back():
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(SystemExit):
        main(["--version"])
    assert main(["list", "compute_curvature_detail"]) == 0
    assert signal.getsignal(signal.SIGTERM) is before


@pytest.mark.parametrize("command", ["reconstruct", "minimal"])
def test_input_colours_and_normals_not_carried_get_a_note(tmp_path, capsys, command):
    from curvdetail.io.ply import write_ply

    V, F = read_mesh(NOSE)
    rgb = {c: np.full(len(V), 200, dtype=np.uint8) for c in ("red", "green", "blue")}
    normals = {f"n{a}": np.full(len(V), 1.0 if a == "z" else 0.0) for a in "xyz"}
    for fields, said in ((rgb, ["vertex colours"]), (normals, ["normals"]), ({**rgb, **normals}, ["vertex colours", "normals"]),
                         ({}, [])):
        write_ply(str(tmp_path / "in.ply"), V, F, fields)
        assert main([command, str(tmp_path / "in.ply"), str(tmp_path / "out.ply"), "--overwrite"]) == 0
        notes = [line for line in capsys.readouterr().err.splitlines() if "in.ply" in line]
        assert [w for w in ("vertex colours", "normals") if any(w in line for line in notes)] == said
        assert all(line.startswith("curvdetail: note: out.ply") for line in notes)
