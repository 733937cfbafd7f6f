"""Reproduce the paper's Fig. 3 remeshing experiment on the public disk patches and measure it.

For every patch (mannequin_nose, mannequin_ear, elephant_trunk: the paper's Fig. 3 patches;
terrainA_10k, camelhead, mannequin_disk_1k) the source is retriangulated once (isotropic, 1 % of
the bbox diagonal: 5.4k-10.6k target vertices, from 640-11,381 source vertices) and every transfer
configuration is run on that same target: transfer {conservative, pointwise} x rows {free, all}
x location {closest, uv}. The default configuration is also run with decimation, and on
terrainA_100k for the timing at 100k.

Usage: python scripts/reproduce_fig3.py [--out out/fig3] [--docs docs/results]
                                        [--meshes DIR] [--quick] [--force]
(DIR defaults to $CURVDETAIL_MESHES, else ../shared/meshes beside the repository; --out to
out/fig3 in the repository.) Writes
  OUT/results.json      every report, each with the retriangulation that made its target, the
                        configurations that failed (with their error) and the peak memory
  OUT/fig3_table.md     the markdown tables and the run's speed paragraph
  OUT/fig3.png          the Fig. 3 patches, default configuration
and with --docs DIR also DIR/fig3_table.md and DIR/fig3.png. With --quick (a subset) only
OUT/results.json and OUT/table_quick.md (--docs is refused: the committed files hold a full
run). Each file is written atomically at the end; one that exists is refused before
any work unless --force is given; a mesh missing from DIR stops the script before
any work. The files in docs/results are in the repository: refreshing them is
``--docs docs/results --force``.

Exit status 0 when every configuration ran; 1 when one failed (everything is still written,
the failure recorded in the JSON's ``failures`` and as a FAILED line in the tables); 2 for a
refused output (a usage error).
"""

import argparse
import inspect
import os
import sys
import time


sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _files  # noqa: E402
from _meshes import MESHES  # noqa: E402

from curvdetail import read_mesh
from curvdetail.curvature.geometry import bbox_diagonal
from curvdetail.remesh import retriangulate
from curvdetail.remesh.experiment import run_experiment

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PATCHES = ["mannequin_nose.obj", "mannequin_ear.obj", "elephant_trunk.obj", "terrainA_10k.obj",
           "camelhead.off", "mannequin_disk_1k.obj"]
FIGURE_PATCHES = ("mannequin_nose.obj", "mannequin_ear.obj", "elephant_trunk.obj")
PARAMETERIZATION_PATCHES = ("mannequin_nose.obj", "elephant_trunk.obj", "camelhead.off")
PARAMETERIZATIONS = ("harmonic", "meshlab_harmonic", "lscm")
CONFIGS = [  # (transfer, rows, location)
    ("conservative", "free", "closest"),
    ("conservative", "all", "closest"),
    ("conservative", "free", "uv"),
    ("pointwise", "free", "closest"),
    ("pointwise", "all", "closest"),
    ("pointwise", "all", "uv"),
]
#: the retriangulation every transfer configuration of a patch shares, as passed to retriangulate
SHARED_RETRIANGULATION = {"method": "isotropic", "target_edge": "1%", "iterations": 10,
                          "max_surface_distance": None, "surface_check": True}
#: retriangulate's defaults, which run_experiment's own retriangulations take
RETRIANGULATE_DEFAULTS = {name: p.default for name, p in inspect.signature(retriangulate).parameters.items()
                          if p.default is not inspect.Parameter.empty}
#: the default configuration run with decimation and on the 100k-vertex source:
#: (method, mesh, target edge as a fraction of the bbox diagonal)
EXTRA_RUNS = [("decimate", "mannequin_ear.obj", 0.03), ("decimate", "camelhead.off", 0.01),
              ("decimate", "terrainA_10k.obj", 0.01)]
EXTRA_RUNS_FULL = [("isotropic", "terrainA_100k.ply", 0.01), ("decimate", "terrainA_100k.ply", 0.01)]


def pct(x, digits=3):
    """A report's figure (already in % of the diagonal) as text."""
    return f"{x:.{digits}f}"


def _ratio(value, spec, suffix=""):
    """A report ratio as table text; "n/a" where the report gives None (an RMS at rounding)."""
    return "n/a" if value is None else f"{value:{spec}}{suffix}"


