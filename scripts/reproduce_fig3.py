"""Reproduce the paper's Fig. 3 remeshing experiment on the public disk patches and measure it.

For every patch (mannequin_nose, mannequin_ear, elephant_trunk: the paper's Fig. 3 patches;
terrainA_10k, camelhead, mannequin_disk_1k) the source is retriangulated once (isotropic, 1 % of
the bbox diagonal) and every transfer configuration is run on that same target:
transfer {conservative, pointwise} x rows {free, all} x location {closest, uv}. The default
configuration is also run with decimation, and on terrainA_100k for the timing at 100k.

Writes (paths relative to the repository):
  out/fig3/results.json           every report
  docs/fig3_table.md              the markdown tables (also copied into docs/remeshing.md,
                                  between its <!-- fig3-table --> markers)
  docs/fig3.png                   the Fig. 3 patches, default configuration
With --quick (a subset) the tables go to out/fig3/table_quick.md and docs/ is left alone.
The files are written all together at the end (scripts/_outputs.py: none is written where one
fails); one that exists is refused before any work unless --force is given. The files in docs/
are in the repository, so a full run (which refreshes them) takes --force.

Usage: python scripts/reproduce_fig3.py [--meshes DIR] [--quick] [--force]
(DIR defaults to $CURVDETAIL_MESHES, else ../shared/meshes beside the repository.)
"""

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _outputs  # noqa: E402

from curvdetail import read_mesh
from curvdetail.remesh import retriangulate
from curvdetail.remesh.experiment import run_experiment

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
#: where docs/remeshing.md holds its copy of the tables
TABLE_BEGIN, TABLE_END = "<!-- fig3-table -->\n", "<!-- /fig3-table -->"
PATCHES = ["mannequin_nose.obj", "mannequin_ear.obj", "elephant_trunk.obj", "terrainA_10k.obj",
           "camelhead.off", "mannequin_disk_1k.obj"]
CONFIGS = [  # (transfer, rows, location)
    ("conservative", "free", "closest"),
    ("conservative", "all", "closest"),
    ("conservative", "free", "uv"),
    ("pointwise", "free", "closest"),
    ("pointwise", "all", "closest"),
    ("pointwise", "all", "uv"),
]


def pct(x, digits=3):
    return f"{100 * x:.{digits}f}"


def _ratio(value, spec, suffix=""):
    """A report ratio as table text; "n/a" where the report gives None (an RMS at rounding)."""
    return "n/a" if value is None else f"{value:{spec}}{suffix}"


def row(name, rep, t_retri=None, method=None):
    """One table line; ``t_retri`` = the time of a retriangulation made outside the experiment
    (shared by several configurations), added to its stage times; ``method`` = how that
    retriangulation was made (the report says "given")."""
    e, b, f, s, o = (rep["error"], rep["baseline_zero_detail"], rep["floor_retriangulated"], rep["seconds"],
                     rep["options"])
    improvement = rep["improvement_over_zero_detail"]          # None where an RMS is rounding
    ok = e["hausdorff_rms"] <= 1e-3 and e["hausdorff_max"] <= 1e-2 and (improvement is None or improvement >= 50)
    loc = o["location"] + (f" ({o['parameterization']})" if o["location"] == "uv" else "")
    total = s["total"] + (t_retri or 0.0)
    t_retri = s["retriangulate"] if t_retri is None else t_retri
    return (f"| {name} | {rep['source']['vertices']:,} | {rep['target']['vertices']:,} | {method or o['method']} | "
            f"{o['transfer']} | {o['rows']} | {loc} | **{pct(e['hausdorff_rms'], 4)}** / {pct(e['hausdorff_max'])} | "
            f"{pct(b['hausdorff_rms'], 2)} / {pct(b['hausdorff_max'], 1)} | "
            f"{pct(f['hausdorff_rms'], 4)} / {pct(f['hausdorff_max'])} | {_ratio(improvement, ',.0f', 'x')} | "
            f"{_ratio(rep['ratio_to_floor'], '.2f')} | {'yes' if ok else 'NO'} | "
            f"{t_retri:.2f} / {s['parameterize']:.2f} / {s['transfer']:.2f} / {s['reconstruct']:.2f} / "
            f"{s['evaluate']:.2f} / {total:.2f} |")


