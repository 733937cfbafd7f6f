"""Two-sided surface distances between meshes (paper Fig. 3, evaluation)."""

import numpy as np

from ..curvature.checks import as_count, as_faces, check_choice, check_referenced, checked_arrays
from ..curvature.geometry import bbox_diagonal, face_double_areas
from ..curvature.errors import CurvdetailError, MeshError, first_indices
from .closest_point import check_points_and_mesh, closest_in_frame, unit_frame

#: Largest ``samples`` (per direction), well below pymeshlab's 32-bit int: 10M is minutes and
#: ~2 GB of samples; 1,000,000 already gives ~1e-3 relative accuracy.
MAX_SAMPLE_COUNT = 10_000_000

#: Face samples per direction: ``SAMPLES_PER_FACE`` times the sampled mesh's triangle count,
#: clamped to [MIN_SAMPLES, MAX_SAMPLES].
SAMPLES_PER_FACE, MIN_SAMPLES, MAX_SAMPLES = 10, 100_000, 1_000_000

#: Meshes whose bounding boxes are more than this many diagonals (of the smaller) apart are
#: measured with the exact engine: pymeshlab's grid search does not return there.
FAR_APART = 1.0


def hausdorff(Va, Fa, Vb, Fb, *, samples=None, engine="exact", seed=0, a_vertex_distance=None):
    """Two-sided Hausdorff distance (max) and RMS distance between two triangle meshes.

    Each direction (a to b, then b to a) alike:

    * ``a_to_b_max``: the largest distance to the surface b over every vertex of a and
      ``samples`` points drawn on a's faces (uniformly by area). It is the one-sided Hausdorff
      distance where that is attained at a vertex, and falls short of it by at most the
      distance to the nearest sample otherwise. ``max`` is the larger of the two directions.
    * ``rms``: ``sqrt((rms_ab^2 + rms_ba^2) / 2)``, each over the face samples alone (uniform by
      area: an estimate of the RMS over the surface). ``mean``: the mean of the two one-sided
      means of the face samples.

    Engines: ``"exact"`` samples from numpy's ``default_rng(seed)``, the same in any process,
    each measured exactly (libigl's AABB tree, `closest_points`).
    ``"meshlab"``: pymeshlab's ``get_hausdorff_distance`` (Monte Carlo samples, closest points
    in single precision), for figures comparable with MeshLab's; its random state carries over
    within a process, so repeated calls give other samples. Meshes more than ``FAR_APART``
    diagonals apart are measured with ``"exact"`` (pymeshlab's search does not return there).
    The vertices are measured exactly by both, in a frame where the two meshes together have
    unit size.

    Parameters
    ----------
    Va, Fa, Vb, Fb : (n, 3) float and (m, 3) int arrays
        The two meshes.
    samples : int or None
        Face samples per direction, 1 to ``MAX_SAMPLE_COUNT``; None: 10 per triangle of the
        sampled mesh, at least 100,000 and at most 1,000,000.
    engine : {"exact", "meshlab"}
    seed : int or None
        Random seed (>= 0) of the ``"exact"`` engine's samples (None: fresh entropy).
    a_vertex_distance : (n_a,) float array or None
        The distances of a's vertices to b, measured already with
        ``vertex_distance(Va, Vb, Fb)`` (the same frame: the figures come out bit for bit those
        of a call without it); None measures them here.

    Returns
    -------
    dict
        ``max``, ``rms``, ``mean`` (absolute lengths), ``a_to_b_max``, ``b_to_a_max``,
        ``samples`` (face samples, both directions) and ``engine`` (the one that ran).

    Raises
    ------
    MeshError
        Malformed meshes (see `check_points_and_mesh`).
    ValueError
        Unknown ``engine``; ``samples`` not a whole number from 1 to 10,000,000; ``seed`` not a
        whole number >= 0; ``a_vertex_distance`` not (n_a,) finite distances >= 0.

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> V, F = grid(5, 5); W = V.copy(); W[:, 2] += 0.01
    >>> round(hausdorff(V, F, W, F)["rms"], 6)
    0.01
    """
    # in a frame where the two together have unit size (as pymeshlab sees them too): areas of
    # huge or tiny meshes neither over- nor underflow
    Va, Vb, _ = check_points_and_mesh(Va, Vb, Fb, names=("Va", "Vb", "Fb"))
    if Va.shape[1] != 3:
        raise MeshError(f"Va has shape {Va.shape}; hausdorff measures surfaces in space, (n, 3).",
                        parameter="Va", value=Va.shape)
    Fa = as_faces(Fa, Va.shape[0], "Fa")              # named as the caller names it
    both = np.vstack([Va, Vb])
    _, both, scale = unit_frame(both[:0], both)
    Va, Fa = checked_arrays(both[:Va.shape[0]], Fa)
    Vb, Fb = checked_arrays(both[Va.shape[0]:], Fb)
    engine = check_choice(engine, "engine", ("exact", "meshlab"), "; use 'exact' or 'meshlab'.")
    samples = _check_samples(samples)
    seed = None if seed is None else as_count(seed, "seed", minimum=0)
    given = _check_vertex_distance(a_vertex_distance, Va.shape[0])
    engine = "exact" if engine == "exact" or _apart(Va, Vb) else "meshlab"
    measure = given is None
    figures = _hausdorff_exact(Va, Fa, Vb, Fb, samples, seed, measure) if engine == "exact" else \
        _hausdorff_meshlab(Va, Fa, Vb, Fb, samples, measure)
    figures = _scaled(figures, scale)
    if given is not None:
        # after scaling: the given distances are absolute (scale * d in this frame, see
        # vertex_distance), and rounding a product is monotonic, so the maxima come out as
        # those of a call that measured the vertices here
        figures["a_to_b_max"] = float(max(figures["a_to_b_max"], given.max()))
        figures["max"] = float(max(figures["a_to_b_max"], figures["b_to_a_max"]))
    return dict(figures, engine=engine)


