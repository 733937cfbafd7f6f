"""Two-sided surface distances between meshes (paper Fig. 3, evaluation)."""

import numpy as np

from ..curvature._validate import as_count, check_choice, as_faces, bbox_diagonal, check_bool, check_mesh, face_double_areas
from ..curvature.errors import MeshError
from .locate import FAR_POINTS, _locate, _unit_frame, check_points_and_mesh

#: Largest ``samples`` (per direction), well below pymeshlab's 32-bit int: 5M took 35 s with
#: pymeshlab and 1M 17 s with the kd-tree engine (grid(50, 50)), so 10M is minutes and ~2 GB of
#: samples; 2e9 effectively hung. 1,000,000 already gives ~1e-3 relative accuracy.
MAX_SAMPLE_COUNT = 10_000_000

#: Face samples per direction: ``SAMPLES_PER_FACE`` times the sampled mesh's triangle count,
#: clamped to [MIN_SAMPLES, MAX_SAMPLES].
SAMPLES_PER_FACE, MIN_SAMPLES, MAX_SAMPLES = 10, 100_000, 1_000_000


def hausdorff(Va, Fa, Vb, Fb, *, samples=None, engine="meshlab", seed=0):
    """Two-sided Hausdorff distance (max) and RMS distance between two triangle meshes.

    pymeshlab ``get_hausdorff_distance`` is run in both directions (a sampled on its faces,
    distances to the closest point of b; then b on a), every parameter passed explicitly. The
    maximum is the larger of the two one-sided maxima; the RMS is the quadratic mean of the two
    one-sided RMS values, ``sqrt((rms_ab^2 + rms_ba^2) / 2)`` (independent of the sample counts).

    ``engine="kdtree"`` replaces pymeshlab for surfaces far apart (a few % of their size and
    more, e.g. the zero-detail baseline), where the cost of pymeshlab's grid search grows with the
    cube of the distance (250 s for one baseline on a 10k-vertex mesh): both surfaces are
    sampled uniformly by area (the same sample counts), the 8 triangles of the other surface
    with the nearest centroids (a ``cKDTree``, 2 % approximate search) are the candidates and the
    exact closest point on those is taken. For a point at distance ``d`` this overestimates by at
    most about ``r^2 / 2d`` (``r`` a triangle's size): negligible for far surfaces, which is
    what this engine is for. Meshes whose bounding boxes are more than one diagonal (of the
    smaller) apart are always measured with it: pymeshlab's search does not return there.
    Both engines work in a frame where the two meshes together have unit size.

    Parameters
    ----------
    Va, Fa, Vb, Fb : the two meshes ((n, 3) float, (m, 3) int)
    samples : int or None   face samples per direction, 1 to ``MAX_SAMPLE_COUNT`` (10,000,000;
                            ~1,000,000 is plenty); ``None`` = 10 per triangle of
                            the sampled mesh, at least 100,000 and at most 1,000,000
    engine : {"meshlab", "kdtree"}
    seed : int or None      random seed (>= 0) of the ``"kdtree"`` engine's samples (None: fresh
                            entropy, as numpy's ``default_rng``)

    Returns
    -------
    dict with ``max``, ``rms``, ``mean`` (absolute lengths), ``a_to_b_max``, ``b_to_a_max``,
    ``samples`` (total), ``engine`` (the one that ran: "kdtree" also for meshes far apart)

    Raises
    ------
    MeshError   malformed meshes; coordinates beyond 1e150 (see :func:`locate`)
    ValueError  unknown ``engine``; ``samples`` not a whole number from 1 to 10,000,000 (bools
                refused); ``seed`` not a whole number >= 0

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> V, F = grid(5, 5); W = V.copy(); W[:, 2] += 0.01
    >>> round(hausdorff(V, F, W, F)["rms"], 6)
    0.01
    """
    # dtypes, scale and distance first; then the meshes in a frame where the two together have
    # unit size (as pymeshlab sees them too): areas of huge or tiny meshes neither over- nor underflow
    Va, Vb, _ = check_points_and_mesh(Va, Vb, Fb, names=("Va", "Vb", "Fb"))
    if Va.shape[1] != 3:
        raise MeshError(f"Va has shape {Va.shape}; hausdorff measures surfaces in space, (n, 3).")
    Fa = as_faces(Fa, Va.shape[0], "Fa")              # named as the caller names it
    both = np.vstack([Va, Vb])
    _, both, scale = _unit_frame(both[:0], both)
    Va, Fa = check_mesh(both[:Va.shape[0]], Fa)
    Vb, Fb = check_mesh(both[Va.shape[0]:], Fb)
    engine = check_choice(engine, "engine", ("meshlab", "kdtree"), "; use 'meshlab' or 'kdtree'.")
    samples = _check_samples(samples)
    seed = None if seed is None else as_count(seed, "seed", minimum=0)
    engine = "kdtree" if engine == "kdtree" or _apart(Va, Vb) else "meshlab"
    figures = _hausdorff_kdtree(Va, Fa, Vb, Fb, samples, seed) if engine == "kdtree" else \
        _hausdorff_meshlab(Va, Fa, Vb, Fb, samples)
    return dict(_scaled(figures, scale), engine=engine)


