"""Two-sided surface distances between meshes (paper Fig. 3, evaluation)."""

import numpy as np

from ..curvature._validate import check_mesh
from .locate import locate

#: Face samples per direction: ``SAMPLES_PER_FACE`` times the sampled mesh's triangle count,
#: clamped to [MIN_SAMPLES, MAX_SAMPLES].
SAMPLES_PER_FACE, MIN_SAMPLES, MAX_SAMPLES = 10, 100_000, 1_000_000


def hausdorff(Va, Fa, Vb, Fb, *, samples=None):
    """Two-sided Hausdorff distance (max) and RMS distance between two triangle meshes.

    pymeshlab ``get_hausdorff_distance`` is run in both directions (a sampled on its faces,
    distances to the closest point of b; then b on a), every parameter passed explicitly. The
    maximum is the larger of the two one-sided maxima; the RMS pools the samples of both
    directions: ``sqrt((n_ab rms_ab^2 + n_ba rms_ba^2) / (n_ab + n_ba))``.

    Parameters
    ----------
    Va, Fa, Vb, Fb : the two meshes ((n, 3) float, (m, 3) int)
    samples : int or None   face samples per direction; ``None`` = 10 per triangle of the sampled
                            mesh, at least 100,000 and at most 1,000,000

    Returns
    -------
    dict with ``max``, ``rms``, ``mean`` (absolute lengths), ``a_to_b_max``, ``b_to_a_max``,
    ``samples`` (total)

    Raises
    ------
    MeshError   malformed meshes

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> V, F = grid(5, 5); W = V.copy(); W[:, 2] += 0.01
    >>> round(hausdorff(V, F, W, F)["rms"], 6)
    0.01
    """
    import pymeshlab

    Va, Fa = check_mesh(Va, Fa)
    Vb, Fb = check_mesh(Vb, Fb)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=Va, face_matrix=Fa.astype(np.int32)))
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=Vb, face_matrix=Fb.astype(np.int32)))
    diag = float(np.linalg.norm(np.vstack([Va, Vb]).max(0) - np.vstack([Va, Vb]).min(0)))
    out = []
    for sampled, target, m in ((0, 1, Fa.shape[0]), (1, 0, Fb.shape[0])):
        n = int(samples) if samples else int(np.clip(SAMPLES_PER_FACE * m, MIN_SAMPLES, MAX_SAMPLES))
        # Every parameter explicitly: pymeshlab keeps values from earlier calls in one process.
        r = ms.get_hausdorff_distance(sampledmesh=sampled, targetmesh=target, savesample=False,
                                      samplevert=False, sampleedge=False, samplefauxedge=False,
                                      sampleface=True, samplenum=n, maxdist=pymeshlab.PureValue(2.0 * diag))
        out.append(r)
    n1, n2 = out[0]["n_samples"], out[1]["n_samples"]
    rms = np.sqrt((n1 * out[0]["RMS"] ** 2 + n2 * out[1]["RMS"] ** 2) / max(n1 + n2, 1))
    mean = (n1 * out[0]["mean"] + n2 * out[1]["mean"]) / max(n1 + n2, 1)
    return {"max": float(max(out[0]["max"], out[1]["max"])), "rms": float(rms), "mean": float(mean),
            "a_to_b_max": float(out[0]["max"]), "b_to_a_max": float(out[1]["max"]), "samples": int(n1 + n2)}


def vertex_distance(V, Vs, Fs):
    """Distance from each point of ``V`` (k, 3) to the closest point of the surface ``(Vs, Fs)``,
    shape (k,) (e.g. per-vertex error of a rebuilt mesh against its source)."""
    return locate(np.asarray(V, dtype=np.float64), Vs, Fs)[2]
