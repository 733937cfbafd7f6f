"""The remeshing experiment of the paper's Fig. 3, end to end, with a JSON-ready report."""

import time

import numpy as np

from ..curvature.errors import CurvdetailError, MeshError, warn

from ..curvature.checks import as_count, check_bool, check_choice
from ..curvature.geometry import bbox_diagonal
from ..curvature.anchors import anchor_vertices
from ..curvature.robust_laplacian import LAPLACIANS, source_detail
from ..curvature.topology import boundary_vertices
from ..curvature.reconstruct import ROW_MODES, Reconstructor
from ..curvature.sparse_solver import resolve_backend
from ._disk import TARGET_BOUNDARY_TOLERANCE, RemeshError  # noqa: F401 (their home before)
from ._disk import check_disk, check_retriangulation, check_surface
from .evaluate import Surface
from .parameterize import METHODS as PARAMETERIZATIONS
from .parameterize import parameterize
from .retriangulate import METHODS as RETRIANGULATIONS
from .retriangulate import retriangulate
from .transfer import LOCATIONS
from .transfer import METHODS as TRANSFERS
from .transfer import squashed_in_plane, transfer_curvature
from .units import as_bbox_length, length_figures

#: Face samples per direction for the zero-detail baseline (it lies ~10 % of the bbox diagonal
#: from the source, where every search is slow); they agree with 100,000 samples to ~1 %
#: (mannequin_nose, mannequin_disk_1k, camelhead).
BASELINE_SAMPLES = 20000

#: RMS distances (in the report's unit, % of the source's bbox diagonal; the figures below are
#: fractions of it) below which a figure is rounding, not
#: a measurement, by the engine that measured it (see `hausdorff`): pymeshlab's works in
#: single precision (a flat square against its retriangulation: RMS 3e-11 to 1.6e-10, max up
#: to 5e-8, where the distances are 0), the exact engine in double (1e-17 to 1e-16). On a
#: flat patch the rebuilt, zero-detail and retriangulated surfaces all lie on the source, and a
#: ratio of two such figures is noise (on those squares the improvement over zero detail came
#: out 0 to 7e-6 and the ratio to the floor 0.3 to 1.3; with a divisor of exactly 0, clamped to
#: 1e-300, up to ~1e284). The report's ratios with such a figure are None, with the reason in
#: ``ratio_notes``; a rebuild that close is never said to be worse than zero detail.
ROUNDING_RMS = {"meshlab": 1e-5, "exact": 1e-10}       # 1e-7 and 1e-12 of the diagonal

#: The report's distance keys: % of the source's bbox diagonal.
RMS, MAX = "hausdorff_rms_percent_of_diagonal", "hausdorff_max_percent_of_diagonal"

#: Measurements of the evaluate stage, reported one by one as ``progress("evaluate", done, total)``.
EVALUATION_STEPS = 5

STAGES = ("retriangulate", "parameterize", "transfer", "reconstruct", "evaluate")

DEFAULTS = {"method": "isotropic", "target_edge": "1%", "transfer": "conservative", "rows": "free",
            "location": "closest", "parameterization": None, "backend": "auto", "surface_check": True,
            "laplacian": "auto"}


class WorseThanZeroDetailWarning(UserWarning):
    """Said by `remesh_experiment` (and so by the ``generate_curvature_remeshing`` filter;
    ``curvdetail remesh`` says it as a note) when the rebuilt surface is farther from the source
    than the zero-detail surface (two-sided Hausdorff RMS): the transferred detail made the
    rebuild worse than no detail at all, so the configuration failed on this patch (the paper's
    pointwise transfer does on camelhead, 36 % RMS against 21 %). The message says what to try
    (`worse_than_zero_detail`); the figures are in the report. Turn it into an error with
    ``warnings.simplefilter("error", WorseThanZeroDetailWarning)``."""


def _option(name, value, cli):
    """An option as the user gives it: ``transfer='conservative'`` or ``--transfer conservative``."""
    return f"--{name.replace('_', '-')} {value}" if cli else f"{name}={value!r}"


