"""Reproduce the paper's Fig. 2: shape editing.

(a) cow: the whole head is the region of interest (x > 0.18), its front (muzzle, ears, horns;
    x > 0.42) the handles; the neck and body stay fixed. The paper's edit ("paper"): only the
    handles' curvature normals are turned, by 35 degrees about the vertical axis, and the
    embedding finds every position of the region. The benchmark-style edit ("moved"): the
    handles are also placed where that turn and a move of 8 % of the diagonal towards the
    reader take them, with their details turned or solved freely. Each with the paper's one-ring
    relations and with one- plus two-ring relations (not the free one).
(b) terrain patch (SRTM, terrainA_10k): the boundary moved by a sine along its arc length, in y
    and in z; the boundary's curvature detail is updated accordingly (recomputed on the
    harmonically deformed patch, the paper) or kept, and the inside rebuilt from the curvature
    coefficients (``edit_boundary``), with the paper's one-ring relations and with one- plus
    two-ring relations. Folded triangles (normals pointing down) are counted.

The JSON holds the settings (``config``: the thresholds, the turn, the offset, the transform;
the terrain's sines), the meshes' vertex and face counts, and the run's time, load and peak
memory.

The figure's edits are the paper's linear one (``CurvatureEditor`` /
``edit_with_selection(method="paper")`` / ``edit_boundary(method="paper")``). Each sub-figure
also runs the default settings: the cow's moved handles through ``edit_with_selection(V, F,
status, T)``, the terrain's sines through ``edit_boundary(V, F, displacement)`` with no option
(both rotation-aware). Every edit reports its folded triangles, its amplification (largest move over the
handles' or the boundary's largest move; the editing filter and ``curvdetail edit`` warn above
``AMPLIFICATION_LIMIT``) and the warnings it raised (the default ones are not silenced).

Usage: python scripts/reproduce_fig2.py [--out out/fig2] [--docs docs/results] [--force]
Writes OUT/fig2.json, OUT/fig2.md, OUT/fig2a.png, OUT/fig2b.png, and with --docs DIR also
DIR/fig2.json, DIR/fig2.md and DIR/fig2.png (one row per sub-figure), each atomically as it is
ready. Before any work, an existing one is refused unless --force is given (the files in
docs/results are in the repository: refreshing them is ``--docs docs/results --force``).
"""

import argparse
import json
import os
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _files  # noqa: E402
from _meshes import MESHES, require  # noqa: E402

from curvdetail import CurvatureEditor, edit_boundary, read_mesh, sine_displacement
from curvdetail.curvature.geometry import bbox_diagonal, folded_triangles
from curvdetail.curvature.errors import FoldedTrianglesWarning
from curvdetail.filters.editing import AMPLIFICATION_LIMIT
from curvdetail.io.deformation import edit_with_selection
from curvdetail.plot import view_direction

Y_UP = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])   # display y-up models with z up
COW_VIEW = (15, 30)


#: the cow edit's settings (x thresholds in the model's units, the offset a fraction of the
#: bounding-box diagonal); the head is turned about the vertical axis through x = pivot_x
COW = {"region_x_above": 0.18, "handles_x_above": 0.42, "turn_degrees": 35.0, "pivot_x": 0.3,
       "offset_towards_reader": 0.08, "view": list(COW_VIEW)}
#: the cow variants: (handle positions, handle details, curvature-stage relations). "paper": only
#: the handles' curvature normals are turned and the embedding finds every position; "moved":
#: the handles are also placed where the turn and the offset take them (edit_with_selection)
COW_VARIANTS = (("paper", "transform", "one-ring"), ("paper", "transform", "one+two-ring"),
                ("moved", "transform", "one-ring"), ("moved", "transform", "one+two-ring"),
                ("moved", "free", "one-ring"), ("moved", "default", "rotation-aware"))


def _warnings(caught):
    return [f"{w.category.__name__}: {w.message}" for w in caught]


def _amplification(V, X, moved_part):
    """Largest move over the largest move of ``moved_part`` (None where that part did not move)."""
    moved = np.linalg.norm(X - V, axis=1)
    on_part = moved[moved_part].max()
    return float(moved.max() / on_part) if on_part > 1e-12 * bbox_diagonal(V) else None


