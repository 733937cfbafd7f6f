"""curvdetail._output: checked, atomic outputs with a normal file's permissions, and the
writers and commands that use it."""

import doctest
import importlib
import os
import stat
import subprocess
import sys

import numpy as np
import pytest

from curvdetail import _output
from curvdetail._output import Output, atomic_output, atomic_outputs, check_output_path
from curvdetail.cli import main
from curvdetail.curvature.errors import MeshError
from curvdetail.curvature.testing import grid

from conftest import run_commit_interrupted_by

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
    with pytest.raises(FileExistsError, match="pass overwrite=True"):
        with atomic_output(path):
            pytest.fail("the block must not run")
    assert os.listdir(tmp_path) == ["a.txt"]


def test_a_refusal_names_the_callers_way_to_replace(tmp_path):
    # Python says overwrite=True (the CLI translates it); the scripts under scripts/ name their own flag
    path = tmp_path / "old.json"
    path.write_text("kept")
    with pytest.raises(FileExistsError, match=r"exists; pass overwrite=True to replace it"):
        check_output_path(path)
    with pytest.raises(FileExistsError, match=r"exists; pass --force to replace it\.$"):
        with atomic_output(path, hint=None, flag="--force"):
            pass
    with pytest.raises(FileExistsError, match="pass --redo to replace it"):
        with atomic_outputs([Output(path, hint=None, flag="--redo")]):
            pass
    assert path.read_text() == "kept"


def test_a_dangling_link_is_not_replaced_without_overwrite(tmp_path):
    link = tmp_path / "a.txt"
    os.symlink(tmp_path / "missing.txt", link)
    with pytest.raises(FileExistsError, match="link to a missing file.*pass overwrite=True"):
        with atomic_output(link):
            pytest.fail("the block must not run")
    assert os.path.islink(link)
    with atomic_output(link, overwrite=True) as tmp:
        with open(tmp, "w") as fh:
            fh.write("new")
    assert not os.path.islink(link) and link.read_text() == "new"


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


def test_a_folder_that_refuses_files_is_named_not_the_temporary_file(tmp_path, monkeypatch):
    # a folder that passes the permission check (os.access) but refuses the temporary file, as
    # /proc does for root: os.open refuses it here, as the OS would, whoever runs the test (root
    # ignores a chmod, and the test used /proc itself), so mkstemp's own error, naming the
    # temporary file, is what must come back naming the output
    import errno

    folder = tmp_path / "refuses"
    folder.mkdir()
    real_open = os.open

    def refusing_open(path, flags, *args, **kwargs):
        if os.path.dirname(os.fsdecode(path)) == str(folder):
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), os.fsdecode(path))
        return real_open(path, flags, *args, **kwargs)

    monkeypatch.setattr(os, "open", refusing_open)
    with pytest.raises(PermissionError, match=r"cannot write '.*m\.ply': Permission denied$") as info:
        with atomic_output(folder / "m.ply"):
            pytest.fail("the block must not run")
    assert ".curvdetail-" not in str(info.value)
    assert os.listdir(folder) == []


def test_doctests():
    result = doctest.testmod(importlib.import_module("curvdetail._output"))
    assert result.attempted > 0 and result.failed == 0, result


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


def _edit_inputs(tmp_path):
    """An 8 x 8 plane with its .sel / .def in tmp_path / "in", and an empty tmp_path / "out";
    returns the ``curvdetail edit`` arguments before OUTPUT, and the out folder."""
    from curvdetail.curvature.testing import grid as _grid
    from curvdetail.io.deformation import write_selection, write_transform
    from curvdetail.io.mesh import write_mesh

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
    args = ["edit", str(src), "--sel", str(tmp_path / "in" / "p.sel"), "--def", str(tmp_path / "in" / "p.def")]
    return args, out


def test_edit_failed_mesh_write_leaves_no_image(tmp_path, capsys, monkeypatch):
    import curvdetail

    args, out = _edit_inputs(tmp_path)

    def broken(*args, **kwargs):
        raise curvdetail.io.MeshFileError("disk full")

    monkeypatch.setattr(curvdetail, "write_mesh", broken)
    rc = main([*args, str(out / "o.ply"), "--image", str(out / "e.png")])
    assert rc == 1
    assert "disk full" in capsys.readouterr().err
    assert os.listdir(out) == []


def test_selection_file_has_normal_permissions(tmp_path, umask_022):
    from curvdetail.io.deformation import write_selection

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


# --- atomic_outputs: several outputs committed together -----------------------------------------

def _write(tmp, text):
    with open(tmp, "w") as fh:
        fh.write(text)


def _failing_replace(monkeypatch, fails_on):
    """Make os.replace fail where a temporary file would be renamed over ``fails_on`` (what a
    destination replaced by a folder, a permission change or a disk error do mid-commit)."""
    real = os.replace

    def replace(src, dst):
        if os.path.basename(src).startswith(".curvdetail-") and os.fspath(dst) == str(fails_on):
            raise PermissionError(13, "Permission denied")
        return real(src, dst)

    monkeypatch.setattr(os, "replace", replace)


