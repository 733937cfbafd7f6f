"""Compare curvature-detail editing with libigl and the survey on the Botsch-Sorkine benchmark.

For each of the four cases (bar, cactus, cylinder, plane) run, with the files' selection and
transform: ours rotation-aware (``edit_with_selection``'s default), the paper's linear edit (handle
details transformed, one-ring relations) and its one- plus two-ring variant, libigl's ARAP
(spokes-and-rims energy, ``MAX_ITER`` iterations from the rest shape, fixed and handle vertices
constrained) and libigl's biharmonic deformation (``igl.harmonic`` with k = 2 on the
displacements). Each result is measured against the survey's ``NAME-laplacian_editing.off`` (same
connectivity: vertex-to-vertex distance, mean and max over the bbox diagonal), for folded triangles
(normal against both its rest normal and the handle-turned one), the mean relative edge-length
change over the edges with a non-fixed end, and the area kept by the free region (status 1) and by
the handles' triangles, and the warnings each run raised. Times: setup (factoring), one iteration
(the iterative methods), and a re-solve (ours: a solve warm-started from the result; paper: a
back-substitution; ARAP: one more iteration from its result); "per iteration / ARAP" is the
per-iteration time over libigl ARAP's on the same case and run.

On the cactus, the turn of the trunk above the arms and of the upper arm (best-fit rotation,
rest to result) and the upper arm's area kept, the parts defined from the rest shape
(`cactus_parts`; the table's caption states the definition).

Usage: python scripts/compare_deformation_benchmark.py [--out docs/results] [--pictures DIR] [--force]
Writes OUT/deformation.json and OUT/deformation.md (and DIR/deformation_NAME.png with --pictures),
each atomically; an existing one is refused before any work unless --force is given.
"""

import argparse
import os
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _files  # noqa: E402
from _meshes import MESHES, require  # noqa: E402

from curvdetail import read_mesh  # noqa: E402
from curvdetail.curvature.rotation_editor import RotationAwareEditor  # noqa: E402
from curvdetail.curvature.geometry import bbox_diagonal, face_double_areas, folded_triangles  # noqa: E402
from curvdetail.io.deformation import (apply_transform, edit_with_selection, read_selection,  # noqa: E402
                                       read_transform)

CASES = ("bar", "cactus", "cylinder", "plane")
METHODS = ("rotation", "paper", "paper one+two-ring", "igl arap", "igl biharmonic")
#: libigl ARAP iterations (its own default is 10; converged figures need more)
MAX_ITER = 100
VIEWS = {"bar": (15, -60), "cactus": (10, -90), "cylinder": (10, 0), "plane": (30, -60)}


def _edges(F):
    e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    return np.unique(e, axis=0)


def _ours(V, F, status, T, method):
    if method == "rotation":
        X = edit_with_selection(V, F, status, T)                    # the default settings
        h = np.flatnonzero(status == 2)
        t = time.perf_counter()
        ed = RotationAwareEditor(V, F, h, roi=np.flatnonzero(status != 0))
        setup = time.perf_counter() - t
        t = time.perf_counter()
        ed.solve(X[h])
        solve = time.perf_counter() - t
        iterations, converged = ed.iterations, ed.converged
        t = time.perf_counter()
        ed.solve(X[h], initial=X)
        return X, {"setup_s": setup, "iterations": iterations, "converged": converged,
                   "iteration_s": solve / max(iterations, 1), "resolve_s": time.perf_counter() - t,
                   "resolve_iterations": ed.iterations, "backend": ed.backend}
    relations = "one+two-ring" if method.endswith("one+two-ring") else "one-ring"
    X, ed = edit_with_selection(V, F, status, T, method="paper", relations=relations, return_editor=True)
    h = ed.position_constrained
    details = ed.detail[h] @ T[:3, :3].T
    ed.solve(positions=X[h], details=details)                  # warm-up
    t = time.perf_counter()
    ed.solve(positions=X[h], details=details)
    resolve = time.perf_counter() - t
    return X, {"setup_s": sum(ed.timings.values()), "iterations": None, "iteration_s": None, "resolve_s": resolve,
               "backend": ed.backend}


def _igl(V, F, status, T, method):
    import igl

    b = np.flatnonzero(status != 1)
    bc = V[b].copy()
    handles = status[b] == 2
    bc[handles] = apply_transform(T, V[b][handles])
    Fi = F.astype(np.int64)
    if method == "igl biharmonic":
        t = time.perf_counter()
        X = V + igl.harmonic(V, Fi, b.astype(np.int64), bc - V[b], 2)
        return X, {"setup_s": None, "iterations": None, "iteration_s": None, "resolve_s": time.perf_counter() - t,
                   "backend": "libigl"}
    data = igl.ARAPData()
    data.energy = igl.ARAP_ENERGY_TYPE_SPOKES_AND_RIMS
    t = time.perf_counter()
    igl.arap_precomputation(V, Fi, 3, b.astype(np.int32), data)
    setup = time.perf_counter() - t
    data.max_iter = MAX_ITER
    U0 = V.copy()
    U0[b] = bc
    t = time.perf_counter()
    X = igl.arap_solve(bc, data, U0)
    solve = time.perf_counter() - t
    data.max_iter = 1
    t = time.perf_counter()
    igl.arap_solve(bc, data, X)
    one = time.perf_counter() - t
    return X, {"setup_s": setup, "iterations": MAX_ITER, "iteration_s": solve / MAX_ITER, "resolve_s": one,
               "backend": "libigl"}


