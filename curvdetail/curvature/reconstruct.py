"""Rebuild vertex positions from curvature detail (the paper's embedding, energy ``E_Q``)."""

import numpy as np
import scipy.sparse as sp

from .checks import as_count, as_index_set, as_values, check_choice
from .geometry import bbox_centre
from .topology import check_every_component_fixed
from .cotan_laplacian import _symmetric_from_upper
from .robust_laplacian import checked_laplacian_triangle
from .errors import ConstraintError, CurvdetailError
from .sparse_solver import SolverError, _upper_triangle, factorize, resolve_backend

ROW_MODES = ("all", "free")


class Reconstructor:
    """Factor the reconstruction system once; rebuild positions for any detail by back-substitution.

    Minimizes the paper's ``E_Q = sum_i |(L X)_i - D_i|^2`` over the free positions ``X_f``, the
    fixed positions ``X_c`` kept exactly; ``L`` is the cotangent Laplacian of ``V_ref`` (positive
    semi-definite, see `cotan_laplacian`), or its mollified version where ``laplacian`` says so. ``rows="all"`` sums over every vertex (the
    paper): normal equations ``(L_:f^T L_:f) X_f = L_:f^T (D - L_:c X_c)``, each solve followed by
    corrected semi-normal refinement (`refine_least_squares`), which keeps the error at
    ~1e-14 of the solution. ``rows="free"`` sums over the free vertices only: the square system
    ``L_ff X_f = D_f - L_fc X_c``. Both reproduce ``V_ref`` from its own detail. Solves run
    relative to the fixed positions' centre, so coordinates far from the origin lose no digits.

    Parameters
    ----------
    V_ref : (n, 3) float array
        Geometry that supplies the cotangent weights.
    F : (m, 3) int array
        Triangles.
    fixed : (k,) int array or (n,) bool mask
        Constrained vertices; every connected piece needs one. For a closed surface, several
        boundary loops or several pieces, `anchor_vertices` gives every boundary vertex
        and one anchor per closed piece.
    rows : {"all", "free"}
        Which residual rows enter the energy.
    backend : str
        Sparse solver backend ("auto" or one of `available_backends`).
    refinement_steps : int, optional
        Least refinement steps of ``rows="all"`` solves (default: the class attribute, 1), at
        most ``MAX_LEAST_REFINEMENT_STEPS``; 0 gives the plain normal-equation solution.
    laplacian : {"auto", "cotan", "robust"}
        "cotan" the plain cotangent Laplacian (refuses zero-area triangles), "robust" the
        mollified one (`robust_laplacian`), "auto" the plain one unless ``V_ref`` has zero-area
        triangles (`choose_laplacian`). Rebuild from the detail of the same Laplacian
        (`checked_laplacian`).

    Attributes
    ----------
    fixed : (k,) int array
        The constrained vertices, in the order given (a mask: increasing).
    free : (n - k,) int array
        The solved-for vertices, increasing.
    backend : str
        The solver backend in use.
    refinement_steps : int
        Least refinement steps of ``rows="all"`` solves.
    laplacian, laplacian_reason : str
        The Laplacian used ("cotan" or "robust") and why.

    Raises
    ------
    MeshError
        If the mesh is malformed (see `check_mesh`), or has zero-area triangles with
        ``laplacian="cotan"`` (``parameter`` "laplacian", ``first``: the first triangles).
    ConstraintError
        If there is no fixed vertex, ``fixed`` is out of range, repeated or a mask of the wrong
        length, or a connected piece has no fixed vertex.
    ValueError
        If ``rows`` or ``laplacian`` is unknown.
    SolverError
        If ``backend`` is unknown or not installed.

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> from curvdetail.curvature import curvature_detail, boundary_vertices
    >>> V, F = grid(8, 8); V[:, 2] = V[:, 0] * V[:, 1]
    >>> rec = Reconstructor(V, F, boundary_vertices(F))       # factors once
    >>> X = rec.solve(curvature_detail(V, F), V[rec.fixed])   # back-substitution only
    >>> bool(abs(X - V).max() < 1e-12)
    True
    """

    #: corrected semi-normal refinement steps after a ``rows="all"`` solve (each costs one
    #: back-substitution); 0 gives the plain normal-equation solution
    refinement_steps = 1

    def __init__(self, V_ref, F, fixed, *, rows="all", backend="auto", refinement_steps=None, laplacian="auto"):
        rows = check_choice(rows, "rows", ROW_MODES, " is not a row mode; use 'all' (the paper's E_Q) or 'free'.")
        if refinement_steps is not None:
            try:
                self.refinement_steps = as_count(refinement_steps, "refinement_steps", minimum=0)
                if self.refinement_steps > MAX_LEAST_REFINEMENT_STEPS:   # every solve runs them all
                    raise ValueError(f"refinement_steps={refinement_steps!r} must be at most "
                                     f"{MAX_LEAST_REFINEMENT_STEPS}: each step is a back-substitution, "
                                     "and beyond a few the corrections are rounding")
            except ValueError as exc:
                raise CurvdetailError(f"{exc} (1, the default, gives solver precision; 0 skips the "
                                      "refinement).", parameter="refinement_steps", value=refinement_steps) from None
        self.rows = rows
        system = self._build(V_ref, F, fixed, backend, laplacian)
        self._factor = factorize(system, symmetric=True, backend=backend, upper=self._upper) \
            if self.free.size else None
        self.backend = self._factor.backend if self._factor is not None else "none"

    def _build(self, V_ref, F, fixed, backend, laplacian):
        """Every check, then the system to factor; ``self._upper`` says whether it is given as its
        upper triangle."""
        V_ref, F, U, diagonal, info = checked_laplacian_triangle(V_ref, F, laplacian)
        self.laplacian, self.laplacian_reason = info["laplacian"], info["laplacian_reason"]
        n = V_ref.shape[0]
        self.n = n
        self.fixed = as_index_set(fixed, n, "fixed")
        if self.fixed.size == 0:
            raise ConstraintError("no fixed vertices: the reconstruction is only determined up to a translation",
                                  parameter="fixed", count=0,
                                  hint="fix at least one vertex per connected piece: the boundary, and on a closed "
                                       "piece an anchor (curvdetail.anchor_vertices(V, F) gives both)")
        # U, L's strict upper triangle, has the edge pattern at half L's size
        check_every_component_fixed(F, n, self.fixed, adjacency=U)
        is_free = np.ones(n, dtype=bool)
        is_free[self.fixed] = False
        self.free = np.flatnonzero(is_free)
        if self.rows == "free":
            # the solvers take the upper triangle of L_ff: cut it, and L_fc, straight from U
            # (1M vertices: 0.15 s, against 0.45 s for building L, slicing it and cutting L_ff's
            # triangle)
            system, self._L_fc = _FreeSystemLayout(U, is_free, self.fixed).values(U, diagonal)
            self._upper = True
            return system
        L = _symmetric_from_upper(U, diagonal)
        self._L_c = L[self.fixed].T.tocsr()                      # (n, k) columns of the fixed ones
                                                                 # (= rows, L is symmetric)
        # L is symmetric, so L_:f = L_f:^T and the normal matrix L_:f^T L_:f is L_f: L_f:^T
        self._L_f = L[self.free]                                 # (f, n) rows of the free vertices
        normal = self._L_f @ self._L_f.T
        # PARDISO takes the upper triangle: cut here, the whole product is gone before it factors
        self._upper = resolve_backend(backend, nnz=normal.nnz) == "pardiso"
        return _upper_triangle(normal) if self._upper else normal

    def solve(self, detail, fixed_positions):
        """Positions whose detail best matches ``detail``, by back-substitution only.

        Parameters
        ----------
        detail : (n, 3) float array
            Target curvature detail ``D`` (the fixed vertices' rows count with ``rows="all"`` only).
        fixed_positions : (k, 3) float array
            Positions of ``self.fixed``, row r for ``fixed[r]``.

        Returns
        -------
        X : (n, 3) float array
            With ``X[self.fixed] == fixed_positions`` exactly.

        Raises
        ------
        ConstraintError
            If ``detail`` or ``fixed_positions`` has the wrong shape or non-finite rows.
        SolverError
            If the ``rows="all"`` refinement stalls (near-degenerate triangles).
        """
        D = as_values(detail, self.n, "detail")
        Xc = as_values(fixed_positions, self.fixed.size, "fixed_positions")
        X = np.empty((self.n, 3))
        X[self.fixed] = Xc
        if self._factor is None:
            return X
        # solved relative to the fixed positions' centre c: L 1 = 0, so the solution moves with
        # c, and large coordinates (UTM, ECEF) do not cancel in L_:c X_c (a 1 mm sphere 1e6 m out
        # came back 4e-6 of its diagonal off); X_c - c is exact for coordinates near c
        centre = bbox_centre(Xc)
        Yc = Xc - centre
        if self.rows == "free":
            X[self.free] = self._factor.solve(D[self.free] - self._L_fc @ Yc) + centre
            return X
        # Normal equations L_:f^T L_:f X_f = L_:f^T r with r = D - L_:c X_c, then corrected
        # semi-normal refinement: the correction is computed from the least-squares residual
        # D - L X = r - L_:f X_f itself (not from the normal-equation residual, which carries the
        # squared condition number), which brings the error from ~cond(L_:f)^2 eps to
        # ~cond(L_:f) eps. L_:f is L_f:^T (L is symmetric).
        # Coordinate by coordinate on contiguous (3, .) rows: one-column sparse products are
        # ~25 % faster than three-column ones, and the solver takes the columns as they are.
        r = np.ascontiguousarray(D.T) - (self._L_c @ Yc).T                    # (3, n)
        X_f = self._factor.solve(np.stack([self._L_f @ rj for rj in r]).T).T   # (3, f)
        X_f = self._refine(X_f, r)
        X[self.free] = X_f.T + centre
        return X

    def _refine(self, X_f, r):
        """Corrected semi-normal refinement of the normal-equation solution ``X_f`` (3, f) for
        the right-hand side ``r`` (3, n): each correction solves the same factored system with
        the least-squares residual ``r - L_:f X_f`` (see `refine_least_squares`)."""
        L_f, L_f_T = self._L_f, self._L_f.T

        def correction(X):
            s = np.stack([L_f @ (rj - L_f_T @ xj) for rj, xj in zip(r, X)])
            return self._factor.solve(s.T).T

        return refine_least_squares(X_f, correction, self.refinement_steps)


