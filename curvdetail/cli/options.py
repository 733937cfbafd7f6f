"""Parts of the ``curvdetail`` command: option types and shared arguments, progress and notes on
stderr, figures on stdout (neither may decide a run's outcome), output checks, and the MeshSet
run of ``apply`` and ``run``."""

import argparse
import json
import os
import sys
import time
import warnings

#: Exit status when OUTPUT is written but an iteration stopped before it converged.
NOT_CONVERGED = 3
#: Exit status when OUTPUT is written but an edit folded triangles or amplified its constraints.
AMPLIFIED = 4

def whole_number_from_one(text):
    """An option's value as an int >= 1 (argparse type)."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number of at least 1")
    return value


def positive_number(text):
    """An option's value as a finite float > 0 (argparse type)."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0.0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive number")
    return value


def length(text):
    """A length option (``--target-edge``): a positive number in model units, or a percentage of
    the bbox diagonal such as ``1%`` (`curvdetail.remesh.units.as_bbox_length`)."""
    from ..remesh.units import as_bbox_length

    number = text if text.strip().endswith("%") else positive_number(text)
    try:
        return as_bbox_length(number, "target_edge")
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive length (e.g. 0.05, or 1% of the "
                                         "bbox diagonal)") from None


def _vertex_indices(text):
    """One ``--fix`` value: an index, or several separated by commas ("0,17,42")."""
    try:
        return [int(part) for part in text.split(",") if part.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a vertex index (put --fix after INPUT OUTPUT, "
                                         "or end its list with --)") from None


def choice(parser, name, choices, default, help):
    parser.add_argument(name, type=str.lower, choices=choices, default=default, help=help)


def add_laplacian(parser, what):
    from ..curvature.robust_laplacian import LAPLACIANS

    choice(parser, "--laplacian", LAPLACIANS, "auto",
           f"{what}: cotan (refuses zero-area triangles), robust (mollified, for zero-area triangles) or "
           "auto (robust only where cotan refuses the mesh; the output says which ran)")


def add_backend(parser):
    from ..curvature.sparse_solver import BACKENDS

    parser.add_argument("--backend", default="auto", help=f"sparse solver: {', '.join(('auto',) + BACKENDS)}")


def add_overwrite(parser, also=()):
    parser.add_argument("--overwrite", action="store_true",
                        help=f"replace {' and '.join(['OUTPUT', *also])} if they exist")


def add_input_output(parser, input_help, output_help):
    """``INPUT OUTPUT``, or ``--example OUTPUT`` for the bundled example mesh."""
    parser.add_argument("input", metavar="INPUT", nargs="?", help=input_help)
    parser.add_argument("output", metavar="OUTPUT", nargs="?", help=output_help)
    parser.add_argument("--example", action="store_true",
                        help="use the bundled example mesh (an SRTM terrain patch) as INPUT")


def add_fix(parser):
    parser.add_argument("--fix", type=_vertex_indices, nargs="*", action="extend", default=None, metavar="I",
                        help="vertex indices to keep fixed, e.g. --fix 0 17 42 or --fix 0,17,42 "
                             "(default: the boundary; a closed piece needs some)")
    parser.add_argument("--fix-boundary", action="store_true", help="with --fix: keep the boundary fixed as well")


def input_output(args):
    """Fill ``args.input`` / ``args.output`` from ``--example``; refuse a missing one."""
    from ..curvature.errors import CurvdetailError

    if args.example:
        if args.output is not None:
            raise CurvdetailError("with --example give only OUTPUT, not INPUT and OUTPUT", parameter="example",
                                  hint="the example is INPUT")
        from ..data import example_path

        args.input, args.output = example_path(), args.input
    if args.input is None or args.output is None:
        raise CurvdetailError("missing INPUT or OUTPUT", hint="or use --example OUTPUT")
    # OUTPUT may replace INPUT with --overwrite, never the package's own example
    return {"other_inputs": [("--example", args.input)]} if args.example else {"inputs": [("INPUT", args.input)]}


def read_checked(path):
    from .. import check_mesh, read_mesh

    return check_mesh(*read_mesh(path))


def read_noting_extras(path, check=True):
    """``(V, F, extras)``: `read_checked` (``check=False``: `read_mesh` alone, for a command
    whose library call checks), and what else INPUT holds per vertex that a command writing new
    geometry does not carry (``"vertex colours"``, ``"normals"``), for `note_not_carried`."""
    from .. import check_mesh, read_mesh

    V, F, fields = read_mesh(path, fields=True)
    extras = [what for what, names in (("vertex colours", ("red", "green", "blue")), ("normals", ("nx", "ny", "nz")))
              if set(names) <= set(fields)]
    return (*(check_mesh(V, F) if check else (V, F)), extras)


def note_not_carried(input_path, output_path, extras):
    """Say on stderr that OUTPUT does not carry INPUT's ``extras`` (from `read_noting_extras`)."""
    if extras:
        name = os.path.basename(os.fspath(output_path))
        say(f"curvdetail: note: {name} does not carry the {' and '.join(extras)} of "
            f"{os.path.basename(os.fspath(input_path))} (new geometry; a PLY output's colours show the distance).")


def fixed_vertices(args, V, F, *, purpose):
    """The vertices ``--fix`` / ``--fix-boundary`` name (the boundary when neither is given)."""
    import numpy as np

    from .. import boundary_vertices
    from ..curvature.errors import ConstraintError

    if args.fix is None:
        fixed = boundary_vertices(F)
    else:
        fixed = np.unique(np.array([i for part in args.fix for i in part], dtype=np.int64))
        if fixed.size == 0:
            raise ConstraintError("--fix was given without vertex indices", parameter="fix",
                                  hint="name some, e.g. --fix 0 17 42, or leave it out to fix the boundary")
        bad = fixed[(fixed < 0) | (fixed >= V.shape[0])]
        if bad.size:
            raise ConstraintError(f"vertex {bad[0]} is out of range 0..{V.shape[0] - 1} ({bad.size} such in all)",
                                  parameter="fix", value=bad, count=int(bad.size), first=bad[:3].tolist(),
                                  hint="give indices of INPUT's vertices")
        if args.fix_boundary:
            fixed = np.union1d(fixed, boundary_vertices(F))
    if fixed.size == 0:
        raise ConstraintError(f"{args.input} is closed (no boundary)", parameter="fix",
                              hint=f"name vertices to fix {purpose}")
    return fixed


def diagonal(V):
    import numpy as np

    return float(np.linalg.norm(np.ptp(V, axis=0)))


#: The stream whose last line is still open (a stage waiting for its seconds), or None.
_open_line = None


def say(text, end="\n"):
    """Write a line to stderr; a broken or full stderr is ignored (a progress line or a note
    must not end a run whose outputs are still to be written)."""
    global _open_line
    if _open_line is sys.stderr and not text.startswith(" "):
        text = "\n" + text
    try:
        sys.stderr.write(text + end)
        sys.stderr.flush()
    except (OSError, ValueError):           # EPIPE, ENOSPC, or a closed stream
        return
    _open_line = sys.stderr if not end else None


def print_figures(text):
    """Print the figures on stdout. Where stdout cannot take them (a full device, a reader gone
    away) the run still succeeded: a note on stderr, and stdout is pointed at /dev/null so that
    Python's final flush does not fail again."""
    try:
        print(text, flush=True)
    except (OSError, ValueError) as exc:
        try:
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        except (OSError, ValueError):       # no file descriptor (a replaced sys.stdout)
            pass
        if not isinstance(exc, BrokenPipeError):        # `| head`: the reader had enough, as for cat
            say(f"curvdetail: note: the figures could not be printed ({exc.strerror or exc})")


class Progress:
    """Stage-by-stage progress on stderr: ``[2/5] parameterize ... 0.41 s``; within a long stage
    (``stage(name, done, total)``) a line per step with the rate and the time to go:
    ``[5/5] evaluate 2/5 (1.20 s, 1.7 per s, ~1.8 s to go)``, from ``quiet_for`` seconds into it."""

    quiet_for = 2.0

    def __init__(self, total, enabled=True):
        self.total, self.done, self.enabled, self._t = total, 0, enabled, None
        self._name, self._steps = None, False

    def stage(self, name, *counts):
        if counts and self._t is not None:
            self._step(*counts)
            return
        self.close()
        self.done += 1
        self._t, self._name, self._steps = time.perf_counter(), name, False
        if self.enabled:
            say(f"[{self.done}/{self.total}] {name} ...", end="")

    def _step(self, done, total):
        elapsed = time.perf_counter() - self._t
        rate = done / max(elapsed, 1e-9)
        if self.enabled and elapsed >= self.quiet_for:        # a long stage only
            self._steps = True
            say(f"[{self.done}/{self.total}] {self._name} {done}/{total} ({elapsed:.2f} s, {rate:.3g} per s, "
                f"~{(total - done) / rate:.1f} s to go)")

    def close(self):
        if self._t is not None and self.enabled:
            seconds = time.perf_counter() - self._t
            say(f"[{self.done}/{self.total}] {self._name} done, {seconds:.2f} s" if self._steps else f" {seconds:.2f} s")
        self._t = None


def _same_file(a, b):
    """Whether two paths name one file: ``os.path.samefile`` (hard links, symbolic links, bind
    mounts) where both exist, else the real paths."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.realpath(a) == os.path.realpath(b)


def check_outputs(args, outputs, *, inputs=(), other_inputs=(), mesh_check=None):
    """Refuse, before any work, outputs that cannot be written.

    ``outputs``: ``(option, path, is_mesh)``, path None where not asked for. ``inputs``: the
    input mesh, which OUTPUT may replace with --overwrite; ``other_inputs`` (scripts, --add
    meshes, --sel / --def, the bundled example): never replaced. Both ``(option, path)``.
    ``mesh_check``: how a mesh OUTPUT is checked (default `curvdetail.io.mesh.check_mesh_output`).
    """
    from ..curvature.errors import CurvdetailError
    from ..io.atomic import check_output_path
    from ..io.mesh import check_mesh_output

    outputs = [(name, path, mesh) for name, path, mesh in outputs if path is not None]
    for name, path, _ in outputs:
        if name == "--image" and not path.lower().endswith(".png"):
            raise CurvdetailError(f"--image {path}: only PNG pictures are written", parameter="image",
                                  value=path, hint="end the name in .png")
    for k, (name, path, mesh) in enumerate(outputs):
        for other, earlier, _ in outputs[:k]:
            if _same_file(path, earlier):
                raise CurvdetailError(f"{path} is given for two outputs ({other} and {name})", value=path)
        protected = [(given, p) for given, p in other_inputs if p is not None]
        if not mesh:
            protected += [(given, p) for given, p in inputs if p is not None]
        for given, p in protected:
            if _same_file(path, p):
                raise CurvdetailError(f"{path} is an input of this run ({given} {p}); writing {name} there "
                                      "would destroy it, even with --overwrite", value=path)
        if mesh:
            try:
                (mesh_check or check_mesh_output)(path, args.overwrite)
            except CurvdetailError as exc:          # the library calls it path
                exc.parameter = "output"
                raise
        else:
            check_output_path(path, args.overwrite, parameter=name.lstrip("-"))


def quality_for(path, quality):
    """``quality`` where ``path``'s format keeps it (PLY), else None."""
    return quality if _is_ply(path) else None


def write_measured(path, V, F, quality, *, diagonal_of, overwrite):
    """Write OUTPUT with its per-vertex ``quality`` (model units) and, in a PLY, vertex colours
    from `curvdetail.plot.COLOUR_MAP` over [0, max |quality|], which MeshLab shows on open.
    Returns that colour range in % of the bbox diagonal of ``diagonal_of`` (vertices; the
    figures' reference), or None where the format keeps neither quality nor colours."""
    import numpy as np

    from ..io.mesh import check_mesh_output, write_mesh, write_mesh_fields
    from ..plot import vertex_colours

    if not _is_ply(path):
        write_mesh(path, V, F, overwrite=overwrite)
        return None
    check_mesh_output(path, overwrite)
    quality = np.asarray(quality, dtype=np.float64)
    top = float(np.abs(quality).max(initial=0.0))
    rgba = vertex_colours(np.abs(quality), top)
    write_mesh_fields(path, V, F, {"quality": quality, **{c: rgba[:, k] for k, c in enumerate(RGBA)}},
                      overwrite=overwrite)
    return [0.0, 100 * top / diagonal(diagonal_of)]


#: The PLY vertex properties of a colour.
RGBA = ("red", "green", "blue", "alpha")


def _is_ply(path):
    return os.path.splitext(os.fspath(path))[1].lower() == ".ply"


def note_dropped(path, attributes=(), *, quality=False, colours=False):
    """Say on stderr what OUTPUT's format dropped that PLY keeps (the vertex quality, the filters'
    ``attributes``); nothing for PLY."""
    if _is_ply(path) or not (quality or attributes):
        return
    lost = (["the vertex quality"] if quality else []) + ([f"the attributes {', '.join(attributes)}"]
                                                          if attributes else [])
    kept = "the geometry and the vertex colours" if colours else "the geometry"
    verb = "is" if lost == ["the vertex quality"] else "are"
    say(f"curvdetail: note: {os.path.basename(os.fspath(path))} holds {kept} only; {' and '.join(lost)} "
        f"{verb} kept by PLY output.")


def plain_json(value):
    """Figures as JSON values: numpy scalars and arrays as numbers and lists, NaN and infinities
    as null."""
    import numpy as np

    if isinstance(value, dict):
        return {(k.item() if isinstance(k, np.generic) else k): plain_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return plain_json(value.tolist()) if isinstance(value, np.ndarray) else [plain_json(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def run_on_file(args, work, *, other_inputs=()):
    """``apply`` / ``run``: check OUTPUT, load INPUT and the --add meshes into a MeshSet, run
    ``work(ms)``, save the current mesh, print the figures as JSON; returns them. OUTPUT may
    replace INPUT (with --overwrite), never an --add mesh or one of ``other_inputs``."""
    from ..filters.files import (attributes_lost_in, check_output_path, load_meshset, save_current_mesh,
                                vertex_colours_kept_in)

    check_outputs(args, [("OUTPUT", args.output, True)], inputs=[("INPUT", args.input)],
                  other_inputs=[*(("--add", p) for p in args.add), *other_inputs], mesh_check=check_output_path)
    ms = load_meshset(args.input, *args.add)
    figures = work(ms)
    save_current_mesh(ms, args.output, overwrite=args.overwrite)
    figures = plain_json(figures)
    print_figures(json.dumps(figures, indent=2, allow_nan=False, default=str))
    note_dropped(args.output, attributes_lost_in(ms, args.output), quality=ms.current_mesh().has_vertex_scalar(),
                 colours=vertex_colours_kept_in(ms, args.output))
    return figures


def figures_status(steps, output):
    """The exit status of ``apply`` / ``run`` from the figures of each step (``(name, figures)``):
    `AMPLIFIED` where an edit folded triangles or amplified its constraints, `NOT_CONVERGED`
    (with a note) where they say ``converged: false``, else 0; the first step's status where
    several apply."""
    from ..filters.editing import AMPLIFICATION_LIMIT

    status = 0
    for name, figures in steps:
        if not isinstance(figures, dict):
            continue
        ratios = [figures.get(key) for key in ("amplification", "detail_amplification")]
        if figures.get("folded_triangles") or any(isinstance(r, float) and r > AMPLIFICATION_LIMIT for r in ratios):
            status = status or AMPLIFIED
        elif figures.get("converged") is False:
            n, last = figures.get("iterations"), figures.get("last_step")
            text = f" after {n} step{'' if n == 1 else 's'}" if isinstance(n, int) else ""
            text += f", last step {last:.2e} of the bbox diagonal" if isinstance(last, float) else ""
            say(f"curvdetail: note: {name} stopped (not converged){text}; {os.path.basename(os.fspath(output))} "
                f"is written all the same (exit status {NOT_CONVERGED}).")
            status = status or NOT_CONVERGED
    return status


#: Python parameter names of the library whose option is named otherwise.
_ALIASES = {"fixed": "fix"}


def _option(args, parameter):
    """The command line's name for a library parameter, or None."""
    if parameter == "overwrite":
        return "--overwrite"
    if parameter in args._options:
        return args._options[parameter]
    if args.command in ("apply", "run"):
        from ..filters import get_filter

        if args.command == "run" or parameter not in get_filter(args.filter).parameter_names:
            return None
        if get_filter(args.filter).parameter(parameter).type == "mesh":
            return f"--add MESH / --param {parameter}"
        return f"--param {parameter}"
    return args._options.get(_ALIASES.get(parameter))


def error_line(exc, args):
    """``curvdetail: error: <problem> (<option>: <hint>)`` from the exception's fields, or its
    message where it names no parameter the command line has."""
    text = " ".join(str(exc).split()) or type(exc).__name__
    hint, parameter = getattr(exc, "hint", None), getattr(exc, "parameter", None)
    option = _option(args, parameter) if isinstance(parameter, str) else None
    if hint and option:
        text = f"{' '.join(str(getattr(exc, 'problem', text)).split())} ({option}: {hint})"
    return f"curvdetail: error: {text}"


def show_warning(message, category, filename, lineno, file=None, line=None):
    """A library warning as one line: a note where it announces a long run or a finding, a
    warning where an edit folded or amplified; other warnings as Python shows them."""
    from ..curvature.errors import FoldedTrianglesWarning
    from ..filters import ScaleWarning
    from ..filters.editing import AmplifiedEditWarning
    from ..remesh import LongRunWarning, WorseThanZeroDetailWarning

    if issubclass(category, (LongRunWarning, WorseThanZeroDetailWarning, ScaleWarning)):
        say(f"note: {message}")
    elif issubclass(category, (FoldedTrianglesWarning, AmplifiedEditWarning)):
        say(f"curvdetail: warning: {message}")
    else:
        _python_showwarning(message, category, filename, lineno, file, line)


_python_showwarning = warnings.showwarning
