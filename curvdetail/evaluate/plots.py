"""Pictures of a study's table (matplotlib, headless), each saved atomically as a PNG.

Each takes the table's rows as dicts (``table.to_pylist()``) and uses the finished cells
(``status == "ok"``) only; figures in % of the source's bounding-box diagonal.
"""

import numpy as np

from ..io.atomic import atomic_write


def label(row, target=False):
    """A configuration's short name: ``isotropic conservative free closest`` (+ target edge)."""
    parts = [row["method"], row["transfer"], row["rows"], row["location"]]
    if row.get("parameterization"):
        parts[-1] += f" ({row['parameterization']})"
    return " ".join(parts + ([row["target_edge"]] if target else []))


def _plain_log_axes(ax):
    """Log axes with tick labels as plain numbers (0.5, 2, 10)."""
    from matplotlib.ticker import LogFormatter

    ax.set(xscale="log", yscale="log")
    for axis in (ax.xaxis, ax.yaxis):       # minor ticks labelled where the axis spans under 2 decades
        axis.set_major_formatter(LogFormatter())
        axis.set_minor_formatter(LogFormatter(labelOnlyBase=False, minor_thresholds=(2, 0.5)))


def _save(fig, path, overwrite, dpi=100):
    with atomic_write(path, overwrite=overwrite) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")


def _ok(rows, *columns):
    return [r for r in rows if r["status"] == "ok" and all(r.get(c) is not None for c in columns)]


def plot_rms_against_target(rows, path, *, overwrite=False):
    """Median RMS over the meshes against the target edge, one line per configuration, with
    the floor (dashed) and zero-detail (dotted) medians of each method; log axes."""
    from matplotlib.figure import Figure

    rows = _ok(rows, "target_edge_percent_of_diagonal", "error_rms_percent_of_diagonal")
    fig = Figure(figsize=(7.5, 5.0), layout="constrained")
    ax = fig.subplots()
    series = {}
    for r in rows:
        for name, column, style in ((label(r), "error_rms_percent_of_diagonal", "o-"),
                                    (f"{r['method']}: floor", "floor_rms_percent_of_diagonal", "s--"),
                                    (f"{r['method']}: zero detail", "zero_detail_rms_percent_of_diagonal", "^:")):
            series.setdefault((name, style), {}).setdefault(r["target_edge_percent_of_diagonal"], []).append(r[column])
    for (name, style), points in sorted(series.items()):
        x = sorted(points)
        ax.plot(x, [np.median(points[v]) for v in x], style, label=name, markersize=4)
    _plain_log_axes(ax)
    ax.set(xlabel="target edge, % of the bbox diagonal",
           ylabel="RMS to the source, % of bbox diagonal\n(median over the meshes)")
    if series:
        ax.legend(fontsize=7)
    _save(fig, path, overwrite)


def plot_ratio_to_floor(rows, path, *, overwrite=False):
    """RMS / floor per mesh (rows) and configuration (columns), coloured on a log scale."""
    from matplotlib.colors import LogNorm
    from matplotlib.figure import Figure

    rows = _ok(rows, "rms_to_floor_ratio")
    meshes = sorted({r["mesh_name"] for r in rows})
    configs = sorted({label(r, target=True) for r in rows})
    M = np.full((len(meshes), len(configs)), np.nan)
    for r in rows:
        M[meshes.index(r["mesh_name"]), configs.index(label(r, target=True))] = r["rms_to_floor_ratio"]
    fig = Figure(figsize=(min(3.0 + 0.45 * len(configs), 30.0), min(3.5 + 0.3 * len(meshes), 30.0)),
                 layout="constrained")
    ax = fig.subplots()
    if rows:
        image = ax.imshow(M, aspect="auto", cmap="viridis", norm=LogNorm(vmin=max(np.nanmin(M), 1e-3)))
        fig.colorbar(image, ax=ax, label="RMS / floor RMS")
        if M.size <= 400:
            for (i, j), value in np.ndenumerate(M):
                ax.text(j, i, f"{value:.3g}", ha="center", va="center", fontsize=7, color="w")
    if len(configs) <= 60:          # more names than fit are left out
        ax.set_xticks(range(len(configs)), configs, rotation=60, ha="right", fontsize=7)
    if len(meshes) <= 90:
        ax.set_yticks(range(len(meshes)), meshes, fontsize=7)
    ax.set_title("rebuilt RMS over the retriangulated floor", fontsize=9)
    _save(fig, path, overwrite)


def plot_time_against_vertices(rows, path, *, overwrite=False):
    """Seconds per cell against the source's vertex count, one colour per method; log axes."""
    from matplotlib.figure import Figure

    rows = _ok(rows, "mesh_vertices", "cell_s")
    fig = Figure(figsize=(6.5, 4.5), layout="constrained")
    ax = fig.subplots()
    for method in sorted({r["method"] for r in rows}):
        chosen = [r for r in rows if r["method"] == method]
        ax.plot([r["mesh_vertices"] for r in chosen], [r["cell_s"] for r in chosen], "o", label=method, alpha=0.7)
    _plain_log_axes(ax)
    ax.set(xlabel="source vertices", ylabel="seconds per cell")
    if rows:
        ax.legend(fontsize=8)
    _save(fig, path, overwrite)
