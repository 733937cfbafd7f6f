"""The ``curvdetail`` command: thin front ends over the library and the filters.

``reconstruct``, ``minimal``, ``remesh`` and ``edit`` parse their options, call the library
function the filters call, write their outputs (each through `curvdetail.io.atomic_write`,
one after another) and print one line of figures; ``list``, ``apply`` and ``run`` run the
filters. Errors carry their facts as fields (``parameter``, ``hint``): the command line says them
with its own option names (`error_line`), never by rewriting the library's sentence.

Exit status: 0 done; 1 an error, said on stderr, OUTPUT not written; 2 a command line argparse
cannot parse; 3 OUTPUT written, but an iteration stopped before it converged; 4 OUTPUT written,
but an edit folded triangles or amplified its constraints; 130 Ctrl-C; 143 SIGTERM. A signal is
an exception in the main thread, taken when the native call in progress (a factorization, a
remeshing) returns; the temporary file of an output being written is removed.
"""

import argparse
import os
import signal
import sys
import time
import warnings

from .options import (AMPLIFIED, NOT_CONVERGED, Progress, add_backend, add_fix, add_input_output, add_laplacian,
                          add_overwrite, check_outputs, choice, diagonal, figures_status, fixed_vertices,
                          error_line, input_output, length, note_dropped, positive_number, print_figures,
                          quality_for, read_checked, run_on_file, say, show_warning, whole_number_from_one,
                          write_measured)
from .options import note_not_carried, read_noting_extras

__all__ = ["AMPLIFIED", "NOT_CONVERGED", "Terminated", "build_parser", "error_line", "main",
           "positive_number", "whole_number_from_one"]

_COMMANDS = {}


