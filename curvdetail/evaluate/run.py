"""Run a study on Dask: every cell not yet in the results folder, each as one task."""

import contextlib
import logging
import os
import sys
import time

from .cell import failed_row
from .study import StudyError
from .table import compact, read_results, write_part, write_results

#: Seconds between rebuilds of results.parquet / results.csv while a study runs.
REBUILD_EVERY = 60.0


def _say(stream, text):
    """A line on ``stream``; a broken or full stream does not stop the study."""
    if stream is None:
        return
    try:
        stream.write(text + "\n")
        stream.flush()
    except (OSError, ValueError):
        pass


@contextlib.contextmanager
def _client(workers, scheduler):
    """A ``distributed.Client``: the one given, one connected to ``scheduler`` (an address), or
    one on a new LocalCluster of ``workers`` single-threaded worker processes."""
    from distributed import Client, LocalCluster

    if scheduler is not None and not isinstance(scheduler, str):
        yield scheduler
    elif scheduler is not None:
        with Client(scheduler) as client:
            yield client
    else:
        with LocalCluster(n_workers=workers or os.cpu_count(), threads_per_worker=1, processes=True,
                          dashboard_address=":0", silence_logs=logging.ERROR) as cluster, Client(cluster) as client:
            yield client


def _check_folder(results):
    """Create the results folder; StudyError where it holds other files but no study."""
    if os.path.isdir(results) and os.listdir(results) and not os.path.isdir(os.path.join(results, "parts")):
        raise StudyError(f"{results} holds other files and no study", parameter="results", value=results,
                         hint="name a new or empty folder, or the results folder of a study to continue it")
    os.makedirs(os.path.join(results, "parts"), exist_ok=True)


def run_study(study, inputs, results, *, workers=None, scheduler=None, cell_timeout=None, cell_memory=None,
              retry_failed=False, ship_meshes="auto", progress=sys.stderr):
    """Run every cell of ``study`` on the meshes ``inputs`` names that ``results`` does not hold yet.

    Each finished cell's row is written at once (``results/parts/<cell key>.parquet``);
    ``results/results.parquet`` and ``results/results.csv`` are rebuilt with the parts every
    `REBUILD_EVERY` seconds, and at the end (also after Ctrl-C) the parts are folded into them
    and removed. A failed cell is a row
    with ``status`` "failed" and its error, one stopped at ``cell_timeout`` or ``cell_memory`` a
    row with "timeout" or "memory".

    Parameters
    ----------
    study : Study
    inputs : str or list of str
        Mesh files, folders or glob patterns (`find_meshes`).
    results : str
        The results folder (created; a study's folder is continued).
    workers : int or None
        Worker processes of the LocalCluster (default: one per core); each runs one cell at a
        time with BLAS/OpenMP threads pinned to 1.
    scheduler : str, distributed.Client or None
        Use this cluster instead (``"tcp://HOST:PORT"`` of ``dask scheduler``).
    cell_timeout : float or None
        Seconds a cell may run before it is stopped.
    cell_memory : float or None
        MiB of resident memory the process of a cell may use before it is stopped (checked
        every 0.1 s).
    retry_failed : bool
        Run the table's cells that did not end "ok" again.
    ship_meshes : "auto", True or False
        True: read each mesh file here once and send its bytes to the workers (no shared path);
        False: the workers read the paths; "auto": ship where ``scheduler`` is given and one
        of its workers does not see the first mesh's path. The ``mesh_shipped`` column says which.
    progress : file or None
        Where progress lines go (cells done / failed / running, rate, time left).

    Returns
    -------
    dict
        ``cells`` (of the study), ``skipped`` (already in the table), ``ran``, ``failed``
        (of those that ran, the ones not "ok") and ``table`` (the whole table, pyarrow).

    Raises
    ------
    StudyError
        An input that names nothing, a results folder that holds other files.
    """
    if workers is not None and scheduler is not None:
        raise StudyError("workers and scheduler both given", parameter="workers",
                         hint="the scheduler's cluster has its own workers; give one of them")
    if ship_meshes not in ("auto", True, False):
        raise StudyError(f"ship_meshes {ship_meshes!r} is not auto, True or False", parameter="ship_meshes",
                         value=ship_meshes)
    for name, limit in (("cell_timeout", cell_timeout), ("cell_memory", cell_memory)):
        if limit is not None and not limit > 0:
            raise StudyError(f"{name} {limit!r} is not a positive number", parameter=name, value=limit)
    results = os.fspath(results)
    cells = study.cells(inputs)
    _check_folder(results)
    table = read_results(results)
    done = {key for key, status in zip(table.column("cell_key").to_pylist(), table.column("status").to_pylist())
            if status == "ok" or not retry_failed}
    todo = [c for c in cells if c.key not in done]
    summary = {"cells": len(cells), "skipped": len(cells) - len(todo), "ran": 0, "failed": 0}
    try:
        if todo:
            _say(progress, f"curvdetail evaluate: {len(todo)} of {len(cells)} cells to run"
                           + (f" ({summary['skipped']} already in {results})" if summary["skipped"] else ""))
            _run(todo, results, workers, scheduler, (cell_timeout, cell_memory), ship_meshes, progress, summary)
    finally:
        summary["table"] = compact(results)
    return summary


