"""Speed and memory of the operations around the solver, each against its peer in the same run.

The reconstruction solve has its own benchmark (bench_reconstruct.py). This one times, on a
height-field grid of the given sizes (a second grid of half the vertices is the "target"
mesh), each case in its own subprocess so that its peak RSS is its own:

* ``edge_curvature_measure`` (the conservative transfer's measure) against the same sums
  keyed by a row-wise ``np.unique(axis=0)``, the implementation it replaced;
* the editor's curvature stage ``(I - C)``: SuperLU against PARDISO (``CurvatureEditor``'s
  ``timings["curvature_setup"]`` and a three-column back-substitution), the two sides of the
  size rule ``CURVATURE_SPLU_MAX``;
* ``hausdorff`` with pymeshlab's engine against the exact engine (1M samples each way; the
  closest-point engine itself against the ones it replaced: bench_closest_point.py);
* ``read_mesh`` (pymeshlab's load with the checks before and after it) against a bare
  ``pymeshlab.MeshSet().load_new_mesh`` and its vertex and face matrices, per format (OBJ, OFF,
  PLY, STL as ``write_mesh`` writes them: ASCII OBJ and OFF, binary PLY and STL); the grid's
  files are written once per size, by a subprocess of their own, into a scratch folder, and
  only the reading is timed.

Usage::

    python scripts/bench_operations.py --sizes 100k --out out/bench_operations.json
    python scripts/bench_operations.py --sizes 100k,1M --out out/bench_operations.json --force

The machine's load average is recorded beside the times (the machine is shared). OUT is written
atomically; an existing OUT is refused before any case runs unless --force is given.
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

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from curvdetail.cli import whole_number_from_one as at_least_one  # noqa: E402 (the CLI's option type)
import _files  # noqa: E402

SIDES = {"10k": 100, "100k": 316, "1M": 1000}
CASES = {
    "edge_measure": ("int64 keys", "np.unique(axis=0)"),
    "curvature_stage": ("splu", "pardiso"),
    "hausdorff": ("meshlab", "exact"),
    "read_obj": ("read_mesh", "pymeshlab"),
    "read_off": ("read_mesh", "pymeshlab"),
    "read_ply": ("read_mesh", "pymeshlab"),
    "read_stl": ("read_mesh", "pymeshlab"),
}
READ_FORMATS = ("obj", "off", "ply", "stl")
#: The environment variable naming the scratch folder of the read cases' files (set by main).
FILES = "BENCH_OPERATIONS_FILES"


def grid_surface(side):
    from curvdetail.curvature.testing import grid

    V, F = grid(side, side)
    x, y = V[:, 0], V[:, 1]
    V[:, 2] = 0.05 * np.sin(6 * np.pi * x) * np.cos(4 * np.pi * y) + 0.02 * np.sin(2 * np.pi * (7 * x + 5 * y))
    return V, F


def _edge_measure_by_rows(V, F):
    """The row-wise unique that ``edge_curvature_measure`` used before (the peer)."""
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    ends = np.stack([F[:, [1, 2]], F[:, [2, 0]], F[:, [0, 1]]], axis=1).reshape(-1, 2)
    g = np.cross(V[ends[:, 1]] - V[ends[:, 0]], np.repeat(n, 3, axis=0))
    E, inverse = np.unique(np.sort(ends, axis=1), axis=0, return_inverse=True)
    meas = np.zeros((E.shape[0], 3))
    np.add.at(meas, inverse.reshape(-1), g)
    return E, meas


def mesh_file(folder, size, extension):
    """The grid's file of one format in the read cases' scratch folder."""
    return os.path.join(folder, f"grid_{size}.{extension}")


def write_files(folder, size):
    """Write the grid of ``size`` in each of ``READ_FORMATS`` into ``folder`` (in a subprocess of
    its own, so that no case's peak RSS holds the writing)."""
    from curvdetail import write_mesh

    V, F = grid_surface(SIDES[size])
    for extension in READ_FORMATS:
        write_mesh(mesh_file(folder, size, extension), V, F, overwrite=True)


def run_read_case(case, variant, size):
    """Time reading the grid's file of the case's format: ``read_mesh`` or bare pymeshlab."""
    import pymeshlab

    from curvdetail import read_mesh

    path = mesh_file(os.environ[FILES], size, case[len("read_"):])
    out = {"file_mb": os.path.getsize(path) / 1e6}
    t = time.perf_counter()
    if variant == "read_mesh":
        V, F = read_mesh(path)
    else:
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(path)
        V, F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    out["seconds"] = time.perf_counter() - t
    out.update(vertices=int(V.shape[0]), faces=int(F.shape[0]),
               peak_rss_gb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0 ** 2)
    return out


def run_case(case, variant, size):
    """Time one variant of one case in this process; a dict of figures."""
    if case.startswith("read_"):
        return run_read_case(case, variant, size)
    from curvdetail import CurvatureEditor, boundary_vertices
    from curvdetail.remesh import hausdorff
    from curvdetail.remesh.transfer import _edge_curvature_measure

    V, F = grid_surface(SIDES[size])
    out = {"vertices": int(V.shape[0])}
    t = time.perf_counter()
    if case == "edge_measure":
        E, _ = _edge_curvature_measure(V, F) if variant == "int64 keys" else _edge_measure_by_rows(V, F)
        out["edges"] = int(E.shape[0])
    elif case == "curvature_stage":
        b = boundary_vertices(F)
        centre = int(np.argmin(np.linalg.norm(V[:, :2] - 0.5, axis=1)))
        handles = np.union1d(b, np.unique(F[(F == centre).any(axis=1)]))
        editor = CurvatureEditor(V, F, handles, handles, rows="free", backend=variant)
        out["setup_s"] = editor.timings["curvature_setup"]
        rhs = np.random.default_rng(0).normal(size=(editor._fd.size, 3))
        solves = []
        for _ in range(3):
            s = time.perf_counter()
            editor._curv.solve(rhs)
            solves.append(time.perf_counter() - s)
        out.update(unknowns=int(editor._fd.size), solve_s=float(np.median(solves)))
    else:                                   # hausdorff
        Vt, Ft = grid_surface(SIDES[size] * 7 // 10)
        h = hausdorff(Vt, Ft, V, F, engine=variant, samples=1_000_000)
        out.update(max=h["max"], rms=h["rms"], samples=h["samples"])
    out["seconds"] = time.perf_counter() - t
    out["peak_rss_gb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0 ** 2
    return out


def in_subprocess(case, variant, size, timeout):
    cmd = [sys.executable, os.path.abspath(__file__), "--child", case, variant, size]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"error": f"over {timeout} s"}
    lines = [line for line in done.stdout.splitlines() if line.startswith("RESULT ")]
    if done.returncode != 0 or not lines:
        return {"error": (done.stderr.strip().splitlines() or ["no output"])[-1]}
    return json.loads(lines[-1][len("RESULT "):])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="100k", help="comma-separated: 10k, 100k, 1M")
    ap.add_argument("--cases", default=",".join(CASES), help="comma-separated: " + ", ".join(CASES))
    ap.add_argument("--out", default="out/bench_operations.json", help="JSON results (default: %(default)s)")
    ap.add_argument("--force", action="store_true", help="replace OUT if it exists")
    ap.add_argument("--timeout", type=at_least_one, default=900, help="seconds per case")
    ap.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    ap.add_argument("--write-files", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        print("RESULT " + json.dumps(run_case(*args.child)), flush=True)
        return 0
    if args.write_files:
        write_files(*args.write_files)
        return 0
    sizes = [s for s in args.sizes.split(",") if s]
    cases = [c for c in args.cases.split(",") if c]
    for option, given, allowed in (("--sizes", sizes, SIDES), ("--cases", cases, CASES)):
        unknown = [name for name in given if name not in allowed]
        if unknown or not given:
            ap.error(f"{option}: {'unknown ' + ', '.join(map(repr, unknown)) if unknown else 'none given'}; "
                     f"choose from {', '.join(allowed)} (a comma list).")
    _files.check_outputs(ap, [args.out], args.force)
    results = []
    with tempfile.TemporaryDirectory(prefix="bench_operations_") as folder:
        os.environ[FILES] = folder                             # for the read cases' subprocesses
        for size in sizes:
            run_cases(cases, size, args.timeout, folder, results)
    report = {"machine": {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count()},
              "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "results": results}
    _files.write_json(args.out, report, args.force, indent=2, end="\n")
    return 0


def run_cases(cases, size, timeout, folder, results):
    """Run ``cases`` at ``size``, each variant in its own subprocess, appending to ``results``."""
    written = None
    for case in cases:
        if case.startswith("read_") and written is None:
            cmd = [sys.executable, os.path.abspath(__file__), "--write-files", folder, size]
            try:
                done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
                written = done.returncode == 0 or (done.stderr.strip().splitlines() or ["no output"])[-1]
            except subprocess.TimeoutExpired:
                written = f"writing the files took over {timeout} s"
        for variant in CASES[case]:
            if case.startswith("read_") and written is not True:
                r = {"error": f"the grid's files were not written: {written}"}
            else:
                r = in_subprocess(case, variant, size, timeout)
            r.update(case=case, variant=variant, size=size, load_average=os.getloadavg()[0])
            results.append(r)
            shown = ", ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}"
                              for k, v in r.items() if k not in ("case", "variant", "size"))
            print(f"{size} {case} [{variant}]: {shown}", flush=True)
    for extension in READ_FORMATS if written is True else ():  # the 1M grid's are ~350 MB in all
        os.remove(mesh_file(folder, size, extension))


if __name__ == "__main__":
    sys.exit(main())
