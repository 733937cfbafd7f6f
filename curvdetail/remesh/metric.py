"""The target's Laplacian and the source's detail, both on the target's hat functions lifted onto the source."""

import numpy as np
import scipy.sparse as sp

from ..curvature.anchors import anchor_vertices
from ..curvature.checks import checked_arrays
from ..curvature.sparse_solver import factorize
from ..curvature.topology import vertex_components
from .closest_point import check_points_and_mesh
from .locate import _locate

#: Quadrature points `source_metric` aims at most for: k^2 per target triangle, k = 4 or 5 or fewer
#: where the target has more triangles than this allows (at least one each): ~0.5 kB each while
#: located.
MAX_METRIC_SAMPLES = 4_000_000

#: A quadrature point whose source triangle turns more than 60 degrees from its target triangle
#: (cos below this: a fold, or another sheet facing away) counts with the target's own metric. A
#: target piece wound against the source has its cosines turned first.
FACING = 0.5


def source_metric(Vs, Fs, Vt, Ft):
    """The target's Laplacian in the source's metric, and the source's detail on the target.

    Over each target triangle ``T`` the source is taken as a height field along ``T``'s normal, and
    the target's hat functions ``phi_i`` are lifted onto it along that normal; which source triangle
    lies over a quadrature point of ``T`` is found by the point's closest point on the source. On
    the source the lifted functions' Dirichlet energy is
    ``K_ij = sum_T A_T grad(phi_i)^T M_T grad(phi_j)`` and the source's detail (the weak mean
    curvature normal, ``D = L V`` on the source's own hat functions) is
    ``D_i = integral over the source of grad(phi_i) . grad(x) = sum_T A_T M_T grad(phi_i)``, with
    ``M_T`` the mean over the quadrature points of ``P_s / c``: ``P_s = I - n_s n_s^T`` the
    tangent projector of the source triangle over the point, ``c = n_s . n_T`` (the height field's
    area element is ``dA_T / c``, a lifted gradient ``P_s grad(phi)``). Both come from the same
    points, so ``K X = D`` is one Galerkin method: the rebuilt ``X`` is the height fields' best
    approximation in the target's space. Rebuilt with the target's own Laplacian (``M_T = P_T``)
    instead, thin parts stretch (the inscribed target's tubes are shorter round); with the detail
    located another way than the points (source edges onto the target), folds are cut.

    A target piece wound against the source gives the same ``K`` and ``D`` as wound with it. A
    target equal to the source gives its cotangent Laplacian and its detail (to rounding); a
    quadrature point whose source triangle turns more than 60 degrees from its target triangle
    (a fold, another sheet facing away) counts with the target's own metric there. Points: 16 per target triangle, 25 where the source's mean edge is
    under half the target's, fewer (at least one) beyond ``MAX_METRIC_SAMPLES``.

    Parameters
    ----------
    Vs, Fs : (n_s, 3) float, (m_s, 3) int arrays
        Source mesh
    Vt, Ft : (n_t, 3) float, (m_t, 3) int arrays
        Target mesh, a retriangulation of the source

    Returns
    -------
    K : (n_t, n_t) scipy.sparse.csr_matrix
        Symmetric, rows summing to zero, positive semi-definite.
    D : (n_t, 3) float array
        The source's detail on the target's lifted hat functions; sums to zero.

    Raises
    ------
    MeshError
        Malformed meshes (as `check_mesh` names them), a zero-area triangle included

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> from curvdetail.curvature import cotan_laplacian, curvature_detail
    >>> Vt, F = grid(5, 5); Vs = Vt.copy(); Vs[:, 2] = 0.5 * Vs[:, 0]    # a flat target under a slope
    >>> K, D = source_metric(Vs, F, Vt, F)          # the lifted hat functions are the source's own
    >>> bool(abs(K - cotan_laplacian(Vs, F)).max() < 1e-12), bool(abs(D - curvature_detail(Vs, F)).max() < 1e-12)
    (True, True)
    """
    Vs, Fs = checked_arrays(Vs, Fs, check_manifold=False, check_unreferenced=False)
    Vt, Ft = checked_arrays(Vt, Ft, check_manifold=False, check_unreferenced=False)
    return _source_metric(Vs, Fs, Vt, Ft)