def worse_than_zero_detail(report, cli=False):
    """The message of a `WorseThanZeroDetailWarning` for an evaluated ``report`` of
    `remesh_experiment`, or None where the rebuild is no farther from the source than the
    zero-detail surface (RMS), lies on the source to rounding (RMS below its engine's
    ``ROUNDING_RMS``) or was not measured. ``cli``: naming the options of ``curvdetail remesh``
    instead of the function's parameters."""
    if "error" not in report or not report.get("baseline_zero_detail"):
        return None
    rms, zero = report["error"][RMS], report["baseline_zero_detail"][RMS]
    if not (rms > zero and rms >= ROUNDING_RMS[report["error"].get("engine", "exact")]):
        return None                                 # not worse, or rounding (a flat patch)
    options = report.get("options", {})
    tries = []
    if options.get("transfer") == "pointwise":
        tries.append(f"the conservative transfer ({_option('transfer', 'conservative', cli)}, the default; the "
                     "pointwise one interpolates K = D / A, which spikes where the source has small vertex "
                     "areas, e.g. sliver triangles)")
    if options.get("location") == "uv":
        tries.append(f"closest-point location ({_option('location', 'closest', cli)}, the default; a planar "
                     "map squeezes elongated parts of the patch)")
    if options.get("rows") == "all":
        tries.append(f"free rows ({_option('rows', 'free', cli)}, the default)")
    if not tries:       # the defaults: measured well below zero detail on every public patch
        edge = "--target-edge" if cli else "target_edge"
        tries.append(f"a shorter target edge ({edge}: a coarse target cannot carry the source's detail), or "
                     f"{_option('method', 'decimate', cli)}, and check the source for noise or sliver triangles")
    return (f"the rebuilt surface is farther from the source than the zero-detail surface (RMS "
            f"{rms:.4g} % against {zero:.4g} % of the bbox diagonal): the transferred detail made it "
            f"worse than no detail at all, so this configuration failed on this patch. Try "
            f"{'; and '.join(tries)}. docs/results/fig3_table.md has what was measured.")


