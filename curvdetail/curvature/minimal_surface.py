"""Minimal surface spanned by fixed vertices (zero curvature detail, Pinkall-Polthier iteration)."""

import numpy as np

from .checks import ZERO_AREA_RELATIVE, as_count, as_index_set, as_positive_number, check_choice
from .geometry import bbox_centre, bbox_diagonal, corner_cotangents, ignoring_underflow, vertex_normals
from .topology import boundary_vertices, check_every_component_fixed, edge_keys, misoriented_edges, vertex_components
from .cotan_laplacian import _assemble_upper, checked_cotan_triangle
from .errors import ConstraintError, CurvdetailError, MeshError, counted, first_indices, them
from .reconstruct import _FreeSystemLayout
from .sparse_solver import factorize


class MinimalSurfaceResult(np.ndarray):
    """(n, 3) positions with the iteration's figures attached (they survive ``copy()``, slicing,
    arithmetic and pickling). Steps are relative to the bbox diagonal of the vertex's piece.

    Attributes
    ----------
    iterations : int
        Steps taken.
    converged : bool
        The last step fell below ``tol``: a bound on that step, not on the distance to the
        iteration's limit (see ``remaining_estimate``).
    last_step : float
        The last step's largest displacement as ``step`` measures it (by default its normal part).
    last_full_step : float
        Its largest displacement, tangential sliding included.
    contraction : float
        ``last_step`` over the step before (nan after fewer than two steps).
    remaining_estimate : float
        How much farther the steps would add up to at that contraction,
        ``last_step * rho / (1 - rho)`` (inf where they do not contract, 0 where nothing is free).
    """

    _FIGURES = ("iterations", "converged", "last_step", "last_full_step", "contraction", "remaining_estimate")

    def __array_finalize__(self, obj):           # views, copies, ufunc results: obj's figures
        for name in self._FIGURES:
            setattr(self, name, getattr(obj, name, None))

    def __reduce__(self):                        # the figures ride along at the end of the state
        constructor, arguments, state = super().__reduce__()
        return constructor, arguments, state + (tuple(getattr(self, name, None) for name in self._FIGURES),)

    def __setstate__(self, state):
        *array_state, figures = state
        super().__setstate__(tuple(array_state))
        for name, value in zip(self._FIGURES, figures):
            setattr(self, name, value)


#: Default stopping tolerance: the last step moved the shape by less than 1e-4 of the bbox
#: diagonal (a bound on the step, not on the distance to the iteration's limit).
DEFAULT_TOL = 1e-4

#: Largest ``|cot|`` of a corner in a usable result (an angle within 1e-6 rad of 0 or 180 degrees);
#: real results stay below ~100, a pinching neck passes 1e3, 1e4, ... within a step or two.
DEGENERATE_COTANGENT = 1e6

#: ... where it also grew this many times over the input's (an input sliver is not refused).
DEGENERATE_GROWTH = 100.0


def _piece_diagonals(V, F, adjacency):
    """``(scale, pieces)``: the bbox diagonal of each vertex's connected piece, shape (n,) (a scalar
    for one piece), and ``(labels, order, starts)`` of the pieces (None for one piece): each
    vertex's piece label, the vertices sorted by piece, and where each piece starts in that order."""
    labels, count = vertex_components(F, V.shape[0], adjacency=adjacency)
    if count == 1:
        return bbox_diagonal(V), None
    order = np.argsort(labels, kind="stable")
    starts = np.flatnonzero(np.r_[True, np.diff(labels[order]) != 0])
    sorted_V = V[order]
    extent = np.maximum.reduceat(sorted_V, starts) - np.minimum.reduceat(sorted_V, starts)
    return np.linalg.norm(extent, axis=1)[labels], (labels, order, starts)


