"""Speed and memory of the closest-point engine against the engines it replaced, in one run.

A wavy height-field grid of ~100k triangles (224 x 224 vertices) and query points drawn in its
bounding box, within 5 % of its diagonal above and below it (seeded: the same points for every
engine). Each engine runs in a subprocess of its own, so that its peak RSS is its own:

* ``libigl``: ``curvdetail.remesh.closest_points`` (libigl's AABB tree, with the input checks
  and the unit frame);
* ``igl_bare``: ``igl.point_mesh_squared_distance`` alone, the floor of the above;
* with ``--old TREE`` (a checkout of the package before the change, e.g. a worktree of
  c7fe65f, put first on PYTHONPATH), the engines it replaced: ``old_meshlab_grid``
  (``locate(engine="auto")``: pymeshlab's closest-face grid, then the exact barycentrics),
  ``old_kdtree`` (``locate(engine="numpy")``: candidates from a kd-tree of centroids) and
  ``old_box_tree`` (``vertex_distance(far=True)``: the numpy bounding-box tree).

Every engine runs ``--repeat`` times, the rounds interleaved (the machine may be shared);
each result has ``seconds`` (the query alone, the mesh and points built before the clock
starts), ``peak_rss_gb`` (the subprocess's, mesh and points included) and
``max_distance_error`` (largest difference from libigl's distances, relative to the diagonal).

Usage::

    python scripts/bench_closest_point.py --points 100k,1M --old /work/wt-closest-old \\
        --out out/bench_closest_point.json
"""

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

SIDE = 224                                   # 224^2 vertices, 2 * 223^2 = 99,458 triangles
POINTS = {"100k": 100_000, "1M": 1_000_000}
NEW = ("libigl", "igl_bare")
OLD = ("old_meshlab_grid", "old_kdtree", "old_box_tree")


def surface():
    """The wavy grid ``(V, F)`` over the unit square."""
    x, y = np.meshgrid(np.linspace(0.0, 1.0, SIDE), np.linspace(0.0, 1.0, SIDE))
    x, y = x.ravel(), y.ravel()
    z = 0.05 * np.sin(6 * np.pi * x) * np.cos(4 * np.pi * y) + 0.02 * np.sin(2 * np.pi * (7 * x + 5 * y))
    V = np.column_stack([x, y, z])
    i, j = np.meshgrid(np.arange(SIDE - 1), np.arange(SIDE - 1))
    a = (j * SIDE + i).ravel()
    F = np.vstack([np.column_stack([a, a + 1, a + SIDE + 1]), np.column_stack([a, a + SIDE + 1, a + SIDE])])
    return V, F


def queries(V, k):
    """``k`` seeded points in the grid's box, within 5 % of its diagonal above and below it."""
    rng = np.random.default_rng(0)
    d = np.linalg.norm(np.ptp(V, axis=0))
    lo, hi = V.min(axis=0) - [0.0, 0.0, 0.05 * d], V.max(axis=0) + [0.0, 0.0, 0.05 * d]
    return lo + rng.random((k, 3)) * (hi - lo)


def run_engine(engine, k):
    """Distances of the ``k`` points by ``engine`` and the seconds the query took."""
    V, F = surface()
    P = queries(V, k)
    t = time.perf_counter()
    if engine == "libigl":
        from curvdetail.remesh import closest_points

        d = np.sqrt(closest_points(P, V, F)[0])
    elif engine == "igl_bare":
        import igl

        d = np.sqrt(igl.point_mesh_squared_distance(P, V, F)[0])
    elif engine == "old_box_tree":
        from curvdetail.remesh import vertex_distance

        d = vertex_distance(P, V, F, far=True)
    else:
        from curvdetail.remesh import locate

        d = locate(P, V, F, engine="auto" if engine == "old_meshlab_grid" else "numpy")[2]
    return d, time.perf_counter() - t


def child(engine, k, out):
    d, seconds = run_engine(engine, int(k))
    np.save(out, d)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0 ** 2
    print("RESULT " + json.dumps({"seconds": seconds, "peak_rss_gb": peak}), flush=True)


def in_subprocess(engine, k, old, folder, timeout):
    """One engine at ``k`` points in its own process (the old tree first on its path for the
    old engines): its figures, and its distances in ``folder``."""
    env = dict(os.environ)
    if engine in OLD:
        env["PYTHONPATH"] = os.pathsep.join([old] + [p for p in [env.get("PYTHONPATH")] if p])
    out = os.path.join(folder, f"{engine}_{k}.npy")
    cmd = [sys.executable, os.path.abspath(__file__), "--child", engine, str(k), out]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return {"error": f"over {timeout} s"}, None
    lines = [line for line in done.stdout.splitlines() if line.startswith("RESULT ")]
    if done.returncode != 0 or not lines:
        return {"error": (done.stderr.strip().splitlines() or ["no output"])[-1]}, None
    return json.loads(lines[-1][len("RESULT "):]), np.load(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", default="100k,1M", help="comma-separated: " + ", ".join(POINTS))
    ap.add_argument("--old", help="a checkout of the package before the change (runs the old engines)")
    ap.add_argument("--out", default="out/bench_closest_point.json", help="JSON results (default: %(default)s)")
    ap.add_argument("--force", action="store_true", help="replace OUT if it exists")
    ap.add_argument("--repeat", type=int, default=2, help="rounds over the engines, interleaved (default: %(default)s)")
    ap.add_argument("--timeout", type=int, default=900, help="seconds per engine and size")
    ap.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        child(*args.child)
        return 0
    from curvdetail.io.atomic import atomic_write, check_output_path

    sizes = [s for s in args.points.split(",") if s]
    if not sizes or any(s not in POINTS for s in sizes):
        ap.error(f"--points: choose from {', '.join(POINTS)} (a comma list).")
    if args.old and not os.path.isdir(os.path.join(args.old, "curvdetail")):
        ap.error(f"--old {args.old}: no curvdetail package there.")
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    check_output_path(args.out, args.force, parameter="--out")
    V, F = surface()
    diagonal = float(np.linalg.norm(np.ptp(V, axis=0)))
    engines = NEW + (OLD if args.old else ())
    results = []
    with tempfile.TemporaryDirectory(prefix="bench_closest_point_") as folder:
        for size in sizes:
            k = POINTS[size]
            reference = None
            for round_, engine in ((i, e) for i in range(max(1, args.repeat)) for e in engines):
                r, d = in_subprocess(engine, k, args.old, folder, args.timeout)
                if engine == "libigl" and reference is None:
                    reference = d
                if d is not None and reference is not None:
                    r["max_distance_error"] = float(np.abs(d - reference).max() / diagonal)
                r.update(engine=engine, points=k, round=round_, load_average=os.getloadavg()[0])
                results.append(r)
                shown = ", ".join(f"{key} {v:.3g}" if isinstance(v, float) else f"{key} {v}" for key, v in r.items())
                print(f"{size}: {shown}", flush=True)
    best = {}
    for r in results:
        if "seconds" in r:
            key = f"{r['engine']} {r['points']}"
            best[key] = min(best.get(key, np.inf), r["seconds"])
    report = {"machine": {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count()},
              "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "old_tree": args.old,
              "mesh": {"vertices": int(V.shape[0]), "triangles": int(F.shape[0]), "diagonal": diagonal},
              "best_seconds": best, "results": results}
    with atomic_write(args.out, overwrite=args.force, parameter="--out") as tmp:
        with open(tmp, "w") as f:
            json.dump(report, f, indent=2)
            f.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
