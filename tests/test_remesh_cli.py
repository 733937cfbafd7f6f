"""The ``curvdetail remesh`` command (curvdetail.cli, remesh section)."""

import importlib
import json
import os

import numpy as np
import pytest

from curvdetail import read_mesh
from curvdetail.cli import main
from curvdetail.curvature.testing import cylinder
from curvdetail.io.mesh import write_mesh

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


def test_remesh_writes_mesh_with_distance_quality_report_and_image(tmp_path, capsys):
    out, rep, img = tmp_path / "nose.ply", tmp_path / "r.json", tmp_path / "f.png"
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(out), "--target-edge", "3%",
               "--report", str(rep), "--image", str(img), "--quiet"])
    assert rc == 0
    report = json.loads(rep.read_text())
    assert report["target"]["vertices"] == read_mesh(str(out))[0].shape[0]
    assert report["options"]["target_edge_percent_of_diagonal"] == pytest.approx(3)
    # the detail was carried over: far closer to the source than the zero-detail surface
    assert report["error"]["hausdorff_rms_percent_of_diagonal"] < report["baseline_zero_detail"]["hausdorff_rms_percent_of_diagonal"] / 10
    assert img.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(out))
    q = ms.current_mesh().vertex_scalar_array()
    # quality = distance to the source; its max is the report's vertex_max (x bbox diagonal)
    assert 100 * q.max() / report["source"]["bbox_diagonal"] == pytest.approx(report["error"]["vertex_max_percent_of_diagonal"], rel=1e-6)
    assert "RMS" in capsys.readouterr().out


def test_missing_source_fails_and_writes_nothing(tmp_path, capsys):
    rc = main(["remesh", str(tmp_path / "none.obj"), str(tmp_path / "o.ply"), "--report", str(tmp_path / "r.json")])
    assert rc == 1
    assert "not found" in capsys.readouterr().err
    assert os.listdir(tmp_path) == []


def test_uv_location_on_a_non_disk_source_fails_saying_what_was_found(tmp_path, capsys):
    src = tmp_path / "tube.ply"
    write_mesh(str(src), *cylinder(n_around=16, n_along=6))
    rc = main(["remesh", str(src), str(tmp_path / "o.ply"), "--location", "uv", "--image", str(tmp_path / "f.png"),
               "--quiet"])
    assert rc == 1
    assert "2 boundary loops" in capsys.readouterr().err
    assert sorted(os.listdir(tmp_path)) == ["tube.ply"]


def test_a_closed_model_is_remeshed_with_one_anchor_and_pictured(tmp_path, capsys):
    report = tmp_path / "r.json"
    rc = main(["remesh", os.path.join(DATA, "spot.obj"), str(tmp_path / "o.ply"), "--target-edge", "3%",
               "--report", str(report), "--image", str(tmp_path / "f.png"), "--quiet"])
    assert rc == 0
    rep = json.loads(report.read_text())
    assert rep["anchors"] == 1 and rep["baseline_zero_detail"] is None
    assert "1 anchor;" in capsys.readouterr().out and (tmp_path / "f.png").stat().st_size > 0


@pytest.mark.parametrize("pct", ["0.0001", "90"])
@pytest.mark.parametrize("quiet", [["--quiet"], []])
def test_absurd_target_edge_fails_with_the_numbers_and_writes_nothing(tmp_path, capsys, pct, quiet):
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / "o.ply"), "--target-edge", f"{pct}%",
               "--report", str(tmp_path / "r.json")] + quiet)
    assert rc == 1
    err = capsys.readouterr().err
    assert "target vertices" in err
    assert "note:" not in err                    # no "this takes minutes" before the refusal
    assert os.listdir(tmp_path) == []


def test_existing_report_is_not_overwritten(tmp_path, capsys):
    rep = tmp_path / "r.json"
    rep.write_text("keep")
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / "o.ply"), "--report", str(rep)])
    assert rc == 1 and rep.read_text() == "keep"
    assert "--overwrite" in capsys.readouterr().err
    assert sorted(os.listdir(tmp_path)) == ["r.json"]