def command(name, help):
    """Register a subcommand: the decorated function adds its arguments to the parser it is given
    and returns the function that runs it (``run(args) -> int``)."""
    def register(add_arguments):
        _COMMANDS[name] = (help, add_arguments)
        return add_arguments
    return register


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread by `main`'s handler, so that every ``finally``
    (the temporary file of `curvdetail.io.atomic_write` included) runs as for Ctrl-C."""


# --- reconstruct / minimal ------------------------------------------------------------------

@command("reconstruct", help="rebuild a mesh from its own curvature detail with the boundary fixed (and one "
                             "anchor vertex on each closed piece)")
def _reconstruct(parser):
    add_input_output(parser, "mesh file", "rebuilt mesh; quality = distance to INPUT (.ply keeps it)")
    choice(parser, "--rows", ("all", "free"), "all",
           "residual rows in E_Q: all vertices (the paper) or free ones only (default: %(default)s)")
    add_laplacian(parser, "the mesh's Laplacian")
    add_fix(parser)
    add_backend(parser)
    add_overwrite(parser)

    def run(args):
        import numpy as np

        from .. import Reconstructor, anchor_vertices
        from ..curvature.cotan_laplacian import laplacian_product
        from ..curvature.robust_laplacian import checked_laplacian, flip_caps

        inputs = input_output(args)
        check_outputs(args, [("OUTPUT", args.output, True)], **inputs)
        V, F, extras = read_noting_extras(args.input, check=False)
        V, F, L, used = checked_laplacian(V, F, args.laplacian)
        D = laplacian_product(L, V)
        # the boundary (or --fix), and an anchor on each piece with no fixed vertex (a closed one),
        # placed on the surface with its zero-area caps flipped away, where areas are defined
        located = F if used["laplacian"] == "cotan" else flip_caps(V, F)
        fixed = anchor_vertices(V, located, detail=D,
                                fixed=None if args.fix is None else fixed_vertices(args, V, F, purpose=""))
        t = time.perf_counter()
        rec = Reconstructor(V, F, fixed, rows=args.rows, backend=args.backend, laplacian=used["laplacian"])
        X = rec.solve(D, V[rec.fixed])
        seconds = time.perf_counter() - t
        dist = np.linalg.norm(X - V, axis=1)
        write_measured(args.output, X, F, dist, diagonal_of=V, overwrite=args.overwrite)
        print_figures(f"max vertex error {dist.max() / diagonal(V):.3e} of the bbox diagonal ({V.shape[0]} "
                      f"vertices, {fixed.size} fixed, rows={args.rows}, laplacian={used['laplacian']}, "
                      f"{seconds:.3f} s)")
        if used["laplacian"] == "robust":
            say(f"note: the robust Laplacian: {used['laplacian_reason']}")
        note_dropped(args.output, quality=True)
        note_not_carried(args.input, args.output, extras)
        return 0

    return run


@command("minimal", help="minimal surface spanned by a mesh's boundary (zero curvature detail)")
def _minimal(parser):
    from ..curvature.minimal_surface import DEFAULT_TOL

    add_input_output(parser, "mesh file with a boundary", "minimal surface; quality = distance moved")
    parser.add_argument("--max-iterations", type=whole_number_from_one, default=200,
                        help="Pinkall-Polthier steps at most (default: %(default)s); if the shape has not "
                             "settled by then, OUTPUT is still written and the exit status is 3")
    parser.add_argument("--tol", type=positive_number, default=DEFAULT_TOL,
                        help="stop when no vertex moves more than TOL x the bbox diagonal in a step "
                             f"(default {DEFAULT_TOL:g})")
    choice(parser, "--step", ("normal", "full"), "normal",
           "what TOL is compared with: the step normal to the surface (default) or the full displacement")
    add_fix(parser)
    add_backend(parser)
    add_overwrite(parser)

    def run(args):
        import numpy as np

        from .. import boundary_vertices, minimal_surface
        from ..curvature.errors import ConstraintError

        inputs = input_output(args)
        check_outputs(args, [("OUTPUT", args.output, True)], **inputs)
        V, F, extras = read_noting_extras(args.input)
        fixed = fixed_vertices(args, V, F, purpose="(a minimal surface needs a boundary to span)")
        loose = np.setdiff1d(boundary_vertices(F), fixed)
        if loose.size:                      # a free boundary shrinks towards nothing
            raise ConstraintError(f"--fix leaves {loose.size} boundary vertices free", parameter="fix_boundary",
                                  count=int(loose.size), first=loose[:3].tolist(),
                                  hint="a minimal surface spans a fixed boundary")
        progress = Progress(args.max_iterations, enabled=sys.stderr.isatty())
        X = minimal_surface(V, F, fixed, max_iterations=args.max_iterations, tol=args.tol, step=args.step,
                            backend=args.backend, callback=lambda i, s: progress.stage(f"step {i}"))
        progress.close()
        write_measured(args.output, X, F, np.linalg.norm(X - V, axis=1), diagonal_of=V, overwrite=args.overwrite)
        state = "converged" if X.converged else "stopped (not converged)"
        step = X.last_step if args.step == "normal" else X.last_full_step
        print_figures(f"{state} after {X.iterations} step{'' if X.iterations == 1 else 's'}, last step {step:.2e} of the bbox diagonal "
                      f"({'normal to the surface' if args.step == 'normal' else 'full displacement'})")
        note_dropped(args.output, quality=True)
        note_not_carried(args.input, args.output, extras)
        return 0 if X.converged else NOT_CONVERGED

    return run


# --- remesh ---------------------------------------------------------------------------------

@command("remesh", help="retriangulate a mesh (closed, holes, pieces), rebuild it from its curvature detail, "
                        "and measure the error (the paper's Fig. 3)")
def _remesh(parser):
    add_input_output(parser, "source mesh: a manifold surface (a disk-topology patch for --location uv)",
                      "rebuilt target mesh; quality = distance to the source (.ply keeps it)")
    choice(parser, "--method", ("isotropic", "decimate"), "isotropic", "retriangulation (default: isotropic)")
    parser.add_argument("--target-edge", type=length, default="1%", metavar="LENGTH",
                        help="target edge length: a percentage of the source's bbox diagonal such as 1%%, or "
                             "a plain number in model units (default: 1%%)")
    choice(parser, "--transfer", ("conservative", "pointwise"), "conservative", "detail transfer (default: conservative)")
    choice(parser, "--rows", ("all", "free"), "free", "residual rows of the reconstruction energy (default: free)")
    choice(parser, "--location", ("closest", "uv"), "closest",
           "locate points by 3D closest point (default) or in a shared planar domain")
    choice(parser, "--parameterization", ("harmonic", "meshlab_harmonic", "lscm"), None,
           "planar domain for --location uv (default: harmonic)")
    parser.add_argument("--no-surface-check", action="store_true",
                        help="isotropic remeshing without its surface-distance check (faster on big targets)")
    add_laplacian(parser, "the source's Laplacian for its detail")
    add_backend(parser)
    parser.add_argument("--report", metavar="R.json", help="write the JSON report here")
    parser.add_argument("--image", metavar="FIG.png", help="write a picture: source, rebuilt, zero-detail baseline")
    parser.add_argument("--no-evaluate", action="store_true",
                        help="skip the distance measurements; OUTPUT gets no quality, no --image")
    parser.add_argument("--quiet", action="store_true", help="no stage progress on stderr (notes are still said)")
    add_overwrite(parser, also=("--report", "--image"))

    def run(args):
        import json

        from ..curvature.errors import CurvdetailError
        from ..io import atomic_write, read_mesh, write_mesh
        from ..plot import COLOUR_MAP
        from ..remesh.experiment import MAX, RMS, WorseThanZeroDetailWarning, run_experiment, worse_than_zero_detail
        from ..remesh.retriangulate import long_run_reason, long_run_vertices

        inputs = input_output(args)
        if args.parameterization is not None and args.location != "uv":
            raise CurvdetailError(f"--parameterization {args.parameterization} applies to --location uv only",
                                  parameter="location", hint="add --location uv or leave --parameterization out")
        if args.no_evaluate and args.image is not None:
            raise CurvdetailError("--image shows the measured distances", parameter="image",
                                  hint="leave out --no-evaluate or --image")
        check_outputs(args, [("OUTPUT", args.output, True), ("--report", args.report, False),
                             ("--image", args.image, False)], **inputs)
        V, F = read_mesh(args.input)
        edge = args.target_edge
        percent = 100 * edge.fraction(diagonal(V))
        if not edge.percent:
            say(f"note: --target-edge {edge} is in model units: {percent:.3g} % of the bbox diagonal "
                f"({diagonal(V):.4g}); write {percent:.3g}% for a percentage")
        count = long_run_vertices(V, F, edge.resolve(diagonal(V)), method=args.method, evaluate=not args.no_evaluate)
        if count is not None:
            say(f"note: a {percent:.3g} % target edge gives about {count:,.0f} target vertices; this takes "
                f"minutes. {long_run_reason(args.method, evaluate=not args.no_evaluate, cli=True)}")
        stages = 3 + (not args.no_evaluate) + (args.location == "uv") + (args.image is not None)
        progress = Progress(stages, enabled=not args.quiet)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", WorseThanZeroDetailWarning)     # said below, after the figures
            result = run_experiment(V, F, method=args.method, target_edge=edge, transfer=args.transfer,
                                    rows=args.rows, location=args.location, parameterization=args.parameterization,
                                    backend=args.backend, evaluate=not args.no_evaluate,
                                    source_path=os.path.abspath(args.input), progress=progress.stage,
                                    surface_check=not args.no_surface_check, laplacian=args.laplacian)
        report = result["report"]
        if args.image is not None:
            from ..plot import save_remeshing_figure

            progress.stage("image")
            save_remeshing_figure(args.image, V, F, result["X"], result["Ft"], result["Z"], result["distance"], report,
                                  zero_distance=result["zero_distance"], overwrite=args.overwrite)
        progress.close()
        if not args.no_evaluate and quality_for(args.output, True):
            report["output"] = {"quality": "distance to the source, model units", "vertex_colours": COLOUR_MAP,
                                "colour_range_percent_of_diagonal": [0.0, report["error"]["vertex_max_percent_of_diagonal"]]}
        if args.report is not None:
            with atomic_write(args.report, overwrite=args.overwrite) as tmp, open(tmp, "w", encoding="utf-8") as fh:
                fh.write(json.dumps(report, indent=2) + "\n")
        if args.no_evaluate:
            write_mesh(args.output, result["X"], result["Ft"], overwrite=args.overwrite)
        else:
            write_measured(args.output, result["X"], result["Ft"], result["distance"], diagonal_of=V,
                           overwrite=args.overwrite)
        counts = f"{report['source']['vertices']:,} -> {report['target']['vertices']:,} vertices"
        if args.no_evaluate:
            print_figures(f"{counts}; not measured (--no-evaluate); {report['seconds']['total']:.2f} s")
            return 0
        e, b, fl = report["error"], report["baseline_zero_detail"], report["floor_retriangulated"]
        zero = "none" if b is None else f"{b[RMS]:.3f} % / {b[MAX]:.2f} %"
        anchors = f"; {report['anchors']} anchor{'s' * (report['anchors'] != 1)}" if report["anchors"] else ""
        print_figures(f"{counts}{anchors}; RMS {e[RMS]:.4f} %, max {e[MAX]:.3f} % of the "
                      f"bbox diagonal (zero detail {zero}, "
                      f"floor {fl[RMS]:.4f} % / {fl[MAX]:.3f} %); "
                      f"{report['seconds']['total']:.2f} s")
        note_dropped(args.output, quality=True)
        worse = worse_than_zero_detail(report, cli=True)
        if worse is not None:           # the run did what was asked: a finding, not an error
            say(f"note: {worse}")
        return 0

    return run


# --- list / apply / run ---------------------------------------------------------------------

@command("list", help="list the filters (curvdetail.filters) with their parameters")
def _list(parser):
    parser.add_argument("filter", metavar="FILTER", nargs="?", help="show this filter only")
    parser.add_argument("--json", action="store_true", help="print JSON (a list of filters, or the one filter)")

    def run(args):
        import json

        from ..filters import get_filter, list_filters
        from ..filters.registry import describe_filter

        specs = [get_filter(args.filter)] if args.filter else list_filters()
        if args.json:
            found = [spec.to_dict() for spec in specs]
            print_figures(json.dumps(found[0] if args.filter else found, indent=2))
        else:
            print_figures("\n\n".join(describe_filter(spec) for spec in specs))
        return 0

    return run


def _add_file_arguments(parser):
    parser.add_argument("input", metavar="INPUT", help="mesh file")
    parser.add_argument("output", metavar="OUTPUT", help="the current mesh afterwards (.ply keeps quality "
                                                         "and attributes)")
    parser.add_argument("--add", action="append", default=[], metavar="MESH",
                        help="load MESH as the next layer (1, 2, ...; the last one is current)")
    add_overwrite(parser)


@command("apply", help="apply one filter to a mesh file and write the current mesh (exit status 3: "
                       "written, but converged: false; 4: written, but an edit folded or amplified)")
def _apply(parser):
    parser.add_argument("filter", metavar="FILTER", help="filter name (see `curvdetail list`)")
    _add_file_arguments(parser)
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                        help="a filter parameter (repeatable); a length in model units (0.01) or in %% of "
                             "the bbox diagonal (1%%)")

    def run(args):
        from ..filters import FilterParameterError, apply, get_filter

        spec = get_filter(args.filter)
        params = {}
        for pair in args.param:
            name, sep, value = (part.strip() for part in pair.partition("="))
            if not sep or not name or name in params:
                raise FilterParameterError(f"--param {pair!r} is not NAME=VALUE or names {name!r} twice",
                                           parameter=name or None)
            try:
                params[name] = spec.parameter(name).parse(value)
            except KeyError:
                params[name] = value            # unknown: apply() names the close matches
        figures = run_on_file(args, lambda ms: apply(ms, spec.name, **params))
        return figures_status([(spec.name, figures)], args.output)

    return run


@command("run", help="run a MeshLab filter script (.mlx) on a mesh file (exit status 3 / 4 as for apply)")
def _run(parser):
    parser.add_argument("script", metavar="SCRIPT", help="MeshLab filter script (.mlx); never written over")
    _add_file_arguments(parser)

    def run(args):
        from ..filters import ScriptError, run_script
        from ..filters.mlx import check_script

        if not check_script(args.script):       # a folder, malformed XML or a bad step: before INPUT
            raise ScriptError(f"{args.script} has no filter steps", parameter="script",
                              hint="add steps, or name another script")
        bar = Progress(0, enabled=sys.stderr.isatty())

        def step(k, total, name):
            bar.total = total
            bar.stage(name)

        def work(ms):
            try:
                return run_script(ms, args.script, progress=step)
            finally:
                bar.close()

        steps = run_on_file(args, work, other_inputs=[("SCRIPT", args.script)])
        name = os.path.basename(args.script)
        return figures_status([(f"{name} step {k} ({done['filter']})", done["figures"])
                               for k, done in enumerate(steps, start=1)], args.output)

    return run


# --- edit -----------------------------------------------------------------------------------

@command("edit", help="deform a mesh with curvature-detail editing, given a benchmark .sel/.def pair "
                      "(exit status 4: written, but the edit folded triangles or amplified the handles' motion)")
def _edit(parser):
    parser.add_argument("mesh", metavar="MESH", help="mesh file (vertex order must match SEL)")
    parser.add_argument("output", metavar="OUTPUT", help="edited mesh; quality = distance moved (.ply keeps it)")
    parser.add_argument("--sel", required=True, metavar="SEL", help="per-vertex status: 0 fixed, 1 free, 2 handle")
    parser.add_argument("--def", dest="transform", required=True, metavar="DEF",
                        help="4x4 handle transform applied to homogeneous handle positions")
    choice(parser, "--method", ("rotation", "paper"), "rotation",
           "rotation: rest details turned with their neighbourhoods (default); paper: the paper's linear edit")
    choice(parser, "--handle-detail", ("transform", "free"), None,
           "--method paper: handles' curvature details transformed by the linear part of DEF (default) or solved")
    choice(parser, "--relations", ("one-ring", "one+two-ring"), None,
           "--method paper: the paper's one-ring coefficients (default) or one- and two-ring together")
    parser.add_argument("--image", metavar="PNG", help="also save a picture: rest (by status) | edited")
    add_backend(parser)
    add_overwrite(parser, also=("--image",))

    def run(args):
        import numpy as np

        from ..curvature.geometry import folded_triangles
        from ..curvature.errors import CurvdetailError, UndeterminedEditError
        from ..io.deformation import edit_with_selection, read_selection, read_transform
        from ..plot import save_panels

        check_outputs(args, [("OUTPUT", args.output, True), ("--image", args.image, False)],
                      inputs=[("MESH", args.mesh)], other_inputs=[("--sel", args.sel), ("--def", args.transform)])
        paper = args.method == "paper"
        if not paper and (args.handle_detail or args.relations):
            raise CurvdetailError("--handle-detail and --relations apply to --method paper only",
                                  parameter="--method", hint="add --method paper, or drop them")
        V, F = read_checked(args.mesh)
        status = read_selection(args.sel, V.shape[0])
        T = read_transform(args.transform)
        t = time.perf_counter()
        try:
            X, editor = edit_with_selection(V, F, status, T, method=args.method, handle_detail=args.handle_detail,
                                            relations=args.relations, backend=args.backend, return_editor=True)
        except UndeterminedEditError as exc:
            raise UndeterminedEditError(exc.problem, f"Add handles (status 2) or fixed vertices (status 0) "
                                                     f"in {args.sel}.") from None
        seconds = time.perf_counter() - t
        moved = np.linalg.norm(X - V, axis=1)
        if args.image:
            save_panels(args.image, [(V, F, "rest (status 0/1/2)", status),
                                     (X, F, f"edited ({args.method})", moved)],
                                  overwrite=args.overwrite)
        write_measured(args.output, X, F, moved, diagonal_of=V, overwrite=args.overwrite)
        counts = np.bincount(status, minlength=3)
        solver = (f"{editor.rank_deficient} rank-deficient rings, {editor.detail_islands} island vertices" if paper
                  else f"{editor.iterations} iterations{'' if editor.converged else ' (not converged)'}")
        print_figures(f"{V.shape[0]} vertices ({counts[0]} fixed, {counts[1]} free, {counts[2]} handles); largest "
                      f"move {moved.max() / diagonal(V):.3e} of the bbox diagonal; {solver}; {seconds:.3f} s")
        note_dropped(args.output, quality=True)
        other = "one-ring" if args.relations == "one+two-ring" else "one+two-ring"
        tries = (f"--relations {other}" + (" or --handle-detail free" if args.handle_detail != "free" else "")
                 if paper else "more handles (status 2) or a larger free region (status 1)")
        code = 0
        handle_move = moved[status == 2].max(initial=0.0)
        if moved.max() > 3.0 * handle_move + 1e-12 * diagonal(V):
            say(f"curvdetail: warning: vertices moved up to {moved.max() / max(handle_move, 1e-300):.1f} times as "
                f"far as the handles; try {tries}.")
            code = AMPLIFIED
        folded = folded_triangles(V, F, X, T[:3, :3])
        if folded.size:
            say(f"curvdetail: warning: {folded.size} of {F.shape[0]} triangles folded over (first: "
                f"{', '.join(map(str, folded[:3]))}); try {tries}.")
            code = AMPLIFIED
        return code

    return run


# --- evaluate -------------------------------------------------------------------------------

@command("evaluate", help="run a study: mesh files x remeshing configurations, on Dask, into a results "
                          "table (exit status 0 when it ran, failed cells included)")
def _evaluate(parser):
    from .evaluate import add_arguments

    return add_arguments(parser)


# --- entry point ----------------------------------------------------------------------------

def build_parser():
    from .. import __version__

    parser = argparse.ArgumentParser(
        prog="curvdetail",
        description="Curvature detail representation of triangle meshes: reconstruct, edit and remesh "
                    "surfaces from their mean-curvature normals.",
        epilog="Exit status: 0 done; 1 an error, said on stderr, and no output written; 2 a command line that "
               "cannot be parsed; 3 OUTPUT written, but an iteration stopped before it converged (minimal, "
               "or a filter of apply/run whose figures say converged: false); 4 OUTPUT written, but edit "
               "folded triangles or amplified the handles' motion (or an editing filter of apply/run did); "
               "130 Ctrl-C, 143 SIGTERM.")
    parser.add_argument("--version", action="version", version=f"curvdetail {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, (help_text, add_arguments) in _COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        p.set_defaults(_run=add_arguments(p),
                       _options={a.dest: a.option_strings[-1] if a.option_strings else a.metavar
                                 for a in p._actions})
    return parser


def _terminate(signum, frame):
    signal.signal(signal.SIGTERM, signal.SIG_IGN)           # once: the cleanup is not cut short
    raise Terminated()


def main(argv=None):
    """Run the ``curvdetail`` command; returns its exit status. SIGTERM raises
    `Terminated` in the main thread while it runs (status 143), Ctrl-C KeyboardInterrupt
    (130): the temporary file of an output being written is removed either way."""
    args = build_parser().parse_args(argv)
    try:
        previous = signal.signal(signal.SIGTERM, _terminate)
    except ValueError:                          # not the main thread: signals are not ours
        previous = None
    try:
        with warnings.catch_warnings():
            warnings.showwarning = show_warning
            return int(args._run(args) or 0)
    except Terminated:
        say("curvdetail: terminated")
        return 143
    except KeyboardInterrupt:
        say("curvdetail: interrupted")
        return 130
    except (ValueError, OSError, RuntimeError) as exc:
        say(error_line(exc, args))
        return 1
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)

