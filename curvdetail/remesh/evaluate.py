"""Two-sided surface distances between meshes (paper Fig. 3, evaluation)."""

import numpy as np

from ..curvature.checks import as_count, as_faces, check_choice, check_referenced, checked_arrays
from ..curvature.geometry import bbox_diagonal, face_double_areas
from ..curvature.errors import CurvdetailError, MeshError, first_indices
from .closest_point import SurfaceTree, as_coordinates, check_points, check_points_and_mesh, unit_frame

#: Largest ``samples`` (per direction), well below pymeshlab's 32-bit int: 10M is minutes and
#: ~2 GB of samples; 1,000,000 already gives ~1e-3 relative accuracy.
MAX_SAMPLE_COUNT = 10_000_000

#: Face samples per direction: ``SAMPLES_PER_FACE`` times the sampled mesh's triangle count,
#: clamped to [MIN_SAMPLES, MAX_SAMPLES]. A one-sided RMS over n samples has the relative standard
#: error cv / (2 sqrt(n)), cv the coefficient of variation of the squared distances: 1.9 to 2.3
#: for the 100k-vertex scan's rebuild and floor (docs/results/scan_100k.md), so 0.3 % at 100,000
#: samples and 0.1 % at 1,000,000 (the two-sided RMS: about 0.7 times that).
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
    each measured exactly (libigl's AABB tree, `SurfaceTree`).
    ``"meshlab"``: pymeshlab's ``get_hausdorff_distance`` (Monte Carlo samples, closest points
    in single precision), for figures comparable with MeshLab's; its random state carries over
    within a process, so repeated calls give other samples. Meshes more than ``FAR_APART``
    diagonals apart are measured with ``"exact"`` (pymeshlab's search does not return there).
    The vertices are measured exactly by both (`SurfaceTree`). `Surface` measures several meshes
    against one surface, checking it and building its tree once.

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
        ``vertex_distance(Va, Vb, Fb)`` (the figures come out bit for bit those of a call
        without it); None measures them here.

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
    return Surface(Vb, Fb, names=("Vb", "Fb")).hausdorff(Va, Fa, samples=samples, engine=engine, seed=seed,
                                                         a_vertex_distance=a_vertex_distance)


class Surface:
    """A triangle mesh that points and other meshes are measured against, checked once and
    searched through one closest-point tree (`SurfaceTree`) for every measurement.

    An experiment measures its rebuilt, zero-detail and retriangulated surfaces against one
    source: ``source = Surface(V, F)``, then ``source.vertex_distance(X)`` and
    ``source.hausdorff(X, Ft)`` for each. ``Surface(Vb, Fb).hausdorff(Va, Fa, ...)`` is
    `hausdorff` ``(Va, Fa, Vb, Fb, ...)`` and ``Surface(Vs, Fs).vertex_distance(P)`` is
    `vertex_distance` ``(P, Vs, Fs)``, bit for bit.

    Parameters
    ----------
    V : (n, 3) float array
        Vertex positions ((n, 2): a planar surface, for `vertex_distance` only).
    F : (m, 3) int array
        Triangles; every vertex used by one.
    names : pair of str
        ``V`` and ``F`` as the caller calls them, for the messages and ``e.parameter``.

    Raises
    ------
    MeshError
        Malformed surface, as `vertex_distance` refuses it.

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> V, F = grid(5, 5); source = Surface(V, F)
    >>> [round(source.hausdorff(V + [0, 0, lift], F)["rms"], 6) for lift in (0.01, 0.02)]
    [0.01, 0.02]
    """

    def __init__(self, V, F, names=("Vs", "Fs")):
        V = as_coordinates(V, names[0])
        _, self.V, self.F = check_points_and_mesh(np.empty((0, V.shape[1])), V, F, names=("points", *names))
        # as hausdorff refuses them: they measure nothing, but stretch the bounding box that the
        # frame, the zero-area test and the far-point limit are taken relative to
        check_referenced(self.V.shape[0], self.F, names[0])
        self.names = names
        self.tree = SurfaceTree(self.V, self.F)
        self._checked = False

    def vertex_distance(self, P, name="V"):
        """`vertex_distance` of the points ``P`` (k, d) to this surface: (k,) exact distances."""
        return self.tree.distance(check_points(P, self.V, (name, *self.names)))

    def hausdorff(self, Va, Fa, *, samples=None, engine="exact", seed=0, a_vertex_distance=None):
        """`hausdorff` of the mesh ``(Va, Fa)`` against this surface (b): the same parameters
        and figures."""
        Va = check_points(Va, self.V, ("Va", *self.names))
        if Va.shape[1] != 3:
            raise MeshError(f"Va has shape {Va.shape}; hausdorff measures surfaces in space, (n, 3).",
                            parameter="Va", value=Va.shape)
        Fa = as_faces(Fa, Va.shape[0], "Fa")              # named as the caller names it
        Va, Fa = _checked_in_frame(Va, Fa)
        if not self._checked:
            _checked_in_frame(self.V, self.F)
            self._checked = True
        engine = check_choice(engine, "engine", ("exact", "meshlab"), "; use 'exact' or 'meshlab'.")
        samples = _check_samples(samples)
        seed = None if seed is None else as_count(seed, "seed", minimum=0)
        given = _check_vertex_distance(a_vertex_distance, Va.shape[0])
        engine = "exact" if engine == "exact" or _apart(Va, self.V) else "meshlab"
        a = SurfaceTree(Va, np.ascontiguousarray(Fa, dtype=np.int64))
        ab = self.tree.distance(Va) if given is None else given          # a's vertices, exactly
        if engine == "exact":
            figures = _hausdorff_exact(a, self.tree, samples, seed)
        else:
            figures = _hausdorff_meshlab(Va, Fa, self.V, self.F, samples)
        # the maxima also over every vertex, measured exactly: face samples miss them, and a
        # maximum sits at a vertex more often than not
        figures["a_to_b_max"] = float(max(figures["a_to_b_max"], ab.max()))
        figures["b_to_a_max"] = float(max(figures["b_to_a_max"], a.distance(self.V).max()))
        figures["max"] = max(figures["a_to_b_max"], figures["b_to_a_max"])
        return dict(figures, engine=engine)


def _checked_in_frame(V, F):
    """`checked_arrays` of the mesh in its unit frame (areas relative to its own size: huge and
    tiny meshes neither over- nor underflow); ``(V, F)`` as given."""
    _, U, _ = unit_frame(V[:0], V)
    return V, checked_arrays(U, F)[1]


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


def _sample_count(samples, F):
    return int(samples) if samples else int(np.clip(SAMPLES_PER_FACE * F.shape[0], MIN_SAMPLES, MAX_SAMPLES))


def _hausdorff_meshlab(Va, Fa, Vb, Fb, samples):
    """pymeshlab's face-sample figures (no vertices) in the meshes' units, measured in a frame where
    the two together have unit size (as its single precision measures best)."""
    import pymeshlab

    both = np.vstack([Va, Vb])
    _, both, scale = unit_frame(both[:0], both)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=both[:Va.shape[0]], face_matrix=Fa.astype(np.int32)))
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=both[Va.shape[0]:], face_matrix=Fb.astype(np.int32)))
    out = []
    for sampled, target, F in ((0, 1, Fa), (1, 0, Fb)):
        # Every parameter explicitly: pymeshlab keeps values from earlier calls in one process.
        r = ms.get_hausdorff_distance(sampledmesh=sampled, targetmesh=target, savesample=False,
                                      samplevert=False, sampleedge=False, samplefauxedge=False,
                                      sampleface=True, samplenum=_sample_count(samples, F),
                                      maxdist=pymeshlab.PureValue(2.0))
        out.append(r)
    rms = np.sqrt(0.5 * (out[0]["RMS"] ** 2 + out[1]["RMS"] ** 2))
    return {"rms": float(scale * rms), "mean": float(scale * 0.5 * (out[0]["mean"] + out[1]["mean"])),
            "a_to_b_max": float(scale * out[0]["max"]), "b_to_a_max": float(scale * out[1]["max"]),
            "samples": int(out[0]["n_samples"] + out[1]["n_samples"])}