def _check_vertex_distance(d, n):
    """``a_vertex_distance`` of `hausdorff` as a (n,) float64 array (None stays None), or
    CurvdetailError (a ValueError) with ``parameter="a_vertex_distance"``."""
    if d is None:
        return None
    fix = "pass vertex_distance(Va, Vb, Fb), or None to measure them here."
    try:
        arr = np.asarray(d)
    except (TypeError, ValueError):             # ragged lists and the like
        arr = np.asarray(None)
    if arr.dtype == bool or arr.dtype.kind not in "fiu" or arr.shape != (n,):
        raise CurvdetailError(f"a_vertex_distance has dtype {arr.dtype} and shape {arr.shape}; it must hold one "
                              f"distance per vertex of Va, shape ({n},)", parameter="a_vertex_distance",
                              value=arr.shape, hint=fix)
    arr = arr.astype(np.float64)
    bad = np.flatnonzero(~(arr >= 0) | ~np.isfinite(arr))
    if bad.size:
        raise CurvdetailError(f"a_vertex_distance: {bad.size} of {n} entries are NaN, infinite or negative "
                              f"(first: {first_indices(bad)})", parameter="a_vertex_distance", count=bad.size,
                              first=bad[:5].tolist(), hint=fix)
    return arr


def _check_samples(samples):
    """``samples`` of `hausdorff` as an int from 1 to ``MAX_SAMPLE_COUNT`` (None stays None)."""
    if samples is None:
        return None
    try:
        count = as_count(samples, "samples")
    except ValueError:
        count = None
    if count is None or count > MAX_SAMPLE_COUNT:
        raise CurvdetailError(f"samples={samples!r} must be a whole number from 1 to {MAX_SAMPLE_COUNT:,}",
                              parameter="samples", value=samples,
                              hint="or None for 10 per triangle (100,000 to 1,000,000); ~1,000,000 is plenty.")
    return count


def _apart(Va, Vb):
    """True if the bounding boxes of the meshes are more than ``FAR_APART`` diagonals (of the
    smaller mesh) apart: pymeshlab's grid search slows down with the distance without bound
    (28 s at 0.1 diagonals for 20,000 samples on a 10k-vertex grid; no answer at 1e10)."""
    gap = np.linalg.norm(np.maximum(np.maximum(Va.min(0) - Vb.max(0), Vb.min(0) - Va.max(0)), 0.0))
    return bool(gap > FAR_APART * min(bbox_diagonal(Va), bbox_diagonal(Vb)))


def _scaled(figures, scale):
    return {k: v if k == "samples" else v * scale for k, v in figures.items()}


def _sample_count(samples, F):
    return int(samples) if samples else int(np.clip(SAMPLES_PER_FACE * F.shape[0], MIN_SAMPLES, MAX_SAMPLES))