def refine_least_squares(X, correction, min_steps, *, stall="raise"):
    """Refine a normal-equation solution ``X`` in place by ``X += correction(X)`` and return it.

    Each corrected semi-normal step contracts the error by about ``cond^2 eps``, which the
    size of the first correction estimates (it is about the first solution's relative error).
    At least ``min_steps`` steps run (none for 0); more follow while the error left, estimated
    from the last correction and the contraction, is above ``REFINEMENT_TOLERANCE`` of the
    solution, up to ``max(MAX_REFINEMENT_STEPS, min_steps)``. Corrections that stop shrinking
    have reached the problem's rounding floor: the result is taken where they are below
    ``REFINEMENT_FLOOR`` of the solution, and SolverError raised where they are not (the normal
    equations are then too ill-conditioned: near-degenerate triangles), as where the steps run
    out above it; ``stall="return"`` returns the last iterate there instead (for callers that
    judge the result themselves)."""
    if not min_steps:
        return X
    size = max(float(np.abs(X).max()), np.finfo(float).tiny)
    previous = None
    for step in range(max(MAX_REFINEMENT_STEPS, min_steps)):
        delta = correction(X)
        X += delta
        relative = float(np.abs(delta).max()) / size
        contraction = relative if previous is None else relative / max(previous, np.finfo(float).tiny)
        if step + 1 >= min_steps and relative * min(contraction, 1.0) <= REFINEMENT_TOLERANCE:
            return X                                            # converged
        if previous is not None and contraction > 0.5 and step + 1 >= min_steps:
            if contraction > 1.0:                               # a correction that grew: undo it
                X -= delta
                relative = previous
            if relative <= REFINEMENT_FLOOR:                    # at the rounding floor
                return X
            break                                               # stalled above it
        previous = relative
    if relative <= REFINEMENT_FLOOR or stall == "return":
        return X
    raise SolverError(
        f"rows='all': the normal equations are too ill-conditioned to solve accurately (the "
        f"refinement stalled at a correction of {relative:.1e} of the solution), most likely from "
        "needle or sliver triangles. Use rows='free', or remesh the near-degenerate triangles away "
        "(e.g. pymeshlab's meshing_isotropic_explicit_remeshing).", parameter="rows", value=relative)