def _hausdorff_exact(a, b, samples, seed):
    """Face-sample figures (no vertices) of the meshes of the `SurfaceTree` s ``a`` and ``b``, each
    sample measured exactly, in the meshes' units."""
    rng = np.random.default_rng(seed)
    d = []
    for sampled, target in ((a, b), (b, a)):
        P, _ = _area_samples(sampled.U, sampled.F, _sample_count(samples, sampled.F), rng)
        d.append(target.distance(P * sampled.scale + sampled.centre) / b.scale)   # of order 1: no overflow
    d1, d2 = d
    return {"rms": float(b.scale * np.sqrt(0.5 * ((d1 ** 2).mean() + (d2 ** 2).mean()))),
            "mean": float(b.scale * 0.5 * (d1.mean() + d2.mean())), "a_to_b_max": float(b.scale * d1.max()),
            "b_to_a_max": float(b.scale * d2.max()), "samples": int(d1.size + d2.size)}


def vertex_distance(V, Vs, Fs):
    """Exact distance from each point of ``V`` to the surface ``(Vs, Fs)`` (e.g. the per-vertex
    error of a rebuilt mesh against its source).

    Bit for bit what ``hausdorff(Va, Fa, Vs, Fs)`` measures for the vertices ``Va = V``, so it
    can be passed to it as ``a_vertex_distance``. To measure many point sets against one
    surface, ``Surface(Vs, Fs).vertex_distance(V)`` builds its tree once.

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
    return Surface(Vs, Fs).vertex_distance(V)


def _area_samples(V, F, n, rng):
    """``n`` points uniformly distributed by area, with their triangle."""
    area = face_double_areas(V, F)
    face = rng.choice(F.shape[0], size=n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    bary = np.column_stack([1 - s, s * (1 - r2), s * r2])
    return (bary[:, :, None] * V[F[face]]).sum(1), face
