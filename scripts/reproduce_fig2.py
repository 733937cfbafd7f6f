"""Reproduce the paper's Fig. 2: shape editing.

(a) cow: the whole head is the region of interest; its front (muzzle, ears, horns) is turned
    by 35 degrees about the vertical axis and moved towards the reader, the handles' curvature
    normals turned with it; the neck and body stay fixed. Shown with the handles' details
    transformed (the paper's one-ring relations, and one- plus two-ring relations) and solved
    freely.
(b) terrain patch (SRTM, terrainA_10k): the boundary moved by a sine along its arc length, in y
    and in z; the boundary's curvature detail is updated accordingly (recomputed on the
    harmonically deformed patch, the paper) or kept, and the inside rebuilt from the curvature
    coefficients (``edit_boundary``), with the paper's one-ring relations and with one- plus
    two-ring relations. Folded triangles (normals pointing down) are counted.

Usage: python scripts/reproduce_fig2.py [--out out/fig2] [--docs docs] [--force]
Writes OUT/fig2.json, OUT/fig2a.png, OUT/fig2b.png (docs/editing_fig2.png with --docs), all
together at the end (scripts/_outputs.py: none is written where one fails). Before any work, an
existing one is refused unless --force is given (the picture in docs/ is in the repository:
refreshing it is ``--docs docs --force``), and so is a --docs folder that does not exist.
"""

import argparse
import io
import json
import os
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _outputs  # noqa: E402
from _meshes import MESHES, require  # noqa: E402

from curvdetail import edit_boundary, read_mesh, sine_displacement
from curvdetail.curvature._validate import bbox_diagonal
from curvdetail.curvature.errors import FoldedTrianglesWarning
from curvdetail.deformation_benchmark import edit_with_selection, view_direction

Y_UP = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])   # display y-up models with z up
COW_VIEW = (15, 30)


def cow():
    V, F = read_mesh(os.path.join(MESHES, "cow.off"))              # y up, head towards +x
    diag = bbox_diagonal(V)
    status = np.where(V[:, 0] > 0.42, 2, np.where(V[:, 0] > 0.18, 1, 0))
    toward = Y_UP.T @ view_direction(*COW_VIEW)                    # the reader, in cow coordinates
    toward[1] = 0.0
    toward /= np.linalg.norm(toward)
    # turn about the vertical (y) axis through the neck, so the muzzle swings towards the reader
    pivot = np.array([0.3, V[status == 2, 1].mean(), V[status == 2, 2].mean()])
    sign = np.sign(np.cross([1.0, 0, 0], toward)[1]) or 1.0
    a = np.radians(35.0) * sign
    R = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = pivot - R @ pivot + 0.08 * diag * toward
    out, meshes = {"model": "cow", "vertices": int(V.shape[0]), "roi": int((status > 0).sum()),
                   "handles": int((status == 2).sum())}, {}
    for mode, relations in (("transform", "one-ring"), ("transform", "one+two-ring"), ("free", "one-ring")):
        t = time.perf_counter()
        X, ed = edit_with_selection(V, F, status, T, handle_detail=mode, relations=relations,
                                    return_editor=True)
        mode = f"{mode}/{relations}"
        out[mode] = {"seconds": time.perf_counter() - t,
                     "max_move_fraction": float(np.linalg.norm(X - V, axis=1).max() / diag),
                     "finite": bool(np.isfinite(X).all()), "rank_deficient": ed.rank_deficient}
        meshes[mode] = X
    return V, F, status, meshes, out


def folded(X, F):
    """Triangles whose normal points down (the patch is a height field, z up)."""
    n = np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]])
    return int((n[:, 2] < 0).sum())


