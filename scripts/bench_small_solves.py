"""Small re-solves on a quiet and on a busy machine: ours against libigl's ``min_quad_with_fixed``.

The system is the one every editor re-solves: the free block ``L_ff`` of the cotangent
Laplacian of a bumpy grid with its boundary fixed, three right-hand sides (x, y, z) built from
new boundary values ``-L_fb Y_b``. Arms: ``factorize(..., backend=B)`` for B in auto, pardiso,
splu, and libigl's ``min_quad_with_fixed_precompute`` / ``min_quad_with_fixed_solve`` (the same
energy, ``pd=True``). A re-solve is timed from the boundary values to the free positions, the
arms interleaved sample by sample, median of ``--repeats``; factor times are the best of three.
Every size runs twice: quiet (as the machine is) and busy (the script starts ``--busy``
processes that spin on the CPU, and stops them on exit, Ctrl-C included). The load average is
recorded at each condition's start and end.

Usage: python scripts/bench_small_solves.py [--sizes 2000,5000,10000,20000,40000] [--repeats 60]
       [--busy 2] [--out docs/results] [--force]
Writes OUT/small_solves.json and OUT/small_solves.md atomically; an existing one is refused
before any work unless --force is given.
"""

import argparse
import os
import signal
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _files  # noqa: E402

from curvdetail.curvature import sparse_solver  # noqa: E402
from curvdetail.curvature.cotan_laplacian import cotan_laplacian  # noqa: E402
from curvdetail.curvature.sparse_solver import factorize  # noqa: E402
from curvdetail.curvature.testing import grid  # noqa: E402

ARMS = ("auto", "pardiso", "splu", "igl")


def system(n_vertices):
    """``(L, free, fixed, V)`` for a bumpy square grid of about ``n_vertices`` vertices."""
    k = int(round(np.sqrt(n_vertices)))
    V, F = grid(k, k)
    V[:, 2] = 0.1 * np.sin(6 * V[:, 0]) * np.cos(5 * V[:, 1])
    L = cotan_laplacian(V, F).tocsr()
    edge = (V[:, 0] <= 0) | (V[:, 0] >= 1) | (V[:, 1] <= 0) | (V[:, 1] >= 1)
    return L, np.flatnonzero(~edge), np.flatnonzero(edge), V


class Arm:
    """One solver, factored once; ``resolve(Yb)`` gives the free positions."""

    def __init__(self, name, L, free, fixed):
        self.name = name
        if name == "igl":
            import igl

            self.igl, self.A, self.known = igl, L.tocsc(), fixed.astype(np.int64)
            self.B = np.zeros((L.shape[0], 3))
            self.Beq = np.zeros((0, 3))
            self.free = free
            self.factor_s = self._best(self._factor_igl)
            self.backend = "libigl"
        else:
            self.Lff, self.Lfb = L[free][:, free].tocsc(), L[free][:, fixed].tocsr()
            self.factor_s = self._best(lambda: setattr(self, "fac", factorize(self.Lff, backend=name)))
            self.backend = self.fac.backend

    @staticmethod
    def _best(factor, times=3):
        best = np.inf
        for _ in range(times):
            t = time.perf_counter()
            factor()
            best = min(best, time.perf_counter() - t)
        return best

    def _factor_igl(self):
        import scipy.sparse as sp

        self.data = self.igl.min_quad_with_fixed_data()
        self.igl.min_quad_with_fixed_precompute(self.A, self.known, sp.csc_matrix((0, self.A.shape[0])), True,
                                                self.data)

    def resolve(self, Yb):
        if self.name == "igl":
            return self.igl.min_quad_with_fixed_solve(self.data, self.B, Yb, self.Beq)[self.free]
        return self.fac.solve(-(self.Lfb @ Yb))


class BusyProcesses:
    """``count`` child processes spinning on the CPU while the block runs; stopped on any exit."""

    def __init__(self, count):
        self.count, self.children = count, []

    def __enter__(self):
        # spins while the parent lives: a parent killed outright (SIGKILL) leaves no spinner behind
        code = "import os\nparent = os.getppid()\nwhile os.getppid() == parent: pass"
        self.children = [subprocess.Popen([sys.executable, "-c", code]) for _ in range(self.count)]
        time.sleep(2.0)                             # let the scheduler see them
        return self

    def __exit__(self, *exc):
        for child in self.children:
            child.kill()
        for child in self.children:
            child.wait()
        self.children = []