def test_atomic_outputs_writes_all_with_normal_permissions(tmp_path, umask_022):
    a, b = tmp_path / "a.txt", tmp_path / "b.txt"
    a.write_text("old a")
    with atomic_outputs([Output(a, hint=None), None, Output(b, hint=None)], overwrite=True) as temps:
        assert temps[1] is None and [os.path.dirname(t) for t in (temps[0], temps[2])] == [str(tmp_path)] * 2
        _write(temps[0], "new a")
        _write(temps[2], "new b")
    assert (a.read_text(), b.read_text()) == ("new a", "new b")
    assert [_mode(a), _mode(b)] == [umask_022] * 2
    assert sorted(os.listdir(tmp_path)) == ["a.txt", "b.txt"]      # no temporary file, no old one kept


@pytest.mark.parametrize("hard_links", [True, False])
def test_a_failed_rename_puts_every_destination_back_as_it_was(tmp_path, monkeypatch, hard_links):
    # each output was renamed on its own: a.txt was replaced (its old content lost) and b.txt
    # written before c.txt failed
    a, b, c = tmp_path / "a.txt", tmp_path / "b.txt", tmp_path / "c.txt"
    a.write_text("old a")
    c.write_text("old c")
    inode_a = os.stat(a).st_ino
    def refused(*args, **kwargs):   # FAT, or another user's file under protected_hardlinks
        raise PermissionError(1, "Operation not permitted")

    if not hard_links:
        monkeypatch.setattr(os, "link", refused)
    _failing_replace(monkeypatch, c)
    with pytest.raises(PermissionError, match=r"cannot write '.*c\.txt': Permission denied; no output was "
                                              r"written, the existing files are as they were"):
        with atomic_outputs([Output(p, hint=None) for p in (a, b, c)], overwrite=True) as temps:
            for tmp, text in zip(temps, ("new a", "new b", "new c")):
                _write(tmp, text)
    assert (a.read_text(), c.read_text()) == ("old a", "old c")
    assert os.stat(a).st_ino == inode_a                             # the very file, not a copy
    assert sorted(os.listdir(tmp_path)) == ["a.txt", "c.txt"]      # no b.txt, temporary or old file


def test_an_old_file_that_cannot_be_put_back_is_named_with_where_it_is(tmp_path, monkeypatch):
    a, b = tmp_path / "a.txt", tmp_path / "b.txt"
    a.write_text("old a")
    real = os.replace

    def replace(src, dst):
        if os.fspath(dst) == str(b) or ".curvdetail-old-" in os.fspath(src):
            raise PermissionError(13, "Permission denied")
        return real(src, dst)

    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(PermissionError, match=r"could not all be taken back: '.*a\.txt' could not be taken "
                                              r"back \(Permission denied\); its old file is kept in "
                                              r"'.*\.curvdetail-old-\w+/a\.txt'"):
        with atomic_outputs([Output(a, hint=None), Output(b, hint=None)], overwrite=True) as temps:
            _write(temps[0], "new a")
            _write(temps[1], "new b")
    kept = [n for n in os.listdir(tmp_path) if n.startswith(".curvdetail-old-")]
    assert len(kept) == 1 and (tmp_path / kept[0] / "a.txt").read_text() == "old a"


def test_atomic_outputs_failed_block_leaves_nothing_and_keeps_the_old_files(tmp_path):
    a, b = tmp_path / "a.txt", tmp_path / "b.txt"
    a.write_text("old a")
    with pytest.raises(RuntimeError):
        with atomic_outputs([Output(a, hint=None), Output(b, hint=None)], overwrite=True) as temps:
            _write(temps[0], "new a")
            assert temps[1] in _output.PENDING                      # for the SIGTERM watcher
            raise RuntimeError("writer failed")
    assert a.read_text() == "old a"
    assert os.listdir(tmp_path) == ["a.txt"]
    assert not _output.PENDING


def test_a_destination_made_a_folder_during_the_work_stops_the_commit_before_any_rename(tmp_path):
    a, b = tmp_path / "a.txt", tmp_path / "b.txt"
    a.write_text("old a")
    with pytest.raises(IsADirectoryError, match=r"'.*b\.txt': it is a folder"):
        with atomic_outputs([Output(a, hint=None, error=FileNotFoundError),
                             Output(b, hint=None, error=FileNotFoundError)], overwrite=True) as temps:
            _write(temps[0], "new a")
            b.mkdir()
    assert a.read_text() == "old a"
    assert sorted(os.listdir(tmp_path)) == ["a.txt", "b.txt"] and os.listdir(b) == []


def test_atomic_outputs_checks_every_destination_before_the_block(tmp_path):
    (tmp_path / "b.txt").write_text("old b")
    with pytest.raises(FileExistsError, match="b.txt exists"):
        with atomic_outputs([Output(tmp_path / "a.txt", hint=None), Output(tmp_path / "b.txt", hint=None)]):
            pytest.fail("the block must not run")
    with pytest.raises(ValueError, match="given for two outputs"):
        with atomic_outputs([Output(tmp_path / name, hint=None) for name in ("a.txt", "./a.txt")]):
            pytest.fail("the block must not run")
    assert os.listdir(tmp_path) == ["b.txt"]