def _total(rep, t_retri=None):
    """End-to-end seconds of a report, with a retriangulation made outside the experiment."""
    return rep["seconds"]["total"] + (t_retri or 0.0)


def row(name, rep, t_retri=None, method=None):
    """One table line; ``t_retri`` = the time of a retriangulation made outside the experiment
    (shared by several configurations), added to its stage times; ``method`` = how that
    retriangulation was made (the report says "given")."""
    e, b, f, s, o = (rep["error"], rep["baseline_zero_detail"], rep["floor_retriangulated"], rep["seconds"],
                     rep["options"])
    improvement = rep["improvement_over_zero_detail"]          # None where an RMS is rounding
    ok = e["hausdorff_rms_percent_of_diagonal"] <= 0.1 and e["hausdorff_max_percent_of_diagonal"] <= 1 and (improvement is None or improvement >= 50)
    loc = o["location"] + (f" ({o['parameterization']})" if o["location"] == "uv" else "")
    total = _total(rep, t_retri)
    t_retri = s["retriangulate"] if t_retri is None else t_retri
    return (f"| {name} | {rep['source']['vertices']:,} | {rep['target']['vertices']:,} | {method or o['method']} | "
            f"{o['transfer']} | {o['rows']} | {loc} | **{pct(e['hausdorff_rms_percent_of_diagonal'], 4)}** / {pct(e['hausdorff_max_percent_of_diagonal'])} | "
            f"{pct(b['hausdorff_rms_percent_of_diagonal'], 2)} / {pct(b['hausdorff_max_percent_of_diagonal'], 1)} | "
            f"{pct(f['hausdorff_rms_percent_of_diagonal'], 4)} / {pct(f['hausdorff_max_percent_of_diagonal'])} | {_ratio(improvement, ',.0f', 'x')} | "
            f"{_ratio(rep['ratio_to_floor'], '.2f')} | {'yes' if ok else 'NO'} | "
            f"{t_retri:.2f} / {s['parameterize']:.2f} / {s['transfer']:.2f} / {s['reconstruct']:.2f} / "
            f"{s['evaluate']:.2f} / {total:.2f} |")


HEADER = ("| patch | source V | target V | retriangulation | transfer | rows | location | "
          "RMS / max (%) | zero-detail RMS / max (%) | floor RMS / max (%) | better than zero | RMS / floor | "
          "targets met | seconds: retriangulate / parameterize / transfer / reconstruct / evaluate / total |\n"
          "|---|---:|---:|---|---|---|---|---:|---:|---:|---:|---:|---|---|")
def retriangulation_record(method, target_edge, diagonal, seconds, shared, **settings):
    """What made a report's target, for the JSON: ``method``, ``target_edge_percent_of_diagonal``
    and ``target_edge_model_units`` (``target_edge`` as the functions take it), the other settings of
    :func:`retriangulate` (``settings`` as passed, the rest its defaults), ``seconds``, and
    ``shared``: True where the script made it once for all the patch's configurations (the
    report's ``options.method`` then says "given"), False where ``run_experiment`` made it."""
    relevant = ("iterations", "max_surface_distance", "surface_check") if method == "isotropic" else ("aggressiveness",)
    from curvdetail.remesh.units import as_bbox_length, length_figures

    record = {"method": method, **length_figures(as_bbox_length(target_edge), diagonal, "target_edge")}
    record.update({name: settings.get(name, RETRIANGULATE_DEFAULTS[name]) for name in relevant})
    record.update(seconds=None if seconds is None else round(seconds, 4), shared=shared)
    return record


def _missing_meshes(folder, names):
    """The files of ``names`` that ``folder`` does not hold."""
    return [name for name in names if not os.path.isfile(os.path.join(folder, name))]