def test_decimation_that_would_refine_names_the_command_line_option(tmp_path, capsys):
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / "o.ply"),
               "--method", "DECIMATE", "--target-edge", "0.5%", "--quiet"])        # any case, as the filter
    assert rc == 1
    err = capsys.readouterr().err
    assert err.startswith("curvdetail: error: ") and "isotropic" in err
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("given", ["6%", " 6 %"])
def test_target_edge_takes_a_percent_sign(tmp_path, capsys, given):
    rep = tmp_path / "r.json"
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / "o.ply"), "--target-edge", given,
               "--method", "decimate", "--report", str(rep), "--quiet"])
    assert rc == 0
    assert json.loads(rep.read_text())["options"]["target_edge_percent_of_diagonal"] == pytest.approx(6)


@pytest.mark.parametrize("value", ["1x", "-1", "0"])
def test_a_target_edge_that_is_no_positive_number_is_an_argument_error(tmp_path, capsys, value):
    with pytest.raises(SystemExit) as exc:
        main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / "o.ply"), "--target-edge", value])
    assert exc.value.code == 2 and "--target-edge" in capsys.readouterr().err
    assert os.listdir(tmp_path) == []


def test_parameterization_without_uv_location_is_refused_not_ignored(tmp_path, capsys):
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / "o.ply"),
               "--parameterization", "lscm", "--quiet"])
    assert rc == 1
    assert "--parameterization lscm applies to --location uv only" in capsys.readouterr().err
    assert os.listdir(tmp_path) == []


def test_no_evaluate_skips_the_measurements(tmp_path, capsys):
    out, rep = tmp_path / "o.ply", tmp_path / "r.json"
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(out), "--target-edge", "3%",
               "--no-evaluate", "--report", str(rep), "--quiet"])
    assert rc == 0
    report = json.loads(rep.read_text())
    assert "error" not in report and report["seconds"]["evaluate"] == 0.0
    assert report["target"]["vertices"] == read_mesh(str(out))[0].shape[0]
    assert "vertices; not measured (--no-evaluate)" in capsys.readouterr().out


def test_no_evaluate_with_an_image_is_refused_before_the_work(tmp_path, capsys):
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / "o.ply"),
               "--no-evaluate", "--image", str(tmp_path / "f.png"), "--quiet"])
    assert rc == 1
    assert "--image shows the measured distances" in capsys.readouterr().err
    assert os.listdir(tmp_path) == []


def test_a_target_edge_asking_for_a_big_mesh_is_announced(tmp_path, capsys, monkeypatch):
    # the nose at 0.1 % took ~10 minutes without a word; the note comes before the work

    monkeypatch.setattr(importlib.import_module("curvdetail.remesh.retriangulate"), "BIG_TARGET", 1_000)
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / "o.ply"), "--target-edge", "2%",
               "--no-evaluate"])
    err = capsys.readouterr().err
    assert rc == 0
    assert "note: a 2 % target edge gives about " in err and "target vertices; this takes minutes." in err
    assert err.index("note:") < err.index("[1/3] retriangulate")
    monkeypatch.setattr(importlib.import_module("curvdetail.remesh.retriangulate"), "BIG_TARGET", 1_000_000)
    main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / "p.ply"), "--target-edge", "2%",
          "--no-evaluate"])
    assert "note:" not in capsys.readouterr().err


def test_a_report_over_the_input_is_refused_even_with_overwrite(tmp_path, capsys):
    # --overwrite replaces outputs; the input mesh replaced by a JSON report was data lost
    src = tmp_path / "src.obj"
    src.write_bytes(open(os.path.join(DATA, "mannequin_nose.obj"), "rb").read())
    before = src.read_bytes()
    for extra in (["--overwrite"], []):      # without it, not "exists; pass --overwrite" either
        rc = main(["remesh", str(src), str(tmp_path / "o.ply"), "--report", str(src), "--quiet", *extra])
        assert rc == 1
        assert "src.obj is an input of this run" in capsys.readouterr().err
    assert src.read_bytes() == before and sorted(os.listdir(tmp_path)) == ["src.obj"]


