#!/usr/bin/env python
"""A/B of the solver layer: an earlier commit (``--baseline``: the one with our own MKL ctypes
bindings) against this checkout and against pypardiso's public API (issue 22, item 6).

The baseline's ``curvdetail/curvature`` (relative imports only) is exported with ``git archive``
and imported in the same process as this checkout's, under the name ``bl_curvature``, so that
the arms run interleaved, sample by sample, on the same matrices: on a shared machine a slow
spell then falls on every arm alike. Per size (grid surface, boundary fixed), in one process:

* ``factor`` (rows "free": upper triangle of ``L_ff``; rows "all": of ``L_f: L_f:^T``), PARDISO
  with the same settings in three arms: ``bindings`` = the baseline's
  ``factorize(..., backend="pardiso", upper=True)`` (its ctypes binding), ``pypardiso`` =
  ``PyPardisoSolver(mtype=2)``, ``factorize(A)`` then ``solve(A, b)``, ``branch`` = this
  checkout's ``factorize``. Factor times, then re-solves of 3 right-hand-side columns.
* ``gram``: the upper triangle of ``L_f: L_f:^T``: ``mkl_sparse_syrk`` (baseline's
  ``_mkl_sparse``) against SciPy's product and a triangle cut.
* ``reconstruct``: ``Reconstructor`` + first solve, baseline and branch, ``backend="auto"``; the
  ratio to the bare factor + solve of the same arm's PARDISO path.
* ``table1`` (``--table1``): ``CurvatureEditor`` end to end on the five Table 1 meshes of
  scripts/reproduce_table1.py, ``backend="auto"`` and ``"pardiso"``, baseline and branch.
* ``memory``: peak RSS of ``Reconstructor`` + solve at each size and row mode, one subprocess per
  arm (baseline, branch).

Usage::

    python scripts/bench_solver_ab.py --baseline c7fe65f --sizes 100k,1M --table1 \\
        --out docs/results/solver_ab.json --overwrite

The JSON holds every sample, the medians and minima, each ratio (baseline time / other time:
above 1 the bindings are faster) and the decision by the issue's rule: own bindings stay where
they beat pypardiso's public API by >= 1.3x on a headline figure (1M factor, 100k re-solve,
Table 1 sizes).
"""

import argparse
import datetime
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SIZES = {"10k": 10_000, "100k": 100_000, "300k": 300_000, "1M": 1_000_000}
RULE = 1.3
IPARM = {1: 1, 2: 3, 8: 0, 10: 8, 11: 0, 13: 0, 24: 1, 25: 2}     # both checkouts' symmetric settings


def _grid(n):
    from curvdetail import boundary_vertices
    from curvdetail.curvature.testing import grid

    side = int(round(np.sqrt(n)))
    V, F = grid(side, side)
    V[:, 2] = 0.1 * np.sin(2 * np.pi * V[:, 0]) * np.sin(2 * np.pi * V[:, 1])
    return V, F, boundary_vertices(F)


def _timed(fn):
    t = time.perf_counter()
    out = fn()
    return time.perf_counter() - t, out


def _summary(samples):
    return {arm: {"median_s": float(np.median(t)), "min_s": float(np.min(t)), "samples_s": [round(x, 5) for x in t]}
            for arm, t in samples.items()}


def _ratios(summary, base, key="median_s"):
    return {arm: round(summary[base][key] and summary[arm][key] / summary[base][key], 3)
            for arm in summary if arm != base}


# --- one size, every arm in this process ----------------------------------------------------------