def speed_paragraph(timings, started, conditions):
    """The run's speed, from the reports of the tables: ``timings`` maps a key
    ("terrainA_10k", "camelhead", "terrainA_100k", "terrainA_100k decimate") to ``(report,
    shared retriangulation seconds or None)``; keys that did not run are left out.
    ``conditions``: scripts/_files.measured_conditions() at the end of the run."""
    def total(key):
        return _total(*timings[key])

    def stage(key, name):
        rep, t_retri = timings[key]
        return t_retri if name == "retriangulate" and t_retri is not None else rep["seconds"][name]

    parts, small = [], []
    for key in ("terrainA_10k", "camelhead"):
        if key in timings:
            detail = key if key != "camelhead" else (
                f"{key}, of which the isotropic remeshing {stage(key, 'retriangulate'):.1f} s and the "
                f"evaluation {stage(key, 'evaluate'):.1f} s")
            small.append(f"{total(key):.1f} s ({detail})")
    if small:
        parts.append("10k-vertex sources end to end " + " and ".join(small))
    key = "terrainA_100k"
    if key in timings:
        parts.append(f"the 100k-vertex {key} {total(key):.1f} s (remeshing {stage(key, 'retriangulate'):.1f}, "
                     f"transfer {stage(key, 'transfer'):.1f}, reconstruct {stage(key, 'reconstruct'):.2f}, "
                     f"evaluate {stage(key, 'evaluate'):.1f})")
    key = "terrainA_100k decimate"
    if key in timings:
        parts.append(f"decimated {total(key):.1f} s (decimation {stage(key, 'retriangulate'):.1f}, "
                     f"evaluate {stage(key, 'evaluate'):.1f})")
    return (f"**Speed** (this run, {started} UTC, {os.cpu_count()} cores shared with other work, load "
            f"average {conditions['load_average'][0]:.1f} at its end; the default configuration, the "
            "seconds of the tables above): " + "; ".join(parts) +
            f". Peak memory of the whole run (one process): {conditions['peak_rss_gb']:.2f} GB.\n")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "fig3"),
                    help="folder for results.json, the tables and the picture (default: out/fig3 in the repository)")
    ap.add_argument("--docs", default=None,
                    help="also refresh DOCS/fig3_table.md and DOCS/fig3.png (the repository's: docs/results)")
    ap.add_argument("--meshes", default=MESHES,
                    help="folder of the public meshes (default: $CURVDETAIL_MESHES, else ../shared/meshes)")
    ap.add_argument("--quick", action="store_true",
                    help="default configuration only, no 100k run; writes OUT/results.json and "
                         "OUT/table_quick.md only")
    ap.add_argument("--force", action="store_true", help="replace output files that exist")
    args = ap.parse_args(argv)
    meshes = args.meshes
    if args.quick and args.docs:
        ap.error("--docs refreshes the committed table and picture, which hold a full run; "
                 "leave out --quick (or --docs).")
    results_json = os.path.join(args.out, "results.json")
    figure = docs_figure = docs_table = None
    if args.quick:
        table_file = os.path.join(args.out, "table_quick.md")
    else:
        table_file, figure = os.path.join(args.out, "fig3_table.md"), os.path.join(args.out, "fig3.png")
        if args.docs is not None:
            docs_table, docs_figure = os.path.join(args.docs, "fig3_table.md"), os.path.join(args.docs, "fig3.png")
    _files.check_outputs(ap, [results_json, table_file, figure, docs_table, docs_figure], args.force)
    if not os.path.isdir(meshes):
        ap.error(f"mesh folder {meshes!r} does not exist; pass --meshes DIR or set CURVDETAIL_MESHES")
    extra_runs = EXTRA_RUNS + ([] if args.quick else EXTRA_RUNS_FULL)
    needed = dict.fromkeys(PATCHES + [name for _, name, _ in extra_runs])
    missing = _missing_meshes(meshes, needed)
    if missing:     # before any work (as _meshes.require, with --meshes as the fix)
        sys.exit(f"{os.path.basename(sys.argv[0])}: {meshes!r} does not hold {', '.join(missing)}; pass "
                 "--meshes DIR (or set CURVDETAIL_MESHES) naming the folder of the public meshes "
                 "(../shared/meshes beside the repository).")

    started = time.strftime("%Y-%m-%d %H:%M", time.gmtime())
    results, failures, lines_main, lines_all = [], [], [], []
    figure_inputs, timings = {}, {}

    def record(rep, retriangulation):
        peak = _files.measured_conditions()["peak_rss_gb"]       # the process's, so far
        entry = dict(rep, retriangulation=retriangulation, peak_rss_gb_so_far=round(peak, 3))
        if retriangulation["shared"]:
            entry["seconds_retriangulate_shared"] = retriangulation["seconds"]
        results.append(entry)

    def failed(name, configuration, exc, retriangulation):
        print(f"{name} {' '.join(map(str, configuration.values()))}: FAILED {exc}", file=sys.stderr)
        failures.append({"source": name, "configuration": configuration,
                         "error": f"{type(exc).__name__}: {exc}", "retriangulation": retriangulation})

    configs = CONFIGS[:1] if args.quick else CONFIGS
    for name in PATCHES:
        V, F = read_mesh(os.path.join(meshes, name))
        t = time.perf_counter()
        Vt, Ft = retriangulate(V, F, **SHARED_RETRIANGULATION)
        t_retri = time.perf_counter() - t
        retri = retriangulation_record(diagonal=bbox_diagonal(V), seconds=t_retri, shared=True,
                                       **SHARED_RETRIANGULATION)
        for transfer, rows, location in configs:
            try:
                out = run_experiment(V, F, transfer=transfer, rows=rows, location=location, target=(Vt, Ft),
                                     source_path=name)
            except Exception as exc:  # a failure is a result too: record it
                failed(name, dict(transfer=transfer, rows=rows, location=location), exc, retri)
                lines_all.append(f"| {name} | {V.shape[0]:,} | {Vt.shape[0]:,} | isotropic | {transfer} | {rows} | "
                                 f"{location} | FAILED: {exc} |")
                continue
            rep = out["report"]
            record(rep, retri)
            short = name.rsplit(".", 1)[0]
            line = row(short, rep, t_retri, method="isotropic")
            lines_all.append(line)
            if (transfer, rows, location) == CONFIGS[0]:
                lines_main.append(line)
                timings[short] = (rep, t_retri)
                if name in FIGURE_PATCHES:
                    figure_inputs[name] = (V, F, out)
            print(line, flush=True)
    params = []
    if not args.quick:
        for name in PARAMETERIZATION_PATCHES:
            V, F = read_mesh(os.path.join(meshes, name))
            t = time.perf_counter()     # made again, as above (the same target)
            Vt, Ft = retriangulate(V, F, **SHARED_RETRIANGULATION)
            t_retri = time.perf_counter() - t
            retri = retriangulation_record(diagonal=bbox_diagonal(V), seconds=t_retri, shared=True,
                                           **SHARED_RETRIANGULATION)
            for param in PARAMETERIZATIONS:
                try:
                    out = run_experiment(V, F, location="uv", parameterization=param, target=(Vt, Ft),
                                         source_path=name)
                except Exception as exc:
                    failed(name, dict(transfer="conservative", rows="free", location="uv", parameterization=param),
                           exc, retri)
                    params.append(f"| {name} | {V.shape[0]:,} | {Vt.shape[0]:,} | isotropic | conservative | free | "
                                  f"uv ({param}) | FAILED: {exc} |")
                    continue
                rep = out["report"]
                record(rep, retri)
                line = row(name.rsplit(".", 1)[0], rep, t_retri, method="isotropic")
                pi = rep["parameterization"]
                params.append(line + f" {pi['flipped_source']} / {pi['flipped_target']} |")
                print(params[-1], flush=True)
    extra = []
    for method, name, target_edge in extra_runs:
        V, F = read_mesh(os.path.join(meshes, name))
        try:
            out = run_experiment(V, F, method=method, target_edge=f"{100 * target_edge!r}%", source_path=name)
        except Exception as exc:
            failed(name, dict(method=method, target_edge=target_edge), exc,
                   retriangulation_record(method, f"{100 * target_edge!r}%", bbox_diagonal(V), None, False))
            extra.append(f"| {name} | {V.shape[0]:,} | - | {method} | FAILED: {exc} |")
            continue
        rep = out["report"]
        record(rep, retriangulation_record(method, f"{100 * target_edge!r}%", rep["source"]["bbox_diagonal"],
                                                 rep["seconds"]["retriangulate"], False))
        short = name.rsplit(".", 1)[0]
        line = row(short + (f" ({100 * target_edge:g} %)" if target_edge != 0.01 else ""), rep)
        extra.append(line)
        if name == "terrainA_100k.ply":
            timings[short + (" decimate" if method == "decimate" else "")] = (rep, None)
        print(line, flush=True)

    conditions = _files.measured_conditions()     # utc (the end), load_average, peak_rss_gb
    _files.write_json(results_json, {
        "started_utc": started, **conditions, "cpus": os.cpu_count(), "status": "failed" if failures else "ok",
        "notes": ("reports: every configuration that ran, each with the retriangulation that made its "
                  "target (shared: made once by the script for all the patch's configurations, given "
                  "to run_experiment, whose options then say method 'given') and the process's peak "
                  "memory after it (peak_rss_gb_so_far; one process runs everything); failures: the "
                  "configurations that raised, with the error"),
        "reports": results, "failures": failures}, args.force, indent=1)
    table = ("### Default configuration (isotropic 1 %, conservative transfer, free rows, closest-point location)\n\n"
             f"{HEADER}\n" + "\n".join(lines_main) +
             # --quick runs the default configuration only, and no 100k-vertex source: its headings say so
             ("" if args.quick else
              "\n\n### Every transfer configuration on the same targets\n\n" + f"{HEADER}\n" + "\n".join(lines_all)) +
             ("\n\n### Decimation (default transfer)\n\n" if args.quick else
              "\n\n### Decimation, and a 100k-vertex source (default transfer)\n\n") + f"{HEADER}\n" + "\n".join(extra) +
             "\n")
    if params:
        table += ("\n### Planar domains for the location (conservative transfer, free rows; the same "
                  "retriangulation, made again)\n\n"
                  + HEADER.replace(" |\n|", " | flipped source / target |\n|", 1) + "---|\n"
                  + "\n".join(params) + "\n")
    table += "\n" + speed_paragraph(timings, started, conditions)
    _files.write_text(table_file, table, args.force)
    if docs_table is not None:
        _files.write_text(docs_table, table, args.force)
    if figure is not None and figure_inputs:
        _figure(figure_inputs, figure, args.force)
        if docs_figure is not None:
            with open(figure, "rb") as fh:
                _files.write_bytes(docs_figure, fh.read(), args.force)
    print(table)
    if failures:
        print(f"{len(failures)} configuration(s) failed: "
              + "; ".join(f"{f['source']} {f['error']}" for f in failures), file=sys.stderr)
        return 1
    return 0