def terrain():
    V, F = read_mesh(os.path.join(MESHES, "terrainA_10k.obj"))
    extent = np.ptp(V[:, :2], axis=0).max()
    out, meshes = {"model": "terrainA_10k", "vertices": int(V.shape[0]), "rest_folded": folded(V, F)}, {}
    for axis, name, amp in ((1, "sine_y", 0.06 * extent), (2, "sine_z", 0.08 * extent)):
        for mode, relations in (("deformed", "one-ring"), ("deformed", "one+two-ring"), ("rest", "one-ring")):
            t = time.perf_counter()
            with warnings.catch_warnings():
                # the paper's one-ring cases fold on purpose here: counted below, not warned
                warnings.simplefilter("ignore", FoldedTrianglesWarning)
                X, info = edit_boundary(V, F, sine_displacement(amp, periods=2, axis=axis),
                                        boundary_detail=mode, relations=relations, return_info=True)
            b = info["boundary"]
            mode = f"{mode}/{relations}"
            out[f"{name}_{mode}"] = {
                "amplitude": float(amp), "periods": 2, "boundary_detail": mode, "relations": relations,
                "seconds": time.perf_counter() - t, "boundary_vertices": int(b.size),
                "max_move_fraction": float(np.linalg.norm(X - V, axis=1).max() / bbox_diagonal(V)),
                "height_range_ratio": float(np.ptp(X[:, 2]) / np.ptp(V[:, 2])),
                "folded_triangles": folded(X, F), "folded_against_rest": info["folded_triangles"],
                "amplification": info["amplification"], "finite": bool(np.isfinite(X).all())}
            meshes[f"{name}_{mode}"] = X
    return V, F, meshes, out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/fig2")
    ap.add_argument("--docs", default=None)
    ap.add_argument("--force", action="store_true", help="replace output files that exist")
    args = ap.parse_args(argv)
    run = _outputs.Run(ap, [os.path.join(args.out, name) for name in ("fig2a.png", "fig2b.png", "fig2.json")]
                       + [os.path.join(args.docs, "editing_fig2.png") if args.docs else None],
                       args.force, makes=[args.out])
    require("cow.off", "terrainA_10k.obj")
    V, F, status, meshes, info_a = cow()
    print(json.dumps(info_a))
    panels = [(V @ Y_UP.T, F, "cow: rest (fixed / region / handle)", status)]
    for mode, label in (("transform/one-ring", "handle details turned (paper)"),
                        ("transform/one+two-ring", "turned, one+two-ring relations"),
                        ("free/one-ring", "handle details free")):
        X = meshes[mode]
        panels.append((X @ Y_UP.T, F, label, np.linalg.norm(X - V, axis=1)))
    run.render_panels(os.path.join(args.out, "fig2a.png"), panels, elev=COW_VIEW[0], azim=COW_VIEW[1])
    Vt, Ft, tmeshes, info_b = terrain()
    print(json.dumps(info_b))
    panels = [(Vt, Ft, "terrain: rest", Vt[:, 2])]
    for key, label in (("sine_y", "sine in y"), ("sine_z", "sine in z")):
        for mode, short in (("deformed/one-ring", "(paper)"), ("deformed/one+two-ring", "one+two-ring")):
            X = tmeshes[f"{key}_{mode}"]
            folds = info_b[key + "_" + mode]["folded_triangles"]
            panels.append((X, Ft, f"{label} {short}\n{folds} folded triangles", X[:, 2]))
    run.render_panels(os.path.join(args.out, "fig2b.png"), panels, elev=35, azim=-60, panel_size=3.0)
    run.write_json(os.path.join(args.out, "fig2.json"), {"cow": info_a, "terrain": info_b}, indent=2)
    if args.docs:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.image as mpimg
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(2, 1, figsize=(11, 6.2))
        for ax, key in zip(axes, ("fig2a", "fig2b")):
            ax.imshow(mpimg.imread(io.BytesIO(run.read(os.path.join(args.out, key + ".png")))))
            ax.set_axis_off()
        fig.tight_layout()
        try:
            run.save_figure(fig, os.path.join(args.docs, "editing_fig2.png"), dpi=75)
        finally:
            plt.close(fig)
    run.commit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