def _workers_see(client, path):
    """Whether a worker of ``client`` sees the file ``path``."""
    client.wait_for_workers(1)
    worker = next(iter(client.scheduler_info()["workers"]))
    return client.run(os.path.exists, path, workers=[worker])[worker]


def _mesh_bytes(cells):
    """The bytes of each readable mesh file of ``cells``, read once: {path: bytes}."""
    data = {}
    for path in dict.fromkeys(cell.path for cell in cells):
        try:
            with open(path, "rb") as fh:
                data[path] = fh.read()
        except OSError:         # the worker then fails to read it too, and its row says why
            pass
    return data


def _run(cells, results, workers, scheduler, limits, ship, progress, summary):
    from distributed import as_completed

    from .runner import evaluate_cell

    with _client(workers, scheduler) as client:
        if ship == "auto":
            ship = scheduler is not None and not _workers_see(client, cells[0].path)
        shipped = {}
        if ship:
            data = _mesh_bytes(cells)
            _say(progress, f"curvdetail evaluate: sending {len(data)} mesh files to the workers")
            shipped = dict(zip(data, client.scatter(list(data.values()), broadcast=False)))
        t0 = last_said = last_rebuild = time.monotonic()        # the rate from here: not the cluster's start
        futures = {client.submit(evaluate_cell, dict(cell.task(), shipped=cell.path in shipped), *limits,
                                 shipped.get(cell.path), key=f"curvdetail-cell-{cell.key}", pure=False): cell
                   for cell in cells}
        for future in as_completed(futures):
            cell = futures[future]
            try:
                row = future.result()
            except Exception as exc:            # the worker itself was lost (KilledWorker), or the like
                row = failed_row(cell.task(), exc)
            write_part(results, row)
            future.release()
            summary["ran"] += 1
            if row["status"] != "ok":
                summary["failed"] += 1
                _say(progress, f"  {row['status']}: {cell.name} {' '.join(str(v) for _, v in cell.config if v)}: "
                               f"{row['error_class']}: {row['error_message']}")
            now = time.monotonic()
            if now - last_said >= 5.0 or summary["ran"] == len(cells):
                last_said = now
                rate = summary["ran"] / max(now - t0, 1e-9)
                left = len(cells) - summary["ran"]
                threads = client.nthreads()         # a worker's queue is not running
                running = sum(min(len(v), threads.get(w, 1)) for w, v in client.processing().items()) if left else 0
                _say(progress, f"cells: {summary['ran']}/{len(cells)} done, {summary['failed']} failed, "
                               f"{running} running; {rate:.2f} cells/s, about {left / rate:.0f} s left")
            if now - last_rebuild >= REBUILD_EVERY:
                last_rebuild = now
                write_results(results, read_results(results))

