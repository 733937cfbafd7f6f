"""Filter ``generate_curvature_remeshing``: the paper's remeshing experiment on the current mesh."""

import os

from ..curvature.geometry import bbox_diagonal
from ..curvature.robust_laplacian import LAPLACIANS
from .apply_curvature_reconstruction import BACKEND_DESCRIPTION, BACKENDS
from .detail_attributes import DETAIL, stamp
from .files import loaded_from
from .meshset import add_layer, get_mesh, layer_id, mesh_arrays, set_vertex_attribute
from .parameters import BBoxLength, Parameter
from .registry import PAPER, filter
from .transfer_curvature_detail import planar_map


@filter(
    name="generate_curvature_remeshing",
    category="Curvature detail",
    description=f"""
        Run the whole remeshing experiment on the current mesh (any manifold surface: closed,
        with holes, several pieces; a disk-topology patch for location 'uv'): retriangulate it
        (pymeshlab isotropic remeshing or fast-simplification decimation, every boundary loop kept
        on the source's), carry its curvature detail over to the new triangulation, rebuild the
        new triangulation from that detail with its boundary fixed and one anchor vertex on each
        closed piece (the report's 'anchors'), and
        measure the two-sided Hausdorff distance to the source next to two baselines (the
        zero-detail surface with the same boundary and the retriangulated surface itself, the
        floor). Adds the retriangulated layer and the rebuilt layer (current; quality = distance
        to the source, none without evaluate; attribute 'curvature_detail' = the transferred
        detail) and, on request, the zero-detail baseline (quality = its distance to the source);
        each quality is the exact distance, the one the Hausdorff maxima are taken over. Returns
        the report of curvdetail.remesh.remesh_experiment (error and baselines in % of the
        source's bbox diagonal, the unit in each key, sizes, options, seconds per stage; source.path the absolute path
        of the file the current layer was read from where curvdetail loaded it (the CLI, or
        curvdetail.filters.files.load_meshset) and unchanged since, as curvdetail remesh reports
        it, else None; source.label the layer's label) with the new layer ids; a rebuild farther
        from the source than the zero-detail surface is said with a
        curvdetail.remesh.WorseThanZeroDetailWarning. {PAPER}, section "Remeshing", Fig. 3.
    """,
    parameters=[
        Parameter("method", "str", "isotropic",
                  "retriangulation: pymeshlab 'isotropic' explicit remeshing or fast-simplification "
                  "'decimate'", choices=("isotropic", "decimate")),
        Parameter("target_edge", "PercentageValue", BBoxLength(1.0, percent=True),
                  "target edge length: a percentage of the bbox diagonal (pymeshlab.PercentageValue, "
                  "'1%') or a plain number in model units", positive=True),
        Parameter("transfer", "str", "conservative",
                  "how detail is carried over: 'conservative' (measure, totals kept) or 'pointwise' "
                  "(the paper: K interpolated, times the target's area)",
                  choices=("conservative", "pointwise")),
        # the same order as apply_curvature_reconstruction's, so that an index means one row mode
        # in every filter (the defaults differ: free here, as SPEC's experiment, all there)
        Parameter("rows", "str", "free", "residual rows of the reconstruction energy E_Q",
                  choices=("all", "free")),
        Parameter("location", "str", "closest",
                  "where target vertices lie on the source: 'closest' point in space or 'uv' "
                  "(shared planar parameterization)", choices=("closest", "uv")),
        Parameter("parameterization", "str", "harmonic", "planar map for location='uv' (only)",
                  choices=("harmonic", "meshlab_harmonic", "lscm")),
        Parameter("backend", "str", "auto", BACKEND_DESCRIPTION, choices=BACKENDS),
        Parameter("surface_check", "bool", True,
                  "isotropic only: refuse an edge collapse or flip that moves the surface by more than "
                  "the target edge (pymeshlab's checksurfdist); false skips it, 25-50 % faster at "
                  "100k-400k target vertices, and the retriangulation may differ where the "
                  "remesher's smoothing would leave the surface"),
        Parameter("laplacian", "str", "auto",
                  "the source's Laplacian for its detail: 'cotan' (refuses zero-area triangles), 'robust' "
                  "(mollified intrinsic cotan, zero-area caps flipped) or 'auto' (cotan unless the source "
                  "has zero-area triangles); the report says which was used and why",
                  choices=LAPLACIANS),
        Parameter("evaluate", "bool", True,
                  "measure the distances to the source (half or more of the time on big meshes with "
                  "decimation, up to half with isotropic remeshing); false leaves the rebuilt and "
                  "zero-detail layers without a vertex quality, so a PLY of them holds none"),
        Parameter("add_baseline", "bool", False, "also add the zero-detail baseline as a layer (none where "
                  "the mesh has a closed piece: with zero detail it collapses onto its anchor)"),
    ],
)
def generate_curvature_remeshing(ms, *, method, target_edge, transfer, rows, location,
                                 parameterization, backend, surface_check, laplacian, evaluate, add_baseline):
    from ..remesh.experiment import run_experiment

    mid = layer_id(ms)
    V, F = mesh_arrays(ms, mid)
    label = get_mesh(ms, mid).label()
    path = loaded_from(ms, mid)
    diagonal = bbox_diagonal(V)
    length = target_edge.resolve(diagonal)
    fraction = target_edge.fraction(diagonal)

    def progress(stage, *counts):   # said once the checks have passed, before the work
        if stage == "retriangulate":
            _warn_of_a_big_target(V, F, target_edge, length, fraction, method, evaluate)

    result = run_experiment(V, F, method=method, target_edge=target_edge, transfer=transfer, rows=rows,
                            location=location, parameterization=planar_map(location, parameterization),
                            backend=backend, evaluate=evaluate, source_path=path, surface_check=surface_check,
                            progress=progress, laplacian=laplacian)
    Ft = result["Ft"]
    layers = {"source": mid,
              "retriangulated": add_layer(ms, result["Vt"], Ft, f"{label} retriangulated")}
    # without evaluation the measured layers get no quality at all, not pymeshlab's zeros
    measured_layer = add_layer if evaluate else _add_layer_without_quality
    if add_baseline and result["Z"] is not None:        # a closed piece has no zero-detail surface
        # the distances the experiment measured for the baseline's Hausdorff maximum (None
        # without evaluation)
        layers["zero_detail"] = measured_layer(ms, result["Z"], Ft, f"{label} zero detail",
                                               quality=result["zero_distance"])
    layers["rebuilt"] = measured_layer(ms, result["X"], Ft, f"{label} rebuilt", quality=result["distance"],
                                       attributes={DETAIL: result["Dt"], **stamp(Ft, result["X"].shape[0])})
    report = dict(result["report"])
    report["source"] = {**report["source"], "label": label}
    report["layers"] = layers
    return report