@ignoring_underflow
def minimal_surface(V, F, fixed, *, max_iterations=200, tol=DEFAULT_TOL, step="normal", backend="auto",
                    callback=None):
    """Minimal surface with the ``fixed`` vertices kept: the paper's validity check, ``D = 0``.

    Each step solves the free rows ``L_ff X_f = -L_fc X_c`` with the cotangent weights of the
    current surface (Pinkall & Polthier 1993), then recomputes the weights. It stops when the
    largest displacement of a step *normal to the surface* is below ``tol`` times the bbox
    diagonal of the vertex's connected piece (tangential sliding, which degrades triangles and
    never stops on irregular meshes, is not counted), or after ``max_iterations`` steps. A piece
    whose step falls below ``tol`` keeps its positions while the others go on. A step that
    collapses triangles raises MeshError.

    Parameters
    ----------
    V : (n, 3) float array
        Initial surface (also the source of the first weights).
    F : (m, 3) int array
        Triangles.
    fixed : (k,) int array or (n,) bool mask
        Vertices that keep their positions, e.g. the boundary.
    max_iterations : int
        At least 1.
    tol : float
        Stopping step, relative to the piece's bbox diagonal, > 0.
    step : {"normal", "full"}
        What ``tol`` is compared with: the step's part normal to the surface, or the whole vertex
        displacement (which on irregular meshes may not fall below ``tol``).
    backend : str
        Sparse solver backend.
    callback : callable, optional
        Called as ``callback(iteration, relative_step)`` after each step.

    Returns
    -------
    X : (n, 3) MinimalSurfaceResult
        The positions, an ndarray with the iteration's figures as attributes.

    Raises
    ------
    MeshError
        If the mesh is malformed, or triangles collapsed (the message says the likely cause).
    ConstraintError
        If ``fixed`` is refused, a piece has no fixed vertex, or a boundary vertex is left free.
    ValueError
        If ``max_iterations``, ``tol``, ``step`` or ``callback`` is not allowed.
    SolverError
        If ``backend`` is unknown or not installed.

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
        raise CurvdetailError(f"callback={callback!r} is not callable; pass a function (iteration, step) or None.",
                              parameter="callback", value=callback)
    V, F, U, diagonal = checked_cotan_triangle(V, F)     # every mesh check; L of the first step
    n = V.shape[0]
    fixed = as_index_set(fixed, n, "fixed")
    if fixed.size == 0:
        raise ConstraintError("no fixed vertices: a minimal surface needs a fixed boundary; pass e.g. "
                              "boundary_vertices(F).", parameter="fixed", count=0)
    check_every_component_fixed(F, n, fixed, adjacency=U)
    is_free = np.ones(n, dtype=bool)
    is_free[fixed] = False
    # a free rim has no minimal surface: it shrinks onto the fixed vertices
    boundary = boundary_vertices(F)
    loose = boundary[is_free[boundary]]
    if loose.size:
        raise ConstraintError(
            f"{counted(loose.size, 'boundary vertex', 'boundary vertices', verb='are')} not fixed (of "
            f"{boundary.size}; first: {first_indices(loose)}): a surface with a free boundary has no "
            "minimal surface (it shrinks onto the fixed vertices until its triangles collapse). Fix the "
            "whole boundary too, e.g. np.union1d(fixed, boundary_vertices(F)).",
            parameter="fixed", count=int(loose.size), first=loose[:3].tolist())
    # the step is measured along vertex normals, which reversed triangles would cancel
    aligned = step == "normal" and misoriented_edges(F).shape[0] > 0
    free = np.flatnonzero(is_free)
    diag = bbox_diagonal(V)
    # steps relative to each vertex's own piece; a piece whose step fell below tol stays put
    scale, pieces = _piece_diagonals(V, F, U)
    settled = factor = cot = None
    centre = bbox_centre(V[fixed])
    layout = _FreeSystemLayout(U, is_free, fixed)    # the same for every step: F does not change
    X = V.copy()
    converged = free.size == 0
    measured = full_step = 0.0 if converged else np.inf
    previous = np.nan
    it = 0
    while not converged and it < max_iterations:
        if it > 0:                          # weights of the current surface
            U, diagonal = _assemble_upper(X, F, cot, check_manifold=False)
        system, L_fc = layout.values(U, diagonal)
        # the pattern of L_ff never changes: refactor redoes the numeric factorization only
        if factor is None:
            factor = factorize(system, symmetric=True, backend=backend, upper=True)
        else:
            factor.refactor(system)
        X_new = X.copy()
        # about the fixed vertices' centre: large coordinates (UTM, ECEF) do not cancel
        X_new[free] = factor.solve(-(L_fc @ (X[fixed] - centre))) + centre
        if settled is not None:
            X_new[settled] = X[settled]
        # one cross product per triangle serves the collapse check and the normals
        cross = np.cross(X_new[F[:, 1]] - X_new[F[:, 0]], X_new[F[:, 2]] - X_new[F[:, 0]])
        dbl = np.sqrt(np.einsum("ij,ij->i", cross, cross))
        collapsed = np.flatnonzero(dbl <= 2.0 * ZERO_AREA_RELATIVE * diag ** 2)
        if collapsed.size == 0:
            # the next step's weights; needles pass an area check, not this one
            cot, _, _ = corner_cotangents(X_new, F, lengths=False)
            largest = np.abs(cot).max(axis=1)
            if largest.max() > DEGENERATE_COTANGENT:
                candidates = np.flatnonzero(largest > DEGENERATE_COTANGENT)
                rest, _, _ = corner_cotangents(V, F[candidates], lengths=False)
                collapsed = candidates[largest[candidates] > DEGENERATE_GROWTH * np.abs(rest).max(axis=1)]
        if collapsed.size:
            raise MeshError(_collapse_message(it + 1, collapsed, dbl, V, F, fixed, U, measured, step, tol),
                            count=int(collapsed.size), first=collapsed[:3].tolist())
        move = X_new - X
        each = np.linalg.norm(move, axis=1) / scale
        full_step = float(each.max())
        if step == "normal":
            normals = vertex_normals(X_new, F, cross, aligned=aligned)
            each = np.abs(np.einsum("ij,ij->i", move, normals)) / scale
        measured, previous = float(each.max()), measured
        if pieces is not None:
            labels, order, starts = pieces
            settled = (np.maximum.reduceat(each[order], starts) < tol)[labels]
        X = X_new
        it += 1
        converged = measured < tol
        if callback is not None:
            callback(it, measured)
    out = X.view(MinimalSurfaceResult)
    out.iterations, out.converged, out.last_step, out.last_full_step = it, bool(converged), measured, full_step
    out.contraction, out.remaining_estimate = _remaining_estimate(measured, previous if it >= 2 else np.nan)
    return out


def _remaining_estimate(last, previous):
    """``(rho, last * rho / (1 - rho))`` with ``rho = last / previous`` (a contraction's error
    bound); ``(nan, inf)`` without a step before, ``(nan or 0, 0)`` after a step of exactly 0."""
    if last == 0.0:
        return (np.nan if np.isnan(previous) else 0.0), 0.0
    if not previous > 0.0:              # nan: one step only
        return np.nan, np.inf
    rho = last / previous
    return rho, (last * rho / (1.0 - rho) if rho < 1.0 else np.inf)


def _collapse_message(iteration, triangles, dbl, V, F, fixed, adjacency, last_step, step, tol):
    """The MeshError text for triangles that collapsed in step ``iteration``, with the likely
    cause from the topology of the first triangle's piece."""
    zero_area = bool(np.all(dbl[triangles] <= 2.0 * ZERO_AREA_RELATIVE * bbox_diagonal(V) ** 2))
    how = ("to zero area", "") if zero_area else ("into needles", "; an angle within 1e-6 rad of 0 or 180 degrees")
    text = (f"minimal surface iteration {iteration}: {counted(triangles.size, 'triangle')} collapsed {how[0]} "
            f"(first: {first_indices(triangles)}{how[1]})")
    if iteration > 1:
        measure = "normal to the surface" if step == "normal" else "whole displacement"
        text += (f"; the step before moved the shape by {last_step:.2e} of the bbox diagonal ({measure}; "
                 f"tol {tol:g})")
    labels, _ = vertex_components(F, V.shape[0], adjacency=adjacency)
    piece = labels[F[triangles[0], 0]]
    in_piece = labels == piece
    piece_faces = F[in_piece[F[:, 0]]]
    boundary = boundary_vertices(piece_faces)
    inner_fixed = np.setdiff1d(fixed[in_piece[fixed]], boundary)
    edges = np.unique(edge_keys(piece_faces)[0]).size
    euler = np.count_nonzero(in_piece) - edges + piece_faces.shape[0]       # 1: a disk (a boundary, genus 0)
    larger_tol = f"a larger tol, e.g. the default {DEFAULT_TOL:g}" if tol < DEFAULT_TOL else "a larger tol"
    how_earlier = f"({larger_tol}, or max_iterations below {iteration})"
    earlier = f", or stop earlier {how_earlier}" if iteration > 1 else ""
    if inner_fixed.size:
        return (f"{text}. {counted(inner_fixed.size, 'fixed vertex', 'fixed vertices', verb='lie')} inside the "
                f"surface (first: {first_indices(inner_fixed)}): a minimal surface cannot be held at isolated "
                f"points, and the iteration pulls the triangles around {them(inner_fixed.size)} into spikes. "
                f"Fix whole curves (e.g. the boundary only){earlier}.")
    if euler == 1 and boundary.size:
        return (f"{text}. This piece is a disk, whose boundary always spans a minimal surface: the "
                "iteration itself degraded the triangles, sliding vertices within the surface to lower "
                f"the discrete area. {f'Stop it earlier {how_earlier} or r' if earlier else 'R'}emesh the "
                "input more evenly (e.g. isotropic remeshing) and try again.")
    return (f"{text}. The fixed vertices may span no minimal surface of this topology (e.g. two circles "
            "too far apart for a catenoid: the neck pinches off); or the iteration degraded the "
            "triangles, sliding vertices within the surface (then "
            f"{'a larger tol or fewer max_iterations stop it earlier, or ' if earlier else ''}remesh the "
            "input more evenly).")