#: ``rows="all"``: refinement continues while the estimated error left is above this fraction of
#: the solution (one step reaches it on ordinary meshes: 1e-18 ... 1e-13 estimated), for at most
#: ``MAX_REFINEMENT_STEPS`` steps
REFINEMENT_TOLERANCE = 1e-12
MAX_REFINEMENT_STEPS = 10
#: the most steps ``refinement_steps`` may ask for (every solve runs that many)
MAX_LEAST_REFINEMENT_STEPS = 100
#: a refinement whose corrections stop shrinking (the rounding floor) is taken where they are
#: below this fraction of the solution (the round-trip bound), else SolverError
REFINEMENT_FLOOR = 1e-9

class _FreeSystemLayout:
    """Where the entries of a symmetric ``L``, given by its strict upper triangle ``U`` (CSR,
    sorted) and diagonal, go in the free-row system: the upper triangle, diagonal included, of
    ``L[free][:, free]`` (CSR, sorted, renumbered to ``0 .. f - 1``) and ``L[free][:, fixed]``
    (CSR, columns in the order of ``fixed``). Built from ``U``'s pattern alone, so that it serves
    every ``U`` with that pattern (the steps of `minimal_surface`)."""

    def __init__(self, U, is_free, fixed):
        n = U.shape[0]
        index = U.indices.dtype
        self._indptr_U, self._indices_U = U.indptr, U.indices
        rows = np.repeat(np.arange(n, dtype=index), np.diff(U.indptr))
        row_free, col_free = is_free[rows], is_free[U.indices]
        self._kept = row_free & col_free
        renumber = (np.cumsum(is_free) - 1).astype(index)
        r, c = renumber[rows[self._kept]], renumber[U.indices[self._kept]]
        f = int(renumber[-1]) + 1 if n else 0
        indptr = np.zeros(f + 1, dtype=index)
        np.cumsum(np.bincount(r, minlength=f) + 1, out=indptr[1:])
        cols = np.empty(indptr[-1], dtype=index)
        # each row: its diagonal first, then its entries in their (increasing) order; the k-th
        # kept entry, in row r, follows k entries and the r + 1 diagonals of rows 0..r
        cols[indptr[:-1]] = np.arange(f, dtype=index)
        self._at = np.arange(r.size, dtype=np.int64) + r + 1
        cols[self._at] = c
        self.pattern = sp.csr_matrix((np.zeros(cols.size), cols, indptr), shape=(f, f))
        self._is_free = is_free
        # L_fc: the edges between a free and a fixed vertex, from either side of the triangle
        position = np.empty(n, dtype=np.int64)
        position[fixed] = np.arange(fixed.size)
        self._mixed = np.flatnonzero(row_free != col_free)
        a, b = rows[self._mixed], U.indices[self._mixed]
        free_end = np.where(row_free[self._mixed], a, b)
        fixed_end = np.where(row_free[self._mixed], b, a)
        self._L_fc_index = (renumber[free_end], position[fixed_end])
        self._L_fc_shape = (f, fixed.size)

    def values(self, U, diagonal):
        """``(upper triangle of L_ff, L_fc)`` for a ``U`` with the layout's pattern."""
        if not (U.indptr is self._indptr_U or np.array_equal(U.indptr, self._indptr_U)) or \
                not (U.indices is self._indices_U or np.array_equal(U.indices, self._indices_U)):
            raise RuntimeError("internal error: the strict upper triangle changed its pattern")
        data = np.empty(self.pattern.nnz)
        data[self.pattern.indptr[:-1]] = diagonal[self._is_free]
        data[self._at] = U.data[self._kept]
        upper = sp.csr_matrix((data, self.pattern.indices, self.pattern.indptr), shape=self.pattern.shape)
        upper.has_sorted_indices = True
        L_fc = sp.csr_matrix((U.data[self._mixed], self._L_fc_index), shape=self._L_fc_shape)
        return upper, L_fc


