"""curvdetail.evaluate and ``curvdetail evaluate``: studies of mesh files x remeshing
configurations on Dask, their table, resumption, failed and timed-out cells."""

import hashlib
import json
import os
import subprocess
import sys
import time

import numpy as np
import pyarrow.csv as pa_csv
import pyarrow.parquet as pq
import pytest

from curvdetail import write_mesh
from curvdetail.cli import main
from curvdetail.curvature.testing import disk
from curvdetail.evaluate import COLUMNS, SCHEMA, Study, StudyError, load_study, read_results, run_study, target_size
from curvdetail.evaluate.study import experiment_target_edge

from conftest import data_path

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ENV = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [ROOT, os.environ.get("PYTHONPATH")])))


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    """Two small bumps (61 and 127 vertices, disks) and a file that is not a mesh."""
    folder = tmp_path_factory.mktemp("meshes")
    for n in (4, 6):
        V, F = disk(n_rings=n)
        V[:, 2] = 0.3 * np.exp(-4 * (V[:, :2] ** 2).sum(1))
        write_mesh(str(folder / f"bump{n}.obj"), V, F)
    (folder / "bad.obj").write_text("this is not a mesh\n")
    return folder


@pytest.fixture(scope="module")
def client():
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, \
            Client(cluster) as c:
        yield c


# --- the study ------------------------------------------------------------------------------

def test_a_grid_is_every_combination_and_uv_takes_a_planar_map():
    study = Study([{"method": ["isotropic", "decimate"], "target_edge": ["1%", "2%"],
                    "location": ["closest", "uv"]}])
    configs = [dict(c) for c in study.configurations()]
    assert len(configs) == 8
    assert {c["parameterization"] for c in configs if c["location"] == "uv"} == {"harmonic"}
    assert {c["parameterization"] for c in configs if c["location"] == "closest"} == {None}


def test_the_pointwise_baseline_adds_the_papers_configuration_to_each_grid():
    configs = [dict(c) for c in Study([{"target_edge": ["1%", "2%"]}], ["pointwise", "floor"]).configurations()]
    paper = [c for c in configs if c["transfer"] == "pointwise"]
    assert len(configs) == 4 and len(paper) == 2
    assert all(c["rows"] == "all" and c["location"] == "uv" for c in paper)


def test_target_sizes_are_normalized_and_a_percentage_is_of_the_diagonal():
    assert [target_size(v) for v in ("0.50 %", "1%", 0.01, "2")] == ["0.5%", "1%", "0.01", "2"]
    assert (experiment_target_edge("1%"), experiment_target_edge("0.01")) == ("1%", 0.01)    # model units
    for bad in ("x", "-1%", 0, True):
        with pytest.raises(StudyError) as e:
            target_size(bad)
        assert e.value.parameter == "target_edge"


def test_toml_and_json_study_files_give_the_same_cells(tmp_path, meshes):
    (tmp_path / "s.toml").write_text('baselines = ["zero_detail"]\n[[grid]]\nmeshes = ["bump*.obj"]\n'
                                     'target_edge = ["5%", "8%"]\n[[grid]]\nmeshes = ["bump4.obj"]\n'
                                     'transfer = "pointwise"\nrows = "all"\n')
    (tmp_path / "s.json").write_text(json.dumps({"baselines": ["zero_detail"], "grid": [
        {"meshes": ["bump*.obj"], "target_edge": ["5%", "8%"]},
        {"meshes": ["bump4.obj"], "transfer": "pointwise", "rows": "all"}]}))
    cells = [load_study(tmp_path / name).cells(meshes) for name in ("s.toml", "s.json")]
    assert cells[0] == cells[1] and len(cells[0]) == 2 * 2 + 1
    assert len({c.key for c in cells[0]}) == 5


