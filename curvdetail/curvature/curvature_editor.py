"""Two-stage mesh editing with curvature coefficients (the paper's Sections 3.1-3.2)."""

import time

import numpy as np

from .checks import as_values, check_bool, check_choice
from .geometry import bbox_centre, bbox_diagonal, centroid_diameter
from .cotan_laplacian import checked_cotan_laplacian, laplacian_product
from .curvature_coefficients import (DEFAULT_MAX_RING, DEFAULT_RCOND, _coefficients, _one_ring_pairs, check_max_ring,
                                     check_rcond)
from ._editor_checks import (RELATIONS, _check_pieces_detail_constrained, _check_reached, _check_relations,  # noqa: F401
                             _check_whole_mesh_constraints,
                             _detail_islands, _index_set, _pattern, _positions_in, _two_ring_pairs, embedding_system,
                             region_mask,                              square_curvature_system, stacked_curvature_system)
from .errors import ConstraintError, UndeterminedEditError, counted, first_indices
from .mixed_voronoi_area import _mixed_voronoi_area_unchecked
from .reconstruct import refine_least_squares
from .sparse_solver import SolverError, _chosen_automatically, factorize, resolve_backend


#: Below this many free-detail unknowns "auto" factors the curvature stage (I - C) with SuperLU
#: (faster back-substitution), from it on with the general "auto" choice (faster factoring).
CURVATURE_SPLU_MAX = 300_000

#: Largest distance (over the bbox diagonal) at which the rest constraints may give back the
#: rest shape; above it the constructor raises UndeterminedEditError (see ``rest_error``).
MAX_REST_ERROR = 1e-3


