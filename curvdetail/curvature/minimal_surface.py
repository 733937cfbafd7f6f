"""Minimal surface spanned by fixed vertices (zero curvature detail, Pinkall-Polthier iteration)."""

import numpy as np

from ._geometry import corner_cotangents
from ._validate import (check_choice, ZERO_AREA_RELATIVE, as_count, as_index_set, as_positive_number, bbox_centre,
                        bbox_diagonal, check_every_component_fixed, misoriented_edges, vertex_components)
from .cotan_laplacian import _assemble_upper, checked_cotan_triangle
from .errors import ConstraintError, MeshError, first_indices
from .reconstruct import _FreeSystemLayout
from .sparse_solver import factorize


class MinimalSurfaceResult(np.ndarray):
    """(n, 3) positions with ``iterations``, ``converged``, ``last_step`` (the last step's largest
    displacement as ``step`` measures it: by default its part normal to the surface) and
    ``last_full_step`` (its largest displacement, tangential sliding included), both relative to
    the bbox diagonal of the vertex's piece, attached."""


#: Default stopping tolerance of :func:`minimal_surface`: the shape moves by less than 1e-4 of the
#: bbox diagonal in a step. The cotangent minimal surface itself is only second-order accurate
#: (the 64 x 33 catenoid is off by 1.5e-4 of its diagonal), so iterating further buys nothing.
DEFAULT_TOL = 1e-4


def _vertex_normals(X, F, face_cross=None, aligned=False):
    """Area-weighted unit vertex normals, shape (n, 3); ``face_cross`` (m, 3), the triangles'
    ``(x1 - x0) x (x2 - x0)``, where the caller has it. ``aligned=True`` is for triangles that
    are not consistently oriented (a Moebius strip cannot be): each triangle's normal enters a
    vertex's sum turned to agree with one of the vertex's triangles, so reversed triangles do not
    cancel it (the result's sign is then arbitrary; the step measure takes its absolute value).
    That triangle is the vertex's largest."""
    fn = np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]]) if face_cross is None else face_cross
    n = X.shape[0]
    if not aligned:
        N = np.column_stack([np.bincount(F.ravel(), weights=np.repeat(fn[:, k], 3), minlength=n)
                             for k in range(3)])
    else:
        # each vertex's reference is its largest triangle: one nearly perpendicular to the rest
        # (a sharp crease) would otherwise flip them and the sum could lie in their plane
        corner_vertex = F.ravel()
        corner_face = np.repeat(np.arange(F.shape[0]), 3)
        size = np.repeat(np.einsum("ij,ij->i", fn, fn), 3)
        order = np.lexsort((size, corner_vertex))
        last = np.flatnonzero(np.r_[corner_vertex[order][1:] != corner_vertex[order][:-1], True])
        reference = np.zeros((n, 3))
        reference[corner_vertex[order][last]] = fn[corner_face[order][last]]
        N = np.zeros((n, 3))
        for corner in range(3):
            sign = np.where(np.einsum("ij,ij->i", fn, reference[F[:, corner]]) < 0, -1.0, 1.0)
            N += np.column_stack([np.bincount(F[:, corner], weights=sign * fn[:, k], minlength=n)
                                  for k in range(3)])
    length = np.linalg.norm(N, axis=1, keepdims=True)
    return N / np.where(length > 0, length, 1.0)


def _piece_diagonals(V, F, adjacency):
    """The bbox diagonal of each vertex's connected piece, shape (n,); a scalar for one piece."""
    labels, count = vertex_components(F, V.shape[0], adjacency=adjacency)
    if count == 1:
        return bbox_diagonal(V)
    order = np.argsort(labels, kind="stable")
    starts = np.flatnonzero(np.r_[True, np.diff(labels[order]) != 0])
    sorted_V = V[order]
    extent = np.maximum.reduceat(sorted_V, starts) - np.minimum.reduceat(sorted_V, starts)
    # a piece of zero extent (unreferenced vertices are refused, so at least a triangle) cannot
    # occur in a checked mesh; the floor keeps the division finite regardless
    piece = np.maximum(np.linalg.norm(extent, axis=1), np.finfo(float).tiny)
    return piece[labels]


