"""The ``curvdetail`` command.

Every subcommand is declared with :func:`command` next to the code that runs it. A failure
anywhere exits non-zero with a ``curvdetail: error: ...`` message on stderr and leaves no output
file behind (outputs are written atomically, last). Ctrl-C (SIGINT) and SIGTERM end a run at
once, even during a long native call, removing the temporary files: exit status 130 or 143.
A run that stops before its iteration converged (``minimal``, or ``apply`` / ``run`` with a filter
whose figures say ``converged: false``) writes OUTPUT all the same and exits with status 3
(:data:`NOT_CONVERGED`); ``edit`` exits with status 4 when its edit folded triangles or amplified the
handles' motion, ``apply`` / ``run`` when an editing filter did.
"""

import argparse
import contextlib
import functools
import os
import signal
import sys
import threading
import time
import warnings

_COMMANDS = {}


def command(name, help):
    """Register a subcommand: the decorated function receives its argparse parser and returns
    the function that runs it (``run(args) -> int``)."""
    def register(add_arguments):
        _COMMANDS[name] = (help, add_arguments)
        return add_arguments
    return register


#: The stream whose last line is still open (a stage's "[1/5] retriangulate ..." waiting for its
#: seconds), or None: a note, error or "interrupted" said meanwhile starts a line of its own.
_open_line = None


def _say(text, stream=None, end="\n", *, continues=False):
    """Write a progress line, note or warning to stderr; False (and nothing raised) when the
    reader has gone away: such lines must not end a run whose outputs are still to be written
    (`curvdetail remesh ... 2>&1 | head` would otherwise stop half-way with status 0).
    ``continues``: the text goes on the line left open (a stage's seconds); otherwise an open
    line is ended first."""
    global _open_line
    stream = stream or sys.stderr
    if not continues and _open_line is stream:
        text = "\n" + text
    try:
        stream.write(text + end)
        stream.flush()
    except (BrokenPipeError, ValueError):       # ValueError: the stream was closed
        return False
    _open_line = None if end.endswith("\n") else stream
    return True


class Progress:
    """Stage-by-stage progress on stderr: ``[2/5] parameterize ... 0.41 s``."""

    def __init__(self, total, enabled=True, stream=None):
        self.total, self.done, self.enabled = total, 0, enabled
        self.stream = stream or sys.stderr
        self._t, self._label = None, None

    def stage(self, name):
        self._finish()
        self.done += 1
        self._t = time.perf_counter()
        self._label = f"[{self.done}/{self.total}] {name} ..."
        if self.enabled:
            self.enabled = _say(self._label, self.stream, end="")

    def _finish(self):
        if self._t is not None and self.enabled:
            seconds = f" {time.perf_counter() - self._t:.2f} s"
            if _open_line is self.stream:
                self.enabled = _say(seconds, self.stream, continues=True)
            else:           # a note came in between: the stage again, on a line of its own
                self.enabled = _say(self._label + seconds, self.stream)
        self._t = None

    def close(self):
        self._finish()


def add_output_arguments(parser, also=()):
    """``--overwrite``; ``also``: the options naming further outputs it replaces as well."""
    files = " and ".join([", ".join(["OUTPUT", *also[:-1]]), *also[-1:]])
    parser.add_argument("--overwrite", action="store_true",
                        help=f"replace {files} if {'they exist' if also else 'it exists'}")


#: how a refusal of an existing output says to replace it, on the command line
OVERWRITE = "--overwrite"


def check_mesh_output(path, overwrite):
    """:func:`curvdetail.io.check_mesh_output`, an existing file refused in the command line's
    words ("pass --overwrite", not Python's overwrite=True)."""
    from ._output import check_output_path
    from .io.mesh import MeshFileError, check_mesh_output as check

    check_output_path(path, overwrite, hint=None, error=MeshFileError, flag=OVERWRITE)
    return check(path, overwrite)


def add_backend_argument(parser):
    from .curvature.sparse_solver import AUTO_RULE, BACKENDS

    parser.add_argument("--backend", default="auto",
                        help=f"sparse solver: {', '.join(('auto',) + BACKENDS)} ({AUTO_RULE})")


def add_input_output_arguments(parser, input_help, output_help):
    """``INPUT OUTPUT`` positionals, or ``--example OUTPUT`` for the bundled example mesh."""
    parser.add_argument("input", metavar="INPUT", nargs="?", help=input_help)
    parser.add_argument("output", metavar="OUTPUT", nargs="?", help=output_help)
    parser.add_argument("--example", action="store_true",
                        help="use the bundled example mesh (an SRTM terrain patch) as INPUT")


def resolve_input_output(args):
    """Fill ``args.input`` / ``args.output`` from ``--example``, check both are given and that
    OUTPUT can be written (:func:`curvdetail.io.check_mesh_output`: existing file, folder,
    a mesh format pymeshlab writes), before any work."""
    if args.example:
        if args.output is not None:
            raise ValueError("with --example give only OUTPUT, not INPUT and OUTPUT.")
        from .data import example_path

        args.input, args.output = example_path(), args.input
        if args.output is not None and os.path.realpath(args.output) == os.path.realpath(args.input):
            # INPUT was not named: replacing it (--overwrite) would rewrite the package's own data
            raise ValueError(f"{args.output} is the bundled example mesh that --example reads; writing "
                             "there would change the installed package even with --overwrite. Name "
                             "another file.")
    if args.input is None or args.output is None:
        raise ValueError("missing INPUT or OUTPUT (or use --example OUTPUT).")
    check_mesh_output(args.output, args.overwrite)


# --- reconstruct / minimal (core issue) -----------------------------------------------------