def remesh_experiment(V, F, *, method="isotropic", target_edge="1%", transfer="conservative", rows="free",
                      location="closest", parameterization=None, backend="auto", evaluate=True,
                      source_path=None, progress=None, target=None, surface_check=True, anchors=1,
                      laplacian="auto"):
    """Retriangulate a surface, carry its curvature detail over, rebuild it, and measure.

    Stages (timed): retriangulate (`retriangulate`), parameterize (only for
    ``location="uv"``: `parameterize`), transfer (`transfer_curvature`, location
    included), reconstruct (target positions from the transferred detail with the target's
    boundary loops fixed and ``anchors`` vertices on each closed piece, see
    `anchor_vertices`: one `Reconstructor` factorization,
    solved for the detail
    and for the zero-detail baseline, the harmonic surface ``(L Z)_free = 0``: with
    ``rows="all"`` a second, free-row factorization gives it), evaluate (`hausdorff` for
    the rebuilt mesh, the zero-detail baseline and the retriangulated surface itself, the
    floor).

    Parameters
    ----------
    V : (n, 3) float array, F : (m, 3) int array
        The source: a manifold, consistently oriented surface (closed, holes, pieces, handles; a
        disk for ``location="uv"``)
    method : {"isotropic", "decimate"}
        Retriangulation
    target_edge : float or str
        Target edge length: model units, or a percentage of the bbox diagonal ("1%",
        PercentageValue(1); see `as_length`)
    transfer : {"conservative", "pointwise"}
        How detail is carried over (conservative: measured better)
    rows : {"free", "all"}
        Residual rows of the reconstruction energy
    location : {"closest", "uv"}
        3D closest point, or a shared planar domain (disks only)
    parameterization : {"harmonic", "meshlab_harmonic", "lscm"} or None
        The planar domain of ``location="uv"`` (None: "harmonic"); refused with
        ``location="closest"``, which uses no planar map
    backend : str
        Sparse solver backend
    evaluate : bool
        Measure distances (the costly part on big meshes), with `hausdorff`'s exact engine and its
        seeded samples: every call repeats the figures exactly
    source_path : str or None
        Recorded in the report
    progress : callable or None
        Called with each stage name as it starts, and in the evaluation (the longest stage of a big
        run) as ``progress("evaluate", done, total)`` after each of its ``EVALUATION_STEPS``
        measurements
    target : tuple (Vt, Ft) or None
        A ready retriangulation to use instead of making one (`check_retriangulation`: as many
        boundary loops, its boundary vertices on the source's boundary polyline, every vertex
        within ``SURFACE_TOLERANCE`` of the source's surface); ``method`` / ``target_edge`` are
        then unused (but still checked), the report's ``options.method`` is ``"given"`` and its
        ``options.target_edge_model_units`` and ``target_edge_percent_of_diagonal`` None, and
        ``seconds.retriangulate`` is 0
    surface_check : bool
        Isotropic retriangulation: check the distance an edge collapse or flip moves the surface
        (pymeshlab's ``checksurfdist``; see `retriangulate`). ``False`` is faster on large
        targets and may change the retriangulation; recorded in ``options.surface_check`` (None
        for a given ``target`` or ``"decimate"``)
    anchors : int
        Fixed vertices on each closed piece of the target (farthest-point sampled from its flattest
        vertex)
    laplacian : {"auto", "cotan", "robust"}
        The source's detail ``D = L V``: "cotan" the plain cotangent Laplacian (refuses zero-area
        triangles); "robust" the mollified one (`robust_laplacian`), and the geometric stages see
        the source with its zero-area caps flipped away (`flip_caps`: the same surface); "auto"
        "cotan" unless the plain checks refuse the source's zero-area triangles. The rebuild on
        the target uses the plain one always

    Returns
    -------
    mesh : tuple ``(X, Ft)``
        The rebuilt target: (p, 3) positions and (q, 3) triangles
    report : dict
        JSON-ready: ``source.{path, vertices, faces, bbox_diagonal}``, ``target.{vertices, faces,
        boundary_vertices, boundary_loops}``, ``anchors`` (fixed vertices on closed pieces),
        ``options``, ``error``, ``baseline_zero_detail`` and ``floor_retriangulated`` (each
        ``{hausdorff_max_percent_of_diagonal, hausdorff_rms_percent_of_diagonal}``, % of the source
        bbox diagonal; ``error`` also has ``vertex_max_percent_of_diagonal``, the largest distance
        of a rebuilt vertex to the source, exact), ``improvement_over_zero_detail`` (zero-detail RMS
        / error RMS) and ``ratio_to_floor`` (error RMS / floor RMS). Where the target has a closed
        piece there is no zero-detail surface (it collapses onto the anchors):
        ``baseline_zero_detail`` and the improvement are None, with the reason in ``ratio_notes``.
        Each ratio is None where one of its two RMS values is rounding, not a measurement (below
        ``ROUNDING_RMS["exact"]``, 1e-10 % of the diagonal; e.g. every surface of a flat patch, or
        a target equal to the source), with the reason under ``ratio_notes`` (``{ratio name:
        reason}``, present only then), ``parameterization`` (flip counts, for ``location="uv"``) and
        ``seconds.{retriangulate, parameterize, transfer, reconstruct, evaluate, total}``,
        ``laplacian`` ("cotan" or "robust": the one used for the source's detail) and
        ``laplacian_reason`` (why, with the zero-area triangles counted and the caps flipped). With
        ``evaluate=False`` the measured keys (``error``, ``baseline_zero_detail``,
        ``floor_retriangulated``, ``improvement_over_zero_detail``, ``ratio_to_floor``) are absent,
        not None

    Raises
    ------
    MeshError
        Malformed or non-manifold source (names the edges); zero-area source triangles with
        ``laplacian="cotan"``, or ones no flip removes (a needle: two vertices at one point) with
        the others
    NotADiskError
        (a MeshError) ``location="uv"`` with a source that is not a disk
    CurvdetailError
        ``target_edge`` not a positive length (even with a ``target``)
    RemeshError
        Absurd target edge (with the numbers), a failed retriangulation, or a ``target`` that is
        not a retriangulation of the source (`check_retriangulation`: other boundary loops,
        vertices more than ``SURFACE_TOLERANCE`` off its surface, or boundary vertices off the
        source's boundary polyline by more than
        ``TARGET_BOUNDARY_TOLERANCE`` = 1e-6 of the larger of the bbox diagonal and the largest
        coordinate)
    ValueError
        Unknown option values, or a ``parameterization`` without ``location="uv"``; ``target`` not a
        pair; ``progress`` not callable; ``evaluate`` or ``surface_check`` not a bool
    SolverError
        Unknown or uninstalled ``backend`` (before any work)

    Warns
    -----
    WorseThanZeroDetailWarning
        The rebuild is farther from the source than the zero-detail surface (RMS;
        ``improvement_over_zero_detail`` below 1, or None where the zero-detail surface lies on the
        source to rounding), and farther than rounding: the configuration failed on this patch; the
        message says what to try

    Examples
    --------
    >>> from curvdetail.curvature.testing import disk
    >>> V, F = disk(n_rings=16); V[:, 2] = 0.3 * np.exp(-4 * (V[:, :2] ** 2).sum(1))
    >>> (X, Ft), report = remesh_experiment(V, F, target_edge="4%")
    >>> report["error"][RMS] < 0.1 * report["baseline_zero_detail"][RMS]
    True
    """
    result = run_experiment(V, F, method=method, target_edge=target_edge, transfer=transfer, rows=rows,
                            location=location, parameterization=parameterization, backend=backend,
                            evaluate=evaluate, source_path=source_path, progress=progress, target=target,
                            surface_check=surface_check, anchors=anchors, laplacian=laplacian)
    return (result["X"], result["Ft"]), result["report"]