HEADER = ("| patch | source V | target V | retriangulation | transfer | rows | location | "
          "RMS / max (%) | zero-detail RMS / max (%) | floor RMS / max (%) | better than zero | RMS / floor | "
          "targets met | seconds: retriangulate / parameterize / transfer / reconstruct / evaluate / total |\n"
          "|---|---:|---:|---|---|---|---|---:|---:|---:|---:|---:|---|---|")


def _with_table(doc, table):
    """The text of ``doc`` with ``table`` between its markers, or None where there is no such
    file or it has no markers (then it is not written)."""
    if not os.path.exists(doc):
        return None
    with open(doc, encoding="utf-8") as fh:
        text = fh.read()
    if TABLE_BEGIN not in text or TABLE_END not in text:
        return None
    return text[:text.index(TABLE_BEGIN) + len(TABLE_BEGIN)] + table + text[text.index(TABLE_END):]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default_meshes = os.environ.get("CURVDETAIL_MESHES", os.path.join(ROOT, "..", "shared", "meshes"))
    ap.add_argument("--meshes", default=default_meshes,
                    help="folder of the public meshes (default: $CURVDETAIL_MESHES, else ../shared/meshes)")
    ap.add_argument("--quick", action="store_true",
                    help="default configuration only, no 100k run; writes out/fig3/ only, not docs/")
    ap.add_argument("--force", action="store_true",
                    help="replace output files that exist (a full run refreshes the committed docs/ files)")
    args = ap.parse_args(argv)
    meshes = args.meshes
    results_json = os.path.join(ROOT, "out", "fig3", "results.json")
    if args.quick:
        table_file, doc, figure = os.path.join(ROOT, "out", "fig3", "table_quick.md"), None, None
    else:
        table_file = os.path.join(ROOT, "docs", "fig3_table.md")
        doc = os.path.join(ROOT, "docs", "remeshing.md")     # the copy between its markers, if it has them
        if _with_table(doc, "") is None:
            doc = None
        figure = os.path.join(ROOT, "docs", "fig3.png")
    run = _outputs.Run(ap, [results_json, table_file, doc, figure], args.force,
                       makes=[os.path.join(ROOT, "out", "fig3")])
    if not os.path.isdir(meshes):
        ap.error(f"mesh folder {meshes!r} does not exist; pass --meshes DIR or set CURVDETAIL_MESHES")
    results, lines_main, lines_all = [], [], []
    figure_inputs = {}
    configs = CONFIGS[:1] if args.quick else CONFIGS
    for name in PATCHES:
        V, F = read_mesh(os.path.join(meshes, name))
        t = time.perf_counter()
        Vt, Ft = retriangulate(V, F, method="isotropic", target_edge=0.01)
        t_retri = time.perf_counter() - t
        for transfer, rows, location in configs:
            try:
                out = run_experiment(V, F, transfer=transfer, rows=rows, location=location, target=(Vt, Ft),
                                     source_path=name)
            except Exception as exc:  # a failure is a result too: record it
                print(f"{name} {transfer} {rows} {location}: FAILED {exc}", file=sys.stderr)
                lines_all.append(f"| {name} | {V.shape[0]:,} | {Vt.shape[0]:,} | isotropic | {transfer} | {rows} | "
                                 f"{location} | FAILED: {exc} |")
                continue
            rep = out["report"]
            results.append(dict(rep, seconds_retriangulate_shared=round(t_retri, 4)))
            line = row(name.rsplit(".", 1)[0], rep, t_retri, method="isotropic")
            lines_all.append(line)
            if (transfer, rows, location) == CONFIGS[0]:
                lines_main.append(line)
                if name in ("mannequin_nose.obj", "mannequin_ear.obj", "elephant_trunk.obj"):
                    figure_inputs[name] = (V, F, out)
            print(line, flush=True)
    params = []
    if not args.quick:
        for name in ("mannequin_nose.obj", "elephant_trunk.obj", "camelhead.off"):
            V, F = read_mesh(os.path.join(meshes, name))
            Vt, Ft = retriangulate(V, F, method="isotropic", target_edge=0.01)
            for param in ("harmonic", "meshlab_harmonic", "lscm"):
                try:
                    out = run_experiment(V, F, location="uv", parameterization=param, target=(Vt, Ft),
                                         source_path=name)
                except Exception as exc:
                    print(f"{name} uv {param}: FAILED {exc}", file=sys.stderr)
                    params.append(f"| {name} | {V.shape[0]:,} | {Vt.shape[0]:,} | isotropic | conservative | free | "
                                  f"uv ({param}) | FAILED: {exc} |")
                    continue
                rep = out["report"]
                results.append(rep)
                line = row(name.rsplit(".", 1)[0], rep, method="isotropic")
                pi = rep["parameterization"]
                params.append(line + f" {pi['flipped_source']} / {pi['flipped_target']} |")
                print(params[-1], flush=True)
    extra = []
    runs = [("decimate", "mannequin_ear.obj", 0.03), ("decimate", "camelhead.off", 0.01),
            ("decimate", "terrainA_10k.obj", 0.01)]
    if not args.quick:
        runs += [("isotropic", "terrainA_100k.ply", 0.01), ("decimate", "terrainA_100k.ply", 0.01)]
    for method, name, target_edge in runs:
        V, F = read_mesh(os.path.join(meshes, name))
        try:
            out = run_experiment(V, F, method=method, target_edge=target_edge, source_path=name)
        except Exception as exc:
            print(f"{name} {method}: FAILED {exc}", file=sys.stderr)
            extra.append(f"| {name} | {V.shape[0]:,} | - | {method} | FAILED: {exc} |")
            continue
        rep = out["report"]
        results.append(rep)
        line = row(name.rsplit(".", 1)[0] + (f" ({100 * target_edge:g} %)" if target_edge != 0.01 else ""), rep)
        extra.append(line)
        print(line, flush=True)
    run.write_json(results_json, results, indent=1)
    table = ("### Default configuration (isotropic 1 %, conservative transfer, free rows, closest-point location)\n\n"
             f"{HEADER}\n" + "\n".join(lines_main) +
             "\n\n### Every transfer configuration on the same targets\n\n" + f"{HEADER}\n" + "\n".join(lines_all) +
             "\n\n### Decimation, and a 100k-vertex source (default transfer)\n\n" + f"{HEADER}\n" + "\n".join(extra) +
             "\n")
    if params:
        table += ("\n### Planar domains for the location (conservative transfer, free rows; retriangulation time "
                  "not counted)\n\n" + HEADER.replace(" |\n|", " | flipped source / target |\n|", 1) + "---|\n"
                  + "\n".join(params) + "\n")
    # --quick: a subset; the committed tables and figure in docs/ stay as they are
    run.write_text(table_file, table)
    text = _with_table(doc, table) if doc else None
    if text is not None:      # refresh the copy between the markers in docs/remeshing.md
        run.write_text(doc, text)
    if figure is not None and figure_inputs:
        with run.stage(figure) as tmp:
            _figure(figure_inputs, tmp)
    run.commit()
    print(table)


