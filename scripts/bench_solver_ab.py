#!/usr/bin/env python
"""A/B of the solver layer: an earlier checkout (``--baseline``, e.g. the commit with our own MKL
ctypes bindings) against this one and against pypardiso's public API (issue 22, item 6).

Cases, each in its own subprocess (peak RSS is its own), the arms of a case taking turns round
after round (the machine is shared; the fastest round is kept):

* ``factor`` (size, rows): PARDISO on the reconstruction matrix as ``Reconstructor`` gives it
  (upper triangle of ``L_ff`` or of ``L_f: L_f:^T``, grid surface): factor, then re-solves of
  3 right-hand-side columns (median). Arms: ``baseline`` and ``branch`` = each checkout's
  ``sparse_solver.factorize(..., backend="pardiso", upper=True)``, ``pypardiso`` =
  ``PyPardisoSolver(mtype=2)`` with the same iparm, ``factorize(A)`` then ``solve(A, b)``.
* ``gram`` (size): the normal matrix ``L_f: L_f:^T``'s upper triangle, ``mkl_sparse_syrk``
  (baseline's ``_mkl_sparse.gram_upper``) against SciPy's product and a triangle cut.
* ``reconstruct`` (size, rows): ``Reconstructor`` end to end + first solve, and a re-solve, with
  ``backend="auto"``, both checkouts.
* ``table1``: ``CurvatureEditor`` end to end (constructor + ``solve_details`` + ``solve``) on the
  five Table 1 meshes (scripts/reproduce_table1.py), ``backend="auto"`` and ``"pardiso"``, both
  checkouts; the median of ``--repeat`` edits.

Usage::

    python scripts/bench_solver_ab.py --baseline c7fe65f --sizes 100k,1M \\
        --out docs/results/solver_ab.json --overwrite

The JSON holds every round, the kept figures, each A/B ratio (baseline / other, > 1: baseline
faster) and the decision by the issue's rule: own bindings stay where they beat pypardiso's public
API by >= 1.3x on a headline figure (1M factor, 100k re-solve, Table 1 sizes).
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


# --- in the child ---------------------------------------------------------------------------------

def _grid(n):
    from curvdetail.curvature.testing import grid

    side = int(round(np.sqrt(n)))
    V, F = grid(side, side)
    V[:, 2] = 0.1 * np.sin(2 * np.pi * V[:, 0]) * np.sin(2 * np.pi * V[:, 1])
    from curvdetail import boundary_vertices

    return V, F, boundary_vertices(F)


def _system(V, F, fixed, rows):
    """The Laplacian rows of the free vertices and the full symmetric system."""
    from curvdetail import cotan_laplacian

    L = cotan_laplacian(V, F).tocsr()
    free = np.setdiff1d(np.arange(V.shape[0]), fixed)
    L_f = L[free]
    A = (L_f @ L_f.T).tocsr() if rows == "all" else L_f[:, free].tocsr()
    return L_f, A


def _rss_gb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0 ** 2


def _time(fn):
    t = time.perf_counter()
    out = fn()
    return time.perf_counter() - t, out


def case_matrix(size, rows, path):
    """Save the upper triangle of the reconstruction matrix, built once for every arm."""
    import scipy.sparse as sp

    V, F, fixed = _grid(SIZES[size])
    M = sp.triu(_system(V, F, fixed, rows)[1], format="csr")
    M.sort_indices()
    sp.save_npz(path, M, compressed=False)
    return {"n": int(M.shape[0]), "nnz_upper": int(M.nnz)}


def case_factor(path, arm, resolves=7):
    import scipy.sparse as sp

    M = sp.csr_matrix(sp.load_npz(path))
    M.sort_indices()
    b = np.random.default_rng(0).normal(size=(M.shape[0], 3))
    rss0 = _rss_gb()
    warm = sp.csr_matrix(sp.diags([2.0] * 8))            # MKL's one-time start-up, outside the timing
    if arm == "pypardiso":
        import pypardiso

        # its documented knob: without it every new solver object searches for MKL (0.1 s)
        os.environ.setdefault("PYPARDISO_MKL_RT", pypardiso.ps.libmkl._name)

        def factor():
            ps = pypardiso.PyPardisoSolver(mtype=2)
            # the iparm both checkouts set: METIS (parallel from 50k unknowns), no iterative
            # refinement, pivot perturbation 1e-8, two-level factorization, parallel solve
            for i, v in {1: 1, 2: 3 if M.shape[0] >= 50_000 else 2, 8: 0, 10: 8, 24: 1, 25: 2}.items():
                ps.set_iparm(i, v)
            ps.factorize(M)
            return ps

        M, real = warm, M
        factor().solve(warm, np.ones(8))
        M = real
        t_factor, ps = _time(factor)
        solve = lambda rhs: ps.solve(M, rhs)                            # noqa: E731
    else:
        from curvdetail.curvature.sparse_solver import factorize

        factorize(warm, backend="pardiso").solve(np.ones(8))
        t_factor, fac = _time(lambda: factorize(M, symmetric=True, backend="pardiso", upper=True))
        solve = fac.solve
    times, x = [], None
    for _ in range(resolves):
        t, x = _time(lambda: solve(b))
        times.append(t)
    Mfull = M + sp.triu(M, k=1).T
    residual = float(np.abs(Mfull @ x - b).max() / np.abs(b).max())
    return {"factor_s": t_factor, "resolve_s": float(np.median(times)), "resolve_min_s": float(min(times)),
            "nnz_upper": int(M.nnz),
            "residual": residual, "peak_rss_gb": _rss_gb(), "inputs_rss_gb": rss0}


def case_gram(size, arm, trials=3):
    import scipy.sparse as sp

    V, F, fixed = _grid(SIZES[size])
    from curvdetail import cotan_laplacian

    L = cotan_laplacian(V, F).tocsr()
    L_f = L[np.setdiff1d(np.arange(V.shape[0]), fixed)]
    if arm == "mkl_syrk":
        from curvdetail.curvature._mkl_sparse import gram_upper

        fn = lambda: gram_upper(L_f)                                    # noqa: E731
    else:
        def fn():
            G = sp.triu(L_f @ L_f.T, format="csr")
            G.sort_indices()
            return G
    best = min(_time(fn)[0] for _ in range(trials))
    return {"product_s": best, "nnz_upper": int(fn().nnz), "peak_rss_gb": _rss_gb()}


def case_reconstruct(size, rows):
    from curvdetail import Reconstructor, curvature_detail

    V, F, fixed = _grid(SIZES[size])
    D = curvature_detail(V, F)
    rss0 = _rss_gb()
    t_build, rec = _time(lambda: Reconstructor(V, F, fixed, rows=rows))
    t_solve, X = _time(lambda: rec.solve(D, V[fixed]))
    t_resolve, X2 = min((_time(lambda: rec.solve(1.5 * D, 1.5 * V[fixed])) for _ in range(3)), key=lambda t: t[0])
    diag = float(np.linalg.norm(V.max(0) - V.min(0)))
    return {"build_s": t_build, "solve_s": t_solve, "total_s": t_build + t_solve, "resolve_s": t_resolve,
            "backend": rec.backend, "max_error": float(np.abs(X - V).max() / diag),
            "max_error_resolve": float(np.abs(X2 - 1.5 * V).max() / (1.5 * diag)),
            "peak_rss_gb": _rss_gb(), "inputs_rss_gb": rss0}


def case_table1(meshes, backend, repeat):
    from curvdetail import CurvatureEditor

    sys.path.insert(0, HERE)
    from reproduce_table1 import edit_case

    data = np.load(meshes)
    pc, positions, dc = edit_case(data["Cat_V"], data["Cat_F"])
    CurvatureEditor(data["Cat_V"], data["Cat_F"], pc, dc, backend=backend).solve()     # warm-up
    out = {}
    for name in ("Cat", "Nose2", "Nose1", "Nose3", "Ear"):
        V, F = data[name + "_V"], data[name + "_F"]
        pc, positions, dc = edit_case(V, F)
        totals = []
        for _ in range(repeat):
            t = time.perf_counter()
            ed = CurvatureEditor(V, F, pc, dc, backend=backend)
            ed.solve_details()
            X = ed.solve(positions=positions)
            totals.append(time.perf_counter() - t)
        out[name] = {"median_s": float(np.median(totals)), "best_s": float(min(totals)),
                     "backend": ed.backend, "checksum": float(np.abs(X).sum())}
    return out


# --- the driver -----------------------------------------------------------------------------------

def run_child(case, checkout, timeout):
    env = dict(os.environ, PYTHONPATH=checkout)
    cmd = [sys.executable, os.path.abspath(__file__), "--case", json.dumps(case)]
    t = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=timeout, cwd=checkout)
    if done.returncode != 0:
        return {"failed": (done.stderr.strip().splitlines() or ["?"])[-1]}
    out = json.loads(done.stdout.strip().splitlines()[-1])
    out["wall_s"] = round(time.perf_counter() - t, 2)
    return out


def export(commit, folder):
    """``curvdetail/`` of ``commit`` into ``folder`` (git archive), for the baseline arm."""
    archive = subprocess.run(["git", "-C", ROOT, "archive", commit, "curvdetail"], capture_output=True, check=True)
    subprocess.run(["tar", "-x", "-C", folder], input=archive.stdout, check=True)
    rev = subprocess.run(["git", "-C", ROOT, "rev-parse", commit], capture_output=True, text=True, check=True)
    return rev.stdout.strip()


def keep_fastest(runs, keys):
    ok = [r for r in runs if "failed" not in r]
    if not ok:
        return runs[-1]
    best = dict(ok[0])
    for k in keys:
        if k in best:
            best[k] = min(r[k] for r in ok)
    best["peak_rss_gb"] = max(r.get("peak_rss_gb", 0) for r in ok)
    return best


def ratio(a, b):
    return round(a / b, 3) if a and b else None


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", help="commit of the A arm (git archive of curvdetail/)")
    ap.add_argument("--sizes", default="100k,1M", help="comma list of 10k, 100k, 300k, 1M for factor/reconstruct")
    ap.add_argument("--cases", default="factor,gram,reconstruct,table1")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--repeat", type=int, default=15, help="Table 1 edits per mesh and round")
    ap.add_argument("--timeout", type=float, default=900.0)
    ap.add_argument("--out", default="docs/results/solver_ab.json")
    ap.add_argument("--overwrite", action="store_true")
    ap.add_argument("--case", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)

    if args.case:
        c = json.loads(args.case)
        fn = {"matrix": lambda: case_matrix(c["size"], c["rows"], c["path"]),
              "factor": lambda: case_factor(c["path"], c["arm"]),
              "gram": lambda: case_gram(c["size"], c["arm"]),
              "reconstruct": lambda: case_reconstruct(c["size"], c["rows"]),
              "table1": lambda: case_table1(c["meshes"], c["backend"], c["repeat"])}[c["kind"]]
        print(json.dumps(fn()))
        return 0

    if not args.baseline:
        ap.error("--baseline COMMIT is required")
    if os.path.exists(args.out) and not args.overwrite:
        ap.error(f"{args.out} exists; pass --overwrite to replace it")
    sys.path.insert(0, ROOT)
    from curvdetail.io.atomic import atomic_write

    sizes = [s.strip() for s in args.sizes.split(",") if s.strip()]
    kinds = [s.strip() for s in args.cases.split(",") if s.strip()]
    work = tempfile.mkdtemp(prefix="solver-ab-")
    base = os.path.join(work, "baseline")
    os.makedirs(base)
    baseline_commit = export(args.baseline, base)
    checkouts = {"baseline": base, "branch": ROOT}
    groups = []                    # (name, {arm: (checkout, case)}, keys to keep fastest)
    for size in sizes:
        for rows in ("free", "all"):
            if "factor" in kinds:
                path = os.path.join(work, f"matrix-{size}-{rows}.npz")
                print(f"matrix {size} rows={rows}: {run_child({'kind': 'matrix', 'size': size, 'rows': rows, 'path': path}, ROOT, args.timeout)}",
                      flush=True)
                groups.append((f"factor {size} rows={rows}",
                               {arm: (checkouts.get(arm, ROOT), {"kind": "factor", "path": path, "arm": arm})
                                for arm in ("baseline", "pypardiso", "branch")},
                               ("factor_s", "resolve_s", "resolve_min_s")))
            if "reconstruct" in kinds:
                groups.append((f"reconstruct {size} rows={rows}",
                               {arm: (checkouts[arm], {"kind": "reconstruct", "size": size, "rows": rows})
                                for arm in ("baseline", "branch")},
                               ("build_s", "solve_s", "total_s", "resolve_s")))
        if "gram" in kinds:
            groups.append((f"gram {size}", {arm: (base, {"kind": "gram", "size": size, "arm": arm})
                                            for arm in ("mkl_syrk", "scipy")}, ("product_s",)))
    if "table1" in kinds:
        sys.path.insert(0, HERE)
        from reproduce_table1 import table1_meshes

        meshes = os.path.join(work, "table1.npz")
        np.savez(meshes, **{f"{k}_{x}": a for k, (V, F) in table1_meshes().items() for x, a in zip("VF", (V, F))})
        for backend in ("auto", "pardiso"):
            groups.append((f"table1 backend={backend}",
                           {arm: (checkouts[arm], {"kind": "table1", "meshes": meshes, "backend": backend,
                                                   "repeat": args.repeat})
                            for arm in ("baseline", "branch")}, ()))

    results = {}
    for name, arms, keys in groups:
        rounds = {arm: [] for arm in arms}
        for r in range(args.rounds):
            for arm, (checkout, case) in arms.items():
                try:
                    got = run_child(case, checkout, args.timeout)
                except subprocess.TimeoutExpired:
                    got = {"failed": f"timed out after {args.timeout:g} s"}
                rounds[arm].append(got)
                print(f"{name:28} {arm:9} round {r + 1}: {json.dumps(got)[:200]}", flush=True)
        if name.startswith("table1"):
            kept = {}
            for arm, runs in rounds.items():
                ok = [x for x in runs if "failed" not in x]
                kept[arm] = {m: {"median_s": min(x[m]["median_s"] for x in ok), "best_s": min(x[m]["best_s"] for x in ok),
                                 "backend": ok[0][m]["backend"], "checksum": ok[0][m]["checksum"]}
                             for m in ok[0] if isinstance(ok[0][m], dict)} if ok else runs[-1]
        else:
            kept = {arm: keep_fastest(runs, keys) for arm, runs in rounds.items()}
        results[name] = {"kept": kept, "rounds": rounds}

    # the A/B ratios and the decision
    decision = []
    for name, res in results.items():
        k = res["kept"]
        if name.startswith("factor"):
            for key in ("factor_s", "resolve_s", "resolve_min_s"):
                res[f"{key}_baseline_over_pypardiso"] = ratio(k["pypardiso"].get(key), k["baseline"].get(key))
                res[f"{key}_baseline_over_branch"] = ratio(k["branch"].get(key), k["baseline"].get(key))
            headline = ("1M" in name and "factor_s") or ("100k" in name and "resolve_min_s")
            if headline:
                decision.append({"figure": f"{name} {headline}", "bindings_speedup":
                                 res[f"{headline}_baseline_over_pypardiso"]})
        elif name.startswith("gram"):
            res["scipy_over_mkl_syrk"] = ratio(k["scipy"].get("product_s"), k["mkl_syrk"].get("product_s"))
        elif name.startswith("reconstruct"):
            res["total_branch_over_baseline"] = ratio(k["branch"].get("total_s"), k["baseline"].get("total_s"))
            res["resolve_branch_over_baseline"] = ratio(k["branch"].get("resolve_s"), k["baseline"].get("resolve_s"))
            res["peak_rss_branch_over_baseline"] = ratio(k["branch"].get("peak_rss_gb"), k["baseline"].get("peak_rss_gb"))
            bare = results.get(name.replace("reconstruct", "factor"), {}).get("kept", {})
            for arm in ("baseline", "branch"):      # Reconstructor + first solve over bare factor + solve
                b = bare.get(arm, {})
                if "factor_s" in b and "total_s" in k[arm]:
                    res[f"{arm}_reconstruct_over_bare"] = ratio(k[arm]["total_s"], b["factor_s"] + b["resolve_min_s"])
        elif name.startswith("table1"):
            if all(isinstance(k[a], dict) and "Ear" in k[a] for a in k):
                res["median_branch_over_baseline"] = {m: ratio(k["branch"][m]["median_s"], k["baseline"][m]["median_s"])
                                                      for m in k["baseline"]}
                if name.endswith("pardiso"):
                    decision.append({"figure": f"{name} Ear median", "bindings_speedup":
                                     res["median_branch_over_baseline"]["Ear"]})
    keep = [d for d in decision if (d["bindings_speedup"] or 0) >= RULE]
    meta = {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "cpus": os.cpu_count(), "machine": platform.platform(), "load_average": os.getloadavg(),
            "baseline_commit": baseline_commit,
            "branch_commit": subprocess.run(["git", "-C", ROOT, "rev-parse", "HEAD"], capture_output=True,
                                            text=True).stdout.strip(),
            "rounds": args.rounds, "sizes": sizes, "rule": f"own bindings stay where they beat pypardiso's "
                                                          f"public API by >= {RULE}x on a headline figure"}
    out = {"meta": meta, "decision": {"headline_figures": decision,
                                      "keep_bindings": bool(keep), "figures_over_rule": keep},
           "results": results}
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with atomic_write(args.out, overwrite=args.overwrite) as tmp:
        with open(tmp, "w") as fh:
            json.dump(out, fh, indent=1)
    print(json.dumps(out["decision"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
