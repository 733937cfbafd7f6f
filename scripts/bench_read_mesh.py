"""Speed and memory of reading a 1M-vertex binary PLY: read_mesh now, read_mesh of another
checkout (the baseline), and pymeshlab's bare load as the peer; writes JSON.

The mesh is a wavy grid (1000 x 1000 vertices, 1,996,002 triangles) written by this checkout's
``write_mesh`` (binary doubles). Each reader runs in a fresh process, A/B interleaved, after a
warm-up read that puts the file in the page cache, with numpy, plyfile and pymeshlab imported
before the clock starts; a process reports its seconds, its peak
resident memory, the memory it held before reading, and a digest of (V, F) (equal digests: the
readers agree).

Usage: python scripts/bench_read_mesh.py --baseline /work/wt-io-old [--out out/bench_read_mesh.json]
       [--side 1000] [--repeats 3] [--overwrite]
"""

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

#: Run in a child: read the file named by argv[1] with argv[2]'s reader and print one JSON line.
CHILD = r"""
import hashlib, json, resource, sys, time
import numpy as np, plyfile, pymeshlab     # imported before timing: the reads alone are compared
path, reader = sys.argv[1], sys.argv[2]
if reader == "pymeshlab":
    import pymeshlab
    def read(p):
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(p)
        return ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
else:
    from curvdetail.io import read_mesh as read
def rss_mib():
    with open("/proc/self/status") as f:
        return next(int(l.split()[1]) for l in f if l.startswith("VmRSS")) / 1024
before = rss_mib()
t = time.perf_counter()
V, F = read(path)
seconds = time.perf_counter() - t
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
h = hashlib.blake2b(np.ascontiguousarray(V, dtype=np.float64).tobytes(), digest_size=8)
h.update(np.ascontiguousarray(F, dtype=np.int64).tobytes())
print(json.dumps({"seconds": seconds, "peak_rss_mib": peak, "rss_before_mib": before,
                  "vertices": len(V), "triangles": len(F), "digest": h.hexdigest()}))
"""


def grid(side):
    """A wavy ``side`` x ``side`` grid: (V, F) with side^2 vertices."""
    x, y = np.meshgrid(np.linspace(0.0, 1.0, side), np.linspace(0.0, 1.0, side), indexing="ij")
    V = np.column_stack([x.ravel(), y.ravel(), 0.05 * (np.sin(9 * x) * np.cos(7 * y)).ravel()])
    k = np.arange(side * side).reshape(side, side)[:-1, :-1].ravel()
    F = np.concatenate([np.column_stack([k, k + side, k + 1]), np.column_stack([k + 1, k + side, k + side + 1])])
    return V, F


def run(reader, path, pythonpath):
    env = dict(os.environ, PYTHONPATH=pythonpath)
    out = subprocess.run([sys.executable, "-c", CHILD, path, reader], env=env, capture_output=True, text=True,
                         check=True, timeout=600, cwd=os.path.dirname(path))     # not this checkout's folder
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", required=True, help="checkout whose read_mesh is the baseline")
    parser.add_argument("--out", default="out/bench_read_mesh.json")
    parser.add_argument("--side", type=int, default=1000, help="grid side: side^2 vertices")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--overwrite", action="store_true")
    args = parser.parse_args(argv)
    sys.path.insert(0, HERE)
    from curvdetail.io import atomic_write, check_output_path, write_mesh

    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    check_output_path(args.out, args.overwrite)
    readers = {"new": HERE, "baseline": os.path.abspath(args.baseline), "pymeshlab": ""}
    with tempfile.TemporaryDirectory(prefix="bench-read-mesh-") as folder:
        path = os.path.join(folder, "grid.ply")
        write_mesh(path, *grid(args.side))
        with open(path, "rb") as f:                 # into the page cache
            while f.read(1 << 24):
                pass
        runs = {name: [] for name in readers}
        for _ in range(args.repeats):
            for name, pythonpath in readers.items():
                runs[name].append(run(name if name == "pymeshlab" else "curvdetail", path, pythonpath))
        size = os.path.getsize(path)
    first = runs["new"][0]
    commits = {name: subprocess.run(["git", "-C", folder, "rev-parse", "--short", "HEAD"], capture_output=True,
                                    text=True).stdout.strip() or None
               for name, folder in (("new", HERE), ("baseline", readers["baseline"]))}
    result = {
        "commits": commits,
        "mesh": {"vertices": first["vertices"], "triangles": first["triangles"], "file_bytes": size,
                 "format": "binary_little_endian PLY, double x y z, int32 triangles"},
        "host": {"machine": platform.machine(), "python": platform.python_version(), "cpus": os.cpu_count(),
                 "load_average": os.getloadavg()},
        "repeats": args.repeats,
        "readers": {name: {"seconds_median": statistics.median(r["seconds"] for r in rs),
                           "seconds": [round(r["seconds"], 4) for r in rs],
                           "peak_rss_mib": max(r["peak_rss_mib"] for r in rs),
                           "peak_over_start_mib": max(r["peak_rss_mib"] - r["rss_before_mib"] for r in rs),
                           "digest": rs[0]["digest"]} for name, rs in runs.items()},
    }
    result["same_arrays"] = len({r["digest"] for r in result["readers"].values()}) == 1
    result["new_over_baseline"] = result["readers"]["new"]["seconds_median"] / \
        result["readers"]["baseline"]["seconds_median"]
    with atomic_write(args.out, overwrite=args.overwrite) as tmp, open(tmp, "w") as f:
        json.dump(result, f, indent=2)
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