def _check_samples(samples):
    if samples is None:
        return None
    try:
        count = as_count(samples, "samples")
    except ValueError:
        raise ValueError(f"samples={samples!r} must be a whole number of at least 1, or None for "
                         "10 per triangle (100,000 to 1,000,000).") from None
    if count > MAX_SAMPLE_COUNT:
        raise ValueError(f"samples={count:,} is more than the limit of {MAX_SAMPLE_COUNT:,} per direction "
                         "(minutes of sampling and GBs beyond it); ~1,000,000 is plenty for 1e-3 relative "
                         "accuracy.")
    return count


def _apart(Va, Vb):
    """True if the bounding boxes of the meshes are more than ``FAR_POINTS`` diagonals (of the
    smaller mesh) apart: pymeshlab's grid search slows down with the distance without bound
    (28 s at 0.1 diagonals for 20,000 samples on a 10k-vertex grid; no answer at 1e10)."""
    gap = np.linalg.norm(np.maximum(np.maximum(Va.min(0) - Vb.max(0), Vb.min(0) - Va.max(0)), 0.0))
    return bool(gap > FAR_POINTS * min(bbox_diagonal(Va), bbox_diagonal(Vb)))


def _scaled(figures, scale):
    return {k: v if k == "samples" else v * scale for k, v in figures.items()}


def _hausdorff_meshlab(Va, Fa, Vb, Fb, samples):
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=Va, face_matrix=Fa.astype(np.int32)))
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=Vb, face_matrix=Fb.astype(np.int32)))
    diag = bbox_diagonal(np.vstack([Va, Vb]))
    out = []
    for sampled, target, m in ((0, 1, Fa.shape[0]), (1, 0, Fb.shape[0])):
        n = int(samples) if samples else int(np.clip(SAMPLES_PER_FACE * m, MIN_SAMPLES, MAX_SAMPLES))
        # Every parameter explicitly: pymeshlab keeps values from earlier calls in one process.
        r = ms.get_hausdorff_distance(sampledmesh=sampled, targetmesh=target, savesample=False,
                                      samplevert=False, sampleedge=False, samplefauxedge=False,
                                      sampleface=True, samplenum=n, maxdist=pymeshlab.PureValue(2.0 * diag))
        out.append(r)
    n1, n2 = out[0]["n_samples"], out[1]["n_samples"]
    rms = np.sqrt(0.5 * (out[0]["RMS"] ** 2 + out[1]["RMS"] ** 2))
    mean = 0.5 * (out[0]["mean"] + out[1]["mean"])
    return {"max": float(max(out[0]["max"], out[1]["max"])), "rms": float(rms), "mean": float(mean),
            "a_to_b_max": float(out[0]["max"]), "b_to_a_max": float(out[1]["max"]), "samples": int(n1 + n2)}