def cow():
    V, F = read_mesh(os.path.join(MESHES, "cow.off"))              # y up, head towards +x
    diag = bbox_diagonal(V)
    status = np.where(V[:, 0] > COW["handles_x_above"], 2, np.where(V[:, 0] > COW["region_x_above"], 1, 0))
    handles, roi = np.flatnonzero(status == 2), np.flatnonzero(status > 0)
    toward = Y_UP.T @ view_direction(*COW_VIEW)                    # the reader, in cow coordinates
    toward[1] = 0.0
    toward /= np.linalg.norm(toward)
    # turn about the vertical (y) axis through the neck, so the muzzle swings towards the reader
    pivot = np.array([COW["pivot_x"], V[handles, 1].mean(), V[handles, 2].mean()])
    sign = np.sign(np.cross([1.0, 0, 0], toward)[1]) or 1.0
    a = np.radians(COW["turn_degrees"]) * sign
    R = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = pivot - R @ pivot + COW["offset_towards_reader"] * diag * toward
    out = {"model": "cow", "vertices": int(V.shape[0]), "faces": int(F.shape[0]),
           "config": {**COW, "transform": T.tolist()}, "roi": int(roi.size), "handles": int(handles.size)}
    meshes = {}
    for positions, handle_detail, relations in COW_VARIANTS:
        t = time.perf_counter()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            if positions == "paper":
                ed = CurvatureEditor(V, F, np.empty(0, dtype=np.int64), handles, roi=roi, relations=relations)
                X = ed.solve(details=ed.detail[handles] @ R.T)
            elif handle_detail == "default":
                X, ed = edit_with_selection(V, F, status, T, return_editor=True)
            else:
                X, ed = edit_with_selection(V, F, status, T, method="paper", handle_detail=handle_detail,
                                            relations=relations, return_editor=True)
        variant = f"{positions}/{handle_detail}/{relations}"
        moved = np.linalg.norm(X - V, axis=1)
        out[variant] = {"handle_positions": positions, "handle_detail": handle_detail, "relations": relations,
                        "position_constrained": int(ed.position_constrained.size),
                        "seconds": time.perf_counter() - t,
                        "max_move_fraction": float(moved.max() / diag),
                        "handle_centroid_move_fraction": float(np.linalg.norm(X[handles].mean(0)
                                                                              - V[handles].mean(0)) / diag),
                        "finite": bool(np.isfinite(X).all()),
                        "rank_deficient": getattr(ed, "rank_deficient", None),
                        "iterations": getattr(ed, "iterations", None),
                        "folded_triangles": int(folded_triangles(V, F, X, R).size),
                        "amplification": _amplification(V, X, handles) if positions == "moved" else None,
                        "warnings": _warnings(caught)}
        meshes[variant] = X
    return V, F, status, meshes, out


def folded(X, F):
    """Triangles whose normal points down (the patch is a height field, z up)."""
    n = np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]])
    return int((n[:, 2] < 0).sum())


#: the terrain edit: a sine of ``periods`` periods along the boundary in the axis given, its
#: amplitude a fraction of the patch's larger horizontal extent
TERRAIN = {"periods": 2, "sines": {"sine_y": (1, 0.06), "sine_z": (2, 0.08)}}