def _vertex_indices(text):
    """One ``--fix`` value: an index, or several separated by commas ("0,17,42")."""
    try:
        return [int(part) for part in text.split(",") if part.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a vertex index (put --fix after INPUT OUTPUT, or end its list with --)") from None


def add_fix_arguments(parser):
    parser.add_argument("--fix", type=_vertex_indices, nargs="*", action="extend", default=None, metavar="I",
                        help="vertex indices to keep fixed, e.g. --fix 0 17 42 or --fix 0,17,42 "
                             "(default: the boundary; a closed piece needs some)")
    parser.add_argument("--fix-boundary", action="store_true",
                        help="with --fix: keep the boundary fixed as well")


def fixed_vertices(args, F, n):
    """The vertices ``--fix`` / ``--fix-boundary`` name (the boundary when neither is given)."""
    import numpy as np

    from .curvature._validate import as_index_set, boundary_vertices
    from .curvature.errors import ConstraintError

    if args.fix is None:
        return boundary_vertices(F)
    indices = [i for part in args.fix for i in part]
    if not indices:                         # "--fix" given without indices
        raise ConstraintError("--fix needs vertex indices (e.g. --fix 0 17 42); leave it out to fix "
                              "the boundary.")
    fixed = as_index_set(indices, n, "--fix")
    return np.union1d(fixed, boundary_vertices(F)) if args.fix_boundary else fixed


@command("reconstruct", help="rebuild a mesh from its own curvature detail with the boundary fixed")
def _reconstruct_command(parser):
    add_input_output_arguments(parser, "mesh file (any format MeshLab reads)",
                               "rebuilt mesh; quality = distance to INPUT (.ply keeps it)")
    parser.add_argument("--rows", type=str.lower, choices=("all", "free"), default="all",
                        help="residual rows in E_Q: all vertices (the paper) or free ones only "
                             "(default: %(default)s)")
    add_fix_arguments(parser)
    add_backend_argument(parser)
    add_output_arguments(parser)

    def run(args):
        import numpy as np

        from . import Reconstructor, curvature_detail, read_mesh, write_mesh
        from .curvature._validate import bbox_diagonal, check_mesh
        from .curvature.errors import ConstraintError

        resolve_input_output(args)
        progress = Progress(4, enabled=sys.stderr.isatty())      # 1M vertices take ~20 s
        progress.stage("read")
        V, F = check_mesh(*read_mesh(args.input))
        fixed = fixed_vertices(args, F, V.shape[0])
        if fixed.size == 0:
            raise ConstraintError(f"{args.input} is closed (no boundary); name vertices to fix with --fix.")
        progress.stage("factor")
        t = time.perf_counter()
        rec = Reconstructor(V, F, fixed, rows=args.rows, backend=args.backend)
        progress.stage("solve")
        X = rec.solve(curvature_detail(V, F), V[rec.fixed])
        seconds = time.perf_counter() - t
        progress.stage("write")
        dist = np.linalg.norm(X - V, axis=1)
        write_mesh(args.output, X, F, quality=_quality_for(args.output, dist), overwrite=args.overwrite)
        progress.close()
        print(f"max vertex error {dist.max() / bbox_diagonal(V):.3e} of the bbox diagonal "
              f"({V.shape[0]} vertices, {fixed.size} fixed, rows={args.rows}, {seconds:.3f} s)")
        _note_geometry_only(args.output, quality=not _keeps_quality(args.output))
        return 0

    return run


#: Exit status of ``minimal``, ``apply`` and ``run`` when OUTPUT is written but an iteration
#: stopped before it converged (``max_iterations`` reached): scripts can tell it from a clean run.
NOT_CONVERGED = 3


@command("minimal", help="minimal surface spanned by a mesh's boundary (zero curvature detail)")
def _minimal_command(parser):
    add_input_output_arguments(parser, "mesh file with a boundary",
                               "minimal surface; quality = distance moved (.ply keeps it)")
    parser.add_argument("--max-iterations", type=_whole_number_from_one, default=200,
                        help="Pinkall-Polthier steps at most (default: %(default)s); if the shape has "
                             "not settled by then, OUTPUT is still written and the exit status is 3")
    from .curvature.minimal_surface import DEFAULT_TOL

    parser.add_argument("--tol", type=_positive_number, default=DEFAULT_TOL,
                        help="stop when no vertex moves more than TOL x the bbox diagonal of its piece "
                             "in a step, as --step measures it (by default normal to the surface: "
                             f"tangential sliding is not counted; default {DEFAULT_TOL:g})")
    parser.add_argument("--step", type=str.lower, choices=("normal", "full"), default="normal",
                        help="what TOL is compared with: the step normal to the surface (default) or "
                             "the full vertex displacement, tangential sliding included")
    add_fix_arguments(parser)
    add_backend_argument(parser)
    add_output_arguments(parser)

    def run(args):
        import numpy as np

        from . import minimal_surface, read_mesh, write_mesh
        from .curvature._validate import boundary_vertices, check_mesh
        from .curvature.errors import ConstraintError, counted

        resolve_input_output(args)
        V, F = check_mesh(*read_mesh(args.input))
        fixed = fixed_vertices(args, F, V.shape[0])
        if fixed.size == 0:
            raise ConstraintError(f"{args.input} is closed: a minimal surface needs a boundary to span "
                                  "(or vertices named with --fix).")
        loose = np.setdiff1d(boundary_vertices(F), fixed)
        if loose.size:                      # only with --fix: a free boundary has no minimal surface
            raise ConstraintError(f"--fix leaves {counted(loose.size, 'boundary vertex', 'boundary vertices')} "
                                  f"free (first: {', '.join(map(str, loose[:3]))}): a minimal surface spans a "
                                  "fixed boundary (a free one shrinks towards nothing); add --fix-boundary.")
        progress = Progress(args.max_iterations, enabled=sys.stderr.isatty())
        X = minimal_surface(V, F, fixed, max_iterations=args.max_iterations, tol=args.tol,
                            step=args.step, backend=args.backend,
                            callback=lambda i, s: progress.stage(f"step {i}"))
        progress.close()
        write_mesh(args.output, X, F, quality=_quality_for(args.output, np.linalg.norm(X - V, axis=1)),
                   overwrite=args.overwrite)
        state = "converged" if X.converged else "stopped (not converged)"
        if args.step == "normal":
            last = (f"last step {X.last_step:.2e} of the bbox diagonal normal to the surface "
                    f"({X.last_full_step:.2e} with tangential sliding)")
        else:
            last = f"last step {X.last_full_step:.2e} of the bbox diagonal (tangential sliding included)"
        print(f"{state} after {counted(X.iterations, 'step')}, {last}")
        _note_geometry_only(args.output, quality=not _keeps_quality(args.output))
        return 0 if X.converged else NOT_CONVERGED

    return run


# --- remesh (remeshing issue) ---------------------------------------------------------------

def _note_a_big_target(V, F, fraction, *, method="isotropic", evaluate=True):
    """A line on stderr when a target edge of ``fraction`` of the bbox diagonal makes a run of
    minutes (:func:`curvdetail.remesh.retriangulate.long_run_vertices`: more than ``BIG_TARGET``
    vertices), saying what takes the time (an estimate only: on a mesh the checks will refuse,
    or a decimation that will be refused, nothing is said)."""
    from .curvature._validate import bbox_diagonal
    from .remesh.retriangulate import long_run_reason, long_run_vertices

    count = long_run_vertices(V, F, fraction * bbox_diagonal(V), method=method, evaluate=evaluate)
    if count is not None:
        _say(f"note: a {100 * fraction:g} % target edge gives about {count:,.0f} target vertices; this takes "
             f"minutes. {long_run_reason(method, evaluate=evaluate, cli=True)}")


def _whole_number_from_one(text):
    """An option's value as an int >= 1, or an argparse error in the option's own terms."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number of at least 1")
    return value


def _positive_number(text):
    """An option's value as a finite float > 0, or an argparse error in the option's own terms."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0.0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive number")
    return value