def test_an_output_that_is_a_folder_is_refused_before_the_work(tmp_path, capsys):
    (tmp_path / "rep.json").mkdir()
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / "o.ply"),
               "--report", str(tmp_path / "rep.json"), "--overwrite", "--quiet"])
    assert rc == 1
    assert "(--report: " in capsys.readouterr().err
    assert sorted(os.listdir(tmp_path)) == ["rep.json"]


@pytest.mark.parametrize("name", ["o.xyzzy", "o.xyz", "o"])     # unknown, points only, no extension
def test_an_output_format_that_cannot_hold_the_mesh_is_refused_before_the_work(tmp_path, capsys, name):
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / name),
               "--report", str(tmp_path / "r.json"), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 1 and name in err and ".ply" in err and ".curvdetail-" not in err
    assert os.listdir(tmp_path) == []


def test_remesh_defaults_are_the_experiment_defaults(tmp_path):
    # the paper's setting: isotropic remeshing at 1 % of the bbox diagonal, and the library's
    # own defaults (conservative transfer, free rows, closest-point location)
    from curvdetail.remesh.experiment import DEFAULTS

    rep = tmp_path / "r.json"
    assert main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / "o.ply"),
                 "--report", str(rep), "--no-evaluate", "--quiet"]) == 0
    options = json.loads(rep.read_text())["options"]
    assert options["target_edge_percent_of_diagonal"] == pytest.approx(1) and options["method"] == "isotropic"
    assert {k: options[k] for k in ("transfer", "rows", "location", "surface_check")} == \
        {k: DEFAULTS[k] for k in ("transfer", "rows", "location", "surface_check")}
    assert DEFAULTS["target_edge"] == "1%" and DEFAULTS["surface_check"] is True


@pytest.mark.parametrize("flag, expected", [([], True), (["--no-surface-check"], False)])
def test_no_surface_check_is_passed_to_the_remesher_and_recorded(tmp_path, isotropic_calls, flag, expected):
    # the ear at 3 % retriangulates to 648 vertices with the check and 644 without (measured)
    from curvdetail.remesh import retriangulate

    src, out, rep = os.path.join(DATA, "mannequin_ear.obj"), tmp_path / "o.ply", tmp_path / "r.json"
    assert main(["remesh", src, str(out), "--target-edge", "3%", "--no-evaluate", "--report", str(rep),
                 "--quiet"] + flag) == 0
    assert [call["checksurfdist"] for call in isotropic_calls] == [expected]
    assert json.loads(rep.read_text())["options"]["surface_check"] is expected
    V, F = read_mesh(src)
    Vt, Ft = retriangulate(V, F, target_edge="3%", surface_check=expected)
    assert read_mesh(str(out))[0].shape == Vt.shape


def test_the_big_target_note_is_said_with_quiet_too(tmp_path, capsys, monkeypatch):
    # --quiet drops the stage progress; the note before minutes of work was dropped with it
    monkeypatch.setattr(importlib.import_module("curvdetail.remesh.retriangulate"), "BIG_TARGET", 1_000)
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / "o.ply"), "--target-edge", "2%",
               "--no-evaluate", "--quiet"])
    err = capsys.readouterr().err
    assert rc == 0
    assert err.startswith("note: a 2 % target edge gives about ") and "this takes minutes." in err
    assert "[1/3]" not in err                    # still no progress


