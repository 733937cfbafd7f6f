"""Comparative evaluation at scale: mesh collections x remeshing configurations, on Dask.

A `Study` (grids of `remesh_experiment` options, from arguments
or a TOML/JSON file, `load_study`) times the meshes of a collection gives cells;
`run_study` runs those not yet in a results folder as Dask tasks, each in a child process
of its worker that a time limit can stop, and writes one table row per cell as it finishes
(`table`: Parquet and CSV); `write_summary` writes a Markdown summary and plots.
``curvdetail evaluate`` is the command line; docs/guide/evaluate.md the guide.
"""

from .run import run_study
from .study import Study, StudyError, find_meshes, load_study, target_size
from .summary import write_summary
from .table import COLUMNS, SCHEMA, read_results

__all__ = ["COLUMNS", "SCHEMA", "Study", "StudyError", "find_meshes", "load_study", "read_results", "run_study",
           "target_size", "write_summary"]
