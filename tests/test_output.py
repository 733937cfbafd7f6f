"""curvdetail._output: checked, atomic outputs with a normal file's permissions, and the
writers and commands that use it."""

import doctest
import importlib
import os
import stat

import numpy as np
import pytest

from curvdetail._output import atomic_output, check_output_path
from curvdetail.cli import main
from curvdetail.curvature.errors import MeshError
from curvdetail.curvature.testing import grid

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


@pytest.fixture
def umask_022():
    old = os.umask(0o022)
    yield 0o644
    os.umask(old)


def _mode(path):
    return stat.S_IMODE(os.stat(path).st_mode)


def test_atomic_output_gives_the_umask_permissions_not_mkstemps_0600(tmp_path, umask_022):
    path = tmp_path / "a.txt"
    with atomic_output(path) as tmp:
        assert _mode(tmp) == 0o600                      # what mkstemp leaves
        with open(tmp, "w") as fh:
            fh.write("x")
    assert path.read_text() == "x"
    assert _mode(path) == umask_022


def test_atomic_output_failed_block_leaves_nothing_and_keeps_the_old_file(tmp_path):
    path = tmp_path / "a.txt"
    path.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_output(path, overwrite=True) as tmp:
            with open(tmp, "w") as fh:
                fh.write("half")
            raise RuntimeError("writer failed")
    assert path.read_text() == "old"
    assert os.listdir(tmp_path) == ["a.txt"]


def test_atomic_output_refuses_an_existing_file_before_the_block(tmp_path):
    path = tmp_path / "a.txt"
    path.write_text("old")
    with pytest.raises(FileExistsError, match="--overwrite"):
        with atomic_output(path):
            pytest.fail("the block must not run")
    assert os.listdir(tmp_path) == ["a.txt"]


def test_check_output_path_names_missing_folder_and_extension(tmp_path):
    with pytest.raises(MeshError, match="does not exist"):
        check_output_path(tmp_path / "no" / "a.ply")
    with pytest.raises(MeshError, match="no file extension"):
        check_output_path(tmp_path / "a")
    assert check_output_path(tmp_path / "a", hint=None) == str(tmp_path / "a")


@pytest.mark.parametrize("overwrite", ["no", 1, None])
def test_overwrite_must_be_a_bool(tmp_path, overwrite):
    # overwrite="no" replaced the file: any truthy value counted as True
    path = tmp_path / "m.ply"
    path.write_text("keep")
    with pytest.raises(ValueError, match=f"overwrite={overwrite!r} must be True or False"):
        check_output_path(path, overwrite)
    assert path.read_text() == "keep"


def test_output_path_that_is_not_a_path_is_named(tmp_path):
    with pytest.raises(ValueError, match="an output path must be a str or os.PathLike; got NoneType"):
        check_output_path(None, error=FileNotFoundError)
    with atomic_output(os.fsencode(tmp_path / "b.txt"), hint=None) as tmp:      # bytes work
        open(tmp, "w").close()
    assert (tmp_path / "b.txt").exists()


def test_a_folder_that_refuses_files_is_named_not_the_temporary_file(tmp_path):
    folder = tmp_path / "ro"
    folder.mkdir()
    os.chmod(folder, 0o500)
    try:
        if os.access(folder, os.W_OK):                  # root ignores permissions: use /proc
            folder = "/proc"
        with pytest.raises(OSError, match=r"cannot write '.*m\.ply': ") as info:    # its own type
            with atomic_output(os.path.join(folder, "m.ply")):
                pass
        assert ".curvdetail-" not in str(info.value) and not isinstance(info.value, ValueError)
    finally:
        os.chmod(tmp_path / "ro", 0o700)


def test_doctests():
    assert doctest.testmod(importlib.import_module("curvdetail._output")).failed == 0


def test_filter_output_mesh_has_normal_permissions(tmp_path, umask_022):
    out = tmp_path / "d.ply"
    rc = main(["apply", "compute_curvature_detail", os.path.join(DATA, "mannequin_nose.obj"), str(out)])
    assert rc == 0
    assert _mode(out) == umask_022


def test_saved_script_has_normal_permissions(tmp_path, umask_022):
    from curvdetail.filters import save_script

    path = tmp_path / "s.mlx"
    save_script(path, ["compute_curvature_detail"])
    assert _mode(path) == umask_022


def test_remesh_outputs_have_normal_permissions(tmp_path, umask_022):
    out, rep, img = tmp_path / "o.ply", tmp_path / "r.json", tmp_path / "f.png"
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(out), "--target-edge", "3",
               "--report", str(rep), "--image", str(img), "--quiet"])
    assert rc == 0
    assert [_mode(p) for p in (out, rep, img)] == [umask_022] * 3


