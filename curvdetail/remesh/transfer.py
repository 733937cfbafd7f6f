"""Carry curvature detail from a source mesh to its retriangulation (paper Fig. 3, step 3)."""

import numpy as np

from ..curvature._validate import check_mesh
from ..curvature.mean_curvature_normal import mean_curvature_normal
from ..curvature.mixed_voronoi_area import mixed_voronoi_area
from .locate import interpolate, locate, spread

METHODS = ("conservative", "pointwise")
LOCATIONS = ("closest", "uv")


def edge_curvature_measure(V, F):
    """The curvature detail of a polyhedral surface as a measure on its edges.

    For edge e, ``c_e = sum over its 1 or 2 triangles of |e| * (outward in-plane conormal of e in
    that triangle)``: zero on a flat interior edge, bending-normal on a folded one, in-plane on a
    boundary edge. Each vertex's detail is half the measure of its edges:
    ``D_i = (L V)_i = 1/2 sum_{e ni i} c_e`` exactly (the area gradient, edge by edge).

    Returns
    -------
    E : (k, 2) int array      undirected edges (sorted pairs)
    c : (k, 3) float array    their measures
    """
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    ends = np.stack([F[:, [1, 2]], F[:, [2, 0]], F[:, [0, 1]]], axis=1).reshape(-1, 2)   # edge k opposite corner k
    vec = V[ends[:, 1]] - V[ends[:, 0]]
    g = np.cross(vec, np.repeat(n, 3, axis=0))                                           # |e| x outward conormal
    key = np.sort(ends, axis=1)
    E, inverse = np.unique(key, axis=0, return_inverse=True)
    meas = np.zeros((E.shape[0], 3))
    np.add.at(meas, inverse.reshape(-1), g)
    return E, meas


def transfer_curvature(Vs, Fs, Vt, Ft, *, method="conservative", location="closest", uv=None,
                       samples_per_edge=None):
    """Curvature detail ``D`` for the target mesh, carried over from the source mesh.

    ``method="pointwise"`` (the paper): the intensive mean curvature normal ``K`` of the source is
    interpolated (barycentric) at each target vertex's location and multiplied by the target's own
    mixed Voronoi area: ``D_t = K(x_t) A_t``.

    ``method="conservative"``: the extensive detail is moved as a measure. The source's detail
    lives on its edges (:func:`edge_curvature_measure`, with ``D_i = 1/2 sum c_e`` exactly); each
    edge's measure is split evenly over sample points along the edge, every sample is located in
    a target triangle and split over its three corners by barycentric weights. Totals are kept
    exactly over any union of target stars, in particular ``sum_t D_t = sum_s D_s`` (to rounding),
    and a target equal to the source gets its own detail back exactly.

    Location: ``"closest"`` = the closest point on the other surface in space (the meshes are
    two triangulations of one surface); ``"uv"`` = point location in a shared planar domain
    given as ``uv=(UVs, UVt)`` (see :func:`parameterize`).

    Parameters
    ----------
    Vs, Fs : (n_s, 3) float, (m_s, 3) int   source mesh
    Vt, Ft : (n_t, 3) float, (m_t, 3) int   target mesh (a retriangulation of the source)
    method : {"conservative", "pointwise"}
    location : {"closest", "uv"}
    uv : tuple (UVs (n_s, 2), UVt (n_t, 2)) or None   required for ``location="uv"``
    samples_per_edge : int or None   conservative only: samples per source edge; ``None`` =
                       enough that samples are at most half the target's mean edge length apart

    Returns
    -------
    Dt : (n_t, 3) float array   target curvature detail (rows of boundary vertices included)

    Raises
    ------
    MeshError    malformed meshes
    ValueError   unknown method / location, or ``uv`` missing or of the wrong shape

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> from curvdetail.curvature import curvature_detail
    >>> V, F = grid(9, 9); V[:, 2] = V[:, 0] ** 2
    >>> D = transfer_curvature(V, F, V, F, method="conservative")   # a mesh onto itself
    >>> bool(np.allclose(D, curvature_detail(V, F), atol=1e-12))
    True
    """
    if method not in METHODS:
        raise ValueError(f"method={method!r} is not a transfer; use 'conservative' or 'pointwise'.")
    if location not in LOCATIONS:
        raise ValueError(f"location={location!r}; use 'closest' (3D closest point) or 'uv' (shared domain).")
    Vs, Fs = check_mesh(Vs, Fs)
    Vt, Ft = check_mesh(Vt, Ft)
    if location == "uv":
        if uv is None or len(uv) != 2:
            raise ValueError("location='uv' needs uv=(UVs, UVt), e.g. from curvdetail.remesh.parameterize.")
        UVs, UVt = (np.asarray(u, dtype=np.float64) for u in uv)
        if UVs.shape != (Vs.shape[0], 2) or UVt.shape != (Vt.shape[0], 2):
            raise ValueError(f"uv shapes {UVs.shape}, {UVt.shape} do not match the meshes "
                             f"({Vs.shape[0]}, 2), ({Vt.shape[0]}, 2).")
        src_dom, tgt_dom = UVs, UVt
    else:
        src_dom, tgt_dom = Vs, Vt
    if method == "pointwise":
        K, _ = mean_curvature_normal(Vs, Fs)
        face, bary, _ = locate(tgt_dom, src_dom, Fs)
        return interpolate(K, Fs, face, bary) * mixed_voronoi_area(Vt, Ft)[:, None]
    E, c = edge_curvature_measure(Vs, Fs)
    length = np.linalg.norm(Vs[E[:, 1]] - Vs[E[:, 0]], axis=1)
    if samples_per_edge is None:
        h_t = np.linalg.norm(Vt[Ft[:, [1, 2, 0]]] - Vt[Ft], axis=2).mean()
        q = np.maximum(1, np.ceil(2.0 * length / h_t)).astype(np.int64)
    else:
        q = np.full(E.shape[0], max(1, int(samples_per_edge)), dtype=np.int64)
    edge = np.repeat(np.arange(E.shape[0]), q)
    start = np.concatenate([[0], np.cumsum(q)[:-1]])
    t = (np.arange(edge.size) - start[edge] + 0.5) / q[edge]
    pts = (1 - t)[:, None] * src_dom[E[edge, 0]] + t[:, None] * src_dom[E[edge, 1]]
    face, bary, _ = locate(pts, tgt_dom, Ft)
    return spread(c[edge] / q[edge, None], Ft, face, bary, Vt.shape[0])
