"""`curvdetail edit MESH --sel SEL --def DEF OUTPUT`: exact constraints, images, clean failures."""

import os

import numpy as np
import pytest

from curvdetail import read_mesh, write_mesh
from curvdetail.cli import main
from curvdetail.curvature.testing import grid
from curvdetail.io.deformation import apply_transform, write_selection, write_transform


def _case(tmp_path):
    V, F = grid(30, 10, size=(3.0, 1.0))
    V[:, 2] = 0.05 * np.sin(4 * V[:, 0]) * np.cos(3 * V[:, 1])
    status = np.where(V[:, 0] < 0.6, 0, np.where(V[:, 0] > 2.4, 2, 1))
    T = np.eye(4)
    T[:3, :3] = [[np.cos(0.5), 0, -np.sin(0.5)], [0, 1, 0], [np.sin(0.5), 0, np.cos(0.5)]]
    T[:3, 3] = [0.2, 0.0, 0.4]
    paths = {k: tmp_path / f"case.{k}" for k in ("off", "sel", "def")}
    write_mesh(paths["off"], V, F)
    write_selection(paths["sel"], status)
    write_transform(paths["def"], T)
    return V, F, status, T, paths


def test_edit_writes_the_mesh_with_fixed_and_handle_vertices_placed(tmp_path, capsys):
    V, F, status, T, p = _case(tmp_path)
    out, png = tmp_path / "out.ply", tmp_path / "out.png"
    rc = main(["edit", str(p["off"]), "--sel", str(p["sel"]), "--def", str(p["def"]), str(out),
               "--image", str(png)])
    assert rc == 0
    X, F2 = read_mesh(out)
    assert np.array_equal(F2, F)
    # PLY stores float32: exact up to its rounding
    assert np.abs(X[status == 0] - V[status == 0]).max() < 1e-6
    assert np.abs(X[status == 2] - apply_transform(np.loadtxt(p["def"]), V[status == 2])).max() < 1e-6
    assert png.stat().st_size > 1000
    captured = capsys.readouterr()
    assert "handles" in captured.out
    assert "warning" not in captured.err      # a benign edit moves nothing farther than the handles


def test_handle_detail_and_relations_options_change_only_the_interior(tmp_path):
    V, F, status, T, p = _case(tmp_path)
    args = [str(p["off"]), "--sel", str(p["sel"]), "--def", str(p["def"]), "--method", "paper"]
    assert main(["edit", *args, str(tmp_path / "a.ply")]) == 0
    assert main(["edit", *args, str(tmp_path / "b.ply"), "--handle-detail", "free"]) == 0
    assert main(["edit", *args, str(tmp_path / "c.ply"), "--relations", "one+two-ring"]) == 0
    A, B, C = (read_mesh(tmp_path / f"{k}.ply")[0] for k in "abc")
    for other in (B, C):                      # constrained vertices: the same in all three
        assert np.array_equal(A[status != 1], other[status != 1])
    assert np.abs(A - B)[status == 1].max() > 1e-3
    # --relations reaches the editor: the free vertices move, to where the library puts them
    assert np.abs(A - C)[status == 1].max() > 1e-2             # 0.063
    from curvdetail.curvature.geometry import bbox_diagonal
    from curvdetail.io.deformation import edit_with_selection

    expected = edit_with_selection(V, F, status, T, method="paper", relations="one+two-ring")
    assert np.abs(C - expected).max() <= 1e-6 * bbox_diagonal(V)
    assert np.abs(A - edit_with_selection(V, F, status, T, method="paper")).max() <= 1e-6 * bbox_diagonal(V)


def test_the_default_method_is_rotation_aware_and_refuses_the_paper_s_options(tmp_path, capsys):
    from curvdetail.io.deformation import edit_with_selection

    V, F, status, T, p = _case(tmp_path)
    args = [str(p["off"]), "--sel", str(p["sel"]), "--def", str(p["def"])]
    assert main(["edit", *args, str(tmp_path / "a.ply")]) == 0
    assert "iterations" in capsys.readouterr().out
    A = read_mesh(tmp_path / "a.ply")[0]
    assert np.abs(A - edit_with_selection(V, F, status, T)).max() < 1e-6          # float32 PLY
    assert np.abs(A - edit_with_selection(V, F, status, T, method="paper"))[status == 1].max() > 1e-3
    for option in (["--relations", "one-ring"], ["--handle-detail", "free"]):
        assert main(["edit", *args, str(tmp_path / "b.ply"), *option]) == 1
        assert "--method" in capsys.readouterr().err
        assert not (tmp_path / "b.ply").exists()