def vertex_distance(V, Vs, Fs, *, far=False):
    """Distance from each point of ``V`` (k, 3) to the closest point of the surface ``(Vs, Fs)``,
    shape (k,) (e.g. per-vertex error of a rebuilt mesh against its source).

    ``far=True`` uses the kd-tree candidates of :func:`hausdorff`'s ``"kdtree"`` engine (fast for
    points far from the surface, overestimating by at most ~``r^2 / 2d``) instead of the exact
    :func:`locate` (whose grid search slows down with the distance).

    Parameters
    ----------
    V : (k, 3) float array    query points, e.g. a rebuilt mesh's vertices (k = 0 allowed); or
                              (k, 2) with a planar ``Vs``
    Vs : (n, 3) float array   the surface's vertex positions ((n, 2) for planar points)
    Fs : (m, 3) int array     its triangles
    far : bool                take the kd-tree candidates instead of the exact search (see above)

    Returns
    -------
    d : (k,) float64 array    unsigned distances, in the unit of the coordinates (0, up to
                              rounding, for a point on the surface), row i for ``V[i]``

    Raises
    ------
    MeshError   malformed points or surface, as :func:`locate` refuses them (names ``V``,
                ``Vs`` and ``Fs``)
    ValueError  ``far`` not a bool

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> Vs, Fs = grid(3, 3)                               # the unit square in z = 0
    >>> P = np.array([[0.5, 0.5, 2.0], [0.2, 0.3, 0.0], [2.0, 0.5, 0.0]])
    >>> vertex_distance(P, Vs, Fs).round(12).tolist()     # above, on, and beside the square
    [2.0, 0.0, 1.0]
    """
    check_bool(far, "far")
    P, Vs, Fs = check_points_and_mesh(V, Vs, Fs, names=("V", "Vs", "Fs"))
    if not far:
        return _locate(P, Vs, Fs)[2]
    P, Vs, scale = _unit_frame(P, Vs)
    return scale * _one_sided_kdtree(P, Vs, Fs, Vs[Fs].mean(axis=1), np.arange(Fs.shape[0]))


def _area_samples(V, F, n, rng):
    """``n`` points uniformly distributed by area, with their triangle, plus every vertex."""
    area = face_double_areas(V, F)
    face = rng.choice(F.shape[0], size=n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    bary = np.column_stack([1 - s, s * (1 - r2), s * r2])
    return (bary[:, :, None] * V[F[face]]).sum(1), face


#: Sample points handled at once by the kd-tree engine: the candidate triangles take
#: chunk x k x 72 bytes and the closest-point arithmetic about ten times that (1M points at
#: once peaked at 3.8 GB).
KDTREE_CHUNK = 100_000


def _one_sided_kdtree(P, V, F, dense, dense_face, k=8, eps=0.02):
    from scipy.spatial import cKDTree

    from .locate import _closest_barycentric

    # a surface of fewer than k triangles: cKDTree pads with a missing-neighbour index
    k = min(k, dense.shape[0])
    tree = cKDTree(dense)
    d = np.empty(P.shape[0])
    for lo in range(0, P.shape[0], KDTREE_CHUNK):
        Q = P[lo:lo + KDTREE_CHUNK]
        _, idx = tree.query(Q, k=k, eps=eps, workers=-1)
        cand = dense_face[idx.reshape(Q.shape[0], k)]
        d[lo:lo + Q.shape[0]] = _closest_barycentric(Q[:, None, :], V[F[cand]])[1].min(axis=1)
    return d


def _hausdorff_kdtree(Va, Fa, Vb, Fb, samples, seed):
    rng = np.random.default_rng(seed)
    out = []
    for (V1, F1), (V2, F2) in (((Va, Fa), (Vb, Fb)), ((Vb, Fb), (Va, Fa))):
        n = int(samples) if samples else int(np.clip(SAMPLES_PER_FACE * F1.shape[0], MIN_SAMPLES, MAX_SAMPLES))
        P, _ = _area_samples(V1, F1, n, rng)
        out.append(_one_sided_kdtree(P, V2, F2, V2[F2].mean(axis=1), np.arange(F2.shape[0])))
    d1, d2 = out
    rms = np.sqrt(0.5 * ((d1 ** 2).mean() + (d2 ** 2).mean()))
    return {"max": float(max(d1.max(), d2.max())), "rms": float(rms), "mean": float(0.5 * (d1.mean() + d2.mean())),
            "a_to_b_max": float(d1.max()), "b_to_a_max": float(d2.max()), "samples": int(d1.size + d2.size)}