def test_edit_failed_mesh_rename_keeps_the_old_picture_and_mesh(tmp_path, capsys, monkeypatch):
    # the picture was renamed first, over the old one, then the mesh's rename failed
    args, out = _edit_inputs(tmp_path)
    (out / "o.ply").write_text("old mesh")
    (out / "e.png").write_text("old picture")
    _failing_replace(monkeypatch, out / "o.ply")
    rc = main([*args, str(out / "o.ply"), "--image", str(out / "e.png"), "--overwrite"])
    assert rc == 1
    assert "o.ply': Permission denied; no output was written" in capsys.readouterr().err
    assert ((out / "o.ply").read_text(), (out / "e.png").read_text()) == ("old mesh", "old picture")
    assert sorted(os.listdir(out)) == ["e.png", "o.ply"]


def test_sigterm_during_a_commit_lets_it_finish(tmp_path):
    # the watcher removed the temporary files at once: outputs renamed before the signal were
    # new, the others old (one possibly missing), and the old files were left in hidden folders.
    # Handshakes, not sleeps: the commit goes on only once the watcher has asked for the commit
    # lock (it was a 1 s sleep), and the main thread then waits for the watcher's thread, which
    # only the watcher's exit ends (it was a 10 s sleep)
    done, out = run_commit_interrupted_by(tmp_path, "SIGTERM")
    assert done.returncode == 128 + 15 and done.stdout == "", (done.stdout, done.stderr)
    assert ((out / "a.txt").read_text(), (out / "b.txt").read_text()) == ("new a", "new b")
    assert sorted(os.listdir(out)) == ["a.txt", "b.txt"]


def test_a_file_name_too_long_for_the_file_system_is_refused_before_the_work(tmp_path):
    # it passed the check and failed only at the rename after the work (OSError, ENAMETOOLONG)
    name_max = os.pathconf(tmp_path, "PC_NAME_MAX")
    too_long = "x" * (name_max - 3) + ".ply"
    long_extension = "a." + "x" * (name_max - 15)            # fits; ".curvdetail-XXXXXXXX.xxx..." does not
    for name, message in ((too_long, rf"its file name is {name_max + 1} bytes long, and the file system of "),
                          (long_extension, rf"its extension is too long for the temporary file it is first written "
                                           rf"to \({name_max + 6} bytes; the file system of ")):
        with pytest.raises(MeshError, match=message + rf"'.*' allows {name_max}"):
            with atomic_output(tmp_path / name, hint=None):
                pytest.fail("the block must not run")
    assert ("x" * (name_max - 4) + ".ply") == check_output_path(str(tmp_path / ("x" * (name_max - 4) + ".ply")))[
        len(str(tmp_path)) + 1:]                                     # the longest name that fits passes
    assert os.listdir(tmp_path) == []


def test_a_file_made_by_another_process_during_the_commit_is_not_replaced(tmp_path, monkeypatch):
    # made after the last check, just before the rename: os.replace put the output over it
    path = tmp_path / "a.txt"
    real_chmod = os.chmod

    def chmod_then_another_process_writes(target, mode, **kwargs):  # between the check and the rename
        real_chmod(target, mode, **kwargs)
        if not path.exists():
            path.write_text("another process's")

    monkeypatch.setattr(os, "chmod", chmod_then_another_process_writes)
    with pytest.raises(FileExistsError, match=r"cannot write '.*a\.txt': it was made while the output was being "
                                              r"written; pass overwrite=True to replace it; no "
                                              r"output was written"):
        with atomic_output(path, hint=None) as tmp:
            _write(tmp, "ours")
    assert path.read_text() == "another process's" and os.listdir(tmp_path) == ["a.txt"]


@pytest.mark.parametrize("refusal", [1, 18, 95])       # EPERM (FAT), EXDEV, EOPNOTSUPP
def test_where_hard_links_are_refused_a_new_output_is_renamed_into_place(tmp_path, monkeypatch, refusal):
    def refused(*args, **kwargs):
        raise OSError(refusal, os.strerror(refusal))

    monkeypatch.setattr(os, "link", refused)
    with atomic_outputs([Output(tmp_path / "a.txt", hint=None), Output(tmp_path / "b.txt", hint=None)]) as temps:
        for tmp, text in zip(temps, ("new a", "new b")):
            _write(tmp, text)
    assert ((tmp_path / "a.txt").read_text(), (tmp_path / "b.txt").read_text()) == ("new a", "new b")
    assert sorted(os.listdir(tmp_path)) == ["a.txt", "b.txt"]


def test_a_new_output_is_one_file_with_no_second_name_left(tmp_path):
    with atomic_output(tmp_path / "a.txt", hint=None) as tmp:
        _write(tmp, "new")
    assert os.stat(tmp_path / "a.txt").st_nlink == 1 and os.listdir(tmp_path) == ["a.txt"]