def run_size(size, repeats, resolves):
    import gc

    import pypardiso
    import scipy.sparse as sp

    import bl_curvature
    from bl_curvature import sparse_solver as bl_solver
    from bl_curvature._mkl_sparse import gram_upper
    from curvdetail import Reconstructor, cotan_laplacian, curvature_detail
    from curvdetail.curvature.sparse_solver import factorize

    os.environ.setdefault("PYPARDISO_MKL_RT", pypardiso.ps.libmkl._name)   # pypardiso's own knob
    V, F, fixed = _grid(SIZES[size])
    D = curvature_detail(V, F)
    L = cotan_laplacian(V, F).tocsr()
    free = np.setdiff1d(np.arange(V.shape[0]), fixed)
    L_f = L[free]
    out = {"n": int(V.shape[0]), "free": int(free.size)}

    class Public:
        """pypardiso's public API: factorize(A), then solve(A, b); MKL's memory freed with it."""

        def __init__(self, M):
            self.ps, self.M = pypardiso.PyPardisoSolver(mtype=2), M
            for i, v in IPARM.items():
                self.ps.set_iparm(i, v if (i != 2 or M.shape[0] >= 50_000) else 2)
            self.ps.factorize(M)

        def __call__(self, b):
            return self.ps.solve(self.M, b)

        def __del__(self):
            self.ps.free_memory(everything=True)

    arms = {"bindings": lambda M: bl_solver.factorize(M, backend="pardiso", upper=True).solve,
            "pypardiso": Public,
            "branch": lambda M: factorize(M, backend="pardiso", upper=True).solve}
    warm = sp.csr_matrix(sp.diags(np.full(50_001, 2.0)))     # each arm's one-time start-up
    for make in arms.values():
        make(warm)(np.ones(warm.shape[0]))
    for rows in ("free", "all"):
        A = L_f[:, free] if rows == "free" else L_f @ L_f.T
        M = sp.triu(A, format="csr")
        M.sort_indices()
        del A
        b = np.random.default_rng(0).normal(size=(M.shape[0], 3))
        Mfull = M + sp.triu(M, k=1).T
        factor_t = {arm: [] for arm in arms}
        solve_t = {arm: [] for arm in arms}
        residual = {}
        for r in range(repeats):
            order = list(arms) if r % 2 == 0 else list(arms)[::-1]
            solvers = {}
            for arm in order:
                t, solvers[arm] = _timed(lambda: arms[arm](M))
                factor_t[arm].append(t)
                gc.collect()
            for _ in range(resolves):
                for arm in order:
                    t, x = _timed(lambda: solvers[arm](b))
                    solve_t[arm].append(t)
            for arm in arms:
                residual[arm] = float(np.abs(Mfull @ solvers[arm](b) - b).max() / np.abs(b).max())
            del solvers
            gc.collect()
        fs, ss = _summary(factor_t), _summary(solve_t)
        out[f"factor rows={rows}"] = {"nnz_upper": int(M.nnz), "factor": fs, "resolve_3_columns": ss,
                                      "relative_residual": residual,
                                      "factor_min_over_bindings": _ratios(fs, "bindings", "min_s"),
                                      "resolve_median_over_bindings": _ratios(ss, "bindings")}
        del M, Mfull
        gc.collect()

    def scipy_upper():
        G = sp.triu(L_f @ L_f.T, format="csr")
        G.sort_indices()
        return G
    gram = {"mkl_syrk": [], "scipy": []}
    for _ in range(max(repeats, 3)):
        for arm, fn in (("mkl_syrk", lambda: gram_upper(L_f)), ("scipy", scipy_upper)):
            gram[arm].append(_timed(fn)[0])
    gs = _summary(gram)
    out["gram"] = {**gs, "scipy_over_mkl_syrk_min": round(gs["scipy"]["min_s"] / gs["mkl_syrk"]["min_s"], 3)}

    diag = float(np.linalg.norm(V.max(0) - V.min(0)))
    recs = {"baseline": bl_curvature.Reconstructor, "branch": Reconstructor}
    for rows in ("free", "all"):
        total = {arm: [] for arm in recs}
        errors = {}
        for r in range(repeats):
            for arm in (list(recs) if r % 2 == 0 else list(recs)[::-1]):
                t, X = _timed(lambda: recs[arm](V, F, fixed, rows=rows).solve(D, V[fixed]))
                total[arm].append(t)
                errors[arm] = float(np.abs(X - V).max() / diag)
                del X
                gc.collect()
        ts = _summary(total)
        bare = out[f"factor rows={rows}"]
        over_bare = {arm: round(ts[arm]["min_s"] / (bare["factor"][b]["min_s"] + bare["resolve_3_columns"][b]["min_s"]), 3)
                     for arm, b in (("baseline", "bindings"), ("branch", "branch"))}
        out[f"reconstruct rows={rows}"] = {"total": ts, "max_error": errors,
                                           "branch_over_baseline_min": round(ts["branch"]["min_s"] / ts["baseline"]["min_s"], 3),
                                           "min_over_bare_factor_and_solve": over_bare}
    return out


