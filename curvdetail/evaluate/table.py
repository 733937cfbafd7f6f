"""The results table of a study: one row per cell, its columns with their units, and its files.

A results folder ``DIR`` holds ``DIR/results.parquet`` + ``DIR/results.csv``, the table, and
while a study runs ``DIR/parts/<cell key>.parquet`` (one file per finished cell, written
atomically as the cell finishes); `compact` folds the parts into the table at the end of a study. Units are in the column names: ``_percent_of_diagonal`` a percentage
of the source's bounding-box diagonal, ``_model_units`` the mesh's own length unit, ``_s``
seconds, ``_mib`` MiB (2^20 bytes).
"""

import glob
import os

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pa_csv
import pyarrow.dataset as ds
import pyarrow.parquet as pq

from ..io.atomic import atomic_write

_S, _F, _I, _B = pa.string(), pa.float64(), pa.int64(), pa.bool_()

#: (column, type, meaning) of every column, in order.
COLUMNS = [
    ("cell_key", _S, "hash of the mesh's content and the configuration: a rerun skips a key in the table"),
    ("status", _S, '"ok", "failed" (the error columns say why), "timeout" or "memory" (stopped at a limit)'),
    ("mesh_name", _S, "file name"),
    ("mesh_path", _S, "absolute path the workers read"),
    ("mesh_blake2b", _S, "blake2b (128 bits, hex) of the file's bytes"),
    ("mesh_shipped", _B, "the file's bytes were sent to the worker (no shared path), not read there"),
    ("mesh_vertices", _I, "vertices of the source"),
    ("mesh_faces", _I, "triangles of the source"),
    ("mesh_closed", _B, "the source has no boundary edge"),
    ("mesh_bbox_diagonal_model_units", _F, "bounding-box diagonal of the source"),
    ("method", _S, "retriangulation"),
    ("target_edge", _S, 'target edge as the study gives it ("1%": of the bbox diagonal)'),
    ("transfer", _S, "detail transfer"),
    ("rows", _S, "residual rows of the reconstruction"),
    ("location", _S, "point location"),
    ("parameterization", _S, 'planar domain of location "uv" (empty otherwise)'),
    ("target_edge_percent_of_diagonal", _F, "target edge length"),
    ("target_edge_model_units", _F, "target edge length"),
    ("target_vertices", _I, "vertices of the retriangulated target"),
    ("target_faces", _I, "triangles of the target"),
    ("target_boundary_loops", _I, "boundary loops of the target"),
    ("anchors", _I, "vertices fixed on the target's closed pieces"),
    ("laplacian", _S, 'the source\'s Laplacian that ran: "cotan", or "robust" where the source has zero-area '
                      'triangles'),
    ("error_rms_percent_of_diagonal", _F, "two-sided Hausdorff RMS, rebuilt surface to source"),
    ("error_max_percent_of_diagonal", _F, "two-sided Hausdorff max, rebuilt surface to source"),
    ("error_vertex_max_percent_of_diagonal", _F, "largest distance of a rebuilt vertex to the source (exact)"),
    ("error_engine", _S, 'distance engine of the error figures ("meshlab" or "exact")'),
    ("zero_detail_rms_percent_of_diagonal", _F, "baseline: the zero-detail (harmonic) surface, RMS (empty where "
                                                "the target has a closed piece: it has none)"),
    ("zero_detail_max_percent_of_diagonal", _F, "baseline: the zero-detail surface, max"),
    ("floor_rms_percent_of_diagonal", _F, "baseline: the retriangulated surface itself, RMS"),
    ("floor_max_percent_of_diagonal", _F, "baseline: the retriangulated surface itself, max"),
    ("improvement_over_zero_detail_ratio", _F, "zero-detail RMS / error RMS (empty where an RMS is rounding)"),
    ("rms_to_floor_ratio", _F, "error RMS / floor RMS (empty where an RMS is rounding)"),
    ("flipped_source", _I, 'location "uv": source triangles flipped in the planar map'),
    ("flipped_target", _I, 'location "uv": target triangles flipped in the planar map'),
    ("backend", _S, "sparse solver that ran"),
    ("read_s", _F, "reading the mesh file"),
    ("retriangulate_s", _F, "stage seconds"),
    ("parameterize_s", _F, "stage seconds"),
    ("transfer_s", _F, "stage seconds"),
    ("reconstruct_s", _F, "stage seconds"),
    ("evaluate_s", _F, "stage seconds"),
    ("experiment_s", _F, "remesh_experiment end to end"),
    ("cell_s", _F, "the cell end to end (read, experiment, table row), as its process measured it"),
    ("peak_rss_mib", _F, "peak resident memory of the process that ran the cell, during the cell"),
    ("worker", _S, "Dask worker that ran the cell"),
    ("pid", _I, "process that ran the cell"),
    ("finished_utc", _S, "when the cell ended (ISO 8601, UTC)"),
    ("warnings", _S, "warnings the experiment gave, joined by ' | '"),
    ("error_class", _S, "exception class of a failed cell"),
    ("error_message", _S, "its message"),
]
SCHEMA = pa.schema([(name, kind) for name, kind, _ in COLUMNS])


def part_path(folder, key):
    return os.path.join(folder, "parts", f"{key}.parquet")


def write_part(folder, row):
    """Write one finished cell's row as ``folder/parts/<cell_key>.parquet``, atomically (a row
    for the same cell replaces it)."""
    os.makedirs(os.path.join(folder, "parts"), exist_ok=True)
    with atomic_write(part_path(folder, row["cell_key"]), overwrite=True) as tmp:
        pq.write_table(pa.Table.from_pylist([row], schema=SCHEMA), tmp)


def _parts(folder):
    return sorted(glob.glob(os.path.join(folder, "parts", "*.parquet")))    # not the hidden temporary files


def read_results(folder):
    """A study's table, also of one still running or stopped: ``folder/results.parquet`` with
    the rows of ``folder/parts`` (a part replaces the row of its cell); `SCHEMA`, empty if neither exists."""
    files = _parts(folder)
    table = ds.dataset(files, schema=SCHEMA, format="parquet").to_table() if files else SCHEMA.empty_table()
    compacted = os.path.join(folder, "results.parquet")
    if os.path.isfile(compacted):
        old = ds.dataset(compacted, schema=SCHEMA, format="parquet").to_table()
        old = old.filter(pc.invert(pc.is_in(old.column("cell_key"), value_set=table.column("cell_key"))))
        table = pa.concat_tables([old, table])
    return table


def write_results(folder, table):
    """``folder/results.parquet`` and ``folder/results.csv`` from ``table``, each atomically."""
    table = table.sort_by([("mesh_name", "ascending"), ("cell_key", "ascending")])
    with atomic_write(os.path.join(folder, "results.parquet"), overwrite=True) as tmp:
        pq.write_table(table, tmp)
    with atomic_write(os.path.join(folder, "results.csv"), overwrite=True) as tmp:
        pa_csv.write_csv(table, tmp)


def compact(folder):
    """Fold the parts into ``folder/results.parquet`` (and .csv) and remove them; the table
    (`read_results`). Nothing is written where there is no part and the table exists."""
    files = _parts(folder)
    table = read_results(folder)
    if files or not os.path.isfile(os.path.join(folder, "results.parquet")):
        write_results(folder, table)
        for path in files:
            os.remove(path)
    return table