def reconstruct(V_ref, F, detail, fixed, fixed_positions, *, rows="all", backend="auto", laplacian="auto",
                return_info=False):
    """Rebuild positions from curvature detail with some vertices fixed (one-off solve).

    Builds a `Reconstructor` and calls `Reconstructor.solve` once; keep a
    ``Reconstructor`` to answer many details or boundary positions with one factorization.

    Parameters
    ----------
    V_ref : (n, 3) float array
        Geometry that supplies the cotangent weights.
    F : (m, 3) int array
        Triangles.
    detail : (n, 3) float array
        Target curvature detail ``D = K A``.
    fixed : (k,) int array or (n,) bool mask
        Constrained vertices, e.g. `anchor_vertices` (the boundary and one anchor per
        closed piece).
    fixed_positions : (k, 3) float array
        Their positions, row r for vertex ``fixed[r]`` (for a mask: in increasing index order).
    rows : {"all", "free"}
        Residual rows in the energy (see `Reconstructor`).
    backend : str
        Sparse solver backend.
    laplacian : {"auto", "cotan", "robust"}
        The Laplacian of ``V_ref`` (see `Reconstructor`; "auto": the plain one unless ``V_ref`` has
        zero-area triangles).
    return_info : bool
        Also return ``info``.

    Returns
    -------
    X : (n, 3) float array
        With ``X[fixed] == fixed_positions`` exactly.
    info : dict
        With ``return_info``: ``{"laplacian": "cotan" or "robust", "laplacian_reason": why}``.

    Raises
    ------
    MeshError
        If the mesh is malformed, or has zero-area triangles with ``laplacian="cotan"``.
    ConstraintError
        If ``fixed`` is refused, a shape is wrong, or a connected piece has no fixed vertex.
    ValueError
        If ``rows`` or ``laplacian`` is unknown.
    SolverError
        If ``backend`` is unknown or not installed, or the refinement stalls.

    Examples
    --------
    >>> from curvdetail.curvature.testing import grid
    >>> from curvdetail.curvature import curvature_detail, boundary_vertices
    >>> V, F = grid(6, 6); V[:, 2] = V[:, 0] ** 2
    >>> b = boundary_vertices(F)
    >>> X = reconstruct(V, F, curvature_detail(V, F), b, V[b], rows="free")
    >>> bool(abs(X - V).max() < 1e-12)
    True
    """
    rec = Reconstructor(V_ref, F, fixed, rows=rows, backend=backend, laplacian=laplacian)
    X = rec.solve(detail, fixed_positions)
    return (X, {"laplacian": rec.laplacian, "laplacian_reason": rec.laplacian_reason}) if return_info else X
