"""Vertices to fix when rebuilding a surface from its detail: the boundary, and anchors on closed pieces."""

import numpy as np

from .checks import as_count, as_index_set, as_values, checked_arrays
from .curvature_detail import curvature_detail
from .mixed_voronoi_area import mixed_voronoi_area
from .topology import boundary_vertices, vertex_components


def anchor_vertices(V, F, k=1, detail=None, fixed=None):
    """Fixed vertices that determine a reconstruction: ``fixed`` (default: every boundary vertex,
    all loops), plus ``k`` anchors on each connected piece with no vertex among them.

    The detail ``D = L X`` sums to zero over a closed piece and fixes its shape up to a
    translation; one fixed vertex removes that freedom, and `Reconstructor` then has a
    unique solution (``rows="free"``: ``L_ff`` is positive definite; ``rows="all"``: ``L_:f`` has
    full column rank). The first anchor of a piece is its *flattest* vertex, the one with the
    smallest ``|D_i| / A_i = |K_i|`` (A: mixed Voronoi area; ties: the smallest index), where the
    transferred detail carries least and a position on the surface is best known; further
    anchors follow by farthest-point sampling (Euclidean) from it.

    Parameters
    ----------
    V : (n, 3) float array
        Vertex positions (the target's, whose positions the anchors keep).
    F : (m, 3) int array
        Triangles.
    k : int
        Anchors per closed piece, at least 1 (at most the piece's vertex count).
    detail : (n, 3) float array or None
        The detail that will be rebuilt (e.g. transferred); None: the detail of ``(V, F)``.
    fixed : (j,) int array, (n,) bool mask or None
        Vertices the caller fixes (a piece holding one gets no anchor); None: the boundary
        vertices. Give ``np.union1d(boundary_vertices(F), selection)`` to fix both.

    Returns
    -------
    fixed : (p,) int64 array
        ``fixed`` and the anchors, increasing, each once.

    Raises
    ------
    MeshError
        If the mesh is malformed (see `check_mesh`).
    ConstraintError
        If ``detail`` or ``fixed`` is malformed.
    ValueError
        If ``k`` is not a whole number >= 1.

    Examples
    --------
    >>> from curvdetail.curvature.testing import icosphere
    >>> from curvdetail.curvature import curvature_detail, reconstruct
    >>> V, F = icosphere(subdivisions=2)
    >>> a = anchor_vertices(V, F)                 # closed: one anchor
    >>> a.size
    1
    >>> X = reconstruct(V, F, curvature_detail(V, F), a, V[a])
    >>> bool(abs(X - V).max() < 1e-12)
    True
    """
    V, F = checked_arrays(V, F)
    n = V.shape[0]
    k = as_count(k, "k")
    D = curvature_detail(V, F) if detail is None else as_values(detail, n, "detail")
    chosen = np.zeros(n, dtype=bool)
    chosen[boundary_vertices(F) if fixed is None else as_index_set(fixed, n, "fixed")] = True
    labels, count = vertex_components(F, n)
    settled = np.zeros(count, dtype=bool)
    settled[labels[chosen]] = True
    flatness = np.linalg.norm(D, axis=1) / mixed_voronoi_area(V, F)
    order = np.argsort(labels, kind="stable")
    starts = np.searchsorted(labels[order], np.arange(count + 1))
    for piece in np.flatnonzero(~settled):
        members = order[starts[piece]:starts[piece + 1]]          # increasing
        picked = [members[np.argmin(flatness[members])]]
        P = V[members]
        far = np.linalg.norm(P - V[picked[0]], axis=1)
        for _ in range(min(k, members.size) - 1):           # farthest-point sampling
            nxt = int(np.argmax(far))
            picked.append(members[nxt])
            far = np.minimum(far, np.linalg.norm(P - P[nxt], axis=1))
        chosen[picked] = True
    return np.flatnonzero(chosen)