def run_table1(meshes, repeats):
    import bl_curvature
    from curvdetail import CurvatureEditor

    sys.path.insert(0, HERE)
    from reproduce_table1 import edit_case

    data = np.load(meshes)
    editors = {"baseline": bl_curvature.CurvatureEditor, "branch": CurvatureEditor}
    out = {}
    for backend in ("auto", "pardiso"):
        for arm in editors:                               # warm-up
            pc, positions, dc = edit_case(data["Cat_V"], data["Cat_F"])
            editors[arm](data["Cat_V"], data["Cat_F"], pc, dc, backend=backend).solve()
        for name in ("Cat", "Nose2", "Nose1", "Nose3", "Ear"):
            V, F = data[name + "_V"], data[name + "_F"]
            pc, positions, dc = edit_case(V, F)
            times = {arm: [] for arm in editors}
            used = {}
            for r in range(repeats):
                for arm in (list(editors) if r % 2 == 0 else list(editors)[::-1]):
                    t = time.perf_counter()
                    ed = editors[arm](V, F, pc, dc, backend=backend)
                    ed.solve_details()
                    ed.solve(positions=positions)
                    times[arm].append(time.perf_counter() - t)
                    used[arm] = ed.backend
            s = _summary(times)
            out[f"{name} backend={backend}"] = {**s, "backends": used,
                                                "branch_over_baseline_median": round(s["branch"]["median_s"] / s["baseline"]["median_s"], 3)}
    return out


def run_memory(size, rows):
    from curvdetail import Reconstructor, curvature_detail

    V, F, fixed = _grid(SIZES[size])
    D = curvature_detail(V, F)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0 ** 2
    Reconstructor(V, F, fixed, rows=rows).solve(D, V[fixed])
    return {"peak_rss_gb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0 ** 2,
            "inputs_rss_gb": before}


# --- the driver -----------------------------------------------------------------------------------