def _percentage(text):
    """``--target-edge`` value: a number of percent, with or without a trailing ``%``."""
    try:
        return float(text.strip().removesuffix("%"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a percentage (e.g. 1 or 1%)") from None


@command("remesh", help="retriangulate a disk patch, rebuild it from its curvature detail, and "
                        "measure the error (the paper's Fig. 3)")
def _remesh_command(parser):
    add_input_output_arguments(parser, "source mesh: a disk-topology patch (one boundary loop)",
                               "rebuilt target mesh; per-vertex quality = distance to SOURCE (.ply keeps it)")
    parser.add_argument("--method", type=str.lower, choices=("isotropic", "decimate"), default="isotropic",
                        help="retriangulation: pymeshlab isotropic remeshing or fast-simplification "
                             "decimation (default: isotropic)")
    parser.add_argument("--target-edge", type=_percentage, default=1.0, metavar="PCT",
                        help="target edge length in %% of the source's bbox diagonal, e.g. 1 or 1%% "
                             "(default: 1)")
    parser.add_argument("--transfer", type=str.lower, choices=("conservative", "pointwise"), default="conservative",
                        help="detail transfer: conservative (edge curvature measure, default) or "
                             "pointwise (the paper: K interpolated times target area)")
    parser.add_argument("--rows", type=str.lower, choices=("all", "free"), default="free",
                        help="residual rows of the reconstruction energy (default: free)")
    parser.add_argument("--location", type=str.lower, choices=("closest", "uv"), default="closest",
                        help="locate points by 3D closest point (default) or in a shared planar domain")
    parser.add_argument("--parameterization", type=str.lower, choices=("harmonic", "meshlab_harmonic", "lscm"),
                        default=None, help="planar domain for --location uv (default: harmonic)")
    parser.add_argument("--no-surface-check", action="store_true",
                        help="isotropic remeshing without its surface-distance check of each collapse "
                             "and flip (25-50 %% faster at 100k-400k target vertices; the retriangulation "
                             "may differ where the remesher's smoothing would leave the surface)")
    add_backend_argument(parser)
    parser.add_argument("--report", metavar="R.json", default=None, help="write the JSON report here")
    parser.add_argument("--image", metavar="FIG.png", default=None,
                        help="write a picture: source, rebuilt coloured by error, zero-detail baseline")
    parser.add_argument("--no-evaluate", action="store_true",
                        help="skip the distance measurements (most of the time on big meshes); OUTPUT "
                             "gets no quality, and --image is not available")
    parser.add_argument("--quiet", action="store_true",
                        help="no stage progress on stderr (notes and warnings, such as the one on a "
                             "target of minutes, are still said)")
    add_output_arguments(parser, also=("--report", "--image"))

    def run(args):
        import json

        from ._output import Output, atomic_outputs, check_output_path
        from .io import MeshFileError, read_mesh, write_mesh
        from .remesh.experiment import WorseThanZeroDetailWarning, run_experiment, worse_than_zero_detail

        resolve_input_output(args)      # checks OUTPUT
        if args.parameterization is not None and args.location != "uv":
            raise ValueError(f"--parameterization {args.parameterization} applies to --location uv only "
                             f"(locating by {args.location} point uses no planar map); add --location uv "
                             "or leave it out.")
        if not (args.target_edge > 0 and args.target_edge < float("inf")):
            raise ValueError(f"--target-edge {args.target_edge:g}: give a positive percentage of the bbox "
                             "diagonal, e.g. 1 for 1 %.")
        # first: an output over an input is refused even with --overwrite, which the existing-
        # file check below would suggest
        _check_image_and_distinct(args.image, args.output, ("--report", args.report),
                                  inputs=[("INPUT", args.input)])
        for extra in (args.report, args.image):
            if extra is not None:
                check_output_path(extra, args.overwrite, hint=None, error=FileNotFoundError, flag=OVERWRITE)
        if args.no_evaluate and args.image is not None:
            raise ValueError("--image shows the measured distances; leave out --no-evaluate or --image.")
        V, F = read_mesh(args.input)
        # a note, not progress: said with --quiet too (the run it announces may take minutes)
        _note_a_big_target(V, F, args.target_edge / 100.0, method=args.method, evaluate=not args.no_evaluate)
        stages = 3 + (not args.no_evaluate) + (args.location == "uv") + (args.image is not None)
        progress = Progress(stages, enabled=not args.quiet)
        try:
            with warnings.catch_warnings():
                # said below, after the figures, in the command line's options
                warnings.simplefilter("ignore", WorseThanZeroDetailWarning)
                result = run_experiment(V, F, method=args.method, target_edge=args.target_edge / 100.0,
                                        transfer=args.transfer, rows=args.rows, location=args.location,
                                        parameterization=args.parameterization, backend=args.backend,
                                        evaluate=not args.no_evaluate, source_path=os.path.abspath(args.input),
                                        progress=progress.stage, surface_check=not args.no_surface_check)
            report = result["report"]
            # all outputs appear together, only once every one of them is written
            outputs = [_extra_output(args.image), _extra_output(args.report),
                       Output(args.output, error=MeshFileError, flag=OVERWRITE)]
            with atomic_outputs(outputs, overwrite=args.overwrite) as (image_tmp, report_tmp, mesh_tmp):
                if image_tmp is not None:
                    progress.stage("image")
                    from .plot import save_remeshing_figure

                    save_remeshing_figure(image_tmp, V, F, result["X"], result["Ft"], result["Z"],
                                          result["distance"], report, overwrite=True)
                if report_tmp is not None:
                    with open(report_tmp, "w", encoding="utf-8") as fh:
                        json.dump(report, fh, indent=2)
                        fh.write("\n")
                write_mesh(mesh_tmp, result["X"], result["Ft"], quality=_quality_for(args.output, result["distance"]),
                           overwrite=True)
        finally:
            progress.close()
        if args.no_evaluate:
            print(f"{report['source']['vertices']:,} -> {report['target']['vertices']:,} vertices; not "
                  f"measured (--no-evaluate); {report['seconds']['total']:.2f} s")
            return 0
        e, b, fl = report["error"], report["baseline_zero_detail"], report["floor_retriangulated"]
        print(f"{report['source']['vertices']:,} -> {report['target']['vertices']:,} vertices; "
              f"RMS {100 * e['hausdorff_rms']:.4f} %, max {100 * e['hausdorff_max']:.3f} % of the bbox "
              f"diagonal (zero detail {100 * b['hausdorff_rms']:.3f} % / {100 * b['hausdorff_max']:.2f} %, "
              f"floor {100 * fl['hausdorff_rms']:.4f} % / {100 * fl['hausdorff_max']:.3f} %); "
              f"{report['seconds']['total']:.2f} s")
        _note_geometry_only(args.output, quality=not _keeps_quality(args.output))
        worse = worse_than_zero_detail(report, cli=True)
        if worse is not None:           # the run did what was asked: a finding, not an error
            _say(f"note: {worse}")
        return 0

    return run


# --- list / apply / run (filter-suite issue) ------------------------------------------------

@command("list", help="list the filters (curvdetail.filters) with their parameters")
def _list_command(parser):
    parser.add_argument("filter", metavar="FILTER", nargs="?", help="show this filter only")
    parser.add_argument("--json", action="store_true",
                        help="print JSON (a list of filters, or the one filter) for scripts")

    def run(args):
        from .filters import get_filter, list_filters
        from .filters.registry import describe_filter

        specs = [get_filter(args.filter)] if args.filter else list_filters()
        if args.json:
            import json

            found = [spec.to_dict() for spec in specs]
            print(json.dumps(found[0] if args.filter else found, indent=2))
        else:
            print("\n\n".join(describe_filter(spec) for spec in specs))
        return 0

    return run


def _filter_params(spec, pairs):
    """``--param NAME=VALUE`` strings -> typed values (unknown names are left to apply())."""
    params = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        name = name.strip()
        if not sep or not name:
            raise ValueError(f"--param {pair!r} is not NAME=VALUE (e.g. --param rows=free).")
        if name in params:
            raise ValueError(f"--param {name} is given twice.")
        try:
            params[name] = spec.parameter(name).parse(value)
        except KeyError:
            params[name] = value
    return params


def _add_layers_argument(parser):
    parser.add_argument("--add", action="append", default=[], metavar="MESH",
                        help="load MESH as the next layer (1, 2, ...; the last one is current), e.g. "
                             "a retriangulation for transfer_curvature_detail")


def _run_on_file(args, work, *, other_inputs=()):
    """Check OUTPUT, load INPUT (and --add meshes) into a MeshSet, ``work(ms)``, print its figures
    as JSON, save the current mesh (quality and curvature attributes kept in PLY); returns the
    figures. OUTPUT may replace INPUT (with --overwrite), never an --add mesh or one of
    ``other_inputs`` (``(option, path)`` pairs: the script of ``run``)."""
    import json

    from . import _output
    from .filters.files import (attributes_lost_in, check_output_path, load_meshset, save_current_mesh,
                                vertex_colours_kept_in)
    from .io import MeshFileError

    _check_image_and_distinct(None, args.output, inputs=[("INPUT", args.input)],
                              other_inputs=[*(("--add", p) for p in args.add), *other_inputs])
    # an existing file refused in the command line's words, then the filters' checks (format hint)
    _output.check_output_path(args.output, args.overwrite, hint=None, error=MeshFileError, flag=OVERWRITE)
    check_output_path(args.output, args.overwrite)
    ms = load_meshset(args.input, *args.add)
    figures = work(ms)
    save_current_mesh(ms, args.output, overwrite=args.overwrite)
    figures = _plain_json(figures)
    print(json.dumps(figures, indent=2, allow_nan=False, default=str))
    # documented, but the next step ("no attribute 'curvature_detail'") is confusing without it
    quality = ms.current_mesh().has_vertex_scalar() and not _keeps_quality(args.output)
    _note_geometry_only(args.output, attributes_lost_in(ms, args.output), quality=quality,
                        colours=vertex_colours_kept_in(ms, args.output))
    return figures


def _plain_json(value):
    """Figures as JSON's own values: numpy scalars and arrays as numbers and lists (default=str
    printed np.int64(3) as "3" and an array as "[1. 2.]"), NaN and infinities as null (json
    wrote NaN, which no JSON reader takes); other objects are left to ``default=str``."""
    import numpy as np

    if isinstance(value, dict):
        return {(key.item() if isinstance(key, np.generic) else key): _plain_json(v) for key, v in value.items()}
    if isinstance(value, np.ndarray):
        return _plain_json(value.tolist())          # a list, or the one value of a 0-d array
    if isinstance(value, (list, tuple)):
        return [_plain_json(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def _keeps_quality(path):
    """Whether :func:`curvdetail.write_mesh` keeps the per-vertex quality in ``path``'s format
    (PLY; OBJ, OFF, STL and the rest drop it, and CTM is written without it: pymeshlab's reader
    crashes on, or misreads, CTM files with a quality)."""
    return os.path.splitext(os.fspath(path))[1].lower() == ".ply"


def _quality_for(path, quality):
    """``quality`` where ``path``'s format keeps it, else None (write_mesh refuses a quality for
    .ctm; the other formats drop it)."""
    return quality if _keeps_quality(path) else None


def _note_geometry_only(path, attributes=(), *, quality=False, colours=False):
    """The note, on stderr, that OUTPUT's format dropped what PLY keeps: the per-vertex quality
    (``quality``) and the filters' custom ``attributes`` (names), and what the file holds: the
    geometry, and the vertex colours where ``colours`` (CTM, OBJ, ... keep a coloured layer's
    colours). Nothing where neither is lost."""
    lost = (["the vertex quality"] if quality else []) + \
           ([f"the attributes {', '.join(attributes)}"] if attributes else [])
    if lost:
        verb = "is" if lost == ["the vertex quality"] else "are"
        kept = "the geometry and the vertex colours" if colours else "the geometry"
        _say(f"curvdetail: note: {os.path.basename(os.fspath(path))} holds {kept} only; "
             f"{' and '.join(lost)} {verb} kept by PLY output.")


def _not_converged_status(steps, output):
    """:data:`NOT_CONVERGED`, with a note on stderr for each, where the figures of a step (``steps``:
    ``(name, figures)`` pairs) say ``converged: false``, as ``curvdetail minimal`` does;
    :data:`AMPLIFIED` where they say an edit folded triangles or amplified its constraints
    beyond the limit (the filter's warning has said how), as ``curvdetail edit`` does; else 0.
    Where both happen, the first step's status."""
    from .curvature.errors import counted
    from .filters.editing import AMPLIFICATION_LIMIT

    status = 0
    for name, figures in steps:
        if not isinstance(figures, dict):
            continue
        ratios = [figures.get(key) for key in ("amplification", "detail_amplification")]
        if figures.get("folded_triangles") or any(isinstance(r, float) and r > AMPLIFICATION_LIMIT for r in ratios):
            status = status or AMPLIFIED
            continue
        if figures.get("converged") is None or figures["converged"]:
            continue
        text = f"{name} stopped (not converged)"
        if isinstance(figures.get("iterations"), int):
            text += f" after {counted(figures['iterations'], 'step')}"
        if isinstance(figures.get("last_step"), float):
            text += f", last step {figures['last_step']:.2e} of the bbox diagonal"
        _say(f"curvdetail: note: {text}; {os.path.basename(os.fspath(output))} is written all the same "
             f"(exit status {NOT_CONVERGED}): allow more iterations or a larger tolerance.")
        status = status or NOT_CONVERGED
    return status


@command("apply", help="apply one filter to a mesh file and write the current mesh (exit status 3: "
                        "written, but the filter's figures say converged: false; 4: written, but an "
                        "edit folded triangles or amplified its constraints)")
def _apply_command(parser):
    parser.add_argument("filter", metavar="FILTER", help="filter name (see `curvdetail list`)")
    parser.add_argument("input", metavar="INPUT", help="mesh file (any format MeshLab reads)")
    parser.add_argument("output", metavar="OUTPUT",
                        help="the current mesh afterwards (.ply keeps quality and attributes)")
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                        help="a filter parameter (repeatable); a length as an absolute value in model "
                             "units (0.01) or as a percentage of the bbox diagonal (1%%)")
    _add_layers_argument(parser)
    add_output_arguments(parser)

    def run(args):
        from .filters import apply, get_filter

        spec = get_filter(args.filter)
        params = _filter_params(spec, args.param)

        def work(ms):
            # generate_curvature_remeshing says beforehand when a target takes minutes (a plain
            # target_edge=0.01 is 0.01 model units): its LongRunWarning, shown as a note by main()
            return apply(ms, spec.name, **params)

        figures = _run_on_file(args, work)
        return _not_converged_status([(spec.name, figures)], args.output)

    return run


@command("run", help="run a MeshLab filter script (.mlx; ours and pymeshlab's) on a mesh file (exit "
                      "status 3: written, but a step's figures say converged: false; 4: written, but "
                      "an editing step folded triangles or amplified its constraints)")
def _run_command(parser):
    parser.add_argument("script", metavar="SCRIPT",
                        help="MeshLab filter script (.mlx); never written over, even with --overwrite")
    parser.add_argument("input", metavar="INPUT", help="mesh file (any format MeshLab reads)")
    parser.add_argument("output", metavar="OUTPUT",
                        help="the current mesh after the script (.ply keeps quality and attributes)")
    _add_layers_argument(parser)
    add_output_arguments(parser)

    def run(args):
        from .filters import ScriptError, run_script
        from .filters.mlx import check_script

        # a folder, malformed XML or a bad step: before reading INPUT
        if not check_script(args.script):
            raise ScriptError(f"{args.script} has no filter steps: nothing would run, and OUTPUT would be a "
                              "copy of INPUT. Add steps (curvdetail list names our filters; MeshLab saves "
                              "its own with Filters > Show current filter script), or name another script.")
        bar = Progress(0, enabled=sys.stderr.isatty())

        def step(k, total, name):
            bar.total = total
            bar.stage(name)

        def work(ms):
            try:
                return run_script(ms, args.script, progress=step)
            finally:
                bar.close()

        steps = _run_on_file(args, work, other_inputs=[("SCRIPT", args.script)])
        script = os.path.basename(args.script)
        return _not_converged_status([(f"{script} step {k} ({done['filter']})", done["figures"])
                                      for k, done in enumerate(steps, start=1)], args.output)

    return run


# --- edit (editing issue) -------------------------------------------------------------------

#: Exit status of ``curvdetail edit`` when OUTPUT is written but triangles folded over or vertices
#: moved more than three times as far as the handles (the warning says so; scripts can tell it
#: from a clean edit); of ``apply`` / ``run`` when an editing filter's figures say the same.
AMPLIFIED = 4


def _edit_retries(args):
    """What an edit that folded or amplified could try instead: the other ``--relations``, and
    ``--handle-detail free`` unless already in use (as apply_curvature_editing suggests)."""
    tries = [f"--relations {'one-ring' if args.relations == 'one+two-ring' else 'one+two-ring'}"]
    if args.handle_detail == "transform":
        tries.append("--handle-detail free")
    return " or ".join(tries)


@command("edit", help="deform a mesh with curvature-detail editing, given a benchmark .sel/.def pair "
                      "(exit status 4: written, but the edit folded triangles or amplified the "
                      "handles' motion)")
def _edit_command(parser):
    parser.add_argument("mesh", metavar="MESH", help="mesh file (vertex order must match SEL)")
    parser.add_argument("output", metavar="OUTPUT", help="edited mesh; quality = distance moved (.ply keeps it)")
    parser.add_argument("--sel", required=True, metavar="SEL",
                        help="per-vertex status file: 0 fixed, 1 free, 2 handle ('#' comments)")
    parser.add_argument("--def", dest="transform", required=True, metavar="DEF",
                        help="4x4 handle transform applied to homogeneous handle positions")
    parser.add_argument("--handle-detail", type=str.lower, choices=("transform", "free"), default="transform",
                        help="handles' curvature details: transformed by the linear part of DEF "
                             "(default) or solved like the free vertices'")
    parser.add_argument("--relations", type=str.lower, choices=("one-ring", "one+two-ring"), default="one-ring",
                        help="curvature stage: the paper's one-ring coefficients (square system) or "
                             "one- and two-ring coefficients together (least squares; steadier "
                             "when handle details are rotated)")
    parser.add_argument("--image", metavar="PNG", help="also save a picture: rest (by status) | edited")
    add_backend_argument(parser)
    add_output_arguments(parser, also=("--image",))

    def run(args):
        import numpy as np

        from . import read_mesh, write_mesh
        from ._output import Output, atomic_outputs, check_output_path
        from .curvature._validate import bbox_diagonal, check_mesh
        from .io.deformation import edit_with_selection, read_selection, read_transform
        from .plot import save_panels
        from .curvature._geometry import folded_triangles
        from .curvature.errors import UndeterminedEditError, counted, first_indices
        from .io import MeshFileError

        _check_image_and_distinct(args.image, args.output, inputs=[("MESH", args.mesh)],
                                  other_inputs=[("--sel", args.sel), ("--def", args.transform)])
        check_mesh_output(args.output, args.overwrite)
        if args.image:
            check_output_path(args.image, args.overwrite, hint=None, error=FileNotFoundError, flag=OVERWRITE)
        progress = Progress(3, enabled=sys.stderr.isatty())
        progress.stage("read")
        V, F = check_mesh(*read_mesh(args.mesh))
        status = read_selection(args.sel, V.shape[0])
        T = read_transform(args.transform)
        progress.stage("factor and solve")
        t = time.perf_counter()
        try:
            X, editor = edit_with_selection(V, F, status, T, handle_detail=args.handle_detail,
                                            relations=args.relations, backend=args.backend,
                                            return_editor=True)
        except UndeterminedEditError as exc:
            other = (" or --relations one-ring" if args.relations == "one+two-ring" else
                     " or --handle-detail transform" if args.handle_detail == "free" else "")
            raise UndeterminedEditError(exc.problem, f"Add handles (status 2) or fixed vertices (status 0) "
                                                     f"in {args.sel}{other}.") from None
        seconds = time.perf_counter() - t
        progress.stage("write")
        moved = np.linalg.norm(X - V, axis=1)
        # the picture and the mesh appear together, only once both are written
        outputs = [_extra_output(args.image or None), Output(args.output, error=MeshFileError, flag=OVERWRITE)]
        with atomic_outputs(outputs, overwrite=args.overwrite) as (image_tmp, mesh_tmp):
            if image_tmp is not None:
                save_panels(image_tmp, [(V, F, "rest (status 0/1/2)", status),
                                        (X, F, f"edited (handle detail: {args.handle_detail})", moved)],
                            overwrite=True)
            write_mesh(mesh_tmp, X, F, quality=_quality_for(args.output, moved), overwrite=True)
        progress.close()
        counts = np.bincount(status, minlength=3)
        print(f"{V.shape[0]} vertices ({counts[0]} fixed, {counts[1]} free, {counted(counts[2], 'handle')}); "
              f"largest move {moved.max() / bbox_diagonal(V):.3e} of the bbox diagonal; "
              f"{counted(editor.rank_deficient, 'rank-deficient ring')}, "
              f"{counted(editor.detail_islands, 'island vertex', 'island vertices')}; {seconds:.3f} s")
        _note_geometry_only(args.output, quality=not _keeps_quality(args.output))
        status_code = 0
        handle_move = moved[status == 2].max()
        if moved.max() > 3.0 * handle_move + 1e-12 * bbox_diagonal(V):
            _say(f"curvdetail: warning: vertices moved up to {moved.max() / max(handle_move, 1e-300):.1f} "
                 "times as far as the handles: the curvature stage amplified the handle details "
                 f"(ill-conditioned coefficients, see docs/editing.md); try {_edit_retries(args)}.")
            status_code = AMPLIFIED
        folded = folded_triangles(V, F, X, T[:3, :3])
        if folded.size:
            # the same count as apply_curvature_editing's (against the rest normal and the
            # handles' turn of it): an edit that folds is not clean whatever it amplified
            _say(f"curvdetail: warning: {counted(folded.size, 'triangle')} of {F.shape[0]} folded over (first: "
                 f"{first_indices(folded)}); try {_edit_retries(args)}.")
            status_code = AMPLIFIED
        return status_code

    return run



# --- entry point ----------------------------------------------------------------------------

def _extra_output(path):
    """The :class:`curvdetail._output.Output` of a report or picture (any name, checked as
    before the work), or None where it is not asked for."""
    from ._output import Output

    return None if path is None else Output(path, hint=None, error=FileNotFoundError, flag=OVERWRITE)


def _check_image_and_distinct(image, output, *extras, inputs=(), other_inputs=()):
    """``--image`` must end in .png (only PNG is written), no two outputs may be one file, and
    no output may replace an input file, with one exception: OUTPUT, the mesh, may replace the
    input mesh (``inputs``) when --overwrite asks for it (checked with the output's other
    conditions). The picture or report over the input mesh, or anything over the other input
    files (``other_inputs``: selections, transforms), is refused even with --overwrite.
    ``extras``, ``inputs`` and ``other_inputs`` are ``(option, path)`` pairs, the option (or
    argument, ``INPUT``) that named the file, said in the refusal."""
    if image is not None and not image.lower().endswith(".png"):
        raise ValueError(f"--image {image}: only PNG pictures are written; end the name in .png.")
    # (option, path, may it replace the input mesh)
    outputs = [(name, p, name == "OUTPUT") for name, p in (("--image", image), ("OUTPUT", output), *extras)
               if p is not None]
    real = [os.path.realpath(p) for _, p, _ in outputs]
    for k, r in enumerate(real):
        if r in real[:k]:
            first = outputs[real.index(r)][0]
            raise ValueError(f"{outputs[k][1]} is given for two outputs ({first} and {outputs[k][0]}); "
                             "name a separate file for each.")
    # (option, input, may OUTPUT replace it): an --add mesh that is INPUT's file as well is
    # another input (it was replaced by OUTPUT over INPUT with --overwrite)
    given_files = [(name, p, True) for name, p in inputs] + [(name, p, False) for name, p in other_inputs]
    for (name, path, is_mesh), r in zip(outputs, real):
        for given_name, given, replaceable in given_files:
            if given is not None and r == os.path.realpath(given) and not (is_mesh and replaceable):
                # where the file is INPUT as well, --overwrite lets OUTPUT replace that one only
                also = [n for n, g, ok in given_files
                        if is_mesh and ok and g is not None and r == os.path.realpath(g)]
                only = (f" (which lets OUTPUT replace {also[0]}, never a file also given as {given_name})"
                        if also else "")
                raise ValueError(f"{path} is an input of this run ({given_name} {given}); writing {name} "
                                 f"there would destroy it even with --overwrite{only}. Name another "
                                 f"file for {name}.")


def build_parser():
    from . import __version__

    parser = argparse.ArgumentParser(
        prog="curvdetail",
        description="Curvature detail representation of triangle meshes: reconstruct, edit and "
                    "remesh surfaces from their mean-curvature normals.",
        epilog="Exit status: 0 done; 1 an error, said on stderr, and no output written; 2 a command "
               "line that cannot be parsed; 3 OUTPUT written, but an iteration stopped before it "
               "converged (minimal, or a filter of apply/run whose figures say converged: false); "
               "4 OUTPUT written, but edit folded triangles or amplified the handles' motion (or an editing filter of "
               "apply/run folded triangles or amplified its constraints); 130 Ctrl-C, 143 SIGTERM.")
    parser.add_argument("--version", action="version", version=f"curvdetail {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name, (help_text, add_arguments) in _COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        p.set_defaults(_run=add_arguments(p))
    return parser


#: The signals that end a run at once, cleanly, with the word said for each: SIGTERM (``timeout``,
#: ``kill``) and SIGINT (Ctrl-C).
_ENDING_SIGNALS = {signal.SIGTERM: "terminated", signal.SIGINT: "interrupted"}


def _watch_sigterm():
    """End the process promptly and cleanly on SIGTERM (``timeout``, ``kill``) and SIGINT
    (Ctrl-C): Python runs its signal handlers (KeyboardInterrupt included) only between bytecodes
    of the main thread, so a handler alone waited for the native call in progress (a
    factorization, pymeshlab's sampling or remeshing: 10 s to minutes). Python's C-level handler
    writes the signal number to a wakeup pipe at once, from any thread; a watcher thread blocked
    on it removes the temporary files of the outputs in progress, says ``curvdetail: terminated``
    or ``curvdetail: interrupted`` and exits with 128 + the signal's number (143, 130), as soon
    as it gets the GIL, which numerical code mostly releases; after the renames of a commit in
    progress, see :mod:`curvdetail._output`. The Python handlers meanwhile do nothing (so no
    KeyboardInterrupt unwinds the main thread as well). A SIGINT that was ignored (a command
    started in the background by a shell) stays ignored. Returns the function that stops the
    watcher and puts everything back; None where this cannot be set up (not the main thread,
    or no wakeup fd): SIGINT then raises KeyboardInterrupt, as before."""
    from . import _output

    if threading.current_thread() is not threading.main_thread():
        return None
    read_fd, write_fd = os.pipe()
    try:
        os.set_blocking(write_fd, False)
        previous_fd = signal.set_wakeup_fd(write_fd, warn_on_full_buffer=False)
    except (ValueError, OSError):         # e.g. Windows, where the wakeup fd must be a socket
        os.close(read_fd)
        os.close(write_fd)
        return None
    # handlers that do nothing: the watcher does the work (SIGTERM's default would kill at once,
    # leaving the temporary files; SIGINT's KeyboardInterrupt would come after the native call)
    previous = {}
    for signum in _ENDING_SIGNALS:
        if signum == signal.SIGINT and signal.getsignal(signum) is signal.SIG_IGN:
            continue
        previous[signum] = signal.signal(signum, lambda signum, frame: None)

    def watch():
        while True:
            got = os.read(read_fd, 64)
            if not got or 0 in got:                     # closed, or stop() asked
                return
            ending = [signum for signum in previous if signum in got]
            if ending:
                # a commit in progress is let finish (milliseconds), so that its outputs are all
                # written or none, and no old file is left in its hidden folder
                _output.COMMIT_LOCK.acquire(timeout=10)
                for path in list(_output.PENDING):
                    with contextlib.suppress(OSError):
                        os.remove(path)
                _say(f"curvdetail: {_ENDING_SIGNALS[ending[0]]}")
                os._exit(128 + ending[0])

    watcher = threading.Thread(target=watch, name="curvdetail-signals", daemon=True)
    watcher.start()

    def stop():
        for signum, handler in previous.items():
            signal.signal(signum, handler if handler is not None else signal.SIG_DFL)
        signal.set_wakeup_fd(previous_fd)
        os.write(write_fd, b"\0")
        watcher.join()
        os.close(read_fd)
        os.close(write_fd)

    return stop


def _show_warning(message, category, filename, lineno, file=None, line=None, *, command=None):
    """A LongRunWarning (a filter in a script about to take minutes) or a
    WorseThanZeroDetailWarning (a remeshing that failed) as a note line; a FoldedTrianglesWarning
    or AmplifiedEditWarning (an edit that folded or amplified) as a warning line; the library's
    advice said in ``command``'s options (:func:`_in_command_words`)."""
    from .curvature.errors import FoldedTrianglesWarning
    from .filters.editing import AmplifiedEditWarning
    from .remesh import LongRunWarning, WorseThanZeroDetailWarning

    if issubclass(category, (LongRunWarning, WorseThanZeroDetailWarning)):
        _say(f"note: {_in_command_words(str(message), command)}")
    elif issubclass(category, (FoldedTrianglesWarning, AmplifiedEditWarning)):
        _say(f"curvdetail: warning: {_in_command_words(str(message), command)}")
    else:
        _default_showwarning(message, category, filename, lineno, file, line)


_default_showwarning = warnings.showwarning


#: Advice that the library gives in its parameters' names (curvdetail.remesh knows no command
#: line), in each command's words: the retriangulation's method is an option of ``remesh`` and a
#: --param of ``apply``, as are the filters' ``evaluate``, ``surface_check`` and ``target_edge``
#: of a long run's note, the solver backend, minimal_surface's ``tol`` and ``max_iterations``, the
#: editing filter's ``relations`` and ``handle_detail``, and a second layer is an --add mesh of
#: ``apply`` (``run``'s script names them as the library does).
_BACKEND_OPTION = {"or use backend='auto'": "or use --backend auto"}   # the commands with --backend
_COMMAND_WORDS = {
    "reconstruct": {**_BACKEND_OPTION},
    "minimal": {**_BACKEND_OPTION,
                # a collapse's advice (curvdetail.curvature.minimal_surface)
                "a larger tol": "a larger --tol", "or max_iterations below": "or --max-iterations below",
                "fewer max_iterations": "a smaller --max-iterations"},
    "remesh": {'use method "isotropic"': "use --method isotropic", **_BACKEND_OPTION},
    "edit": {**_BACKEND_OPTION,
             "relations='one-ring' makes": "--relations one-ring makes",
             "; use 'pardiso' or 'splu', or": "; use --backend pardiso or splu, or",
             "or relations='one+two-ring' (": "or --relations one+two-ring ("},
    "apply": {'use method "isotropic"': "use --param method=isotropic",
              "(evaluate=False ": "(--param evaluate=false ",
              "(surface_check=False ": "(--param surface_check=false ",
              "pymeshlab.PercentageValue(1) is 1 %": "--param target_edge=1% is 1 %",
              "or use backend='auto'": "or use --param backend=auto",
              "relations='one-ring' makes": "--param relations=one-ring makes",
              "; it has no default that works.": "; it has no default that works: give it with --param "
                                                 "NAME=VALUE.",
              "; use 'pardiso' or 'splu', or": "; use --param backend=pardiso or splu, or",
              "or relations='one+two-ring' (": "or --param relations=one+two-ring (",
              # apply_curvature_editing's warning: what to try
              "try relations='one+two-ring'": "try --param relations=one+two-ring",
              "try relations='one-ring'": "try --param relations=one-ring",
              ", handle_detail='free'": ", --param handle_detail=free",
              # a filter of two layers given one: apply loads the second with --add
              "load or generate the retriangulation as another layer (e.g. sourcemesh=0, targetmesh=1)":
                  "load the retriangulation as another layer with --add MESH (e.g. --param sourcemesh=0 "
                  "--param targetmesh=1, the defaults with one --add)",
              "name two different layers (e.g. sampledmesh=1, targetmesh=0)":
                  "name two different layers, loading the second with --add MESH (e.g. --param sampledmesh=1 "
                  "--param targetmesh=0, the defaults with one --add)",
              # apply runs one filter: a selection is made by an earlier step of a script
              "Select vertices to keep (e.g. with compute_selection_by_condition_per_vertex) "
              "or fix the boundary.":
                  "Select vertices to keep in a `curvdetail run` script (e.g. with "
                  "compute_selection_by_condition_per_vertex before this step), rebuild from the mesh's own "
                  "detail with `curvdetail reconstruct INPUT OUTPUT --fix I ...`, or fix the boundary "
                  "(--param fix_boundary=true)."},
}

#: Advice of every command: an existing output is replaced with --overwrite, Python's
#: ``overwrite=True`` (the filters and write_mesh) being no use in a shell.
_EVERY_COMMANDS_WORDS = {"pass overwrite=True": "pass --overwrite"}


def _in_command_words(message, command):
    """``message`` with the library's advice said in ``command``'s options (see
    :data:`_COMMAND_WORDS`, :data:`_EVERY_COMMANDS_WORDS`)."""
    for library, words in (*_COMMAND_WORDS.get(command, {}).items(), *_EVERY_COMMANDS_WORDS.items()):
        message = message.replace(library, words)
    return message


def main(argv=None):
    parser = build_parser()
    args = parser.parse_args(argv)
    stop_watching = _watch_sigterm()
    try:
        with warnings.catch_warnings():
            warnings.showwarning = functools.partial(_show_warning, command=args.command)
            return int(args._run(args) or 0)
    except KeyboardInterrupt:
        _say("curvdetail: interrupted")
        return 130
    except BrokenPipeError:
        # the reader of stdout went away (`curvdetail list | head`): not an error of ours, as for
        # cat(1); stdout carries only the final figures, written after every output file (stderr
        # lines go through _say, which never raises); stdout is pointed at /dev/null so that
        # Python's final flush does not fail again
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except (ValueError, OSError, RuntimeError) as exc:
        # the whole message: pymeshlab's first line alone ("Unable to open file") hid the reason
        message = str(exc).strip() or type(exc).__name__
        _say(f"curvdetail: error: {_in_command_words(message, args.command)}")
        return 1
    finally:
        if stop_watching is not None:
            stop_watching()


if __name__ == "__main__":
    sys.exit(main())