def _figure(inputs, path, force=False):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from curvdetail.remesh.figure import _draw, _view_frame

    fig = plt.figure(figsize=(10, 3.2 * len(inputs)))
    for r, (name, (V, F, out)) in enumerate(inputs.items()):
        rep = out["report"]
        R = _view_frame(V, F)
        centre = 0.5 * (V.max(0) + V.min(0))
        P = (V - centre) @ R.T
        scale = float((P.max(0) - P.min(0)).max())
        e, b = rep["error"], rep["baseline_zero_detail"]
        panels = [(V, F, None, f"{name.rsplit('.', 1)[0]}: {V.shape[0]:,} vertices"),
                  (out["X"], out["Ft"], out["distance"],
                   f"rebuilt, {rep['target']['vertices']:,} vertices\nRMS {pct(e['hausdorff_rms'])} %, "
                   f"max {pct(e['hausdorff_max'], 2)} %"),
                  (out["Z"], out["Ft"], None,
                   f"zero detail\nRMS {pct(b['hausdorff_rms'], 2)} %, max {pct(b['hausdorff_max'], 1)} %")]
        for c, (X, T, val, title) in enumerate(panels):
            ax = fig.add_subplot(len(inputs), 3, 3 * r + c + 1, projection="3d")
            _draw(ax, X, T, R, centre, scale, values=val,
                  vmax=None if val is None else float(val.max()), title=title)
    fig.suptitle("Fig. 3 patches rebuilt from transferred curvature detail (colour: distance to the source, "
                 "0 to its max)\n% of the source bbox diagonal", fontsize=9)
    try:
        _outputs.save_figure(fig, path, force, dpi=70, bbox_inches="tight")
    finally:
        plt.close(fig)


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