def measure(sizes, repeats, busy):
    rows = []
    rng = np.random.default_rng(0)
    for n in sizes:
        L, free, fixed, V = system(n)
        arms = [Arm(name, L, free, fixed) for name in ARMS]
        row = {"vertices": int(V.shape[0]), "free": int(free.size), "nnz_free_block": int(arms[0].Lff.nnz),
               "busy_processes": busy, "auto_backend": arms[0].backend, "load_average_start": os.getloadavg()[0],
               "factor_s": {a.name: a.factor_s for a in arms}}
        samples = {a.name: [] for a in arms}
        error = 0.0
        for r in range(repeats + 3):                # three warm-up rounds
            Yb = V[fixed] + 0.01 * rng.normal(size=(fixed.size, 3))
            out = {}
            for a in (arms if r % 2 else arms[::-1]):   # alternate the order
                t = time.perf_counter()
                out[a.name] = a.resolve(Yb)
                if r >= 3:
                    samples[a.name].append(time.perf_counter() - t)
            ref = out["igl"]
            error = max(error, max(float(np.abs(x - ref).max()) for x in out.values()))
        row["resolve_ms"] = {k: 1e3 * float(np.median(v)) for k, v in samples.items()}
        row["resolve_ms_p90"] = {k: 1e3 * float(np.percentile(v, 90)) for k, v in samples.items()}
        row["max_difference"] = error
        row["load_average_end"] = os.getloadavg()[0]
        print(row, flush=True)
        rows.append(row)
    return rows


def table(rows):
    lines = ["| vertices | nnz of L_ff | machine | auto takes | re-solve auto / pardiso / splu / libigl (ms) | "
             "auto / libigl | factor auto / pardiso / splu / libigl (ms) | load start-end |",
             "|---:|---:|---|---|---|---:|---|---|"]
    for r in rows:
        t, f = r["resolve_ms"], r["factor_s"]
        lines.append(f"| {r['vertices']} | {r['nnz_free_block']} | "
                     f"{'busy (%d spinning)' % r['busy_processes'] if r['busy_processes'] else 'as is'} | "
                     f"{r['auto_backend']} | " + " / ".join(f"{t[a]:.2f}" for a in ARMS) +
                     f" | {t['auto'] / t['igl']:.2f} | " + " / ".join(f"{1e3 * f[a]:.1f}" for a in ARMS) +
                     f" | {r['load_average_start']:.1f}-{r['load_average_end']:.1f} |")
    return "\n".join(lines)


def _stop(signum, frame):
    raise SystemExit(128 + signum)              # unwinds through BusyProcesses.__exit__


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="2000,5000,10000,20000,40000", help="vertex counts (default: %(default)s)")
    ap.add_argument("--repeats", type=int, default=60, help="re-solves per arm and size (default: %(default)s)")
    ap.add_argument("--busy", type=int, default=2, help="spinning processes of the busy runs (default: %(default)s)")
    ap.add_argument("--out", default="docs/results", help="folder for small_solves.json/.md (default: %(default)s)")
    ap.add_argument("--force", action="store_true", help="replace output files that exist")
    args = ap.parse_args(argv)
    json_path, md_path = (os.path.join(args.out, "small_solves" + ext) for ext in (".json", ".md"))
    _files.check_outputs(ap, [json_path, md_path], args.force)
    signal.signal(signal.SIGTERM, _stop)
    signal.signal(signal.SIGINT, signal.default_int_handler)   # Ctrl-C also where a shell ignored it
    sizes = [int(s) for s in args.sizes.split(",")]
    started = time.perf_counter()
    rows = measure(sizes, args.repeats, 0)
    with BusyProcesses(args.busy):
        rows += measure(sizes, args.repeats, args.busy)
    text = table(rows)
    print(text)
    env, conditions = _files.environment(), _files.measured_conditions()
    _files.write_json(json_path, {"rows": rows, "arms": ARMS, "repeats": args.repeats,
                                  "small_system_nnz": sparse_solver.SMALL_SYSTEM_NNZ,
                                  "seconds": time.perf_counter() - started, **env, **conditions},
                      args.force, indent=2, end="\n")
    _files.write_text(md_path, "# Small re-solves on a busy machine (issue 26, item 4)\n\n"
                      f"Written by `python scripts/bench_small_solves.py --force` "
                      f"({time.perf_counter() - started:.0f} s). The free block `L_ff` of a bumpy grid's cotangent "
                      "Laplacian (boundary fixed), 3 right-hand sides from new boundary values; a re-solve is "
                      "boundary values to free positions, median of "
                      f"{args.repeats}, arms interleaved; factor: best of 3. \"busy\": {args.busy} processes "
                      "spinning on the CPU, started by the script. The machine's own load is in the last column "
                      f"(1-minute load average). The rule measured: `\"auto\"` takes SuperLU (one thread) below "
                      f"{sparse_solver.SMALL_SYSTEM_NNZ:,} stored entries, else PARDISO.\n\n" + _files.environment_line(env) + "\n\n" + text + "\n",
                      args.force)
    return 0


if __name__ == "__main__":
    sys.exit(main())
