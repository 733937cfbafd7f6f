"""The remeshing experiment on the public models and disk patches: RMS and max against the retriangulated floor.

For each closed model (spot, bunny, cow, mannequin, elephant) and each disk patch (the Fig. 3
patches, the terrains and the mannequin opened at the neck), those present in the mesh folder,
and each target edge (isotropic, 1 % of the bbox diagonal by default), runs
:func:`curvdetail.remesh.remesh_experiment` with its defaults (conservative transfer, free rows,
closest-point location, one anchor per closed piece) and records the rebuilt surface's Hausdorff
RMS and max, the floor's (the retriangulated surface itself), their ratios, the anchors used
and the seconds. The issue's target: RMS within 1.5x of the floor, max within 1.5x of the floor's max.

Usage: python scripts/reproduce_closed.py [--meshes DIR] [--target-edge 1 [0.5 ...]]
                                          [--models NAME ...] [--out docs/results] [--force]
(DIR defaults to $CURVDETAIL_MESHES, else ../shared/meshes beside the repository.) Writes
OUT/closed_models.json (every report) and OUT/closed_models.md (the table); an existing file is
refused before any work unless --force is given.
"""

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _files  # noqa: E402
from _meshes import MESHES  # noqa: E402

from curvdetail import read_mesh  # noqa: E402
from curvdetail.remesh import remesh_experiment  # noqa: E402
from curvdetail.remesh.experiment import MAX, RMS  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MODELS = ["spot.obj", "bunny.off", "cow.off", "mannequin.off", "elephant.obj"]
#: the public disk patches (one boundary loop): Fig. 3's, the terrains, the mannequin open at the neck
DISKS = ["mannequin_nose.obj", "mannequin_ear.obj", "elephant_trunk.obj", "camelhead.off", "mannequin_disk_1k.obj",
         "terrainA_1k.obj", "terrainA_10k.obj", "terrainA_100k.ply"]
#: the issue's target: RMS and max within this factor of the floor's
TARGET_RATIO = 1.5