def test_existing_output_is_refused_without_overwrite(tmp_path, capsys):
    V, F, status, T, p = _case(tmp_path)
    out = tmp_path / "out.ply"
    out.write_text("keep me")
    args = ["edit", str(p["off"]), "--sel", str(p["sel"]), "--def", str(p["def"]), str(out)]
    assert main(args) == 1
    assert "exists" in capsys.readouterr().err and out.read_text() == "keep me"
    assert main(args + ["--overwrite"]) == 0


def test_malformed_selection_fails_cleanly_and_leaves_no_output(tmp_path, capsys):
    V, F, status, T, p = _case(tmp_path)
    p["sel"].write_text("# bad\n" + "\n".join(["0", "1", "7"] * 100))
    out = tmp_path / "out.ply"
    rc = main(["edit", str(p["off"]), "--sel", str(p["sel"]), "--def", str(p["def"]), str(out)])
    err = capsys.readouterr().err
    assert rc == 1 and err.startswith("curvdetail: error:") and "line 4" in err
    assert not out.exists()


def test_an_amplified_edit_is_written_with_exit_status_4(tmp_path, capsys, monkeypatch):
    # the cactus benchmark with its default options moved vertices by 19x the bbox diagonal and
    # exited 0: a script could not tell; the same result is now written with status 4
    import curvdetail.io.deformation as benchmark

    V, F, status, T, p = _case(tmp_path)
    real = benchmark.edit_with_selection

    def blown_up(*args, **kwargs):
        X, editor = real(*args, **kwargs)
        X = X.copy()
        X[status == 1] += [0.0, 0.0, 50.0]          # free vertices far beyond the handle motion
        return X, editor

    monkeypatch.setattr(benchmark, "edit_with_selection", blown_up)
    out = tmp_path / "out.ply"
    rc = main(["edit", str(p["off"]), "--sel", str(p["sel"]), "--def", str(p["def"]), str(out)])
    assert rc == 4
    assert "warning: vertices moved up to" in capsys.readouterr().err
    assert read_mesh(str(out))[0].shape == V.shape


def test_output_over_an_input_file_is_refused_even_with_overwrite(tmp_path, capsys):
    V, F, status, T, paths = _case(tmp_path)
    # a selection file whose name a mesh writer would take
    sel = tmp_path / "selection.ply"
    os.rename(paths["sel"], sel)
    before = sel.read_bytes()
    rc = main(["edit", str(paths["off"]), str(sel), "--sel", str(sel), "--def", str(paths["def"]),
               "--overwrite"])
    assert rc == 1
    # the refusal names the option that gave the file and the output that would replace it
    assert f"(--sel {sel})" in capsys.readouterr().err
    assert sel.read_bytes() == before
    paths["sel"] = sel
    # the mesh over the input mesh is what --overwrite asks for
    assert main(["edit", str(paths["off"]), str(paths["off"]), "--sel", str(paths["sel"]),
                 "--def", str(paths["def"]), "--overwrite"]) == 0


def test_a_selection_that_does_not_determine_the_edit_is_refused_with_what_to_change(tmp_path, capsys):
    # a flat grid, one strip fixed, three handles: the curvature stage is singular, and the
    # shape came back 2.4 diagonals off without a word; the message named the library's roi
    V, F = grid(30, 30)
    status = np.ones(V.shape[0], dtype=int)
    status[V[:, 0] < 0.05] = 0
    status[[450, 451, 480]] = 2
    write_mesh(tmp_path / "plane.obj", V, F)
    write_selection(tmp_path / "q.sel", status)
    write_transform(tmp_path / "p.def", np.eye(4))
    rc = main(["edit", str(tmp_path / "plane.obj"), "--sel", str(tmp_path / "q.sel"), "--def",
               str(tmp_path / "p.def"), str(tmp_path / "o.ply"), "--method", "paper"])
    err = capsys.readouterr().err
    assert rc == 1 and "do not determine the edit" in err
    # in the command's terms: the .sel file; not the library's roi, nor the default it already has
    assert "Add handles (status 2) or fixed vertices (status 0) in" in err and "q.sel" in err
    assert "roi" not in err and "--handle-detail" not in err
    assert not (tmp_path / "o.ply").exists()