def child(task, paths, timeout):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(paths))
    done = subprocess.run([sys.executable, os.path.abspath(__file__), "--task", json.dumps(task)],
                          capture_output=True, text=True, env=env, timeout=timeout)
    if done.returncode != 0:
        return {"failed": (done.stderr.strip().splitlines() or ["?"])[-1]}
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", help="commit of the bindings arm (its curvdetail/curvature is exported)")
    ap.add_argument("--sizes", default="100k,1M", help="comma list of 10k, 100k, 300k, 1M")
    ap.add_argument("--repeats", type=int, default=None, help="factorizations per arm (default 5, 3 at 1M)")
    ap.add_argument("--resolves", type=int, default=10, help="re-solves per arm and factorization")
    ap.add_argument("--table1", action="store_true", help="also the Table 1 edits (15 per mesh and arm)")
    ap.add_argument("--timeout", type=float, default=1800.0)
    ap.add_argument("--out", default="docs/results/solver_ab.json")
    ap.add_argument("--overwrite", action="store_true")
    ap.add_argument("--task", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)

    if args.task:
        t = json.loads(args.task)
        result = {"size": lambda: run_size(t["size"], t["repeats"], t["resolves"]),
                  "table1": lambda: run_table1(t["meshes"], t["repeats"]),
                  "memory": lambda: run_memory(t["size"], t["rows"])}[t["kind"]]()
        print(json.dumps(result))
        return 0

    if not args.baseline:
        ap.error("--baseline COMMIT is required")
    if os.path.exists(args.out) and not args.overwrite:
        ap.error(f"{args.out} exists; pass --overwrite to replace it")
    sys.path.insert(0, ROOT)
    from curvdetail.io.atomic import atomic_write

    work = tempfile.mkdtemp(prefix="solver-ab-")
    base = os.path.join(work, "baseline")
    os.makedirs(os.path.join(work, "bl"))
    os.makedirs(base)
    archive = subprocess.run(["git", "-C", ROOT, "archive", args.baseline, "curvdetail"], capture_output=True, check=True)
    subprocess.run(["tar", "-x", "-C", base], input=archive.stdout, check=True)
    os.symlink(os.path.join(base, "curvdetail", "curvature"), os.path.join(work, "bl", "bl_curvature"))
    both = [ROOT, os.path.join(work, "bl")]
    rev = lambda c: subprocess.run(["git", "-C", ROOT, "rev-parse", c], capture_output=True, text=True).stdout.strip()  # noqa: E731
    meta = {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "cpus": os.cpu_count(), "machine": platform.platform(), "load_average_at_start": os.getloadavg(),
            "baseline_commit": rev(args.baseline), "branch_commit": rev("HEAD"),
            "rule": f"own bindings stay where they beat pypardiso's public API by >= {RULE}x on a headline figure"}
    results = {}
    for size in [s.strip() for s in args.sizes.split(",") if s.strip()]:
        task = {"kind": "size", "size": size, "repeats": args.repeats or (3 if size == "1M" else 5),
                "resolves": args.resolves}
        results[size] = child(task, both, args.timeout)
        print(size, json.dumps(results[size])[:400], flush=True)
        for rows in ("free", "all"):
            results[size][f"peak_rss_gb rows={rows}"] = {
                arm: child({"kind": "memory", "size": size, "rows": rows}, [path], args.timeout)
                for arm, path in (("baseline", base), ("branch", ROOT))}
    if args.table1:
        sys.path.insert(0, HERE)
        from reproduce_table1 import table1_meshes

        meshes = os.path.join(work, "table1.npz")
        np.savez(meshes, **{f"{k}_{x}": a for k, (V, F) in table1_meshes().items() for x, a in zip("VF", (V, F))})
        results["table1"] = child({"kind": "table1", "meshes": meshes, "repeats": 15}, both, args.timeout)
        print("table1", json.dumps(results["table1"])[:400], flush=True)

    # the decision: bindings against pypardiso's public API on the headline figures
    headline = []
    for size, key, figure in (("1M", "factor rows=free", "factor"), ("1M", "factor rows=all", "factor"),
                              ("100k", "factor rows=free", "resolve_3_columns"),
                              ("100k", "factor rows=all", "resolve_3_columns")):
        r = results.get(size, {}).get(key)
        if r and figure in r:
            stat = "min_s" if figure == "factor" else "median_s"
            headline.append({"figure": f"{size} {key} {figure} ({stat})",
                             "pypardiso_over_bindings": round(r[figure]["pypardiso"][stat] / r[figure]["bindings"][stat], 3)})
    for name, r in results.get("table1", {}).items():
        if name.endswith("backend=pardiso") and "branch_over_baseline_median" in r:
            headline.append({"figure": f"Table 1 {name} (median; branch = pypardiso)",
                             "pypardiso_over_bindings": r["branch_over_baseline_median"]})
    over = [h for h in headline if h["pypardiso_over_bindings"] >= RULE]
    meta["load_average_at_end"] = os.getloadavg()
    out = {"meta": meta, "decision": {"headline_figures": headline, "keep_bindings": bool(over),
                                      "figures_over_rule": over}, "results": results}
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with atomic_write(args.out, overwrite=args.overwrite) as tmp:
        with open(tmp, "w") as fh:
            json.dump(out, fh, indent=1)
    print(json.dumps(out["decision"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