def _hausdorff_meshlab(Va, Fa, Vb, Fb, samples, measure_a=True):
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=Va, face_matrix=Fa.astype(np.int32)))
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=Vb, face_matrix=Fb.astype(np.int32)))
    diag = bbox_diagonal(np.vstack([Va, Vb]))
    out = []
    for sampled, target, F in ((0, 1, Fa), (1, 0, Fb)):
        # Every parameter explicitly: pymeshlab keeps values from earlier calls in one process.
        r = ms.get_hausdorff_distance(sampledmesh=sampled, targetmesh=target, savesample=False,
                                      samplevert=False, sampleedge=False, samplefauxedge=False,
                                      sampleface=True, samplenum=_sample_count(samples, F),
                                      maxdist=pymeshlab.PureValue(2.0 * diag))
        out.append(r)
    n1, n2 = out[0]["n_samples"], out[1]["n_samples"]
    rms = np.sqrt(0.5 * (out[0]["RMS"] ** 2 + out[1]["RMS"] ** 2))
    mean = 0.5 * (out[0]["mean"] + out[1]["mean"])
    # the maxima also over every vertex, measured exactly: face samples miss them, and a
    # maximum sits at a vertex more often than not (a's: by the caller, if it measured them)
    ab = max(out[0]["max"], _surface_distance(Va, Vb, Fb).max()) if measure_a else out[0]["max"]
    ba = max(out[1]["max"], _surface_distance(Vb, Va, Fa).max())
    return {"max": float(max(ab, ba)), "rms": float(rms), "mean": float(mean),
            "a_to_b_max": float(ab), "b_to_a_max": float(ba), "samples": int(n1 + n2)}


def vertex_distance(V, Vs, Fs):
    """Exact distance from each point of ``V`` to the surface ``(Vs, Fs)`` (e.g. the per-vertex
    error of a rebuilt mesh against its source).

    Measured in `hausdorff`'s frame (the points and the surface together of unit size), so
    ``vertex_distance(Va, Vb, Fb)`` is bit for bit what ``hausdorff(Va, Fa, Vb, Fb)`` measures
    for a's vertices and can be passed to it as ``a_vertex_distance``.

    Parameters
    ----------
    V : (k, 3) float array
        Query points (k = 0 allowed); or (k, 2) with a planar ``Vs``.
    Vs : (n, 3) float array
        The surface's vertex positions ((n, 2) for planar points).
    Fs : (m, 3) int array
        Its triangles.

    Returns
    -------
    d : (k,) float array
        Unsigned distances, in the unit of the coordinates, row i for ``V[i]``.

    Raises
    ------
    MeshError
        Malformed points or surface, as `locate` refuses them (naming ``V``,
        ``Vs`` and ``Fs``); vertices of ``Vs`` used by no triangle, as `hausdorff` refuses them.

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> Vs, Fs = grid(3, 3)                               # the unit square in z = 0
    >>> P = np.array([[0.5, 0.5, 2.0], [0.2, 0.3, 0.0], [2.0, 0.5, 0.0]])
    >>> vertex_distance(P, Vs, Fs).round(12).tolist()     # above, on, and beside the square
    [2.0, 0.0, 1.0]
    """
    P, Vs, Fs = check_points_and_mesh(V, Vs, Fs, names=("V", "Vs", "Fs"))
    # as hausdorff (check_mesh) refuses them: they measure nothing, but stretch the bounding box
    # that the frame, the zero-area test and the far-point limit are taken relative to
    check_referenced(Vs.shape[0], Fs, "Vs")
    both = np.vstack([P, Vs])
    _, both, scale = unit_frame(both[:0], both)
    return scale * _surface_distance(both[:P.shape[0]], both[P.shape[0]:], Fs)


def _surface_distance(P, V, F):
    """Exact distance from each point of ``P`` (k, d) to the surface ``(V, F)``, in the frame given."""
    return np.sqrt(closest_in_frame(P, V, F, bary=False)[0])


def _area_samples(V, F, n, rng):
    """``n`` points uniformly distributed by area, with their triangle."""
    area = face_double_areas(V, F)
    face = rng.choice(F.shape[0], size=n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    bary = np.column_stack([1 - s, s * (1 - r2), s * r2])
    return (bary[:, :, None] * V[F[face]]).sum(1), face


def _hausdorff_exact(Va, Fa, Vb, Fb, samples, seed, measure_a=True):
    rng = np.random.default_rng(seed)
    out = []
    for (V1, F1), (V2, F2), vertices in (((Va, Fa), (Vb, Fb), measure_a), ((Vb, Fb), (Va, Fa), True)):
        n = _sample_count(samples, F1)
        P, _ = _area_samples(V1, F1, n, rng)
        d = _surface_distance(np.vstack([P, V1]) if vertices else P, V2, F2)
        out.append((d[:n], d[n:].max() if vertices else -np.inf))
    (d1, v1), (d2, v2) = out
    rms = np.sqrt(0.5 * ((d1 ** 2).mean() + (d2 ** 2).mean()))
    ab, ba = max(d1.max(), v1), max(d2.max(), v2)
    return {"max": float(max(ab, ba)), "rms": float(rms), "mean": float(0.5 * (d1.mean() + d2.mean())),
            "a_to_b_max": float(ab), "b_to_a_max": float(ba), "samples": int(d1.size + d2.size)}