def terrain():
    V, F = read_mesh(os.path.join(MESHES, "terrainA_10k.obj"))
    extent = np.ptp(V[:, :2], axis=0).max()
    out = {"model": "terrainA_10k", "vertices": int(V.shape[0]), "faces": int(F.shape[0]),
           "config": TERRAIN, "rest_folded": folded(V, F)}
    meshes = {}
    for name, (axis, fraction) in TERRAIN["sines"].items():
        amp = fraction * extent
        for mode, relations in (("deformed", "one-ring"), ("deformed", "one+two-ring"), ("rest", "one-ring"),
                                ("default", "default")):
            displacement = sine_displacement(amp, periods=TERRAIN["periods"], axis=axis)
            t = time.perf_counter()
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                if mode == "default":             # every option at its default, every warning said
                    X, info = edit_boundary(V, F, displacement, return_info=True)
                else:
                    # the paper's one-ring cases fold on purpose here: counted below, not warned
                    warnings.simplefilter("ignore", FoldedTrianglesWarning)
                    X, info = edit_boundary(V, F, displacement, method="paper", boundary_detail=mode, relations=relations,
                                            return_info=True)
            b = info["boundary"]
            variant = f"{mode}/{relations}"
            out[f"{name}_{variant}"] = {
                "amplitude": float(amp), "periods": TERRAIN["periods"], "boundary_detail": mode,
                "relations": relations, "warnings": _warnings(caught),
                "seconds": time.perf_counter() - t, "boundary_vertices": int(b.size),
                "max_move_fraction": float(np.linalg.norm(X - V, axis=1).max() / bbox_diagonal(V)),
                "height_range_ratio": float(np.ptp(X[:, 2]) / np.ptp(V[:, 2])),
                "folded_triangles": folded(X, F), "folded_against_rest": info["folded_triangles"],
                "amplification": info["amplification"], "finite": bool(np.isfinite(X).all())}
            meshes[f"{name}_{variant}"] = X
    return V, F, meshes, out


def _cell(value):
    return "-" if value is None else f"{value:.2f}"


def _said(messages):
    """The warnings' categories, for a table cell (their messages are in the JSON)."""
    return ", ".join(sorted({m.split(":")[0] for m in messages})) or "none"


