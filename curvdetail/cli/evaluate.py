"""``curvdetail evaluate``: a study of mesh files x remeshing configurations on Dask."""

import os

from .options import positive_number, say, whole_number_from_one


def _names(text):
    """A comma-separated option value as a list: ``"isotropic,decimate"``."""
    return [part.strip() for part in text.split(",") if part.strip()]


def add_arguments(parser):
    """The ``evaluate`` command's arguments; returns its run function."""
    parser.add_argument("inputs", metavar="INPUT", nargs="+", help="mesh files, folders or glob patterns")
    parser.add_argument("--results", required=True, metavar="DIR",
                        help="results folder: DIR/results.parquet, DIR/results.csv and one part per cell; "
                             "a rerun continues the study there, skipping the cells it holds")
    parser.add_argument("--study", metavar="STUDY", help="study file (.toml or .json): grids of configurations, "
                                                         "baselines (instead of the options below)")
    grid = parser.add_argument_group("one grid of configurations (comma-separated lists; every combination)")
    for name, example in (("method", "isotropic,decimate"), ("target-edge", "0.5%,1%,2% (of the bbox diagonal)"),
                          ("transfer", "conservative,pointwise"), ("rows", "free,all"), ("location", "closest,uv"),
                          ("parameterization", "harmonic,lscm (location uv)"),
                          ("baselines", "pointwise (adds the paper's configuration; zero_detail and floor are "
                                        "in every row)")):
        grid.add_argument(f"--{name}", type=_names, metavar="LIST", help=f"e.g. {example}".replace("%", "%%"))
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=whole_number_from_one, metavar="N",
                       help="worker processes of a local Dask cluster (default: one per core)")
    where.add_argument("--scheduler", metavar="ADDRESS", help="an existing Dask cluster, e.g. tcp://HOST:8786")
    parser.add_argument("--ship-meshes", choices=("auto", "yes", "no"), default="auto",
                        help="send the mesh files' bytes to the workers (yes), let them read the paths (no), or "
                             "send them where a --scheduler's worker does not see the paths (auto, the default)")
    parser.add_argument("--cell-timeout", type=positive_number, metavar="S",
                        help="stop a cell after S seconds and record it as timed out")
    parser.add_argument("--cell-memory", type=positive_number, metavar="MIB",
                        help="stop a cell whose process uses more than MIB MiB of memory, and record it")
    parser.add_argument("--retry-failed", action="store_true", help="run the cells that did not end ok again")
    parser.add_argument("--summary", metavar="DIR", help="write DIR/summary.md and plots of the whole table")
    parser.add_argument("--overwrite", action="store_true", help="replace the files of an earlier --summary")
    return run


def run(args):
    from ..curvature.errors import CurvdetailError
    from ..evaluate import Study, load_study, run_study, write_summary
    from ..evaluate.summary import FILES
    from ..io.atomic import check_output_path

    options = {k: getattr(args, k) for k in ("method", "target_edge", "transfer", "rows", "location",
                                             "parameterization") if getattr(args, k) is not None}
    if args.study is not None:
        if options or args.baselines:
            raise CurvdetailError(f"--study and --{next(iter(options), 'baselines').replace('_', '-')} both given",
                                  parameter="study", hint="put the options in the study file, or leave it out")
        study = load_study(args.study)
    else:
        study = Study([options], args.baselines or ())
    if args.summary is not None and os.path.isdir(args.summary):      # refused before the study runs
        for name in FILES:
            check_output_path(os.path.join(args.summary, name), args.overwrite)
    out = run_study(study, args.inputs, args.results, workers=args.workers, scheduler=args.scheduler,
                    cell_timeout=args.cell_timeout, cell_memory=args.cell_memory, retry_failed=args.retry_failed,
                    ship_meshes={"auto": "auto", "yes": True, "no": False}[args.ship_meshes])
    table = out["table"]
    status = table.column("status").to_pylist()
    say(f"curvdetail evaluate: {out['ran']} cells run, {out['skipped']} already in {args.results}; the table holds "
        f"{len(status)} cells: {status.count('ok')} ok, {status.count('failed')} failed, "
        f"{status.count('timeout')} timed out, {status.count('memory')} over the memory limit")
    if args.summary is not None:
        write_summary(table, args.summary, overwrite=args.overwrite)
    return 0
