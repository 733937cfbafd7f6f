"""Reproduce the paper's Fig. 1: mesh editing with curvature detail and curvature coefficients.

(a) elephant: the left ear lengthened (its tip region pulled outwards) and the right ear
    deformed towards the reader;
(b) cactus: three feature points (the tips of the two arms and the top) moved, everything
    else embedded from the precomputed curvature coefficients, the foot fixed;
(c) mannequin_devil: the curvature details of a horn's tip (the vertices within 3 % of the
    diagonal of it) scaled, with only the neck boundary fixed in position, so that the whole
    head is reconstructed. The paper shortens the curvature normals to lengthen the horn; with
    the detail D = K A constrained (rest areas), D x 0.5 shortens the horn and D x 2 lengthens
    it, while the intensive curvature normal |K| at the lengthened tip does get shorter (both
    are reported, with the other horn's length and the head's height as controls).

Feature points are found from the geometry (extreme vertices; the horn tips as the highest
sharp local z-maxima on the face side, see ``horn_tips``), the regions of interest by
Euclidean distance. The JSON holds each edit's settings (``config``, radii and moves as
fractions of the bounding-box diagonal), sizes, and the run's time, load and peak memory.
Every edit is one CurvatureEditor (constructor = all factoring) and one solve.

Every edit is the paper's linear one (``CurvatureEditor``, one-ring relations), so the figure is
the paper's. (a) and (b) also run the default edit, rotation-aware (``RotationAwareEditor`` with
its default settings, as ``edit_with_selection`` and ``apply_curvature_editing`` run it) with the
same handles, region and moves; (c) scales details, which only the paper's edit does. Every edit
reports its folded triangles (normal against its rest one), its amplification (largest move over
the handles' largest move; ``apply_curvature_editing`` and ``curvdetail edit`` warn above
``AMPLIFICATION_LIMIT``) and the warnings it raised.

Usage: python scripts/reproduce_fig1.py [--out out/fig1] [--docs docs/results] [--force]
Writes OUT/fig1.json, OUT/fig1.md, OUT/fig1a.png, OUT/fig1b.png, OUT/fig1c.png, and with --docs DIR
also DIR/fig1.json, DIR/fig1.md and DIR/fig1.png (one row per sub-figure), each atomically as it is
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

from curvdetail import CurvatureEditor, boundary_vertices, mean_curvature_normal, read_mesh
from curvdetail.curvature.geometry import bbox_diagonal, folded_triangles
from curvdetail.curvature.rotation_editor import RotationAwareEditor
from curvdetail.filters.editing import AMPLIFICATION_LIMIT

Y_UP = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])   # display y-up models with z up

#: the edits' settings; radii and moves are fractions of the bounding-box diagonal
ELEPHANT = {"roi_radius": 0.25, "handle_radius": 0.04,
            "left_ear_move": [-0.12, -0.05, 0.0],                 # lengthen the left ear
            "right_ear_move": [0.0, 0.0, 0.15]}                   # right ear towards the reader
CACTUS = {"handle_radius": 0.03, "foot_height": 0.12,             # foot: fraction of the height
          "tip_moves": {"-y arm": [0.0, -0.1, 0.05], "+y arm": [0.1, 0.08, 0.0],
                        "top": [-0.08, 0.0, 0.04]}}
DEVIL = {"horn_radius": 0.03, "base_ring": [0.05, 0.06], "detail_scales": [0.5, 2.0],
         "min_tip_curvature_over_median": 2.0}


def near(V, i, radius):
    return np.flatnonzero(np.linalg.norm(V - V[i], axis=1) < radius)


def checks(V, F, X, handles, caught):
    """Folded triangles, amplification (None for unmoved handles) and the warnings caught."""
    moved = np.linalg.norm(X - V, axis=1)
    on_handles = moved[handles].max() if handles.size else 0.0
    amplification = float(moved.max() / on_handles) if on_handles > 1e-12 * bbox_diagonal(V) else None
    return {"folded_triangles": int(folded_triangles(V, F, X, np.eye(3)).size), "amplification": amplification,
            "amplified": amplification is not None and amplification > AMPLIFICATION_LIMIT,
            "warnings": [f"{w.category.__name__}: {w.message}" for w in caught]}


def default_edit(V, F, handles, roi, P):
    """The default (rotation-aware) edit of the same handles, region and positions."""
    t = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ed = RotationAwareEditor(V, F, handles, roi=roi)
        X = ed.solve(P)
    return X, {"seconds": time.perf_counter() - t, "iterations": ed.iterations, "converged": ed.converged,
               "max_move_fraction": float(np.linalg.norm(X - V, axis=1).max() / bbox_diagonal(V)),
               **checks(V, F, X, handles, caught)}


def summary(name, V, F, X, ed, seconds, config):
    moved = np.linalg.norm(X - V, axis=1)
    return {"model": name, "vertices": int(V.shape[0]), "faces": int(F.shape[0]),
            "config": config, "roi": int(ed.roi.size),
            "position_constrained": int(ed.position_constrained.size),
            "detail_constrained": int(ed.detail_constrained.size),
            "rank_deficient": ed.rank_deficient, "detail_islands": ed.detail_islands,
            "max_move_fraction": float(moved.max() / bbox_diagonal(V)),
            "finite": bool(np.isfinite(X).all()), "seconds": seconds}


def elephant():
    V, F = read_mesh(os.path.join(MESHES, "elephant.obj"))       # y up, trunk towards +z
    diag = bbox_diagonal(V)
    left, right = int(np.argmin(V[:, 0])), int(np.argmax(V[:, 0]))  # the ear tips
    roi = np.union1d(near(V, left, ELEPHANT["roi_radius"] * diag),
                     near(V, right, ELEPHANT["roi_radius"] * diag))
    hl, hr = (near(V, i, ELEPHANT["handle_radius"] * diag) for i in (left, right))
    handles = np.concatenate([hl, hr])
    t = time.perf_counter()
    ed = CurvatureEditor(V, F, handles, handles, roi=roi)
    P = V[handles].copy()
    P[:hl.size] += np.asarray(ELEPHANT["left_ear_move"]) * diag
    P[hl.size:] += np.asarray(ELEPHANT["right_ear_move"]) * diag
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        X = ed.solve(positions=P)
    info = summary("elephant", V, F, X, ed, time.perf_counter() - t, ELEPHANT)
    info.update(checks(V, F, X, handles, caught))
    Xd, info["default"] = default_edit(V, F, handles, roi, P)
    info["default_panel"] = (Xd, "default (rotation-aware)")
    return V, F, X, info, True


def cactus():
    V, F = read_mesh(os.path.join(MESHES, "cactus.off"))           # z up
    diag = bbox_diagonal(V)
    radius = CACTUS["handle_radius"] * diag
    tips = [int(np.argmin(V[:, 1])), int(np.argmax(V[:, 1])), int(np.argmax(V[:, 2]))]
    foot = V[:, 2] < V[:, 2].min() + CACTUS["foot_height"] * np.ptp(V[:, 2])
    roi = np.flatnonzero(~foot)
    handles = np.unique(np.concatenate([near(V, i, radius) for i in tips]))
    t = time.perf_counter()
    ed = CurvatureEditor(V, F, handles, handles, roi=roi)           # coefficients precomputed here
    P = V[handles].copy()
    for i, shift in zip(tips, CACTUS["tip_moves"].values()):
        sel = np.linalg.norm(P - V[i], axis=1) < radius
        P[sel] += np.asarray(shift) * diag
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        X = ed.solve(positions=P)
    info = summary("cactus", V, F, X, ed, time.perf_counter() - t, CACTUS)
    info.update(checks(V, F, X, handles, caught))
    Xd, info["default"] = default_edit(V, F, handles, roi, P)
    info["default_panel"] = (Xd, "default (rotation-aware)")
    return V, F, X, info, False


def horn_tips(V, F, K):
    """The two horn tips of mannequin_devil (z up, face towards -y): the two highest local
    z-maxima (above every neighbour) on the face side (y below the middle) whose curvature normal
    ``|K|`` is more than ``min_tip_curvature_over_median`` times the median, one on each side of
    x = 0, the edited one first. The crown is higher than both but smooth (``|K|`` below the
    median there). Raises ``ValueError`` where none is found, rather than edit something else."""
    z = V[:, 2]
    edges = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    highest_neighbour = np.full(V.shape[0], -np.inf)
    np.maximum.at(highest_neighbour, edges[:, 0], z[edges[:, 1]])
    np.maximum.at(highest_neighbour, edges[:, 1], z[edges[:, 0]])
    curvature = np.linalg.norm(K, axis=1)
    sharp = curvature > DEVIL["min_tip_curvature_over_median"] * np.median(curvature)
    face_side = V[:, 1] < 0.5 * (V[:, 1].min() + V[:, 1].max())
    candidates = np.flatnonzero((z > highest_neighbour) & sharp & face_side)
    tips = []
    for side in (V[:, 0] > 0, V[:, 0] < 0):
        on_side = candidates[side[candidates]]
        if on_side.size == 0:
            raise ValueError("mannequin_devil: no sharp local z-maximum on the face side (y below the "
                             "middle) at " + ("x > 0" if not tips else "x < 0") + "; the mesh is not "
                             "the expected one (z up, face towards -y, horns on top): check "
                             "$CURVDETAIL_MESHES/mannequin_devil.off.")
        tips.append(int(on_side[np.argmax(z[on_side])]))
    return tips


def devil():
    V, F = read_mesh(os.path.join(MESHES, "mannequin_devil.off"))  # z up, face towards -y
    diag = bbox_diagonal(V)
    K0, _ = mean_curvature_normal(V, F)
    tip, other = horn_tips(V, F, K0)                                # the x > 0 horn is edited
    inner, outer = DEVIL["base_ring"]

    def horn_length(X, i):
        """Tip to the centre of the ring of vertices around the horn's base (rest distances)."""
        ring = np.setdiff1d(near(V, i, outer * diag), near(V, i, inner * diag))
        return np.linalg.norm(X[i] - X[ring].mean(0))

    horn = near(V, tip, DEVIL["horn_radius"] * diag)
    neck = boundary_vertices(F)
    dc = np.concatenate([neck, horn])
    t = time.perf_counter()
    ed = CurvatureEditor(V, F, neck, dc)                            # whole head rebuilt
    results = {}
    for scale in DEVIL["detail_scales"]:
        D = ed.detail[dc].copy()
        D[neck.size:] *= scale                                      # scale the horn's details
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            X = ed.solve(details=D)
        K, _ = mean_curvature_normal(X, F)
        results[scale] = {
            "X": X, **checks(V, F, X, neck, caught),
            "horn_length_ratio": float(horn_length(X, tip) / horn_length(V, tip)),
            "other_horn_length_ratio": float(horn_length(X, other) / horn_length(V, other)),
            "head_height_ratio": float(np.ptp(X[:, 2]) / np.ptp(V[:, 2])),
            "max_move_fraction": float(np.linalg.norm(X - V, axis=1).max() / diag),
            "tip_curvature_normal_ratio": float(np.linalg.norm(K[horn], axis=1).mean()
                                                / np.linalg.norm(K0[horn], axis=1).mean())}
    low, high = min(results), max(results)
    X = results[high]["X"]
    curvature = np.linalg.norm(K0, axis=1)
    info = summary("mannequin_devil", V, F, X, ed, time.perf_counter() - t, DEVIL)
    info.update(tip=tip, tip_position=V[tip].tolist(), other_tip=other,
                horn_vertices=int(horn.size), tip_curvature_over_median=float(curvature[tip] / np.median(curvature)))
    for scale, r in results.items():
        info[f"detail_x{scale}"] = {k: v for k, v in r.items() if k != "X"}
    info.update({k: info[f"detail_x{high}"][k] for k in ("folded_triangles", "amplification", "amplified")})
    info["warnings"] = sorted({w for r in results.values() for w in r["warnings"]})
    info["extra_panel"] = (results[low]["X"], f"horn detail x{low:g}: horn length "
                                              f"x{results[low]['horn_length_ratio']:.2f}")
    info["edited_label"] = (f"horn detail x{high:g}: horn length x{results[high]['horn_length_ratio']:.2f},\n"
                            f"|K| at the tip x{results[high]['tip_curvature_normal_ratio']:.2f}")
    return V, F, X, info, False