def cactus_parts(V, status):
    """``{"trunk above the arms": mask, "upper arm": mask}`` of the rest cactus (z up, arms along y).

    An arm: the vertices more than 1 % of the bbox diagonal beyond the fixed foot's y-extent on
    its side; the upper arm: the arm whose lowest vertex is higher; its junction: its vertices
    within 3 % of the diagonal of that side; the trunk above the arms: the free vertices within the
    foot's y-extent above the junction's highest vertex.
    """
    foot = V[status == 0, 1]
    margin = 0.01 * bbox_diagonal(V)
    arms = [V[:, 1] < foot.min() - margin, V[:, 1] > foot.max() + margin]
    upper, side = max(zip(arms, (foot.min(), foot.max())), key=lambda a: V[a[0], 2].min())
    junction = upper & (np.abs(V[:, 1] - side) < 3 * margin)
    trunk = (status == 1) & (V[:, 1] >= foot.min()) & (V[:, 1] <= foot.max()) & (V[:, 2] > V[junction, 2].max())
    return {"trunk above the arms": trunk, "upper arm": upper}


def turn_degrees(P, Q):
    """Angle (degrees) of the rotation that best maps the points ``P`` to ``Q``, centroids removed."""
    U, _, Wt = np.linalg.svd((Q - Q.mean(0)).T @ (P - P.mean(0)))
    R = U @ np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Wt))]) @ Wt
    return float(np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1.0, 1.0))))


def measure_parts(V, F, X, parts):
    """Turn (degrees) of each part and the area kept by the upper arm's triangles."""
    arm = parts["upper arm"][F].all(axis=1)
    return {"turn_trunk": turn_degrees(V[parts["trunk above the arms"]], X[parts["trunk above the arms"]]),
            "turn_upper_arm": turn_degrees(V[parts["upper arm"]], X[parts["upper arm"]]),
            "area_upper_arm": float(face_double_areas(X, F[arm]).sum() / face_double_areas(V, F[arm]).sum())}


def measure(V, F, status, T, X, ref, E):
    diag = bbox_diagonal(V)
    dist = np.linalg.norm(X - ref, axis=1) / diag
    in_region = (status[E] != 0).any(axis=1)
    l0 = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)[in_region]
    l1 = np.linalg.norm(X[E[:, 0]] - X[E[:, 1]], axis=1)[in_region]
    A0, A1 = face_double_areas(V, F), face_double_areas(X, F)
    free, handle = (status[F] == 1).all(axis=1), (status[F] == 2).any(axis=1)
    return {"mean": float(dist.mean()), "max": float(dist.max()),
            "folded": int(folded_triangles(V, F, X, T[:3, :3]).size),
            "edge_change": float(np.mean(np.abs(l1 - l0) / l0)),
            "area_free": float(A1[free].sum() / A0[free].sum()),
            "area_handle": float(A1[handle].sum() / A0[handle].sum()),
            "finite": bool(np.isfinite(X).all())}


def run_case(name, folder):
    V, F = read_mesh(os.path.join(folder, name + ".off"))
    status = read_selection(os.path.join(folder, name + ".sel"), V.shape[0])
    T = read_transform(os.path.join(folder, name + ".def"))
    ref, Fr = read_mesh(os.path.join(folder, name + "-laplacian_editing.off"))
    if not np.array_equal(Fr, F):
        raise ValueError(f"{name}: the reference result has a different connectivity.")
    E = _edges(F)
    row = {"case": name, "vertices": int(V.shape[0]), "faces": int(F.shape[0]),
           "counts": np.bincount(status, minlength=3).tolist(), "survey": measure(V, F, status, T, ref, ref, E)}
    parts = cactus_parts(V, status) if name == "cactus" else None
    if parts:
        row["parts"] = {k: int(v.sum()) for k, v in parts.items()}
        row["handle_turn"] = turn_degrees(V[status == 2], apply_transform(T, V[status == 2]))
        row["survey"].update(measure_parts(V, F, ref, parts))
    results = {}
    for method in METHODS:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            X, times = (_igl if method.startswith("igl") else _ours)(V, F, status, T, method)
        row[method] = {**measure(V, F, status, T, X, ref, E), **times,
                       "warnings": [f"{w.category.__name__}: {w.message}" for w in caught]}
        if parts:
            row[method].update(measure_parts(V, F, X, parts))
        results[method] = X
        print(name, method, {k: (round(v, 4) if isinstance(v, float) else v) for k, v in row[method].items()},
              flush=True)
    return row, (V, F, status, results, ref)


def _cell(value, fmt):
    return "-" if value is None else format(value, fmt)