def test_remesh_output_without_extension_fails_before_any_work(tmp_path, capsys, monkeypatch):
    import curvdetail.remesh.experiment as experiment

    monkeypatch.setattr(experiment, "run_experiment", lambda *a, **k: pytest.fail("work was done"))
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / "o"),
               "--report", str(tmp_path / "r.json")])
    assert rc == 1
    assert "no file extension" in capsys.readouterr().err
    assert os.listdir(tmp_path) == []


def test_remesh_failed_mesh_write_leaves_no_report_or_image(tmp_path, capsys, monkeypatch):
    import curvdetail.io

    def broken(*args, **kwargs):
        raise curvdetail.io.MeshFileError("disk full")

    monkeypatch.setattr(curvdetail.io, "write_mesh", broken)
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / "o.ply"),
               "--target-edge", "3", "--report", str(tmp_path / "r.json"),
               "--image", str(tmp_path / "f.png"), "--quiet"])
    assert rc == 1
    assert "disk full" in capsys.readouterr().err
    assert os.listdir(tmp_path) == []


def test_edit_failed_mesh_write_leaves_no_image(tmp_path, capsys, monkeypatch):
    import curvdetail
    from curvdetail.curvature.testing import grid as _grid
    from curvdetail.deformation_benchmark import write_selection, write_transform
    from curvdetail.io import write_mesh

    V, F = _grid(8, 8)
    src = tmp_path / "in" / "plane.obj"
    src.parent.mkdir()
    write_mesh(str(src), V, F)
    write_selection(tmp_path / "in" / "p.sel", np.where(V[:, 0] < 0.2, 0, np.where(V[:, 0] > 0.8, 2, 1)))
    T = np.eye(4)
    T[2, 3] = 0.2
    write_transform(tmp_path / "in" / "p.def", T)
    out = tmp_path / "out"
    out.mkdir()

    def broken(*args, **kwargs):
        raise curvdetail.io.MeshFileError("disk full")

    monkeypatch.setattr(curvdetail, "write_mesh", broken)
    rc = main(["edit", str(src), str(out / "o.ply"), "--sel", str(tmp_path / "in" / "p.sel"),
               "--def", str(tmp_path / "in" / "p.def"), "--image", str(out / "e.png")])
    assert rc == 1
    assert "disk full" in capsys.readouterr().err
    assert os.listdir(out) == []


def test_selection_file_has_normal_permissions(tmp_path, umask_022):
    from curvdetail.deformation_benchmark import write_selection

    V, _ = grid(3, 3)
    write_selection(tmp_path / "a.sel", np.zeros(V.shape[0], dtype=int))
    assert _mode(tmp_path / "a.sel") == umask_022


def test_remesh_refuses_one_file_for_two_outputs(tmp_path, capsys):
    out = tmp_path / "o.ply"
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(out), "--report", str(out), "--quiet"])
    assert rc == 1
    assert "given for two outputs" in capsys.readouterr().err
    assert os.listdir(tmp_path) == []


def test_edit_refuses_a_picture_that_is_not_png_before_work(tmp_path, capsys):
    rc = main(["edit", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / "o.ply"),
               "--sel", str(tmp_path / "missing.sel"), "--def", str(tmp_path / "missing.def"),
               "--image", str(tmp_path / "e.jpg")])
    assert rc == 1
    assert "only PNG pictures" in capsys.readouterr().err
    assert os.listdir(tmp_path) == []


def test_a_folder_without_write_permission_is_named_before_the_work(tmp_path, monkeypatch, capsys):
    # it was found only by mkstemp, after the whole run (root ignores permissions, so the test
    # makes os.access say what a user without write permission would get)
    locked = tmp_path / "locked"
    locked.mkdir()
    real_access = os.access
    monkeypatch.setattr(os, "access", lambda p, mode, **kw: False if os.fspath(p) == str(locked)
                        else real_access(p, mode, **kw))
    with pytest.raises(PermissionError, match=r"cannot write '.*m\.ply': folder '.*locked' is not writable"):
        check_output_path(locked / "m.ply", error=FileNotFoundError)
    with pytest.raises(MeshError, match="is not writable"):
        check_output_path(locked / "m.ply")
    nose = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "mannequin_nose.obj")
    rc = main(["remesh", nose, str(tmp_path / "o.ply"), "--report", str(locked / "r.json"), "--quiet"])
    assert rc == 1 and "is not writable" in capsys.readouterr().err
    assert sorted(os.listdir(tmp_path)) == ["locked"]