def test_the_fig3_study_file_holds_the_scripts_configurations():
    study = load_study(os.path.join(ROOT, "scripts", "studies", "fig3.toml"))
    configs = {(c["method"], c["target_edge"], c["transfer"], c["rows"], c["location"], c["parameterization"])
               for c in map(dict, study.configurations())}
    assert ("isotropic", "1%", "pointwise", "all", "uv", "harmonic") in configs
    assert ("decimate", "3%", "conservative", "free", "closest", None) in configs
    assert len(configs) == 6 + 2 + 2     # transfer configurations, two more planar maps, decimation at 1 and 3 %


@pytest.mark.parametrize("grid, parameter", [({"colour": "red"}, "colour"), ({"method": "remesh"}, "method"),
                                             ({"rows": []}, "rows")])
def test_a_bad_grid_names_its_option(grid, parameter):
    with pytest.raises(StudyError) as e:
        Study([grid])
    assert e.value.parameter == parameter


def test_inputs_or_patterns_that_name_nothing_are_refused(tmp_path, meshes):
    with pytest.raises(StudyError) as e:
        Study([{}]).cells([str(tmp_path / "none*.obj")])
    assert e.value.parameter == "inputs"
    with pytest.raises(StudyError) as e:
        Study([{"meshes": ["camelhead.off"]}]).cells(meshes)
    assert e.value.parameter == "meshes" and e.value.value == "camelhead.off"


def test_a_results_folder_with_other_files_is_refused(tmp_path, meshes):
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(StudyError) as e:
        run_study(Study([{}]), meshes, tmp_path)
    assert e.value.parameter == "results"


# --- running it -----------------------------------------------------------------------------

@pytest.mark.slow
def test_a_study_writes_a_row_per_cell_with_units_and_resumes(tmp_path, meshes, client):
    results = tmp_path / "study"
    study = Study([{"target_edge": ["5%", "8%"]}])
    out = run_study(study, meshes, results, scheduler=client, progress=None)
    assert (out["cells"], out["ran"], out["failed"]) == (6, 6, 2)
    table = pq.read_table(results / "results.parquet")
    assert table.schema == SCHEMA and pa_csv.read_csv(results / "results.csv").num_rows == 6
    rows = {(r["mesh_name"], r["target_edge"]): r for r in table.to_pylist()}
    for name, n in (("bump4.obj", 61), ("bump6.obj", 127)):
        data = (meshes / name).read_bytes()
        for size in ("5%", "8%"):
            r = rows[name, size]
            assert r["status"] == "ok" and r["mesh_blake2b"] == hashlib.blake2b(data, digest_size=16).hexdigest()
            assert (r["mesh_vertices"], r["mesh_closed"]) == (n, False)
            # units: the percentage of the diagonal is the study's, the length that share of the diagonal
            assert r["target_edge_percent_of_diagonal"] == pytest.approx(float(size[:-1]), rel=1e-12)
            assert np.isclose(r["target_edge_model_units"], r["target_edge_percent_of_diagonal"] / 100
                              * r["mesh_bbox_diagonal_model_units"], rtol=1e-12)
            # the rebuild beats zero detail by far; the ratio columns are the RMS columns' quotients
            assert r["error_rms_percent_of_diagonal"] < 0.2 * r["zero_detail_rms_percent_of_diagonal"]
            assert np.isclose(r["rms_to_floor_ratio"],
                              r["error_rms_percent_of_diagonal"] / r["floor_rms_percent_of_diagonal"])
            stages = sum(r[f"{s}_s"] for s in ("retriangulate", "parameterize", "transfer", "reconstruct",
                                                 "evaluate"))
            assert stages <= r["experiment_s"] + 1e-3 and r["experiment_s"] <= r["cell_s"]
            assert r["peak_rss_mib"] > 10 and r["worker"].startswith("tcp://")
    for size in ("5%", "8%"):
        bad = rows["bad.obj", size]
        assert (bad["status"], bad["error_class"], bad["mesh_vertices"]) == ("failed", "MeshFileError", None)

    # the parts are folded into results.parquet: a rerun skips its cells and writes nothing
    assert list((results / "parts").iterdir()) == [] and {r["mesh_shipped"] for r in rows.values()} == {False}
    written = (results / "results.parquet").stat().st_mtime_ns
    again = run_study(study, meshes, results, scheduler=client, progress=None)
    assert (again["skipped"], again["ran"]) == (6, 0) and again["table"].num_rows == 6
    assert (results / "results.parquet").stat().st_mtime_ns == written

    more = run_study(Study([{"target_edge": ["5%", "8%", "9%"]}]), meshes, results, scheduler=client, progress=None)
    assert (more["skipped"], more["ran"]) == (6, 3) and read_results(results).num_rows == 9
    retry = run_study(study, meshes, results, scheduler=client, retry_failed=True, progress=None)
    assert (retry["ran"], retry["failed"]) == (2, 2) and read_results(results).num_rows == 9    # bad.obj again