def markdown(cow_, terrain_, env):
    """The Fig. 2 page: one table per sub-figure."""
    lines = ["# Fig. 2: shape editing (the paper's edit, and the default)", "",
             "Written by `python scripts/reproduce_fig2.py --docs docs/results --force`; settings, counts and "
             "the run's load in [fig2.json](fig2.json). Moves in % of the bounding-box diagonal.", "",
             _files.environment_line(env), "",
             f"(a) cow ({cow_['vertices']} vertices, region {cow_['roi']}, handles {cow_['handles']}): head "
             f"turned by {cow_['config']['turn_degrees']:g} degrees. Handle positions \"paper\": only the "
             "handles' curvature normals turned; \"moved\": the handles also placed by the turn and a move of "
             f"{100 * cow_['config']['offset_towards_reader']:g} % towards the reader.", "",
             "The last row is the default edit (`edit_with_selection(V, F, status, T)`, rotation-aware). Folded: "
             "normal against both its rest one and the turned one; amplification: largest move over the "
             f"handles' largest move (the editing filter and `curvdetail edit` warn above {AMPLIFICATION_LIMIT:g}; "
             "- where the handles are not placed); warnings: the categories of those the edit raised (their "
             "messages in the JSON).", "",
             "| handle positions | handle detail | relations | largest move (%) | handle centroid move (%) | folded "
             "| amplification | warnings | seconds |",
             "|---|---|---|---:|---:|---:|---:|---|---:|"]
    for positions, detail, relations in COW_VARIANTS:
        r = cow_[f"{positions}/{detail}/{relations}"]
        lines.append(f"| {positions} | {detail} | {relations} | {100 * r['max_move_fraction']:.1f} | "
                     f"{100 * r['handle_centroid_move_fraction']:.1f} | {r['folded_triangles']} | "
                     f"{_cell(r['amplification'])} | {_said(r['warnings'])} | {r['seconds']:.2f} |")
    lines += ["", f"(b) {terrain_['model']} ({terrain_['vertices']} vertices, {terrain_['faces']} triangles): "
              f"the boundary moved by {terrain_['config']['periods']} periods of a sine; folded = normals "
              "pointing down (at rest: " + str(terrain_["rest_folded"]) + "); \"default\": `edit_boundary` with no "
              "option, rotation-aware (the paper's rows silence its FoldedTrianglesWarning); amplification: largest move over the "
              "boundary's largest move.", "",
              "| sine | amplitude | boundary detail | relations | largest move (%) | height range | folded | "
              "folded against rest normals | amplification | warnings | seconds |",
              "|---|---:|---|---|---:|---:|---:|---:|---:|---|---:|"]
    for key, r in terrain_.items():
        if isinstance(r, dict) and "boundary_detail" in r:
            lines.append(f"| {key.split('_')[0] + '_' + key.split('_')[1]} | {r['amplitude']:.3g} | "
                         + ("default (rotation-aware) | - | " if r["boundary_detail"] == "default" else
                            f"{r['boundary_detail']} | {r['relations']} | ")
                         + f"{100 * r['max_move_fraction']:.1f} | "
                         f"x{r['height_range_ratio']:.2f} | {r['folded_triangles']} | {r['folded_against_rest']} | "
                         f"{_cell(r['amplification'])} | {_said(r['warnings'])} | {r['seconds']:.2f} |")
    lines += ["", "![Fig. 2](fig2.png)", ""]
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/fig2", help="folder for fig2.json and the pictures (default: %(default)s)")
    ap.add_argument("--docs", default=None,
                    help="also write DOCS/fig2.md, fig2.json and fig2.png (the repository's: docs/results)")
    ap.add_argument("--force", action="store_true", help="replace output files that exist")
    args = ap.parse_args(argv)
    docs = [os.path.join(args.docs, "fig2" + ext) for ext in (".md", ".json", ".png")] if args.docs else []
    _files.check_outputs(ap, [os.path.join(args.out, name)
                              for name in ("fig2a.png", "fig2b.png", "fig2.json", "fig2.md")] + docs,
                         args.force)
    require("cow.off", "terrainA_10k.obj")
    V, F, status, meshes, info_a = cow()
    print(json.dumps(info_a))
    panels = [(V @ Y_UP.T, F, "cow: rest (fixed / region / handle)", status)]
    for variant, label in (("paper/transform/one-ring", "paper: handle normals turned,\npositions free"),
                           ("paper/transform/one+two-ring", "handle normals turned, positions\nfree, one+two-ring"),
                           ("moved/transform/one-ring", "handles moved,\ndetails turned"),
                           ("moved/transform/one+two-ring", "handles moved, details\nturned, one+two-ring"),
                           ("moved/free/one-ring", "handles moved,\ndetails free"),
                           ("moved/default/rotation-aware", "default: handles moved,\nrotation-aware")):
        X = meshes[variant]
        label += f"\nlargest move {100 * info_a[variant]['max_move_fraction']:.0f} %"
        panels.append((X @ Y_UP.T, F, label, np.linalg.norm(X - V, axis=1)))
    _files.render_panels(os.path.join(args.out, "fig2a.png"), panels, args.force, elev=COW_VIEW[0], azim=COW_VIEW[1],
                         panel_size=3.0)
    Vt, Ft, tmeshes, info_b = terrain()
    print(json.dumps(info_b))
    panels = [(Vt, Ft, "terrain: rest", Vt[:, 2])]
    for key, label in (("sine_y", "sine in y"), ("sine_z", "sine in z")):
        for mode, short in (("deformed/one-ring", "(paper)"), ("deformed/one+two-ring", "one+two-ring")):
            X = tmeshes[f"{key}_{mode}"]
            folds = info_b[key + "_" + mode]["folded_triangles"]
            panels.append((X, Ft, f"{label} {short}\n{folds} folded triangles", X[:, 2]))
    _files.render_panels(os.path.join(args.out, "fig2b.png"), panels, args.force, elev=35, azim=-60, panel_size=3.0)
    env = _files.environment()
    result = {"cow": info_a, "terrain": info_b, **env, **_files.measured_conditions()}
    page = markdown(info_a, info_b, env)
    for folder in [args.out] + ([args.docs] if args.docs else []):
        _files.write_json(os.path.join(folder, "fig2.json"), result, args.force, indent=2, end="\n")
        _files.write_text(os.path.join(folder, "fig2.md"), page, args.force)
    if args.docs:
        # one row per sub-figure, each picture at its own resolution
        _files.stack_pictures(os.path.join(args.docs, "fig2.png"),
                              [os.path.join(args.out, key + ".png") for key in ("fig2a", "fig2b")], args.force)
    return 0


if __name__ == "__main__":
    sys.exit(main())