def minimal_surface(V, F, fixed, *, max_iterations=200, tol=DEFAULT_TOL, step="normal", backend="auto",
                    callback=None):
    """Minimal surface with the ``fixed`` vertices kept: the paper's validity check, ``D = 0``.

    Each step solves the free rows ``L_ff X_f = -L_fc X_c`` with the cotangent weights of the
    current surface (a cotangent-harmonic step; Pinkall & Polthier 1993), then recomputes the
    weights. It stops when the shape has settled: when the largest displacement of a step
    *normal to the surface* (projected on the area-weighted vertex normals of the new surface) is
    below ``tol`` times the bbox diagonal of the vertex's connected piece (the mesh's, for one
    piece), or after ``max_iterations`` steps. ``step="full"`` compares the whole displacement
    instead (the largest vertex step, as the issue words it).

    Why the normal part: after the first few steps the shape is found, but on irregular meshes
    the vertices keep sliding *within* the surface, because sliding lowers the discrete area by
    degrading triangles; Pinkall-Polthier's iteration never stops doing that. On the mannequin
    nose (640 vertices) the full step is still 2e-4 of the diagonal after 200 steps and 1.6e-4
    after 400, nearly all of it tangential, while the normal part is below 1e-4 from step ~40
    on. On a symmetric grid (the catenoid) a tangential drift of ~2.4e-7 per step goes on forever
    while the normal step falls to 1e-11. The full step is reported as ``last_full_step``.

    Parameters
    ----------
    V : (n, 3) float array      initial surface (also the source of the first weights)
    F : (m, 3) int array        triangles
    fixed : (k,) int array or (n,) bool mask   vertices that keep their positions, e.g. the boundary
    max_iterations : int        at least 1
    tol : float                 stop when no vertex moves more than ``tol`` x its piece's bbox
                                diagonal across the surface in a step (default 1e-4,
                                :data:`DEFAULT_TOL`), > 0
    step : {"normal", "full"}   what ``tol`` is compared with: the step's part normal to the
                                surface (triangles need not be consistently oriented) or the whole
                                vertex displacement (tangential sliding included: on irregular
                                meshes it may not fall below ``tol`` in ``max_iterations``)
    backend : str               sparse solver backend
    callback : callable or None called as ``callback(iteration, relative_step)`` after each step
                                (``relative_step``: the step that ``tol`` is compared with)

    Returns
    -------
    X : (n, 3) float array (a :class:`MinimalSurfaceResult` with ``.iterations``,
        ``.converged``, ``.last_step`` and ``.last_full_step``)

    Raises
    ------
    MeshError         malformed mesh, or triangles collapsed during the iteration (the boundary
                      spans no minimal surface of this topology, e.g. two circles too far apart)
    ConstraintError   bad fixed set or a piece with no fixed vertex
    ValueError        ``max_iterations`` not a whole number >= 1, ``tol`` not a positive number,
                      ``step`` not "normal" or "full"
    SolverError       an unknown or uninstalled ``backend``

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> from curvdetail.curvature import boundary_vertices
    >>> V, F = grid(9, 9); V[:, 2] = V[:, 0] * (1 - V[:, 0]) * V[:, 1] * (1 - V[:, 1])  # bump, flat rim
    >>> X = minimal_surface(V, F, boundary_vertices(F))
    >>> bool(abs(X[:, 2]).max() < 1e-9)      # the plane spanned by a planar boundary
    True
    """
    max_iterations = as_count(max_iterations, "max_iterations")
    tol = as_positive_number(tol, "tol", " (relative to the bbox diagonal)")
    step = check_choice(step, "step", ("normal", "full"), "; use 'normal' (the step across the surface) "
                        "or 'full' (the whole vertex displacement).")
    if callback is not None and not callable(callback):
        raise ValueError(f"callback={callback!r} is not callable; pass a function (iteration, step) or None.")
    V, F, U, diagonal = checked_cotan_triangle(V, F)     # every mesh check; L of the first step
    n = V.shape[0]
    fixed = as_index_set(fixed, n, "fixed")
    if fixed.size == 0:
        raise ConstraintError("no fixed vertices: a minimal surface needs a fixed boundary; pass e.g. "
                              "boundary_vertices(F).")
    check_every_component_fixed(F, n, fixed, adjacency=U)
    # the step is measured along vertex normals, which reversed triangles cancel: the iteration
    # ran to max_iterations "not converged". Where triangles are not consistently oriented (or
    # cannot be: a Moebius strip), the normals are summed sign-aligned instead (1M vertices: the
    # check ~0.9 s, a fifth of a step)
    aligned = step == "normal" and misoriented_edges(F).shape[0] > 0
    is_free = np.ones(n, dtype=bool)
    is_free[fixed] = False
    free = np.flatnonzero(is_free)
    diag = bbox_diagonal(V)
    # steps are measured against the diagonal of each vertex's own piece: against the whole
    # mesh's, a small piece next to a big one (or far from it) counted as settled long before it
    # was (a nose beside an ear 10 units away stopped after 4 of its 44 steps)
    scale = _piece_diagonals(V, F, U)
    factor = None
    centre = bbox_centre(V[fixed])
    layout = _FreeSystemLayout(U, is_free, fixed)    # the same for every step: F does not change
    X = V.copy()
    converged = free.size == 0
    measured = full_step = 0.0 if converged else np.inf
    it = 0
    while not converged and it < max_iterations:
        if it > 0:                          # weights of the current surface
            cot, _, _ = corner_cotangents(X, F, lengths=False)
            U, diagonal = _assemble_upper(X, F, cot, check_manifold=False)
        system, L_fc = layout.values(U, diagonal)
        # the pattern of L_ff never changes: the solver keeps its ordering and symbolic analysis
        # and redoes only the numeric factorization (PARDISO, 1M vertices: ~1.5 of ~5.5 s)
        if factor is None:
            factor = factorize(system, symmetric=True, backend=backend, upper=True)
        else:
            factor.refactor(system)
        X_new = X.copy()
        # about the fixed vertices' centre: large coordinates (UTM, ECEF) do not cancel
        X_new[free] = factor.solve(-(L_fc @ (X[fixed] - centre))) + centre
        # one cross product per triangle serves the collapse check and the normals
        cross = np.cross(X_new[F[:, 1]] - X_new[F[:, 0]], X_new[F[:, 2]] - X_new[F[:, 0]])
        dbl = np.sqrt(np.einsum("ij,ij->i", cross, cross))
        collapsed = np.flatnonzero(dbl <= 2.0 * ZERO_AREA_RELATIVE * diag ** 2)
        if collapsed.size:
            raise MeshError(
                f"minimal surface iteration {it + 1}: {collapsed.size} triangles collapsed (first: "
                f"{first_indices(collapsed)}); the fixed vertices span no minimal surface of this "
                "topology (e.g. two circles too far apart for a catenoid)."
            )
        move = X_new - X
        full_step = float((np.linalg.norm(move, axis=1) / scale).max())
        if step == "normal":
            normals = _vertex_normals(X_new, F, cross, aligned=aligned)
            measured = float((np.abs(np.einsum("ij,ij->i", move, normals)) / scale).max())
        else:
            measured = full_step
        X = X_new
        it += 1
        converged = measured < tol
        if callback is not None:
            callback(it, measured)
    out = X.view(MinimalSurfaceResult)
    out.iterations, out.converged, out.last_step, out.last_full_step = it, bool(converged), measured, full_step
    return out