@pytest.mark.parametrize("name", ["o.obj", "o.off"])
def test_an_output_without_quality_says_it_is_left_out(tmp_path, capsys, name):
    # --help promises quality = distance to SOURCE; OBJ and OFF cannot hold it: said, as the
    # other commands say it (and nothing where there is no quality to lose, or PLY keeps it)
    src = os.path.join(DATA, "mannequin_nose.obj")
    assert main(["remesh", src, str(tmp_path / name), "--target-edge", "4%", "--quiet"]) == 0
    assert capsys.readouterr().err == (f"curvdetail: note: {name} holds the geometry only; the vertex quality "
                                       "is kept by PLY output.\n")
    assert main(["remesh", src, str(tmp_path / f"n{name}"), "--target-edge", "4%", "--quiet", "--no-evaluate"]) == 0
    assert main(["remesh", src, str(tmp_path / "o.ply"), "--target-edge", "4%", "--quiet"]) == 0
    assert capsys.readouterr().err == ""


def test_a_plain_target_edge_is_model_units_and_a_percentage_of_the_diagonal_the_same_mesh(tmp_path, capsys):
    # terrainA_1k's diagonal is 15.27: 0.76 model units and 5 % name the same edge (to rounding)
    from curvdetail.curvature.geometry import bbox_diagonal
    from curvdetail.data import example_path
    from curvdetail.io import read_mesh

    d = bbox_diagonal(read_mesh(example_path())[0])
    reports = {}
    for name, given in (("pct", "5%"), ("abs", repr(0.05 * d))):
        rep = tmp_path / f"{name}.json"
        assert main(["remesh", "--example", str(tmp_path / f"{name}.ply"), "--target-edge", given,
                     "--no-evaluate", "--report", str(rep), "--quiet"]) == 0
        reports[name] = json.loads(rep.read_text())
    err = capsys.readouterr().err
    assert err.count("is in model units") == 1                       # the plain number only
    for r in reports.values():
        assert r["options"]["target_edge_percent_of_diagonal"] == pytest.approx(5.0, rel=1e-12)
        assert r["options"]["target_edge_model_units"] == pytest.approx(0.05 * d, rel=1e-12)
    assert reports["pct"]["target"] == reports["abs"]["target"]


def test_the_written_ply_carries_viridis_colours_over_the_reported_range(tmp_path, capsys):
    from plyfile import PlyData

    from curvdetail.plot import vertex_colours

    out, rep = tmp_path / "o.ply", tmp_path / "r.json"
    assert main(["remesh", "--example", str(out), "--target-edge", "4%", "--report", str(rep), "--quiet"]) == 0
    vertex = PlyData.read(str(out))["vertex"]
    report = json.loads(rep.read_text())
    lo, hi = report["output"]["colour_range_percent_of_diagonal"]
    assert lo == 0 and hi == report["error"]["vertex_max_percent_of_diagonal"]
    q = np.asarray(vertex["quality"])
    rgba = np.stack([vertex[c] for c in ("red", "green", "blue", "alpha")], axis=1)
    assert np.array_equal(rgba, vertex_colours(q, q.max()))
    assert tuple(rgba[np.argmax(q), :3]) == (253, 231, 37)          # viridis' top colour at the max


@pytest.mark.parametrize("quiet", [False, True])
def test_the_evaluation_says_how_far_it_is_with_a_rate_unless_quiet(tmp_path, capsys, monkeypatch, quiet):
    from curvdetail.cli.options import Progress

    monkeypatch.setattr(Progress, "quiet_for", 0.0)            # every step, not only from 2 s on
    rc = main(["remesh", os.path.join(DATA, "mannequin_nose.obj"), str(tmp_path / "o.ply"), "--target-edge", "4%",
               *(["--quiet"] if quiet else [])])
    err = capsys.readouterr().err
    steps = [line for line in err.splitlines() if line.startswith("[4/4] evaluate ") and "per s" in line]
    assert rc == 0 and len(steps) == (0 if quiet else 5)
    assert quiet or steps[-1].startswith("[4/4] evaluate 5/5")