def _add_layer_without_quality(ms, V, F, label, *, quality=None, attributes=None):
    """`add_layer` of a layer that has no vertex quality
    (``quality`` must be None). A ``pymeshlab.Mesh`` made from arrays always has one, all 0,
    which a PLY of the layer would carry as if it were measured; a layer loaded from a file
    without one has none. So the layer is loaded from a temporary binary PLY (doubles: exact)."""
    import tempfile

    from ..io import write_mesh

    assert quality is None
    with tempfile.TemporaryDirectory(prefix="curvdetail-layer-") as folder:
        path = os.path.join(folder, "layer.ply")
        write_mesh(path, V, F)
        ms.load_new_mesh(path)
    mid = int(ms.current_mesh_id())
    ms.current_mesh().set_label(label)
    for name, values in (attributes or {}).items():
        set_vertex_attribute(ms, mid, name, values)
    return mid


def _warn_of_a_big_target(V, F, target_edge, length, fraction, method, evaluate):
    """A LongRunWarning before a run of minutes (a retriangulation of more than BIG_TARGET
    vertices, edges of ``length``, ``fraction`` of the diagonal; not for a decimation that will
    be refused), saying what takes the time: a plain target_edge=0.01 is 0.01 model units (on a
    15 km terrain 1.3M vertices, 10 minutes without a word), not 1 %."""
    from ..curvature.errors import warn
    from ..remesh.retriangulate import LongRunWarning, long_run_reason, long_run_vertices

    count = long_run_vertices(V, F, length, method=method, evaluate=evaluate)
    if count is not None:
        warn(f"target_edge={target_edge} ({100 * fraction:.3g} % of the bbox diagonal) gives about "
                      f"{count:,.0f} target vertices; this takes minutes. {long_run_reason(method, evaluate)} "
                      "A plain number is in model units; pymeshlab.PercentageValue(1) is 1 % of the diagonal.",
                      LongRunWarning)
