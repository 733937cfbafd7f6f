"""One cell of a study: read the mesh, run `remesh_experiment`, and
make the table row (`COLUMNS`) of its figures or its error."""

import os
import resource
import sys
import time
import warnings
from datetime import datetime, timezone

from ..curvature.geometry import bbox_diagonal
from ..curvature.topology import boundary_edges
from ..io.mesh import read_mesh
from ..remesh.experiment import MAX, RMS, remesh_experiment
from .study import CONFIG_KEYS, experiment_target_edge

_STAGES = ("retriangulate", "parameterize", "transfer", "reconstruct", "evaluate")


def base_row(task):
    """The row's mesh identity and configuration, from a cell's task dict (`Cell.task`)."""
    return {"cell_key": task["key"], "mesh_name": task["name"], "mesh_path": task["path"],
            "mesh_blake2b": task["blake2b"], "mesh_shipped": task.get("shipped", False), **{k: task[k] for k in CONFIG_KEYS}}


def failed_row(task, exc=None, *, status="failed", error_class=None, message=None):
    """The row of a cell that did not finish: ``exc``'s class and message, or those given."""
    return dict(base_row(task), status=status, error_class=error_class or type(exc).__name__,
                error_message=message if message is not None else str(exc), finished_utc=_now())


def _now():
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


def _reset_peak_memory():
    """Start a new peak of resident memory for this process (Linux; elsewhere a no-op)."""
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
    except OSError:
        pass


def _peak_memory_mib():
    """Peak resident memory since `_reset_peak_memory` (Linux), else of the process's life."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / 2.0 ** (20 if sys.platform == "darwin" else 10)


def report_columns(report):
    """The table's columns from a ``remesh_experiment`` report."""
    o, s = report["options"], report["seconds"]
    row = {"mesh_bbox_diagonal_model_units": report["source"]["bbox_diagonal"],
           "target_edge_percent_of_diagonal": o.get("target_edge_percent_of_diagonal"),
           "target_edge_model_units": o.get("target_edge_model_units"),
           "target_vertices": report["target"]["vertices"], "target_faces": report["target"]["faces"],
           "target_boundary_loops": report["target"].get("boundary_loops"), "anchors": report.get("anchors"),
           "laplacian": report.get("laplacian"),
           "backend": o.get("backend"), "experiment_s": s["total"],
           **{f"{stage}_s": s[stage] for stage in _STAGES}}
    if "error" in report:
        for key, name in (("error", "error"), ("baseline_zero_detail", "zero_detail"),
                          ("floor_retriangulated", "floor")):
            figures = report[key] or {}         # no zero-detail surface where the target has a closed piece
            row[f"{name}_rms_percent_of_diagonal"] = figures.get(RMS)
            row[f"{name}_max_percent_of_diagonal"] = figures.get(MAX)
        row.update(error_vertex_max_percent_of_diagonal=report["error"]["vertex_max_percent_of_diagonal"],
                   error_engine=report["error"]["engine"],
                   improvement_over_zero_detail_ratio=report["improvement_over_zero_detail"],
                   rms_to_floor_ratio=report["ratio_to_floor"])
    row.update({k: report.get("parameterization", {}).get(k) for k in ("flipped_source", "flipped_target")})
    return row


def run_cell(task):
    """Run one cell in this process; its row (a dict). Never raises for the cell's own failure:
    an unreadable mesh or a refused configuration is a row with ``status="failed"``.

    Parameters
    ----------
    task : dict
        `task`: ``path``, ``name``, ``blake2b``, ``key``, ``shipped``, optional ``read_path`` (the
        file to read where not ``path``) and the configuration (``method``, ``target_edge`` as ``"1%"``, ...).
    """
    t0 = time.perf_counter()
    _reset_peak_memory()
    row = base_row(task)
    try:
        V, F = read_mesh(task.get("read_path", task["path"]))     # a shipped file's copy on this worker
        row.update(mesh_vertices=int(V.shape[0]), mesh_faces=int(F.shape[0]),
                   mesh_closed=bool(boundary_edges(F).shape[0] == 0),
                   mesh_bbox_diagonal_model_units=float(bbox_diagonal(V)), read_s=time.perf_counter() - t0)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            _, report = remesh_experiment(
                V, F, method=task["method"], target_edge=experiment_target_edge(task["target_edge"]),
                transfer=task["transfer"], rows=task["rows"], location=task["location"],
                parameterization=task["parameterization"], source_path=task["path"])
        row.update(report_columns(report), status="ok",
                   warnings=" | ".join(f"{w.category.__name__}: {w.message}" for w in caught) or None)
    except Exception as exc:        # a failed cell is a result: its row says why
        row.update(status="failed", error_class=type(exc).__name__, error_message=str(exc))
    row.update(cell_s=time.perf_counter() - t0, peak_rss_mib=_peak_memory_mib(), pid=os.getpid(),
               finished_utc=_now())
    return row