#: Below the table: where the misses come from (measured with this code).
NOTES = """
## Where the misses come from

The reconstruction is exact given the target's own detail (rebuilt from `L Vt`, cow, mannequin_ear,
elephant_trunk and camelhead return `Vt` to 1e-14 of the diagonal): the error is all in the
transferred detail.

- **cow.off** at both edges: the max sits at the tail's tip, and the rebuilt tail is stretched
  along its axis (at 1 % the displacement grows linearly from 0 at the root to 0.66 % at the tip,
  about 2 % strain; at 0.5 % the tip's vertices are 0.30 % off). The tail is about 2 % of the
  diagonal across, some six target edges round at 1 %; the transferred detail's sum over the tail
  beyond a cut exceeds the target's own by 1-4 %, and a long thin appendage is the softest
  direction of the rebuild, so the mismatch adds up along it (the detail error of the tail and the
  rear, x < -0.43, alone moves the tip 0.78 %, that of the rest 0.03 %). Not a location error:
  relocating every tail sample found on the body's triangles (or the reverse) onto its own part
  moves none.
- **cow.off, 0.5 %, fixed**: the source has two vertices at one point (621 and 2761, an unwelded seam
  vertex where two cone tips touch) and the target keeps the pair. A sample on the seam lies at
  distance 0 from both sheets, whose facing normals agree (cos 0.72-0.98), so half of each tip's
  detail went to the other tip and the rebuilt tips opened by 0.7 % (max 0.71-0.73 %).
  A sample is now kept on the side its own triangles lie on (`remesh.locate.own_side`): max 0.30-0.32 %,
  RMS 2.42x -> 2.13x the floor; no other model's figures move. (These figures, and the ones of the
  second look below, were measured with pymeshlab's sampled Hausdorff; the table is measured with
  the exact engine's seeded samples, which repeat from run to run.)
- **Disk patches at 0.5 %** (mannequin_ear, elephant_trunk, camelhead; the max is within target
  everywhere): the rebuild's error is a smooth deformation (95 % of it survives 20 one-ring
  averaging steps), does not change with 4x the edge samples, and is a slightly flattened surface:
  scaling the transferred detail by 1.001 lowers mannequin_ear's ratio from 1.44x to 1.32x at 1 %
  and from 1.85x to 1.69x at 0.5 %. A systematic discretization error, not a location error.

Second look (load about 2 on the 2-core machine; figures are vertex-to-source distances or
pymeshlab Hausdorff ratios to the floor, on one saved retriangulation per model):

- **The tail's excess is the cut-corner perimeter deficit.** The detail summed over a region is
  the conormal flux through the region's cut, which on a tube is its perimeter along the axis. The
  target's vertices lie on the source's facets and its edges cut across the source's folds, so its
  tube is inscribed and shorter round: at 1 % the perimeters of plane cuts y < 0, -0.05, -0.1, -0.12
  are 2.6, 0.8, 0.8 and 0.6 % longer on the source than on the target. The transferred sum beyond
  those cuts is 0.6, 1.1, 1.1 and 0.4 % larger than the target's own. The source and target areas
  of the tail (face-sampled, x < -0.45, y < 0) differ by 1.3 %. The ~2 % strain matches. It is not
  the coarse k-gon of the first guess: at 1 % the target is finer round the tail than the source
  (38 against 30 segments at y = -0.1). The cause is confirmed: scaling the transferred detail of
  the tail's vertices alone (x < -0.43, y < 0) by 0.99 lowers cow 1 % from 0.038 % RMS and 0.645 %
  max to 0.026 % and 0.24 % (floor 0.022 % and about 0.27 %). At 0.5 % the best factor is 0.995,
  which lowers 0.017 % and 0.295 % to 0.014 % and 0.164 % (floor 0.008 %, so RMS stays about 1.7x
  and the rest of that miss is not the tail).
- **No per-vertex form of that correction works.** Some variants transfer the source's area
  measure with the same machinery and multiply the detail by (own barycentric area) / (transferred
  area), so they transfer K = detail / area and multiply by the target's area. All of them make
  things worse. With area on the edge samples, the ratio is noisy (1st to 99th percentile
  0.39-18), and after 1-8 one-ring smoothings it still gives 13-24x RMS at cow 1 %. With 1.4 M
  face samples the ratio is accurate (median 0.9975, tail 0.987) but gives 7x (0.25-0.28 %). The
  ratio divided by its global mean still gives 6x, or 0.034 % RMS and 0.57 % max after 100
  smoothings. A spatially varying factor with a gradient puts a net force of about (grad r) |D| on
  the free vertices, and the rebuild is far more sensitive to that than to the 1 % flux error. A
  global factor rescales the whole model about its anchor. Only a constant factor over a whole
  appendage helps, and choosing appendages is not a transfer. On mannequin_ear at 0.5 % the same
  ratio moves RMS from 0.008 % to 0.011-0.015 %.
- **Disks at 0.5 %: the options do not help.** On mannequin_ear, rows="all" gives the same RMS
  ratio (1.84x, max 0.93x). location="uv" gives 22x RMS and 6.9x max, and 27x with rows="all".
  The pointwise K A_t transfer gives 45x and 12.6x (cow 1 %: 143x and 73x). Sharpening the
  transferred detail by a one-ring unsharp mask, D + a (D - W D), is 16x worse already at a = 0.25.
  Most of the residual displacement is tangential (0.0117 % against 0.0076 % normal). Its normal
  part does not follow the target's own normal detail (correlation -0.06), so it is not a
  curvature-proportional flattening. The conservative transfer gives the rebuild the Galerkin load
  of the source surface on the target's hat functions, so the rebuild is the Ritz projection of
  the source on the target, while the floor is the interpolant. Both are second order, and a
  ratio of 1.5-2x between them is plausibly the method's own limit at this refinement (not proven
  here). Nothing was made the default.

Tried for the tail, not adopted: a stricter normal test (cos > 0.5: 25x RMS at 1 %), 2 or 3
anchors (no change), samples moved 0.1-0.25 target edges inward along their normal (RMS worse),
the detail rescaled by the target/source area ratio (worse everywhere), the pointwise transfer
(60-136x). The floor's max measured on pymeshlab's samples moved between runs (cow at 0.5 %:
0.10-0.19 % over six runs); the exact engine's seeded samples give one figure.
"""