#: the rebuilt panels' colours, distance 0 to the row's largest: the plain panels' light
#: blue-grey, then amber, then red (shaded like the plain panels, so the shape reads as well)
DISTANCE_COLOURS = [(0.75, 0.78, 0.85), (0.98, 0.78, 0.30), (0.78, 0.08, 0.06)]


def _figure(inputs, path, force=False):
    """The Fig. 3 picture: one row per patch (source, rebuilt target coloured by each vertex's
    distance to the source with a colour bar in % of the bbox diagonal, zero-detail baseline),
    drawn by curvdetail.plot as the remeshing figure is. ``inputs``: ``{name: (V, F,
    run_experiment's dict)}``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LinearSegmentedColormap

    from curvdetail.plot import draw_mesh, top_view

    cmap = LinearSegmentedColormap.from_list("distance", DISTANCE_COLOURS)
    view = dict(elev=50.0, azim=20.0)
    fig, rows = plt.subplots(len(inputs), 3, figsize=(10.5, 3.4 * len(inputs)), squeeze=False)
    for axes, (name, (V, F, out)) in zip(rows, inputs.items()):
        rep = out["report"]
        R = top_view(V, F)
        e, b = rep["error"], rep["baseline_zero_detail"]
        draw_mesh(axes[0], V @ R.T, F, title=f"{name.rsplit('.', 1)[0]}: {V.shape[0]:,} vertices", **view)
        draw_mesh(axes[2], out["Z"] @ R.T, out["Ft"], **view,
                  title=f"zero detail\nRMS {pct(b['hausdorff_rms_percent_of_diagonal'], 2)} %, max {pct(b['hausdorff_max_percent_of_diagonal'], 1)} %")
        scale = draw_mesh(axes[1], out["X"] @ R.T, out["Ft"], 100 * out["distance"] / bbox_diagonal(V), cmap=cmap,
                          title=f"rebuilt, {rep['target']['vertices']:,} vertices\nRMS {pct(e['hausdorff_rms_percent_of_diagonal'])} %, "
                                f"max {pct(e['hausdorff_max_percent_of_diagonal'], 2)} %", **view)
        # in the panel's own lower margin, so that the rebuilt surface is drawn as large as the others
        bar = fig.colorbar(scale, cax=axes[1].inset_axes([0.15, -0.08, 0.7, 0.035]), orientation="horizontal")
        bar.set_label("distance to the source, % of the bbox diagonal", fontsize=8)
        bar.ax.tick_params(labelsize=7)
    fig.subplots_adjust(hspace=0.25)
    fig.suptitle("Fig. 3 patches rebuilt from transferred curvature detail (default configuration; all "
                 "figures % of the source's bbox diagonal)", fontsize=10)
    try:
        _files.save_figure(fig, path, force, dpi=80, bbox_inches="tight")
    finally:
        plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