@pytest.mark.slow
def test_shipped_meshes_run_where_the_workers_cannot_read_the_path(tmp_path, meshes, client, monkeypatch):
    import curvdetail.evaluate.run as run

    source = tmp_path / "in" / "bump4.obj"
    source.parent.mkdir()
    source.write_bytes((meshes / "bump4.obj").read_bytes())
    read = run._mesh_bytes

    def read_then_hide(cells):          # the file is gone once read: no worker can open its path
        data = read(cells)
        source.rename(tmp_path / "hidden.obj")
        return data

    monkeypatch.setattr(run, "_mesh_bytes", read_then_hide)
    out = run_study(Study([{"target_edge": "8%"}]), source, tmp_path / "r", scheduler=client, ship_meshes=True,
                    progress=None)
    (row,) = out["table"].to_pylist()
    assert (row["status"], row["mesh_shipped"], row["mesh_vertices"], row["mesh_path"]) == ("ok", True, 61,
                                                                                            str(source))
    assert not source.exists()


@pytest.mark.slow
def test_auto_ships_only_where_a_worker_does_not_see_the_path(tmp_path, meshes, client, monkeypatch):
    import curvdetail.evaluate.run as run

    study = Study([{"target_edge": "8%"}])
    out = run_study(study, meshes / "bump4.obj", tmp_path / "a", scheduler=client, progress=None)
    assert out["table"].column("mesh_shipped").to_pylist() == [False]      # a local cluster sees the file
    monkeypatch.setattr(run, "_workers_see", lambda client, path: False)
    out = run_study(study, meshes / "bump4.obj", tmp_path / "b", scheduler=client, progress=None)
    assert out["table"].column("mesh_shipped").to_pylist() == [True]


def test_a_bad_ship_meshes_is_refused(tmp_path, meshes):
    with pytest.raises(StudyError) as e:
        run_study(Study([{}]), meshes, tmp_path / "r", ship_meshes="always")
    assert e.value.parameter == "ship_meshes"


@pytest.mark.slow
def test_a_cell_past_its_time_limit_is_stopped_and_the_study_goes_on(tmp_path, meshes, client):
    # terrainA_1k at 0.2 % of the diagonal: ~150k target vertices, tens of seconds; bump4 at 5 %
    # ~0.3 s, spot (closed) ~1 s
    study = Study([{"meshes": ["terrainA_1k.obj"], "target_edge": "0.2%"},
                   {"meshes": ["bump4.obj", "spot.obj"], "target_edge": "5%"}])
    out = run_study(study, [data_path("terrainA_1k.obj"), data_path("spot.obj"), str(meshes / "bump4.obj")],
                    tmp_path / "s", scheduler=client, cell_timeout=5.0, progress=None)
    rows = {r["mesh_name"]: r for r in out["table"].to_pylist()}
    slow = rows["terrainA_1k.obj"]
    assert (slow["status"], slow["error_class"]) == ("timeout", "CellTimeout")
    with pytest.raises(ProcessLookupError):         # its process was killed, not left running
        os.kill(slow["pid"], 0)
    assert rows["bump4.obj"]["status"] == "ok"
    # a closed surface: rebuilt with an anchor, and no zero-detail surface to compare with
    spot = rows["spot.obj"]
    assert (spot["status"], spot["mesh_closed"], spot["anchors"]) == ("ok", True, 1)
    assert spot["zero_detail_rms_percent_of_diagonal"] is None and spot["improvement_over_zero_detail_ratio"] is None