class CurvatureEditor:
    """Edit a mesh through its curvature detail: factor once, re-solve for any constraint values.

    Two stages (the paper's Sections 3.1-3.2). The curvature stage gives the details ``D_u`` of
    the region's vertices without a detail constraint: the square system
    ``(I - C)_uu D_u = C_uk D_k`` (``C`` from `curvature_coefficients`, LU-factored), or
    with ``relations="one+two-ring"`` the least squares of ``|(I - C) D|^2 + |(I - C2) D|^2``.
    The embedding stage gives the positions minimizing ``E_Q = sum_i |(L X)_i - D_i|^2`` over the
    free positions, as `Reconstructor`. Vertices outside ``roi`` keep their rest positions
    and details. The constructor does all factoring; `solve` only back-substitutes. With
    ``roi=None``, moving the position constraints by a similarity ``x -> s R x + t`` and the
    detail constraints by ``D -> s R D`` moves the result by the same similarity (see
    docs/guide/editing.md, "The two-stage editor").

    Parameters
    ----------
    V : (n, 3) float array
        Rest positions.
    F : (m, 3) int array
        Triangles.
    position_constrained : (p,) int array or (n,) bool mask
        Vertices whose positions are given to `solve` (the handles), inside ``roi``.
    detail_constrained : (q,) int array or (n,) bool mask
        Vertices whose curvature details are given to `solve`, inside ``roi``; may overlap
        ``position_constrained``.
    roi : (r,) int array or (n,) bool mask, optional
        Region of interest, in any order (a set is taken too); None is the whole mesh.
    rows : {"all", "free"}
        Embedding rows: every row that involves a free position (the paper; normal equations), or
        the free vertices' rows only (a square system: sparser, faster re-solves).
    relations : {"one-ring", "one+two-ring"}
        Curvature stage: the paper's one-ring relations, or two-ring ones as well (twice the
        equations: far less amplification of inconsistent constraints, a denser factorization).
    rcond : float
        Singular-value threshold of `curvature_coefficients`.
    max_ring : int
        Widest ring of `curvature_coefficients` (1: the paper's one-ring everywhere).
    backend : str
        Sparse solver backend ("auto" or one of `available_backends`).

    Attributes
    ----------
    detail : (n, 3) float array
        Rest detail ``D = L V``.
    laplacian, coefficients : (n, n) scipy.sparse.csr_matrix
        ``L`` and ``C`` of the rest shape; ``coefficients_two_ring`` is ``C2``
        (``relations="one+two-ring"`` only).
    roi : (r,) int array
        The region, increasing; ``position_constrained`` and ``detail_constrained`` as given.
    backend : dict
        Solver backend of each stage, ``{"curvature": ..., "embedding": ...}`` ("none": no unknowns).
    timings : dict
        Constructor seconds: ``coefficients``, ``curvature_setup``, ``embedding_setup``,
        ``rest_check``.
    widened_rings, rank_deficient : int
        Vertices whose coefficients span a ring wider than the one-ring, and whose ring detail is
        rank-deficient (``widened_vertices``, ``rank_deficient_vertices``: the vertices).
    detail_islands : int
        Free vertices whose detail no constraint reaches (cut off by flat vertices); they keep
        their rest detail.
    rest_error : float
        Distance from ``V`` of the result for the rest values, over the bbox diagonal.

    Raises
    ------
    MeshError
        If the mesh is malformed.
    ConstraintError
        If constraint indices are out of range, repeated or outside ``roi``, ``roi`` is empty,
        there are too few constraints, or a free region touches no constraint.
    UndeterminedEditError
        If the constraints do not determine the edit (``rest_error`` above `MAX_REST_ERROR`,
        or the curvature stage cannot be factored).
    ValueError
        If ``rows``, ``relations`` or ``rcond`` is not one of its choices.
    SolverError
        If ``backend`` is unknown or not installed, or the embedding cannot be factored.

    Examples
    --------
    >>> import numpy as np
    >>> from curvdetail.curvature.testing import grid
    >>> from curvdetail.curvature import boundary_vertices
    >>> V, F = grid(15, 15); V[:, 2] = np.sin(3 * V[:, 0]) * np.cos(2 * V[:, 1])
    >>> b = boundary_vertices(F)
    >>> ed = CurvatureEditor(V, F, b, b)                   # factors both stages
    >>> X = ed.solve(positions=V[b], details=ed.detail[b])  # back-substitution only
    >>> bool(abs(X - V).max() < 1e-9)
    True
    """

    #: corrected semi-normal refinement steps of every normal-equation solve (0: none)
    refinement_steps = 1

    def __init__(self, V, F, position_constrained, detail_constrained, *, roi=None,
                 rows="all", relations="one-ring", rcond=DEFAULT_RCOND, max_ring=DEFAULT_MAX_RING,
                 backend="auto"):
        rows = check_choice(rows, "rows", ("all", "free"),
                            " is not a row mode; use 'all' (the paper's E_Q) or 'free'.")
        relations = _check_relations(relations)
        rcond = check_rcond(rcond)
        max_ring = check_max_ring(max_ring)
        resolve_backend(backend)           # an unknown or missing backend fails before the work
        if relations == "one-ring":        # so does one the nonsymmetric curvature stage cannot use
            try:
                resolve_backend(backend, symmetric=False)
            except SolverError as exc:
                raise SolverError(f"relations='one-ring' makes the curvature stage a nonsymmetric system: "
                                  f"{exc.problem}", parameter="backend", value=exc.value,
                                  hint=f"{(exc.hint or '').rstrip('.')}, or relations='one+two-ring' (symmetric)") from None
        V, F, L = checked_cotan_laplacian(V, F)       # every mesh check, and L in the same pass
        self.relations = relations
        n = V.shape[0]
        # own read-only copies: a later edit of the caller's array must not reach the editor
        V, F = V.copy(), F.copy()
        V.flags.writeable = F.flags.writeable = False
        self.n, self.V, self.F, self.rows = n, V, F, rows
        pc = _index_set(position_constrained, n, "position_constrained", "positions")
        dc = _index_set(detail_constrained, n, "detail_constrained", "details")
        in_roi = region_mask(n, roi, (("position_constrained", pc), ("detail_constrained", dc)))
        if in_roi.all():
            _check_whole_mesh_constraints(pc, dc)
        _check_pieces_detail_constrained(F, in_roi, dc)
        self.position_constrained, self.detail_constrained = pc, dc
        self.roi = np.flatnonzero(in_roi)

        t0 = time.perf_counter()
        D = laplacian_product(L, V)
        rows, cols = _one_ring_pairs(F, n)
        A, size = _mixed_voronoi_area_unchecked(V, F), centroid_diameter(V)     # rotation-invariant
        C, rank, _, ring = _coefficients(D, A, rows, cols, n, rcond, size, max_ring=max_ring)
        crows, ccols, cvals = _pattern(C)     # the one-ring, wider where a ring was widened
        self.detail, self.coefficients, self.laplacian = D, C, L
        for state in (D, C.data, L.data, pc, dc):      # read-only: solves read them again
            state.flags.writeable = False
        self.rank_deficient = int(np.count_nonzero(rank < 3))
        self.widened_rings = int(np.count_nonzero(ring > 1))
        self.rank_deficient_vertices = np.flatnonzero(rank < 3)
        self.widened_vertices = np.flatnonzero(ring > 1)
        t1 = time.perf_counter()

        # -- curvature stage: unknown details fd = roi \ dc --------------------------------
        free_d = in_roi.copy()
        free_d[dc] = False
        _check_reached(crows, ccols, free_d, n, "detail", "detail_constrained")
        if relations == "one+two-ring":
            rows2, cols2 = _two_ring_pairs(rows, cols, n)
            C2, rank2, _, _ = _coefficients(D, A, rows2, cols2, n, rcond, size, max_ring=max_ring,
                                            adjacency=(rows, cols))
            rows2, cols2, cvals2 = _pattern(C2)
            self.coefficients_two_ring = C2
            island = _detail_islands(np.concatenate([crows, rows2]), np.concatenate([ccols, cols2]),
                                     np.concatenate([cvals, cvals2]), free_d, np.maximum(rank, rank2), n)
        else:
            island = _detail_islands(crows, ccols, cvals, free_d, rank, n)
        self.detail_islands = int(np.count_nonzero(island))
        self._user_dc = dc.size
        dc = np.concatenate([dc, np.flatnonzero(island)])     # islands keep their rest detail
        free_d[island] = False
        fd = np.flatnonzero(free_d)
        self._fd, self._dc = fd, dc
        at_fd = _positions_in(fd, n)
        at_dc = _positions_in(dc, n)
        curv_backend = "splu" if _chosen_automatically(backend) and fd.size < CURVATURE_SPLU_MAX else backend
        if relations == "one+two-ring":
            self._stacked_system(D, in_roi, fd, dc, at_fd, at_dc, (crows, ccols, cvals),
                                 (rows2, cols2, cvals2), backend)
        else:
            self._square_system(D, in_roi, free_d, fd, dc, at_fd, at_dc, crows, ccols, cvals, curv_backend)
        t2 = time.perf_counter()
        self._embedding(L, V, F, in_roi, pc, rows, cols, backend)
        self._response = None
        t3 = time.perf_counter()
        self._undetermined_details = None         # (a message) see _check_rest_details
        self.rest_error = self._check_rest_state()
        self.timings = {"coefficients": t1 - t0, "curvature_setup": t2 - t1,
                        "embedding_setup": t3 - t2, "rest_check": time.perf_counter() - t3}
        self.backend = {"curvature": self._curv.backend if self._curv else "none",
                        "embedding": self._embed.backend if self._embed else "none"}

    def _check_rest_state(self):
        """Distance from ``V`` (over the bbox diagonal) of the shape the rest constraints give
        (the embedding's response to the curvature stage's rest-detail error: anything but
        rounding is a singular system); UndeterminedEditError above `MAX_REST_ERROR`."""
        error = 0.0
        if self._curv is not None and self._embed is not None:
            dc_rest = self.detail[self._dc]
            Du = self._curvature_solve(dc_rest)
            dD = np.zeros_like(self._D_R_rest)
            dD[self._R_fd_at] = Du[self._R_fd] - self.detail[self._fd][self._R_fd]
            if dD.any():
                dX = self._embed.solve(dD if self._A_T is None else self._A_T @ dD)
                error = float(np.linalg.norm(dX, axis=1).max()) / bbox_diagonal(self.V)
        elif self._curv is not None:
            self._check_rest_details()
        if not error <= MAX_REST_ERROR:       # NaN included
            raise UndeterminedEditError(
                f"the constraints do not determine the edit: solved with their rest values they give "
                f"back a shape {error:.2g} of the bbox diagonal off the rest shape (the curvature stage "
                f"is singular to working precision with these {self._user_dc} detail constraints: "
                "groups of rings can turn together).", self._undetermined_advice(), parameter="detail_constrained")
        return error

    def _check_rest_details(self):
        """Every roi position given: where the rest constraints give back details further than
        `MAX_REST_ERROR` of the roi's largest rest detail from the rest ones,
        `solve_details` and ``solve(..., return_details=True)`` raise UndeterminedEditError."""
        Du = self._curvature_solve(self.detail[self._dc])
        scale = float(np.linalg.norm(self.detail[self.roi], axis=1).max())
        error = float(np.linalg.norm(Du - self.detail[self._fd], axis=1).max())
        if not error <= MAX_REST_ERROR * scale:       # NaN included
            self._undetermined_details = (
                f"the constraints do not determine the details: every position in the roi is given, and "
                f"the rest detail constraints give back details {error / max(scale, np.finfo(float).tiny):.2g} "
                f"of the largest rest detail off the rest ones (the curvature stage is singular to working "
                f"precision with these {self._user_dc} detail constraints).")

    def _refuse_undetermined_details(self):
        if self._undetermined_details is not None:
            raise UndeterminedEditError(self._undetermined_details, self._undetermined_advice(),
                                        parameter="detail_constrained")

    def _undetermined_advice(self):
        # on flat and near-flat regions the stacked relations are singular where the square
        # one-ring system is not (a flat grid, 3 detail constraints: 0.055 off, one-ring exact)
        other = "use relations='one-ring', " if self.relations == "one+two-ring" else ""
        return (f"Constrain more details (e.g. the handles' or the region border's), {other}or pass a "
                "smaller roi.")

    def _factor_curvature_stage(self, M, symmetric, backend):
        """factorize(M), a failure named as constraints that do not determine the edit."""
        try:
            return factorize(M, symmetric=symmetric, backend=backend)
        except SolverError as exc:
            raise UndeterminedEditError(f"the constraints do not determine the edit: the curvature stage "
                                        f"could not be factored with these {self._user_dc} detail "
                                        f"constraints ({exc})", self._undetermined_advice(),
                                        parameter="detail_constrained") from None

    def _square_system(self, D, in_roi, free_d, fd, dc, at_fd, at_dc, rows, cols, cvals, curv_backend):
        """The paper's linear-system form (see `square_curvature_system`)."""
        M, self._C_dc, self._d_const = square_curvature_system(D, in_roi, free_d, fd, dc, at_fd, at_dc,
                                                               rows, cols, cvals)
        # "auto" takes SuperLU (symmetric mode, no pivoting) for (I - C) below CURVATURE_SPLU_MAX
        # unknowns, for its faster back-substitution (see there).
        self._curv = self._factor_curvature_stage(M, False, curv_backend) if fd.size else None
        self._Au = None                                     # square: solved exactly, no refinement

    def _stacked_system(self, D, in_roi, fd, dc, at_fd, at_dc, rel1, rel2, backend):
        """Both relations in least squares (see `stacked_curvature_system`)."""
        self._Au, self._AuT, self._Bdc, self._b_rest = stacked_curvature_system(D, in_roi, fd, dc, at_fd, at_dc,
                                                                                rel1, rel2)
        normal = (self._AuT @ self._Au).tocsr()
        self._curv = self._factor_curvature_stage(normal, True, backend) if fd.size else None

    def _embedding(self, L, V, F, in_roi, pc, rows, cols, backend):
        """E_Q over the rows that involve the free positions (see `embedding_system`)."""
        parts, system = embedding_system(L, V, in_roi, pc, rows, cols, self._fd, self._dc, self.detail,
                                         self.rows == "all")
        vars(self).update(parts)
        self._embed = factorize(system, symmetric=True, backend=backend) if self._fp.size else None

    def solve_details(self, details=None):
        """Curvature stage only: every vertex's detail, by back-substitution.

        Parameters
        ----------
        details : (q, 3) float array, optional
            Details of ``detail_constrained`` (row r for vertex ``detail_constrained[r]``); None
            gives the rest values.

        Returns
        -------
        D : (n, 3) float array
            Given values at ``detail_constrained``, solved ones elsewhere in the roi, rest values
            outside it.

        Raises
        ------
        UndeterminedEditError
            If every roi position is given and the detail constraints do not determine the
            details (also from ``solve(..., return_details=True)``).
        """
        self._refuse_undetermined_details()
        Dk = self._details(details)
        D = self.detail.copy()
        D[self._dc] = Dk
        if self._curv is not None:
            D[self._fd] = self._curvature_solve(Dk)
        return D

    def solve(self, positions=None, details=None, *, return_details=False):
        """Edited positions for new constraint values, by back-substitution only (no factoring).

        Parameters
        ----------
        positions : (p, 3) float array, optional
            Positions of ``position_constrained`` (row r for vertex ``position_constrained[r]``);
            None gives the rest positions.
        details : (q, 3) float array, optional
            Curvature details ``D = K A`` of ``detail_constrained``; None gives the rest values.
            Under a similarity with linear part ``s R`` a detail becomes ``s R D``.
        return_details : bool
            Also return the curvature stage's details.

        Returns
        -------
        X : (n, 3) float array
            ``X[position_constrained] == positions`` exactly; vertices outside the roi keep their
            rest positions exactly.
        D : (n, 3) float array
            Only with ``return_details=True``.

        Raises
        ------
        ConstraintError
            If ``positions`` or ``details`` is not of shape (p, 3) / (q, 3) of finite numbers.
        UndeterminedEditError
            With ``return_details=True``, as `solve_details`.
        ValueError
            If ``return_details`` is not True or False.
        """
        return_details = check_bool(return_details, "return_details")
        if return_details:
            self._refuse_undetermined_details()
        return self._solve(self._positions(positions), self._details(details), return_details)

    def _solve(self, Xk, Dk, return_details=False, fast_path=True):
        response = self._response          # one read: precompute_handles may replace it
        if response is not None and fast_path and not return_details:
            fast = self._fast_path(response, Xk, Dk)
            if fast is not None:
                return fast
        D_R = self._D_R_rest.copy()
        Du = None
        if self._curv is not None:
            Du = self._curvature_solve(Dk)
            D_R[self._R_fd_at] = Du[self._R_fd]
        D_R[self._R_dc_at] = Dk[self._R_dc]
        X = self.V.copy()
        X[self._pc] = Xk
        if self._embed is not None:
            # about the constraints' centre: -L_ext (V_ext - c) = rhs_const + w_ext (c - c0)
            centre = bbox_centre(Xk) if Xk.size else self._centre
            rhs = (D_R + self._rhs_const + self._exterior_weight[:, None] * (centre - self._centre)
                   - self._L_pc @ (Xk - centre))
            X[self._fp] = self._embedding_solve(rhs) + centre
        if not return_details:
            return X
        D = self.detail.copy()
        D[self._dc] = Dk
        if Du is not None:
            D[self._fd] = Du
        return X, D

    def _curvature_solve(self, Dk=None, *, columns=None):
        """The curvature stage's unknown details for the constraint values ``Dk`` (q, 3), or its
        response to the detail constraints ``columns`` (one column each, values 1). The square
        system is solved exactly; the stacked least squares (``relations="one+two-ring"``) through
        its normal equations and corrected semi-normal refinement (`refine_least_squares`,
        at least ``refinement_steps`` steps; where it stalls, as on near-null directions of detail
        islands, the last iterate is taken and the rest check judges the shape it gives)."""
        if self._Au is None:
            rhs = self._C_dc[:, columns].toarray() if columns is not None else self._d_const + self._C_dc @ Dk
            return self._curv.solve(rhs)
        b = -self._Bdc[:, columns].toarray() if columns is not None else self._b_rest - self._Bdc @ Dk
        x = self._curv.solve(self._AuT @ b)
        return refine_least_squares(x, lambda x: self._curv.solve(self._AuT @ (b - self._Au @ x)),
                                    self.refinement_steps, stall="return")

    def _embedding_solve(self, rhs):
        """Free positions minimizing ``|A X_f - rhs|`` over the rows ``R`` (rows="all"), or
        solving the square system (rows="free"); ``rhs`` (|R|, k). The normal equations are
        followed by corrected semi-normal refinement, as in `Reconstructor`
        (`refine_least_squares`: at least ``refinement_steps`` steps, more where the error
        estimate asks, SolverError where it stalls): without it the error grows with the
        squared condition number."""
        if self._A_T is None:
            return self._embed.solve(rhs)
        X = self._embed.solve(self._A_T @ rhs)
        return refine_least_squares(X, lambda X: self._embed.solve(self._A_T @ (rhs - self._A @ X)),
                                    self.refinement_steps)

    def precompute_handles(self, handles, positions=None, details=None):
        """Precompute the response to the constraints of a few vertices, for real-time edits.

        Both stages are linear in the constraint values, so the result is the solution at a base
        state plus one response column per handle vertex, computed here by back-substitution.
        Afterwards a `solve` whose values differ from the base only at ``handles`` is one
        dense ``(free x h) @ (h x 3)`` product (exact up to rounding); any other falls back to the
        full solve. Threads may share the editor; of calls made at once, the last to finish stays.

        Parameters
        ----------
        handles : (h,) int array
            Position- and/or detail-constrained vertices whose values will change (any order).
        positions, details : float arrays, optional
            The base constraint values, as in `solve` (None: rest values).

        Returns
        -------
        self : CurvatureEditor

        Raises
        ------
        ConstraintError
            If ``handles`` are out of range, repeated, or not constrained vertices, or
            ``positions`` / ``details`` are refused as in `solve`.
        """
        h = _index_set(handles, self.n, "handles")
        is_p = np.zeros(self.n, dtype=bool)
        is_p[self._pc] = True
        is_d = np.zeros(self.n, dtype=bool)
        is_d[self._dc[:self._user_dc]] = True
        stray = h[~(is_p[h] | is_d[h])]
        if stray.size:
            raise ConstraintError(f"handles: {counted(stray.size, 'vertex', 'vertices', verb='are')} neither position- nor detail-"
                                  f"constrained (first: {first_indices(stray)}); only constrained "
                                  "values can change between solves.", parameter="handles",
                                  count=int(stray.size), first=stray[:3].tolist())
        Xk, Dk = self._positions(positions), self._details(details)
        base = self._solve(Xk, Dk, fast_path=False)     # not another thread's response
        jp = np.flatnonzero(np.isin(self._pc, h))              # rows of positions that may change
        jd = np.flatnonzero(np.isin(self._dc[:self._user_dc], h))
        f = self._fp.size
        Gp = np.zeros((f, jp.size))
        Gd = np.zeros((f, jd.size))
        if self._embed is not None and jp.size:
            rhs = -self._L_pc[:, jp].toarray()
            Gp = self._embedding_solve(rhs)
        if self._embed is not None and jd.size:
            dR = np.zeros((self._R.size, jd.size))
            if self._curv is not None:
                du = self._curvature_solve(columns=jd)
                dR[self._R_fd_at] = du[self._R_fd]
            at = np.full(self._dc.size, -1, dtype=np.int64)
            at[np.flatnonzero(self._R_dc)] = self._R_dc_at
            hit = at[jd] >= 0
            dR[at[jd][hit], np.flatnonzero(hit)] += 1.0
            Gd = self._embedding_solve(dR)
        keep_p = np.ones(self._pc.size, dtype=bool)
        keep_p[jp] = False
        keep_d = np.ones(self._dc.size, dtype=bool)
        keep_d[jd] = False
        G = np.zeros((self.n, jp.size + jd.size))           # response of every vertex
        G[self._fp] = np.hstack([Gp.reshape(f, jp.size), Gd.reshape(f, jd.size)])    # f may be 0
        # one assignment of a complete response: a solve in another thread sees the old or the new
        self._response = {"X": base, "Xk": Xk.copy(), "Dk": Dk.copy(), "jp": jp, "jd": jd,
                          "G": G, "keep_p": keep_p, "keep_d": keep_d}
        return self

    def _fast_path(self, r, Xk, Dk):
        if not (np.array_equal(Xk[r["keep_p"]], r["Xk"][r["keep_p"]])
                and np.array_equal(Dk[r["keep_d"]], r["Dk"][r["keep_d"]])):
            return None
        delta = np.vstack([Xk[r["jp"]] - r["Xk"][r["jp"]], Dk[r["jd"]] - r["Dk"][r["jd"]]])
        # einsum, not BLAS: with an inner dimension of a few handles the threaded GEMM is slower
        X = r["X"] + np.einsum("nk,kc->nc", r["G"], delta)
        X[self._pc] = Xk
        return X

    def _positions(self, positions):
        if positions is None:
            return self.V[self._pc]
        return as_values(positions, self._pc.size, "positions")

    def _details(self, details):
        if details is None:
            return self.detail[self._dc]
        given = as_values(details, self._user_dc, "details")
        if self._dc.size == self._user_dc:
            return given
        return np.concatenate([given, self.detail[self._dc[self._user_dc:]]])
