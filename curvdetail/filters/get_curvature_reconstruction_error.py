"""Filter ``get_curvature_reconstruction_error``: two-sided Hausdorff distance between two layers."""

import numpy as np

from ..curvature._validate import bbox_diagonal
from .errors import FilterError
from .meshset import get_mesh, layer_id, mesh_arrays
from .parameters import Parameter
from .registry import PAPER, filter


def _one_way(ms, sampled, target, samplenum):
    import pymeshlab

    return ms.get_hausdorff_distance(
        sampledmesh=sampled, targetmesh=target, savesample=False, samplevert=True, sampleedge=False,
        samplefauxedge=False, sampleface=True, samplenum=int(samplenum),
        maxdist=pymeshlab.PercentageValue(100.0))


@filter(
    name="get_curvature_reconstruction_error",
    category="Curvature detail",
    description=f"""
        Measure how far a rebuilt surface lies from a reference: the two-sided Hausdorff distance
        between the sampled layer (by default the current one, e.g. the retriangulation rebuilt
        from transferred curvature detail) and the target layer (by default layer 0, the source as
        loaded), with pymeshlab's get_hausdorff_distance sampling vertices and faces in both
        directions. Returns the maximum and RMS distances as fractions of the target's bounding-box
        diagonal (the evaluation of the paper's remeshing experiment, Fig. 3), and the one-sided
        figures. With set_quality the sampled layer's vertex quality becomes its distance to the
        target, so MeshLab colours the error. {PAPER}, section "Remeshing", Fig. 3.
    """,
    parameters=[
        Parameter("sampledmesh", "mesh", None, "layer whose error is measured (default: current)"),
        Parameter("targetmesh", "mesh", 0, "reference layer the distances are measured to"),
        Parameter("samplenum", "int", 0,
                  "surface samples per direction; 0 picks 10 per face of the larger mesh, at least "
                  "100000", min=0),
        Parameter("set_quality", "bool", True,
                  "set the sampled layer's vertex quality to its distance to the target"),
    ],
)
def get_curvature_reconstruction_error(ms, *, sampledmesh, targetmesh, samplenum, set_quality):
    sampled = layer_id(ms, sampledmesh, "sampledmesh")
    target = layer_id(ms, targetmesh, "targetmesh")
    if sampled == target:
        raise FilterError(f"sampledmesh and targetmesh are both layer {sampled}; name two different "
                          "layers (e.g. sampledmesh=1, targetmesh=0).")
    mesh_arrays(ms, sampled)                       # both must be triangle meshes
    Vt, _ = mesh_arrays(ms, target)
    if samplenum == 0:
        faces = max(get_mesh(ms, sampled).face_number(), get_mesh(ms, target).face_number())
        samplenum = max(100_000, 10 * faces)
    current = ms.current_mesh_id()
    forward = _one_way(ms, sampled, target, samplenum)
    backward = _one_way(ms, target, sampled, samplenum)
    if set_quality:
        import pymeshlab

        ms.compute_scalar_by_distance_from_another_mesh_per_vertex(
            measuremesh=sampled, refmesh=target, signeddist=False,
            maxdist=pymeshlab.PercentageValue(100.0))
    ms.set_current_mesh(current)
    diag = bbox_diagonal(Vt)
    n1, n2 = forward["n_samples"], backward["n_samples"]
    rms = float(np.sqrt((n1 * forward["RMS"] ** 2 + n2 * backward["RMS"] ** 2) / (n1 + n2)))
    worst = max(forward["max"], backward["max"])
    return {
        "hausdorff_max": float(worst / diag),
        "hausdorff_rms": float(rms / diag),
        "sampled_to_target_max": float(forward["max"] / diag),
        "sampled_to_target_rms": float(forward["RMS"] / diag),
        "target_to_sampled_max": float(backward["max"] / diag),
        "target_to_sampled_rms": float(backward["RMS"] / diag),
        "max": float(worst),
        "RMS": rms,
        "diagonal": diag,
        "n_samples": int(n1 + n2),
        "sampledmesh": sampled,
        "targetmesh": target,
    }