@pytest.mark.slow
def test_a_cell_past_its_memory_limit_is_stopped(tmp_path, client):
    # the cell process holds ~200 MiB once the package is imported; this cell grows to GBs
    out = run_study(Study([{"target_edge": "0.2%"}]), data_path("terrainA_1k.obj"), tmp_path / "s",
                    scheduler=client, cell_memory=100, progress=None)
    (row,) = out["table"].to_pylist()
    assert (row["status"], row["error_class"]) == ("memory", "CellMemoryLimit")
    with pytest.raises(ProcessLookupError):
        os.kill(row["pid"], 0)


@pytest.mark.slow
def test_the_command_runs_a_study_on_a_local_cluster_and_writes_a_summary(tmp_path, meshes, capsys):
    args = ["evaluate", str(meshes / "bump4.obj"), str(meshes / "bad.obj"), "--results", str(tmp_path / "r"),
            "--method", "isotropic,decimate", "--target-edge", "8%", "--workers", "2", "--summary", str(tmp_path / "s")]
    assert main(args) == 0         # failed cells included (decimation cannot refine bump4; bad.obj)
    table = read_results(tmp_path / "r")
    assert sorted(table.column("status").to_pylist()) == ["failed", "failed", "failed", "ok"]
    assert table.column("mesh_shipped").to_pylist() == [False] * 4     # auto: a local cluster reads the paths
    text = (tmp_path / "s" / "summary.md").read_text()
    assert "| isotropic conservative free closest 8% | 1 / 2 |" in text
    for name in ("rms_against_target.png", "ratio_to_floor.png", "time_against_vertices.png"):
        assert (tmp_path / "s" / name).read_bytes()[:4] == b"\x89PNG"
    assert main(args) == 1 and "--overwrite" in capsys.readouterr().err     # the summary exists


def test_the_command_says_its_options(capsys):
    with pytest.raises(SystemExit) as e:
        main(["evaluate", "--help"])
    assert e.value.code == 0 and "--target-edge LIST" in capsys.readouterr().out


@pytest.mark.slow
def test_a_study_runs_on_a_dask_scheduler_and_worker_started_apart(tmp_path, meshes):
    file = tmp_path / "scheduler.json"
    started = [subprocess.Popen([sys.executable, "-m", "dask", "scheduler", "--port", "0", "--no-dashboard",
                                 "--scheduler-file", str(file)], env=ENV, stderr=subprocess.DEVNULL)]
    try:
        for _ in range(300):
            if file.exists() and file.stat().st_size:
                break
            time.sleep(0.1)
        started.append(subprocess.Popen([sys.executable, "-m", "dask", "worker", "--nthreads", "1",
                                         "--no-dashboard", "--scheduler-file", str(file)], env=ENV,
                                        stderr=subprocess.DEVNULL))
        address = json.loads(file.read_text())["address"]
        out = run_study(Study([{"target_edge": "8%"}]), meshes / "bump6.obj", tmp_path / "r", scheduler=address,
                        progress=None)
        (row,) = out["table"].to_pylist()
        assert row["status"] == "ok" and row["worker"].startswith("tcp://")
    finally:
        for process in reversed(started):
            process.terminate()
            process.wait(30)


def test_every_column_has_a_meaning_and_one_name():
    names = [name for name, _, _ in COLUMNS]
    assert len(set(names)) == len(names) == len(SCHEMA) and all(meaning for _, _, meaning in COLUMNS)