def _said(messages):
    """The warnings' categories, for a table cell (their messages are in the JSON)."""
    return ", ".join(sorted({m.split(":")[0] for m in messages})) or "none"


def markdown(report, env):
    """The Fig. 1 page: one table of the edits, one of the horn's detail scales."""
    lines = ["# Fig. 1: mesh editing with curvature detail (the paper's edit, `CurvatureEditor`, and the default)", "",
             "Written by `python scripts/reproduce_fig1.py --docs docs/results --force`; settings, counts and "
             "the run's load in [fig1.json](fig1.json). Moves in % of the bounding-box diagonal.", "",
             _files.environment_line(env), "",
             "Each edit also runs as the default, rotation-aware edit where it can (same handles, region and "
             "moves; (c) scales details, which only the paper's edit does). Folded: triangles whose normal turned "
             "against its rest one; amplification: largest move over the handles' largest move (the editing "
             f"filter and `curvdetail edit` warn above {AMPLIFICATION_LIMIT:g}; - where the handles do not move); "
             "warnings: the categories of those the edit raised (their messages in the JSON).", "",
             "| edit | model | method | vertices | faces | region | position constrained | detail constrained | "
             "largest move (%) | folded | amplification | warnings | iterations | seconds |",
             "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|"]

    def cells(x):
        amp = "-" if x["amplification"] is None else f"{x['amplification']:.2f}"
        return (f"{100 * x['max_move_fraction']:.1f} | {x['folded_triangles']} | {amp} | "
                f"{_said(x['warnings'])}")

    for key, r in zip("abc", report):
        lines.append(f"| ({key}) | {r['model']} | paper | {r['vertices']} | {r['faces']} | {r['roi']} | "
                     f"{r['position_constrained']} | {r['detail_constrained']} | {cells(r)} | - | {r['seconds']:.2f} |")
        if "default" in r:
            d = r["default"]
            lines.append(f"| ({key}) | {r['model']} | default (rotation-aware) | {r['vertices']} | {r['faces']} | "
                         f"{r['roi']} | {r['position_constrained']} | - | {cells(d)} | {d['iterations']}"
                         f"{'' if d['converged'] else ' (not converged)'} | {d['seconds']:.2f} |")
    devil_ = report[-1]
    lines += ["", f"(c) the horn's curvature detail `D = K A` scaled ({devil_['horn_vertices']} vertices; "
              "ratios to the rest shape):", "",
              "| horn detail | horn length | other horn length | head height | mean \|K\| at the tip | "
              "largest move (%) |", "|---|---:|---:|---:|---:|---:|"]
    for scale in DEVIL["detail_scales"]:
        r = devil_[f"detail_x{scale}"]
        lines.append(f"| x{scale:g} | {r['horn_length_ratio']:.2f} | {r['other_horn_length_ratio']:.2f} | "
                     f"{r['head_height_ratio']:.2f} | {r['tip_curvature_normal_ratio']:.2f} | "
                     f"{100 * r['max_move_fraction']:.1f} |")
    lines += ["", "![Fig. 1](fig1.png)", ""]
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/fig1", help="folder for fig1.json and the pictures (default: %(default)s)")
    ap.add_argument("--docs", default=None,
                    help="also write DOCS/fig1.md, fig1.json and fig1.png (the repository's: docs/results)")
    ap.add_argument("--force", action="store_true", help="replace output files that exist")
    args = ap.parse_args(argv)
    # (elevation, azimuth); (c) shows both horns, the edited one in front
    views = {"fig1a": (10, 0), "fig1b": (10, -90), "fig1c": (10, 20)}
    docs = [os.path.join(args.docs, "fig1" + ext) for ext in (".md", ".json", ".png")] if args.docs else []
    _files.check_outputs(ap, [os.path.join(args.out, key + ".png") for key in views]
                         + [os.path.join(args.out, "fig1.json"), os.path.join(args.out, "fig1.md")] + docs,
                         args.force)
    require("elephant.obj", "cactus.off", "mannequin_devil.off")
    report = []
    for key, make in (("fig1a", elephant), ("fig1b", cactus), ("fig1c", devil)):
        V, F, X, info, y_up = make()
        extra = info.pop("extra_panel", None)
        default = info.pop("default_panel", None)
        label = info.pop("edited_label", "the paper's edit (colour: distance moved)")
        report.append(info)
        show = (lambda P: P @ Y_UP.T) if y_up else (lambda P: P)
        moved = np.linalg.norm(X - V, axis=1)
        elev, azim = views[key]
        panels = [(show(V), F, f"{info['model']}: rest")]
        if extra is not None:
            panels.append((show(extra[0]), F, extra[1], np.linalg.norm(extra[0] - V, axis=1)))
        panels.append((show(X), F, label, moved))
        if default is not None:
            panels.append((show(default[0]), F, default[1], np.linalg.norm(default[0] - V, axis=1)))
        _files.render_panels(os.path.join(args.out, key + ".png"), panels, args.force, elev=elev, azim=azim)
        print(json.dumps(info))
    env = _files.environment()
    result = {"edits": report, **env, **_files.measured_conditions()}
    page = markdown(report, env)
    for folder in [args.out] + ([args.docs] if args.docs else []):
        _files.write_json(os.path.join(folder, "fig1.json"), result, args.force, indent=2, end="\n")
        _files.write_text(os.path.join(folder, "fig1.md"), page, args.force)
    if args.docs:
        # one row per sub-figure, each picture at its own resolution (100 dpi, 4 in per panel)
        _files.stack_pictures(os.path.join(args.docs, "fig1.png"),
                              [os.path.join(args.out, key + ".png") for key in views], args.force)
    return 0


if __name__ == "__main__":
    sys.exit(main())