def test_a_free_piece_no_constraint_reaches_is_refused_in_the_selections_terms(tmp_path, capsys):
    # two separate grids, the second all free: the message named the library's detail_constrained
    # and roi, not the .sel file
    V, F = grid(10, 10)
    V2, F2 = np.vstack([V, V + [2.0, 0.0, 0.0]]), np.vstack([F, F + V.shape[0]])
    status = np.ones(V2.shape[0], dtype=int)
    status[:10] = 0
    status[55] = 2
    write_mesh(tmp_path / "two.obj", V2, F2)
    write_selection(tmp_path / "q.sel", status)
    write_transform(tmp_path / "p.def", np.eye(4))
    rc = main(["edit", str(tmp_path / "two.obj"), "--sel", str(tmp_path / "q.sel"), "--def",
               str(tmp_path / "p.def"), str(tmp_path / "o.ply")])
    err = capsys.readouterr().err
    assert rc == 1 and "1 connected free region touches no" in err
    assert "Add handles (status 2) or fixed vertices (status 0) in" in err and "q.sel" in err
    assert "roi" not in err and "detail_constrained" not in err
    assert not (tmp_path / "o.ply").exists()


def test_an_edit_that_folds_triangles_is_written_with_exit_status_4(tmp_path, capsys):
    # terrainA_1k, handles within 8 % of the diagonal of the centre turned by 0.8 rad about x,
    # region within 30 %: 12 triangles fold over while nothing moves more than 1.2x as far as the
    # handles, so the amplification rule alone let it exit 0; apply_curvature_editing warned
    from scipy.spatial import cKDTree

    from curvdetail.curvature.geometry import folded_triangles

    V, F = read_mesh(os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "terrainA_1k.obj"))
    diagonal = np.linalg.norm(np.ptp(V, axis=0))
    centre = int(np.argmin(np.linalg.norm(V - V.mean(axis=0), axis=1)))
    handles = np.flatnonzero(np.linalg.norm(V - V[centre], axis=1) < 0.08 * diagonal)
    status = np.where(cKDTree(V[handles]).query(V)[0] <= 0.3 * diagonal, 1, 0)
    status[handles] = 2
    T = np.eye(4)
    T[1:3, 1:3] = [[np.cos(0.8), -np.sin(0.8)], [np.sin(0.8), np.cos(0.8)]]
    T[:3, 3] = V[handles].mean(axis=0) - T[:3, :3] @ V[handles].mean(axis=0)
    paths = {k: tmp_path / f"terrain.{k}" for k in ("off", "sel", "def")}
    write_mesh(paths["off"], V, F)
    write_selection(paths["sel"], status)
    write_transform(paths["def"], T)
    out = tmp_path / "out.ply"
    rc = main(["edit", str(paths["off"]), "--sel", str(paths["sel"]), "--def", str(paths["def"]), str(out),
               "--method", "paper"])
    err = capsys.readouterr().err
    X = read_mesh(str(out))[0]
    moved = np.linalg.norm(X - V, axis=1)
    assert moved.max() < 3.0 * moved[handles].max()                        # not amplified (1.2x)
    folded = folded_triangles(V, F, X, T[:3, :3])
    assert folded.size == 12
    assert rc == 4
    assert f"warning: 12 of {F.shape[0]} triangles folded over" in err and "--relations one+two-ring" in err
    # the default, rotation-aware edit of the same case folds nothing and exits 0
    rc = main(["edit", str(paths["off"]), "--sel", str(paths["sel"]), "--def", str(paths["def"]),
               str(tmp_path / "rotation.ply")])
    assert rc == 0 and "warning" not in capsys.readouterr().err
    assert folded_triangles(V, F, read_mesh(str(tmp_path / "rotation.ply"))[0], T[:3, :3]).size == 0


def _mirrored_free_region(X, status):
    """``X`` with the free vertices mirrored across the strip's midline: their triangles fold over,
    and nothing moves more than the strip's width (under the handles' move)."""
    X = X.copy()
    free = status == 1
    X[free, 1] = 1.0 - X[free, 1]
    return X


def _blown_up_free_region(X, status):
    """``X`` with the free vertices moved 50 units up: far beyond the handle motion."""
    X = X.copy()
    X[status == 1] += [0.0, 0.0, 50.0]
    return X


@pytest.mark.parametrize("spoil, warning", [(_mirrored_free_region, "folded over"),
                                            (_blown_up_free_region, "times as far as the handles")])