def _check_planar_map(UV, F, which, parameterization):
    """RemeshError where the planar map ``UV`` of the ``which`` mesh collapses triangles of ``F``
    (`squashed_in_plane`), named as the parameterization's doing with the
    experiment's options (pymeshlab's float32 LSCM of camelhead decimated at 5 % collapsed one
    whose 3D area is ordinary; the transfer called it a zero-area triangle of the mesh)."""
    other = ('parameterization "harmonic" (the default for location "uv") or '
             if parameterization != "harmonic" else "")
    squashed_in_plane(UV, F, f"the {parameterization} parameterization of the {which}",
                      f'Use {other}location "closest" (the default, no planar map).', RemeshError)


def _ratios(report, unmeasured):
    """``improvement_over_zero_detail`` and ``ratio_to_floor`` of a ``report`` measured with the
    exact engine, each None where one of its RMS figures is below that engine's ``ROUNDING_RMS``
    or was not measured (``unmeasured``: figure key -> why), and ``ratio_notes`` saying why,
    where one is None."""
    floor = ROUNDING_RMS["exact"]

    def rounding(key, what, then):
        if report[key] is None:
            return unmeasured[key]
        rms = report[key][RMS]
        if rms >= floor:
            return None
        return (f"{what} lies on the source to rounding (RMS {rms:.3g} % of the bbox diagonal, below the "
                f"{floor:g} % the exact engine resolves): {then}")

    out, notes = {}, {}
    rebuilt = "the rebuilt surface"
    for name, top, bottom, reasons in (
            ("improvement_over_zero_detail", "baseline_zero_detail", "error",
             (("baseline_zero_detail", "the zero-detail surface", "the source has no detail to carry over "
               "(e.g. a flat patch), so there is nothing to improve on"),
              ("error", rebuilt, "the ratio would divide by rounding noise"))),
            ("ratio_to_floor", "error", "floor_retriangulated",
             (("floor_retriangulated", "the retriangulated surface", "there is no floor to compare with "
               "(e.g. a flat patch, or a target equal to the source)"),
              ("error", rebuilt, "the ratio would be one of rounding noise")))):
        reason = next(filter(None, (rounding(*r) for r in reasons)), None)
        if reason is None:
            out[name] = report[top][RMS] / report[bottom][RMS]
        else:
            out[name] = None
            notes[name] = reason
    if notes:
        out["ratio_notes"] = notes
    return out


def _check_choice(name, value, choices):
    """``value`` as a str if it is one of ``choices``, else ValueError (an array or list is
    refused by name: ``in`` compared it element-wise, and a one-element array passed)."""
    return check_choice(value, name, choices, f" is not one of {', '.join(map(repr, choices))}.")


def _source(V, F, laplacian):
    """The checked source ``(V, F, loops)`` for the geometric stages, its detail (None: the plain
    cotan one, which the transfer computes itself) and the report's ``laplacian`` and
    ``laplacian_reason``, by `source_detail` (its zero-area caps flipped away where the robust
    Laplacian runs; a needle, two vertices at one point, is still refused, naming it)."""
    F_located, detail, used = source_detail(V, F, laplacian)
    what = "the source" if detail is None else "the source (its zero-area caps flipped)"
    return (*check_surface(V, F_located, what), detail, used)


