"""A study's summary: a Markdown table and three plots, from its results table."""

import os

import numpy as np

from ..io.atomic import atomic_write, check_output_path
from .plots import label, plot_ratio_to_floor, plot_rms_against_target, plot_time_against_vertices

#: The files `write_summary` writes into its folder.
FILES = ("summary.md", "rms_against_target.png", "ratio_to_floor.png", "time_against_vertices.png")


def _stats(values, spec=".3g"):
    values = [v for v in values if v is not None]
    if not values:
        return "-"
    return f"{np.median(values):{spec}} / {max(values):{spec}}"


def _table(groups, first):
    lines = [f"| {first} | cells ok / all | RMS median / max (%) | RMS/floor median / max | zero-detail RMS "
             "median / max (%) | floor RMS median / max (%) | seconds median / max |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    for name, rows in sorted(groups.items()):
        ok = [r for r in rows if r["status"] == "ok"]
        col = {c: [r[c] for r in ok] for c in ("error_rms_percent_of_diagonal", "rms_to_floor_ratio", "cell_s",
                                               "zero_detail_rms_percent_of_diagonal", "floor_rms_percent_of_diagonal")}
        lines.append(f"| {name} | {len(ok)} / {len(rows)} | {_stats(col['error_rms_percent_of_diagonal'])} | "
                     f"{_stats(col['rms_to_floor_ratio'])} | {_stats(col['zero_detail_rms_percent_of_diagonal'])} | "
                     f"{_stats(col['floor_rms_percent_of_diagonal'])} | {_stats(col['cell_s'], spec='.2f')} |")
    return "\n".join(lines)


def summary_markdown(rows):
    """The Markdown summary of a study's rows (dicts): counts, the figures per configuration
    (over the meshes) and per mesh (over the configurations), and the cells that failed."""
    status = {s: sum(r["status"] == s for r in rows) for s in ("ok", "failed", "timeout", "memory")}
    by_config, by_mesh = {}, {}
    for r in rows:
        by_config.setdefault(label(r, target=True), []).append(r)
        by_mesh.setdefault(r["mesh_name"], []).append(r)
    counts = (f"{len(rows)} cells: {status['ok']} ok, {status['failed']} failed, {status['timeout']} timed out, "
              f"{status['memory']} over the memory limit")
    text = [f"# Study summary\n\n{counts}. Distances in % of the source's bbox diagonal; RMS/floor is the rebuilt "
            "RMS over the retriangulated surface's own.\n",
            "## Per configuration (method transfer rows location target edge), over the meshes\n",
            _table(by_config, "configuration"), "\n## Per mesh, over the configurations\n", _table(by_mesh, "mesh")]
    failed = [r for r in rows if r["status"] != "ok"]
    if failed:
        text += ["\n## Cells that did not finish\n", "| mesh | configuration | status | error |", "|---|---|---|---|"]
        text += [f"| {r['mesh_name']} | {label(r, target=True)} | {r['status']} | {r['error_class']}: "
                 f"{' '.join(str(r['error_message']).split())[:160]} |" for r in failed]
    return "\n".join(text) + "\n"


def write_summary(table, folder, *, overwrite=False):
    """Write ``summary.md`` (`summary_markdown`) and the plots (RMS against target edge per
    configuration, RMS/floor per mesh and configuration, seconds against vertex count) into
    ``folder`` (created), each atomically.

    Parameters
    ----------
    table : pyarrow.Table
        A study's table (`read_results`).
    folder : str
    overwrite : bool
        Replace the files of an earlier summary.

    Returns
    -------
    list of str
        The paths written (`FILES`).

    Raises
    ------
    FileExistsError
        A file of `FILES` exists and ``overwrite`` is False (before any is written).
    """
    os.makedirs(folder, exist_ok=True)
    paths = [check_output_path(os.path.join(folder, name), overwrite) for name in FILES]
    rows = table.to_pylist()
    with atomic_write(paths[0], overwrite=overwrite) as tmp, open(tmp, "w", encoding="utf-8") as fh:
        fh.write(summary_markdown(rows))
    for path, plot in zip(paths[1:], (plot_rms_against_target, plot_ratio_to_floor, plot_time_against_vertices)):
        plot(rows, path, overwrite=overwrite)
    return paths
