"""Reproduce the paper's Fig. 1: mesh editing with curvature detail and curvature coefficients.

(a) elephant: the left ear lengthened (its tip region pulled outwards) and the right ear
    deformed towards the reader;
(b) cactus: three feature points (the tips of the two arms and the top) moved, everything
    else embedded from the precomputed curvature coefficients, the foot fixed;
(c) mannequin_devil: the curvature details of the horn's tip scaled, with only the neck
    boundary fixed in position, so that the whole head is reconstructed. The paper shortens the
    curvature normals to lengthen the horn; with the detail D = K A constrained (rest areas),
    D x 0.5 shortens the horn and D x 2 lengthens it, while the intensive curvature normal
    |K| at the lengthened tip does get shorter (both are reported).

Feature points are found from the geometry (extreme vertices), the regions of interest by
Euclidean distance. Every edit is one CurvatureEditor (constructor = all factoring) and one
solve. Usage: python scripts/reproduce_fig1.py [--out out/fig1] [--docs docs] [--force]
Writes OUT/fig1.json, OUT/fig1a.png, OUT/fig1b.png, OUT/fig1c.png (docs/editing_fig1.png with --docs),
all together at the end (scripts/_outputs.py: none is written where one fails). Before any work,
an existing one is refused unless --force is given (the picture in docs/ is in the repository:
refreshing it is ``--docs docs --force``), and so is a --docs folder that does not exist.
"""

import argparse
import io
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _outputs  # noqa: E402
from _meshes import MESHES, require  # noqa: E402

from curvdetail import CurvatureEditor, boundary_vertices, mean_curvature_normal, read_mesh
from curvdetail.curvature._validate import bbox_diagonal

Y_UP = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])   # display y-up models with z up


def near(V, i, radius):
    return np.flatnonzero(np.linalg.norm(V - V[i], axis=1) < radius)


def summary(name, V, X, ed, seconds):
    moved = np.linalg.norm(X - V, axis=1)
    return {"model": name, "vertices": int(V.shape[0]), "roi": int(ed.roi.size),
            "position_constrained": int(ed.position_constrained.size),
            "detail_constrained": int(ed.detail_constrained.size),
            "rank_deficient": ed.rank_deficient, "detail_islands": ed.detail_islands,
            "max_move_fraction": float(moved.max() / bbox_diagonal(V)),
            "finite": bool(np.isfinite(X).all()), "seconds": seconds}


def elephant():
    V, F = read_mesh(os.path.join(MESHES, "elephant.obj"))       # y up, trunk towards +z
    diag = bbox_diagonal(V)
    left, right = int(np.argmin(V[:, 0])), int(np.argmax(V[:, 0]))  # the ear tips
    roi = np.union1d(near(V, left, 0.25 * diag), near(V, right, 0.25 * diag))
    hl, hr = near(V, left, 0.04 * diag), near(V, right, 0.04 * diag)
    handles = np.concatenate([hl, hr])
    t = time.perf_counter()
    ed = CurvatureEditor(V, F, handles, handles, roi=roi)
    P = V[handles].copy()
    P[:hl.size] += [-0.12 * diag, -0.05 * diag, 0.0]                # lengthen the left ear
    P[hl.size:] += [0.0, 0.0, 0.15 * diag]                          # right ear towards the reader
    X = ed.solve(positions=P)
    return V, F, X, summary("elephant", V, X, ed, time.perf_counter() - t), True


def cactus():
    V, F = read_mesh(os.path.join(MESHES, "cactus.off"))           # z up
    diag = bbox_diagonal(V)
    tips = [int(np.argmin(V[:, 1])), int(np.argmax(V[:, 1])), int(np.argmax(V[:, 2]))]
    foot = V[:, 2] < V[:, 2].min() + 0.12 * np.ptp(V[:, 2])
    roi = np.flatnonzero(~foot)
    handles = np.unique(np.concatenate([near(V, i, 0.03 * diag) for i in tips]))
    t = time.perf_counter()
    ed = CurvatureEditor(V, F, handles, handles, roi=roi)           # coefficients precomputed here
    P = V[handles].copy()
    for i, shift in zip(tips, ([0, -0.1, 0.05], [0.1, 0.08, 0.0], [-0.08, 0.0, 0.04])):
        sel = np.linalg.norm(P - V[i], axis=1) < 0.03 * diag
        P[sel] += np.asarray(shift) * diag
    X = ed.solve(positions=P)
    return V, F, X, summary("cactus", V, X, ed, time.perf_counter() - t), False