def run_experiment(V, F, *, method="isotropic", target_edge="1%", transfer="conservative", rows="free",
                   location="closest", parameterization=None, backend="auto", evaluate=True,
                   source_path=None, progress=None, target=None, surface_check=True, anchors=1,
                   laplacian="auto"):
    """`remesh_experiment` returning everything as a dict: ``X``, ``Ft``, ``Vt`` (the
    retriangulated surface), ``Z`` (zero-detail baseline; None where the target has a closed
    piece), ``Dt``, ``distance`` and
    ``zero_distance`` (the exact distance of each vertex of ``X``, of ``Z``, to the source: the
    ones the Hausdorff maxima are taken over; None when ``evaluate=False``) and ``report``."""
    method = _check_choice("method", method, RETRIANGULATIONS)
    transfer = _check_choice("transfer", transfer, TRANSFERS)
    rows = _check_choice("rows", rows, ROW_MODES)
    location = _check_choice("location", location, LOCATIONS)
    laplacian = _check_choice("laplacian", laplacian, LAPLACIANS)
    if parameterization is not None:
        parameterization = _check_choice("parameterization", parameterization, PARAMETERIZATIONS)
        if location != "uv":
            raise CurvdetailError(f"parameterization={parameterization!r} applies to location='uv' only "
                                  f"(location={location!r} uses no planar map); pass location='uv' or "
                                  "leave parameterization out.", parameter="parameterization")
    elif location == "uv":
        parameterization = "harmonic"
    resolve_backend(backend)               # an unknown or missing backend fails before the work
    # checked even with a ready target, where it is only recorded: a bad value is a mistake
    # either way (as pymeshlab checks every parameter of a filter)
    length = as_bbox_length(target_edge, "target_edge")
    if target is not None and (not isinstance(target, (tuple, list)) or len(target) != 2):
        raise CurvdetailError(f"target must be a pair (Vt, Ft), a ready retriangulation, or None; got "
                              f"{type(target).__name__}.", parameter="target")
    check_bool(evaluate, "evaluate")
    check_bool(surface_check, "surface_check")
    if progress is not None and not callable(progress):
        raise CurvdetailError(f"progress must be callable (called with each stage name) or None; got "
                              f"{type(progress).__name__}.", parameter="progress")
    anchors = as_count(anchors, "anchors")
    if location == "uv":
        check_disk(V, F, "the source")          # the planar map needs a disk: said before any work
    V, F, loops_s, detail, used = _source(V, F, laplacian)
    d = bbox_diagonal(V)
    seconds = dict.fromkeys(STAGES, 0.0)
    t_all = time.perf_counter()

    def stage(name):
        if progress is not None:
            progress(name)
        return time.perf_counter()

    def measured(done):                     # within the evaluation: measurements done so far
        if progress is not None:
            progress("evaluate", done, EVALUATION_STEPS)

    if target is None:
        t = stage("retriangulate")
        Vt, Ft = retriangulate(V, F, method=method, target_edge=length, surface_check=surface_check)
        seconds["retriangulate"] = time.perf_counter() - t
    else:
        Vt, Ft, _ = check_surface(*target, "the target")
        check_retriangulation(V, F, Vt, Ft, boundary_tolerance=TARGET_BOUNDARY_TOLERANCE, advice="Pass one made "
                              "by curvdetail.remesh.retriangulate, or target=None to make it here.")

    uv, param_info = None, None
    if location == "uv":
        t = stage("parameterize")
        UVs, UVt, param_info = parameterize(V, F, Vt, Ft, method=parameterization, backend=backend)
        for which, UV, T in (("source", UVs, F), ("target", UVt, Ft)):
            _check_planar_map(UV, T, which, parameterization)
        uv = (UVs, UVt)
        seconds["parameterize"] = time.perf_counter() - t

    t = stage("transfer")
    Dt = transfer_curvature(V, F, Vt, Ft, method=transfer, location=location, uv=uv, detail=detail)
    seconds["transfer"] = time.perf_counter() - t

    t = stage("reconstruct")
    boundary_t = boundary_vertices(Ft)
    fixed = anchor_vertices(Vt, Ft, k=anchors, detail=Dt)
    rec = Reconstructor(Vt, Ft, fixed, rows=rows, backend=backend)
    X = rec.solve(Dt, Vt[fixed])
    # the baseline is the harmonic surface (L Z)_free = 0 whatever the rows: with rows="all",
    # D = 0 would give the least-squares argmin |L Z|^2 instead, another surface (nose: 9.1 %
    # RMS against the harmonic 10.3 %), and the baseline would change with the option. A closed
    # piece has none: with zero detail it collapses onto its anchors.
    Z = None
    if fixed.size == boundary_t.size:
        harmonic = rec if rows == "free" else Reconstructor(Vt, Ft, fixed, rows="free", backend=backend)
        Z = harmonic.solve(np.zeros_like(Dt), Vt[fixed])
        del harmonic
    seconds["reconstruct"] = time.perf_counter() - t
    solver = rec.backend
    del rec                     # its factors (~290 MB at 400k vertices) are not needed to evaluate

    report = {
        "source": {"path": None if source_path is None else str(source_path), "vertices": int(V.shape[0]),
                   "faces": int(F.shape[0]), "bbox_diagonal": d},
        "target": {"vertices": int(Vt.shape[0]), "faces": int(Ft.shape[0]),
                   "boundary_vertices": int(boundary_t.size), "boundary_loops": len(loops_s)},
        "anchors": int(fixed.size - boundary_t.size),
        "options": {"method": "given" if target is not None else method,
                    **(length_figures(length, d, "target_edge") if target is None else
                       dict.fromkeys(("target_edge_model_units", "target_edge_percent_of_diagonal"))),
                    "transfer": transfer, "rows": rows,
                    "location": location, "parameterization": parameterization if location == "uv" else None,
                    "backend": solver,
                    "surface_check": (bool(surface_check) if target is None and method == "isotropic"
                                      else None),
                    "laplacian": laplacian},
        **used,
    }
    if param_info is not None:
        report["parameterization"] = param_info
    out = {"X": X, "Ft": Ft, "Vt": Vt, "Z": Z, "Dt": Dt, "distance": None, "zero_distance": None}
    if evaluate:
        t = stage("evaluate")
        source = Surface(V, F)              # checked, and its closest-point tree built, once
        # each vertex set searched once, exactly: these distances are the per-vertex figures
        # (quality, vertex_max) and hausdorff takes them for its maxima
        out["distance"] = source.vertex_distance(X)
        measured(1)

        def measure(key, P, dist, n):
            """The figures of P's surface against the source, or None and why (a baseline only)."""
            try:
                if P is None:
                    raise MeshError("the target has a closed piece, which with zero detail collapses onto its "
                                    "anchors: there is no zero-detail surface to compare with")
                h = source.hausdorff(P, Ft, samples=n, engine="exact", a_vertex_distance=dist)
            except MeshError as exc:
                if Z is not None and key != "baseline_zero_detail":
                    raise
                # a harmonic surface spanning several small loops degenerates (zero-area triangles)
                return None, exc.problem if P is None else ("the zero-detail surface is degenerate (zero-area "
                                                            "triangles): there is no baseline to compare with")
            return {MAX: 100 * h["max"] / d, RMS: 100 * h["rms"] / d}, None

        done = {"error": measure("error", X, out["distance"], None)}
        measured(2)
        done["floor_retriangulated"] = measure("floor_retriangulated", Vt, None, None)
        measured(3)
        out["zero_distance"] = None if Z is None else source.vertex_distance(Z)
        measured(4)
        done["baseline_zero_detail"] = measure("baseline_zero_detail", Z, out["zero_distance"], BASELINE_SAMPLES)
        measured(EVALUATION_STEPS)
        for key in ("error", "baseline_zero_detail", "floor_retriangulated"):
            report[key] = done[key][0]
        report["error"]["engine"] = "exact"
        report["error"]["vertex_max_percent_of_diagonal"] = float(100 * out["distance"].max() / d)
        report.update(_ratios(report, {key: why for key, (_, why) in done.items()}))
        seconds["evaluate"] = time.perf_counter() - t
        worse = worse_than_zero_detail(report)
        if worse is not None:
            warn(worse, WorseThanZeroDetailWarning)
    seconds["total"] = time.perf_counter() - t_all
    report["seconds"] = {k: round(v, 4) for k, v in seconds.items()}
    out["report"] = report
    return out
