"""Filter ``get_curvature_reconstruction_error``: two-sided Hausdorff distance between two layers."""

from ..curvature.checks import check_mesh
from ..curvature.geometry import bbox_diagonal
from ..curvature.errors import MeshError
from .errors import FilterError
from .meshset import layer_id, mesh_arrays, set_vertex_quality
from .parameters import Parameter
from .registry import PAPER, filter


@filter(
    name="get_curvature_reconstruction_error",
    category="Curvature detail",
    description=f"""
        Measure how far a rebuilt surface lies from a reference: the two-sided Hausdorff distance
        between the sampled layer (by default the current one, e.g. the retriangulation rebuilt
        from transferred curvature detail) and the target layer (by default layer 0, the source as
        loaded), with pymeshlab's get_hausdorff_distance sampling the faces in both directions
        and every vertex measured exactly, for the maxima (curvdetail.remesh.hausdorff, engine
        'meshlab'; the remeshing report uses its seeded 'exact' engine, so the sampled figures
        differ a little; layers more than one bounding-box diagonal apart are measured with the
        'exact' engine instead, and the figures say which engine ran). Returns the
        maximum and RMS distances in % of the target's bounding-box diagonal and in model units
        (the unit in each key) (the
        evaluation of the paper's remeshing experiment, Fig. 3), and the one-sided figures. With
        set_quality the sampled layer's vertex quality becomes its distance to the target in
        model units (the exact distance of each vertex, the one the maxima are taken over), and
        its vertex colours viridis over [0, its max], which MeshLab shows on open; that range is
        the figure colour_range_percent_of_diagonal. {PAPER}, section "Remeshing", Fig. 3.
    """,
    parameters=[
        Parameter("sampledmesh", "mesh", None, "layer whose error is measured (default: current)"),
        Parameter("targetmesh", "mesh", 0, "reference layer the distances are measured to"),
        # max: remesh.evaluate.MAX_SAMPLE_COUNT (a literal: importing curvdetail.remesh here would
        # load it with every filter), refused before the layers are read
        Parameter("samplenum", "int", 0,
                  "face samples per direction, at most 10000000 (~1000000 is plenty); 0 picks 10 per "
                  "triangle of the sampled mesh, between 100000 and 1000000", min=0, max=10_000_000),
        Parameter("set_quality", "bool", True,
                  "set the sampled layer's vertex quality to its distance to the target"),
    ],
)
def get_curvature_reconstruction_error(ms, *, sampledmesh, targetmesh, samplenum, set_quality):
    from ..remesh import hausdorff, vertex_distance

    sampled = layer_id(ms, sampledmesh, "sampledmesh")
    target = layer_id(ms, targetmesh, "targetmesh")
    if sampled == target:
        raise FilterError(f"sampledmesh and targetmesh are both layer {sampled}", parameter="sampledmesh",
                          hint="name two different layers (e.g. sampledmesh 1, targetmesh 0)")
    Va, Fa = mesh_arrays(ms, sampled)
    Vb, Fb = mesh_arrays(ms, target)
    # the sampled layer's vertices searched once, exactly: the quality and hausdorff's maxima
    # (which takes them as they are, in its own frame: the same figures as measuring them there)
    try:
        distance = vertex_distance(Va, Vb, Fb)
        h = hausdorff(Va, Fa, Vb, Fb, samples=samplenum or None, engine="meshlab", a_vertex_distance=distance)
    except MeshError as exc:
        raise _naming_the_layer(exc, ms, ("sampledmesh", sampled, Va, Fa),
                                ("targetmesh", target, Vb, Fb)) from None
    diag = bbox_diagonal(Vb)
    colours = {}
    if set_quality:
        lo, hi = set_vertex_quality(ms, sampled, distance)
        colours = {"colour_range_percent_of_diagonal": [100 * lo / diag, 100 * hi / diag]}
    return {
        "hausdorff_max_percent_of_diagonal": 100 * h["max"] / diag,
        "hausdorff_rms_percent_of_diagonal": 100 * h["rms"] / diag,
        "hausdorff_mean_percent_of_diagonal": 100 * h["mean"] / diag,
        "sampled_to_target_max_percent_of_diagonal": 100 * h["a_to_b_max"] / diag,
        "target_to_sampled_max_percent_of_diagonal": 100 * h["b_to_a_max"] / diag,
        "hausdorff_max_model_units": h["max"],
        "hausdorff_rms_model_units": h["rms"],
        "hausdorff_mean_model_units": h["mean"],
        "bbox_diagonal_model_units": diag,
        "samples": h["samples"],
        "engine": h["engine"],
        "sampledmesh": sampled,
        "targetmesh": target,
        **colours,
    }


def _naming_the_layer(exc, ms, *layers):
    """``exc`` told of the layer it is about (the measuring functions name their arguments, which
    a filter user never sees): the first of ``layers`` (role, id, V, F) that the mesh checks refuse
    gives its own message; ``exc`` as it is where none does. Error path only."""
    for role, layer, V, F in layers:
        try:
            check_mesh(V, F)
        except MeshError as problem:
            label = ms.mesh(layer).label()
            named = f"layer {layer}, {label!r}" if label else f"layer {layer}"
            return type(problem)(f"{role} ({named}): {problem}")
    return exc