def run(path, percent, anchors=1):
    """One experiment's figures (% of the bbox diagonal) and its report; ``error`` where it failed."""
    V, F = read_mesh(path)
    t = time.perf_counter()
    try:
        _, report = remesh_experiment(V, F, target_edge=f"{percent:g}%", source_path=os.path.basename(path),
                                      anchors=anchors)
    except ValueError as exc:
        return {"model": os.path.basename(path), "target_edge_percent": percent,
                "error": f"{type(exc).__name__}: {exc}"}
    seconds = time.perf_counter() - t
    e, fl = report["error"], report["floor_retriangulated"]
    return {"model": os.path.basename(path), "target_edge_percent": percent,
            "source_vertices": report["source"]["vertices"], "target_vertices": report["target"]["vertices"],
            "anchors": report["anchors"], "rms_percent": e[RMS], "max_percent": e[MAX],
            "floor_rms_percent": fl[RMS], "floor_max_percent": fl[MAX],
            "ratio_rms": report["ratio_to_floor"], "ratio_max": e[MAX] / fl[MAX],
            "seconds": round(seconds, 2), "report": report}


def table(rows):
    lines = ["| model | edge % | V source | V target | anchors | RMS % | floor RMS % | RMS / floor | max % | "
             "floor max % | max / floor | s |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['model']} | {r['target_edge_percent']:g} | FAILED: {r['error']} |" + " |" * 10)
            continue
        ok = lambda x: f"{x:.2f}" + ("" if x <= TARGET_RATIO else " (over)")  # noqa: E731
        lines.append(f"| {r['model']} | {r['target_edge_percent']:g} | {r['source_vertices']:,} | "
                     f"{r['target_vertices']:,} | {r['anchors']} | {r['rms_percent']:.4f} | {r['floor_rms_percent']:.4f} | "
                     f"{ok(r['ratio_rms'])} | {r['max_percent']:.3f} | {r['floor_max_percent']:.3f} | "
                     f"{ok(r['ratio_max'])} | {r['seconds']:.1f} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--meshes", default=MESHES, help="folder of the public meshes")
    parser.add_argument("--target-edge", type=float, nargs="+", default=[1.0], metavar="PCT",
                        help="target edges in %% of the bbox diagonal (default: 1)")
    parser.add_argument("--models", nargs="+", default=MODELS + DISKS, metavar="NAME",
                        help="mesh files to run (default: the closed models and the disk patches)")
    parser.add_argument("--anchors", type=int, default=1, metavar="K", help="anchors per closed piece (default: 1)")
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "results"), help="output folder")
    parser.add_argument("--force", action="store_true", help="replace existing outputs")
    args = parser.parse_args(argv)
    if args.anchors < 1:
        parser.error("--anchors takes a whole number >= 1")
    if any(not 0 < pct < 100 for pct in args.target_edge):
        parser.error("--target-edge takes percentages between 0 and 100")
    json_path = os.path.join(args.out, "closed_models.json")
    md_path = os.path.join(args.out, "closed_models.md")
    _files.check_outputs(parser, [json_path, md_path], args.force)
    models = [m for m in args.models if os.path.exists(os.path.join(args.meshes, m))]
    if not models:
        sys.exit(f"{args.meshes!r} holds none of {', '.join(args.models)}; pass --meshes or set CURVDETAIL_MESHES.")
    rows = []
    for pct in args.target_edge:
        for model in models:
            row = run(os.path.join(args.meshes, model), pct, args.anchors)
            rows.append(row)
            if "error" in row:
                print(f"{model} {pct:g} %: FAILED {row['error']}", file=sys.stderr)
                continue
            print(f"{model} {pct:g} %: RMS {row['rms_percent']:.4f} % (floor {row['floor_rms_percent']:.4f} %, "
                  f"{row['ratio_rms']:.2f}x), max {row['max_percent']:.3f} % ({row['ratio_max']:.2f}x), "
                  f"{row['anchors']} anchor(s), {row['seconds']:.1f} s", file=sys.stderr)
    heading = ("# The remeshing experiment on closed models and disk patches\n\nIsotropic retriangulation, "
               "conservative transfer, free rows, closest-point location; a disk patch keeps its boundary loop fixed, "
               f"a closed model gets {args.anchors} anchor(s) (farthest-point sampled from its flattest vertex). "
               "Figures are "
               "two-sided Hausdorff distances in % of the bbox diagonal; the floor is the retriangulated surface "
               f"itself. Target: both ratios within {TARGET_RATIO}x. Written by scripts/reproduce_closed.py.\n\n")
    _files.write_json(json_path, {"target_ratio": TARGET_RATIO, "anchors": args.anchors, "runs": rows}, args.force,
                      end="\n", indent=1)
    _files.write_text(md_path, heading + table(rows) + NOTES, args.force)
    return 0 if all("error" not in r for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
