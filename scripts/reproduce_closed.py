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
## Where the figures come from

The reconstruction is exact given the target's own detail (rebuilt from `L Vt`, every model
returns `Vt` to 1e-14 of the diagonal): the error is all in the transferred detail.

- **The transfer is one Galerkin method** (`transfer_curvature`, `source_metric`): the source's
  detail on the target's hat functions lifted onto the source (its weak mean curvature normal),
  rebuilt with the target's Laplacian in the source's metric, both integrated at the same 16
  points of each target triangle. Each half of that removed a miss of an earlier transfer, which
  carried the detail as a measure along the source's edges (`metric="target"`):
  - rebuilt with the target's own Laplacian, that measure stretched thin parts, the target being
    inscribed (its tubes shorter round than the source's): cow.off's tail by 2 % (1 %: RMS 1.69x,
    max 2.13x the floor) and fine targets flattened (0.5 %: mannequin_ear 1.83x, elephant_trunk
    1.66x, camelhead 1.81x RMS);
  - rebuilt in the source's metric but integrated along the edges' own map (source to target,
    where the metric's points go target to source), it cut a fin-like crest: cow.off's horn tips
    touch along a seam from a vertex both horns share, and at 0.5 % the max sat on horn A's crest
    there (1.69x; RMS 1.33x).
- **cow.off's seam** also needs each edge sample kept on its own horn where the detail is carried
  on the edges (a given detail, or `metric="target"`): a sample on the seam is at distance 0 from
  both horns, and a triangle sharing only the seam's vertex with the stepped sample's is not taken
  as the same side (`remesh.locate.own_side`).
- **Anchors**: a closed piece's one anchor (its flattest vertex, pinned to its target position)
  fixes the translation; it is picked among many nearly flat vertices, so small changes of the
  detail can move it and the piece with it (the cow at 0.5 % read 1.26-1.35x RMS across
  rounding-level changes of an earlier transfer).
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