def devil():
    V, F = read_mesh(os.path.join(MESHES, "mannequin_devil.off"))  # z up, face towards +x
    diag = bbox_diagonal(V)
    side = V[:, 1] > 0.25 * V[:, 1].max()
    tip = int(np.flatnonzero(side)[np.argmax(V[side, 2])])          # tip of the +y horn
    horn = near(V, tip, 0.03 * diag)
    ring = np.setdiff1d(near(V, tip, 0.06 * diag), near(V, tip, 0.05 * diag))   # around its base
    neck = boundary_vertices(F)
    dc = np.concatenate([neck, horn])
    t = time.perf_counter()
    ed = CurvatureEditor(V, F, neck, dc)                            # whole head rebuilt
    K0, _ = mean_curvature_normal(V, F)
    results = {}
    for scale in (0.5, 2.0):
        D = ed.detail[dc].copy()
        D[neck.size:] *= scale                                      # scale the horn's details
        X = ed.solve(details=D)
        K, _ = mean_curvature_normal(X, F)
        results[scale] = {
            "X": X,
            "horn_length_ratio": float(np.linalg.norm(X[tip] - X[ring].mean(0))
                                       / np.linalg.norm(V[tip] - V[ring].mean(0))),
            "tip_curvature_normal_ratio": float(np.linalg.norm(K[horn], axis=1).mean()
                                                / np.linalg.norm(K0[horn], axis=1).mean())}
    X = results[2.0]["X"]
    info = summary("mannequin_devil", V, X, ed, time.perf_counter() - t)
    for scale, r in results.items():
        info[f"detail_x{scale}"] = {k: v for k, v in r.items() if k != "X"}
    info["extra_panel"] = (results[0.5]["X"],
                           f"horn detail x0.5: horn length x{results[0.5]['horn_length_ratio']:.2f}")
    info["edited_label"] = (f"horn detail x2: horn length x{results[2.0]['horn_length_ratio']:.2f},\n"
                            f"|K| at the tip x{results[2.0]['tip_curvature_normal_ratio']:.2f}")
    return V, F, X, info, False


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/fig1")
    ap.add_argument("--docs", default=None)
    ap.add_argument("--force", action="store_true", help="replace output files that exist")
    args = ap.parse_args(argv)
    views = {"fig1a": (10, 0), "fig1b": (10, -90), "fig1c": (10, -30)}
    run = _outputs.Run(ap, [os.path.join(args.out, key + ".png") for key in views]
                       + [os.path.join(args.out, "fig1.json"),
                          os.path.join(args.docs, "editing_fig1.png") if args.docs else None],
                       args.force, makes=[args.out])
    require("elephant.obj", "cactus.off", "mannequin_devil.off")
    report, docs_panels = [], []
    for key, make in (("fig1a", elephant), ("fig1b", cactus), ("fig1c", devil)):
        V, F, X, info, y_up = make()
        extra = info.pop("extra_panel", None)
        label = info.pop("edited_label", "edited (colour: distance moved)")
        report.append(info)
        show = (lambda P: P @ Y_UP.T) if y_up else (lambda P: P)
        moved = np.linalg.norm(X - V, axis=1)
        elev, azim = views[key]
        panels = [(show(V), F, f"{info['model']}: rest")]
        if extra is not None:
            panels.append((show(extra[0]), F, extra[1], np.linalg.norm(extra[0] - V, axis=1)))
        panels.append((show(X), F, label, moved))
        run.render_panels(os.path.join(args.out, key + ".png"), panels, elev=elev, azim=azim)
        docs_panels += [(show(V), F, f"({key[-1]}) rest"), (show(X), F, f"({key[-1]}) edited", moved)]
        print(json.dumps(info))
    if args.docs:
        # one small composite: rest / edited for each of (a), (b), (c); each pair its own camera
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.image as mpimg
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(1, 3, figsize=(12, 3.2))
        for ax, key in zip(axes, views):
            ax.imshow(mpimg.imread(io.BytesIO(run.read(os.path.join(args.out, key + ".png")))))
            ax.set_axis_off()
        fig.tight_layout()
        try:
            run.save_figure(fig, os.path.join(args.docs, "editing_fig1.png"), dpi=80)
        finally:
            plt.close(fig)
    run.write_json(os.path.join(args.out, "fig1.json"), report, indent=2)
    run.commit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