def _source_metric(Vs, Fs, Vt, Ft, src_dom=None, tgt_dom=None):
    """`source_metric` on checked arrays; ``src_dom, tgt_dom``: a shared planar map (n_s, 2),
    (n_t, 2) to locate in, or None for the 3D closest point."""
    T = Vt[Ft]
    cross = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
    double_area = np.linalg.norm(cross, axis=1)
    n = cross / double_area[:, None]
    # grad(phi_k) = n x (opposite edge) / (2A), corner k of each triangle
    G = np.cross(n[:, None, :], T[:, [2, 0, 1]] - T[:, [1, 2, 0]]) / double_area[:, None, None]
    h_t = np.linalg.norm(T[:, [1, 2, 0]] - T, axis=2).mean()
    h_s = np.linalg.norm(Vs[Fs[:, [1, 2, 0]]] - Vs[Fs], axis=2).mean()
    k = max(1, int(min(max(4, np.ceil(2 * h_t / h_s)), 5, np.sqrt(MAX_METRIC_SAMPLES / Ft.shape[0]))))
    B = _subdivision_centroids(k)
    tri = np.repeat(np.arange(Ft.shape[0]), B.shape[0])
    if tgt_dom is None:
        P = np.einsum("qk,tkd->tqd", B, T).reshape(-1, 3)
        face = _locate(*check_points_and_mesh(P, Vs, Fs, names=("target samples", "Vs", "Fs")))[0]
    else:
        Q = np.einsum("qk,tkd->tqd", B, tgt_dom[Ft]).reshape(-1, tgt_dom.shape[1])
        face = _locate(*check_points_and_mesh(Q, src_dom, Fs, names=("target samples", "uv[0] (UVs)", "Fs")))[0]
    ns = np.cross(Vs[Fs[:, 1]] - Vs[Fs[:, 0]], Vs[Fs[:, 2]] - Vs[Fs[:, 0]])[face]
    ns /= np.linalg.norm(ns, axis=1, keepdims=True)
    c = np.einsum("ij,ij->i", ns, n[tri])
    # a target piece wound against the source: its points' cosines turned, then read as the rest
    piece = vertex_components(Ft, Vt.shape[0])[0][Ft[:, 0]][tri]
    c *= np.where(np.bincount(piece, weights=c) < 0, -1.0, 1.0)[piece]
    away = c < FACING
    ns[away], c[away] = n[tri][away], 1.0
    # A_T M_T, M_T the mean of (I - n_s n_s^T) / c over the triangle's points (no (points, 3, 3) array)
    w = (0.5 * double_area[:, None] / B.shape[0]) / c.reshape(-1, B.shape[0])
    ns = ns.reshape(-1, B.shape[0], 3)
    AM = w.sum(axis=1)[:, None, None] * np.eye(3) - np.einsum("tq,tqd,tqe->tde", w, ns, ns)
    MG = np.einsum("tde,tje->tjd", AM, G)                           # A_T M_T grad(phi_j), (m, 3, 3)
    local = np.einsum("tid,tjd->tij", G, MG)
    rows, cols = np.repeat(Ft, 3, axis=1), np.tile(Ft, (1, 3))
    N = Vt.shape[0]
    K = sp.csr_matrix((local.ravel(), (rows.ravel(), cols.ravel())), shape=(N, N))
    D = np.column_stack([np.bincount(Ft.ravel(), weights=MG[:, :, d].ravel(), minlength=N) for d in range(3)])
    return K, D


def _subdivision_centroids(k):
    """Barycentric coordinates (k^2, 3) of the centroids of a triangle cut into k^2 equal ones."""
    i, j = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
    up = np.column_stack([(i + 1 / 3).ravel(), (j + 1 / 3).ravel()])[(i + j).ravel() < k]
    down = np.column_stack([(i + 2 / 3).ravel(), (j + 2 / 3).ravel()])[(i + j).ravel() < k - 1]
    uv = np.vstack([up, down]) / k
    return np.column_stack([1 - uv.sum(axis=1), uv])


def rebuilt_in_metric(K, D, Vt, Ft):
    """Positions ``X`` with ``(K X)_i = D_i`` at every free vertex; kept where they are: the
    target's boundary and one vertex of each closed piece (`anchor_vertices`; any would do: ``K``
    annihilates translations, so the rest is the same up to that piece's translation)."""
    fixed = np.zeros(Vt.shape[0], dtype=bool)
    fixed[anchor_vertices(Vt, Ft, detail=D)] = True
    free = ~fixed
    X = Vt.copy()
    K = K.tocsr()
    rhs = D[free] - K[free][:, fixed] @ Vt[fixed]
    X[free] = factorize(K[free][:, free].tocsc()).solve(rhs)
    return X
