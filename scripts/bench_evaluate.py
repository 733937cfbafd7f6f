"""Benchmark of curvdetail.evaluate: the overhead of a study cell against calling
remesh_experiment directly, and the rate of 1 against 2 Dask workers on a 24-cell study.

Usage: python scripts/bench_evaluate.py [--out out/bench_evaluate.json] [--meshes DIR] [--repeat N]
                                        [--force]
Overhead: the same cells (terrainA_1k, isotropic at 1, 1.5, 2 and 3 %, conservative transfer) run
directly in this process (read_mesh + remesh_experiment) and as a study on a warm 1-worker
LocalCluster (its cell process already started), interleaved ``--repeat`` times; the overhead
per cell is the difference of the medians divided by the cells (it includes the study's own
fixed costs: hashing, reading and writing the table), and the orchestration per cell the study's
wall clock less the seconds its cells measured themselves (``cell_s``). Scaling: a 24-cell study
(terrainA_1k, mannequin_ear, terrainA_10k x target 1 %, 2 % x transfer conservative, pointwise x
rows free, all) on 1 and on 2 workers, interleaved; the rate is cells per second of wall clock
from submitting to the last row (the cluster's start is reported apart), and the workers' busy
fraction the cells' own seconds over workers x wall clock (near 1: the scheduling kept every
worker busy, and a rate below 2x is the cells running slower side by side, e.g. on a machine
that other work shares).
"""

import argparse
import os
import statistics
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _files  # noqa: E402
from _meshes import MESHES, require  # noqa: E402

from curvdetail import read_mesh
from curvdetail.evaluate import Study, run_study
from curvdetail.evaluate.study import experiment_target_edge
from curvdetail.remesh import remesh_experiment

OVERHEAD_MESH, OVERHEAD_SIZES = "terrainA_1k.obj", ["1%", "1.5%", "2%", "3%"]
SCALING_MESHES = ["terrainA_1k.obj", "mannequin_ear.obj", "terrainA_10k.obj"]
SCALING_GRID = {"target_edge": ["1%", "2%"], "transfer": ["conservative", "pointwise"], "rows": ["free", "all"]}


def _direct(path, sizes):
    t = time.perf_counter()
    for size in sizes:
        V, F = read_mesh(path)
        remesh_experiment(V, F, target_edge=experiment_target_edge(size), source_path=path)
    return time.perf_counter() - t


def _study(client, study, inputs):
    with tempfile.TemporaryDirectory() as folder:
        t = time.perf_counter()
        out = run_study(study, inputs, os.path.join(folder, "r"), scheduler=client, progress=None)
        seconds = time.perf_counter() - t
    bad = [r for r in out["table"].to_pylist() if r["status"] != "ok"]
    if bad:
        sys.exit(f"bench_evaluate: {len(bad)} cells failed: {bad[0]['error_class']}: {bad[0]['error_message']}")
    return seconds, out["table"]


def _cluster(workers):
    from distributed import Client, LocalCluster

    t = time.perf_counter()
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0")
    return cluster, Client(cluster), time.perf_counter() - t


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join("out", "bench_evaluate.json"))
    ap.add_argument("--meshes", default=MESHES)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--force", action="store_true", help="replace OUT if it exists")
    args = ap.parse_args(argv)
    _files.check_outputs(ap, [args.out], args.force)
    require(*SCALING_MESHES)
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    path = os.path.join(args.meshes, OVERHEAD_MESH)

    cluster, client, start = _cluster(1)
    try:
        overhead_study = Study([{"target_edge": OVERHEAD_SIZES}])
        _study(client, Study([{"target_edge": "3%"}]), path)         # starts the worker's cell process
        _direct(path, ["3%"])                                          # and warms this one alike
        direct, study, orchestration = [], [], []
        cells = len(OVERHEAD_SIZES)
        for _ in range(args.repeat):
            direct.append(_direct(path, OVERHEAD_SIZES))
            seconds, table = _study(client, overhead_study, path)
            study.append(seconds)
            orchestration.append((seconds - sum(table.column("cell_s").to_pylist())) / cells)
        overhead = {"mesh": OVERHEAD_MESH, "cells": cells, "direct_s": direct, "study_s": study,
                    "overhead_per_cell_s": (statistics.median(study) - statistics.median(direct)) / cells,
                    "orchestration_per_cell_s": orchestration, "cluster_start_1_worker_s": start}
        print(f"overhead per cell: {overhead['overhead_per_cell_s']:.3f} s (direct {direct}, study {study}; "
              f"orchestration per cell {orchestration})", flush=True)
    finally:
        client.close()
        cluster.close()

    scaling_study = Study([SCALING_GRID])
    inputs = [os.path.join(args.meshes, name) for name in SCALING_MESHES]
    runs, starts, busy = {1: [], 2: []}, {1: [], 2: []}, {1: [], 2: []}
    for _ in range(args.repeat):
        for workers in (1, 2):
            cluster, client, start = _cluster(workers)
            try:
                seconds, table = _study(client, scaling_study, inputs)
            finally:
                client.close()
                cluster.close()
            runs[workers].append(seconds)
            starts[workers].append(start)
            busy[workers].append(sum(table.column("cell_s").to_pylist()) / (seconds * workers))
            print(f"{workers} worker(s): {table.num_rows} cells in {seconds:.1f} s ({table.num_rows / seconds:.3f} "
                  f"cells/s, workers busy {100 * busy[workers][-1]:.0f} % of the time)", flush=True)
    n = len(scaling_study.cells(inputs))
    rate = {w: n / statistics.median(s) for w, s in runs.items()}
    scaling = {"meshes": SCALING_MESHES, "grid": SCALING_GRID, "cells": n, "study_s": runs,
               "cluster_start_s": starts, "worker_busy_fraction": busy, "cells_per_s": rate,
               "speedup_2_over_1": rate[2] / rate[1]}
    print(f"2 workers / 1 worker: {scaling['speedup_2_over_1']:.2f}x", flush=True)
    _files.write_json(args.out, {**_files.measured_conditions(), "cpus": os.cpu_count(), "repeat": args.repeat,
                                 "overhead": overhead, "scaling": scaling}, args.force, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
