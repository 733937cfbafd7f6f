"""Minimal surface spanned by fixed vertices (zero curvature detail, Pinkall-Polthier iteration)."""

import numpy as np

from ._validate import (as_index_set, bbox_diagonal, check_every_component_fixed, check_mesh,
                        face_double_areas, ZERO_AREA_RELATIVE)
from .cotan_laplacian import _cotan_laplacian_unchecked
from .errors import ConstraintError, MeshError, first_indices
from .sparse_solver import factorize


class MinimalSurfaceResult(np.ndarray):
    """(n, 3) positions with ``iterations``, ``converged`` and ``last_step`` (relative) attached."""


def minimal_surface(V, F, fixed, *, max_iterations=200, tol=1e-6, backend="auto", callback=None):
    """Minimal surface with the ``fixed`` vertices kept: the paper's validity check, ``D = 0``.

    Each step solves the free rows ``L_ff X_f = -L_fc X_c`` with the cotangent weights of the
    current surface (a cotangent-harmonic step; Pinkall & Polthier 1993), then recomputes the
    weights. It stops when the largest vertex displacement of a step is below
    ``tol * bbox_diagonal`` or after ``max_iterations`` steps.

    Parameters
    ----------
    V : (n, 3) float array      initial surface (also the source of the first weights)
    F : (m, 3) int array        triangles
    fixed : (k,) int array or (n,) bool mask   vertices that keep their positions, e.g. the boundary
    max_iterations : int        at least 1
    tol : float                 relative step size at which to stop, > 0
    backend : str               sparse solver backend
    callback : callable or None called as ``callback(iteration, relative_step)`` after each step

    Returns
    -------
    X : (n, 3) float array (a :class:`MinimalSurfaceResult` with ``.iterations``,
        ``.converged`` and ``.last_step``)

    Raises
    ------
    MeshError         malformed mesh, or triangles collapsed during the iteration (the boundary
                      spans no minimal surface of this topology, e.g. two circles too far apart)
    ConstraintError   bad fixed set or a piece with no fixed vertex

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> from curvdetail.curvature import boundary_vertices
    >>> V, F = grid(9, 9); V[:, 2] = V[:, 0] * (1 - V[:, 0]) * V[:, 1] * (1 - V[:, 1])  # bump, flat rim
    >>> X = minimal_surface(V, F, boundary_vertices(F))
    >>> bool(abs(X[:, 2]).max() < 1e-9)      # the plane spanned by a planar boundary
    True
    """
    V, F = check_mesh(V, F)
    n = V.shape[0]
    fixed = as_index_set(fixed, n, "fixed")
    if fixed.size == 0:
        raise ConstraintError("no fixed vertices: a minimal surface needs a fixed boundary; pass e.g. "
                              "boundary_vertices(F).")
    check_every_component_fixed(F, n, fixed)
    if int(max_iterations) < 1:
        raise ValueError(f"max_iterations={max_iterations} must be at least 1.")
    if not (np.isfinite(tol) and tol > 0):
        raise ValueError(f"tol={tol} must be a positive number (relative to the bbox diagonal).")
    free = np.setdiff1d(np.arange(n), fixed)
    diag = bbox_diagonal(V)
    X = V.copy()
    step, it, converged = np.inf, 0, free.size == 0
    while not converged and it < int(max_iterations):
        L = _cotan_laplacian_unchecked(X, F)
        Lf = L[free]
        rhs = -(Lf[:, fixed] @ X[fixed])
        X_new = X.copy()
        X_new[free] = factorize(Lf[:, free], symmetric=True, backend=backend).solve(rhs)
        dbl = face_double_areas(X_new, F)
        collapsed = np.flatnonzero(dbl <= 2.0 * ZERO_AREA_RELATIVE * diag ** 2)
        if collapsed.size:
            raise MeshError(
                f"minimal surface iteration {it + 1}: {collapsed.size} triangles collapsed (first: "
                f"{first_indices(collapsed)}); the fixed vertices span no minimal surface of this "
                "topology (e.g. two circles too far apart for a catenoid)."
            )
        step = float(np.abs(X_new - X).max()) / diag
        X = X_new
        it += 1
        converged = step < tol
        if callback is not None:
            callback(it, step)
    out = X.view(MinimalSurfaceResult)
    out.iterations, out.converged, out.last_step = it, bool(converged), step
    return out