def table(rows):
    lines = ["| case | method | to survey mean / max (% diag) | folded | warnings | edge-length change "
             "| area free / handle | setup (s) | iterations | per iteration (ms) | per iteration / ARAP | re-solve (ms) |",
             "|---|---|---|---:|---|---:|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        arap = r["igl arap"]["iteration_s"]
        for m in METHODS:
            x = r[m]
            lines.append(f"| {r['case']} | {m} | {100 * x['mean']:.2f} / {100 * x['max']:.2f} | {x['folded']} | "
                         f"{', '.join(sorted({w.split(':')[0] for w in x['warnings']})) or 'none'} | {x['edge_change']:.4f} | {x['area_free']:.3f} / {x['area_handle']:.3f} | "
                         f"{_cell(x['setup_s'], '.3f')} | {_cell(x['iterations'], 'd')} | "
                         f"{_cell(x['iteration_s'] and 1e3 * x['iteration_s'], '.2f')} | "
                         f"{_cell(x['iteration_s'] and x['iteration_s'] / arap, '.2f')} | {1e3 * x['resolve_s']:.1f} |")
    return "\n".join(lines)


def parts_table(row):
    """The cactus's parts: turns against the handle's and the upper arm's area kept."""
    lines = [f"Cactus parts (the handle turns {row['handle_turn']:.1f} degrees; targets: the trunk within 10 degrees "
             "of it, the upper arm >= 0.90 of its area). The parts, from the rest shape: an arm is the vertices more "
             "than 1 % of the bbox diagonal beyond the fixed foot's y-extent (the trunk's width) on its side; the "
             "upper arm is the arm whose lowest vertex is higher; the trunk above the arms is the free vertices "
             "within the foot's y-extent above the upper arm's junction (its vertices within 3 % of the diagonal "
             f"of the trunk's side) ({row['parts']['trunk above the arms']} and {row['parts']['upper arm']} "
             "vertices). Turn: angle of the best-fit rotation of the part, rest to result (Kabsch); area: over the "
             "triangles with all three vertices in the arm.", "",
             "| method | trunk turn (degrees) | upper arm turn (degrees) | upper arm area kept |", "|---|---:|---:|---:|"]
    for m in ("survey", *METHODS):
        x = row[m]
        lines.append(f"| {m} | {x['turn_trunk']:.1f} | {x['turn_upper_arm']:.1f} | {x['area_upper_arm']:.3f} |")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/results", help="folder for deformation.json/.md (default: %(default)s)")
    ap.add_argument("--pictures", default=None, help="also write DIR/deformation_NAME.png, the methods side by side")
    ap.add_argument("--force", action="store_true", help="replace output files that exist")
    args = ap.parse_args(argv)
    json_path, md_path = (os.path.join(args.out, "deformation" + ext) for ext in (".json", ".md"))
    pictures = [os.path.join(args.pictures, f"deformation_{n}.png") for n in CASES] if args.pictures else []
    _files.check_outputs(ap, [json_path, md_path, *pictures], args.force)
    require("deformation")
    folder = os.path.join(MESHES, "deformation")
    rows = []
    for k, name in enumerate(CASES):
        row, (V, F, status, results, ref) = run_case(name, folder)
        rows.append(row)
        if pictures:
            lo, hi = ref.min(0), ref.max(0)
            pad = 0.5 * (hi - lo)            # a diverged result is drawn clipped to the survey's box
            panels = [(V, F, "rest: fixed / free / handle", status)]
            panels += [(np.clip(results[m], lo - pad, hi + pad), F,
                        f"{m}\n{row[m]['folded']} folded, edges {row[m]['edge_change']:.3f}") for m in METHODS]
            panels.append((ref, F, "survey: Laplacian editing"))
            elev, azim = VIEWS[name]
            _files.render_panels(pictures[k], panels, args.force, elev=elev, azim=azim, panel_size=2.6)
    text = table(rows) + "\n\n" + "".join(parts_table(r) for r in rows if "parts" in r)
    print(text)
    conditions = _files.measured_conditions()
    _files.write_json(json_path, {"methods": METHODS, "igl_arap_iterations": MAX_ITER, "rows": rows, **conditions},
                      args.force, indent=2, end="\n")
    images = "".join(f"\n![{n}]({os.path.relpath(p, os.path.dirname(os.path.abspath(md_path)))})\n"
                     for n, p in zip(CASES, map(os.path.abspath, pictures)))
    _files.write_text(md_path, "# Deformation benchmark (Botsch & Sorkine 2008)\n\n"
                      "Written by `python scripts/compare_deformation_benchmark.py --pictures docs/results --force` "
                      "(see docs/guide/editing.md); distances over the rest bbox diagonal, edge-length change relative "
                      "to the rest lengths, areas as fractions of the rest areas. Times on a shared host, load "
                      f"average {conditions['load_average'][0]:.1f} at the end (deformation.json): "
                      "compare them within a run only.\n\n" + text + "\n" + images, args.force)
    return 0


if __name__ == "__main__":
    sys.exit(main())