@pytest.mark.parametrize("options, tries", [
    ([], "try more handles (status 2) or a larger free region (status 1)."),
    (["--method", "paper"], "try --relations one+two-ring or --handle-detail free."),
    (["--method", "paper", "--relations", "one+two-ring"], "try --relations one-ring or --handle-detail free."),
    (["--method", "paper", "--handle-detail", "free"], "try --relations one+two-ring."),
    (["--method", "paper", "--handle-detail", "free", "--relations", "one+two-ring"], "try --relations one-ring."),
])
def test_the_warnings_suggest_only_options_not_in_use(tmp_path, capsys, monkeypatch, spoil, warning, options,
                                                      tries):
    # the bar with --handle-detail free --relations one+two-ring folded 96 triangles and was told
    # "try --relations one-ring or --handle-detail free"; an amplified edit was always told
    # "--relations one+two-ring or --handle-detail free", whatever it ran with
    import curvdetail.io.deformation as benchmark

    V, F, status, T, p = _case(tmp_path)
    real = benchmark.edit_with_selection
    monkeypatch.setattr(benchmark, "edit_with_selection",
                        lambda *args, **kwargs: (lambda X, editor: (spoil(X, status), editor))(*real(*args, **kwargs)))
    rc = main(["edit", str(p["off"]), "--sel", str(p["sel"]), "--def", str(p["def"]), str(tmp_path / "out.ply"),
               *options])
    lines = [line for line in capsys.readouterr().err.splitlines() if "warning:" in line]
    assert rc == 4 and any(warning in line for line in lines), lines
    assert all(line.endswith(tries) for line in lines), lines     # the fold line too, where the blow-up folds


@pytest.mark.parametrize("name", ["out.obj", "out.off"])
def test_an_output_without_quality_says_it_is_left_out(tmp_path, capsys, name):
    # --help promises quality = distance moved; OBJ and OFF cannot hold it: said, as the other
    # commands say it
    V, F, status, T, p = _case(tmp_path)
    assert main(["edit", str(p["off"]), "--sel", str(p["sel"]), "--def", str(p["def"]), str(tmp_path / name)]) == 0
    assert capsys.readouterr().err == (f"curvdetail: note: {name} holds the geometry only; the vertex quality "
                                       "is kept by PLY output.\n")
    assert read_mesh(str(tmp_path / name))[0].shape == V.shape
    assert main(["edit", str(p["off"]), "--sel", str(p["sel"]), "--def", str(p["def"]), str(tmp_path / "o.ply")]) == 0
    assert capsys.readouterr().err == ""


def test_overwrite_replaces_the_image_too_and_its_help_says_so(tmp_path, capsys):
    # the help said "replace OUTPUT if it exists", but --overwrite replaces an existing --image
    # as well (and remesh's --report and --image)
    _, _, _, _, p = _case(tmp_path)
    out, png = tmp_path / "out.ply", tmp_path / "old.png"
    png.write_bytes(b"not a picture")
    argv = ["edit", str(p["off"]), "--sel", str(p["sel"]), "--def", str(p["def"]), str(out), "--image", str(png)]
    assert main(argv) == 1 and png.read_bytes() == b"not a picture" and not out.exists()
    assert main(argv + ["--overwrite"]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    capsys.readouterr()
    for command, options in (("edit", ("OUTPUT", "--image")), ("remesh", ("OUTPUT", "--report", "--image"))):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        overwrite = " ".join(capsys.readouterr().out.split()).split("--overwrite ")[-1]
        assert all(option in overwrite for option in options)


def test_a_backend_that_is_not_installed_is_told_in_options(tmp_path, capsys, monkeypatch):
    # "or use backend='auto'" is Python; edit's option is --backend auto
    import curvdetail.curvature.sparse_solver as solver

    monkeypatch.setattr(solver, "available_backends", lambda: ["cholmod", "splu"])
    V, F, status, T, p = _case(tmp_path)
    out = tmp_path / "out.ply"
    assert main(["edit", str(p["off"]), "--sel", str(p["sel"]), "--def", str(p["def"]), str(out),
                 "--backend", "pardiso"]) == 1
    err = capsys.readouterr().err
    assert "'pardiso'" in err and "(--backend: " in err and "'auto'" in err, err
    assert not out.exists()


def test_a_backend_the_one_ring_stage_cannot_use_is_named_in_options(tmp_path, capsys, monkeypatch):
    # --backend cholmod (symmetric positive definite only) on the nonsymmetric one-ring stage was
    # called "the constraints do not determine the edit ... constrain more details"
    import curvdetail.curvature.sparse_solver as solver

    monkeypatch.setattr(solver, "available_backends", lambda: ["cholmod", "splu"])
    V, F, status, T, p = _case(tmp_path)
    out = tmp_path / "out.ply"
    assert main(["edit", str(p["off"]), "--sel", str(p["sel"]), "--def", str(p["def"]), str(out),
                 "--method", "paper", "--backend", "cholmod"]) == 1
    err = capsys.readouterr().err
    assert "(--backend: " in err and "one+two-ring" in err, err
    assert "do not determine" not in err and not out.exists()
