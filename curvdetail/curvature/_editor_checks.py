"""Graph, constraint and curvature-stage helpers of the curvature-detail editors (private)."""

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .checks import as_index_set, check_choice
from .geometry import bbox_centre
from .errors import ConstraintError, UndeterminedEditError, counted, first_indices
from .topology import vertex_components

RELATIONS = ("one-ring", "one+two-ring")


def region_mask(n, roi, constrained):
    """(n,) bool mask of ``roi`` (None: every vertex). ConstraintError if ``roi`` is empty or a
    ``(name, indices)`` pair of ``constrained`` has vertices outside it (``e.count``, ``e.first``)."""
    in_roi = np.ones(n, dtype=bool)
    if roi is not None:
        r = _index_set(roi, n, "roi")
        if r.size == 0:
            raise ConstraintError("roi is empty: nothing would be edited", parameter="roi", count=0,
                                  hint="pass the vertices to edit, or roi=None for the whole mesh")
        in_roi[:] = False
        in_roi[r] = True
    for name, idx in constrained:
        out = idx[~in_roi[idx]]
        if out.size:
            raise ConstraintError(
                f"{name}: {counted(out.size, 'vertex', 'vertices', verb='lie')} outside the roi (first: "
                f"{first_indices(out)}); vertices outside the roi are fixed already", parameter=name,
                count=int(out.size), first=out[:3].tolist(), hint="add them to the roi or drop them")
    return in_roi


def _check_whole_mesh_constraints(pc, dc):
    """ConstraintError where the roi is the whole mesh and the constraints leave a translation
    (no position) or a linear map of the details (fewer than three) free."""
    if pc.size == 0:
        raise ConstraintError("position_constrained is empty and the roi is the whole mesh: the "
                              "result is only determined up to a translation. Constrain at least "
                              "one vertex per connected piece, or pass a smaller roi.",
                              parameter="position_constrained", count=0)
    if dc.size < 3:
        state = "is empty" if dc.size == 0 else f"has only {counted(dc.size, 'vertex', 'vertices')}"
        raise ConstraintError(f"detail_constrained {state} and the roi is the whole mesh: the "
                              "curvature stage is only determined up to a linear map (9 unknowns, "
                              "3 per constrained detail). Constrain the details of at least three "
                              "vertices (e.g. the handles), or pass a smaller roi.",
                              parameter="detail_constrained", count=int(dc.size))


def _check_relations(relations):
    """``relations`` as one of `RELATIONS`, or ValueError naming them."""
    return check_choice(relations, "relations", RELATIONS,
                        "; use 'one-ring' (the paper's relations) or 'one+two-ring'.")


def _index_set(indices, n, name, values=None):
    """`as_index_set`, with None, a set, True/False among numbers and fractions named as
    such (the first three were "dtype object" or read as vertices 1 and 0, the last named only
    by its dtype). Whole floats (3.0) are indices. A set has no order: where row r of the
    ``values`` given to solve belongs to ``name[r]`` it is refused, elsewhere (``values`` None:
    a region, the handles of precompute_handles) it is taken."""
    if indices is None:
        raise ConstraintError(f"{name} is None; pass vertex indices ([] for none) or an ({n},) boolean mask.",
                              parameter=name)
    if isinstance(indices, (set, frozenset)):
        if values is not None:
            raise ConstraintError(f"{name} is a {type(indices).__name__}, which has no order; pass a list or "
                                  f"array of vertex indices (row r of the {values} belongs to {name}[r]), e.g. "
                                  f"sorted({name}).", parameter=name)
        try:
            indices = sorted(indices)
        except TypeError:               # values that do not compare: as_index_set names them
            indices = list(indices)
    if isinstance(indices, (list, tuple)):
        flags = [isinstance(i, (bool, np.bool_)) for i in indices]
        if any(flags) and not all(flags):       # numpy reads [True, 3] as vertices 1 and 3
            raise ConstraintError(f"{name} has True/False among its vertex indices (first at position "
                                  f"{flags.index(True)}); pass indices only, or an ({n},) boolean mask.",
                                  parameter=name, first=[flags.index(True)])
    return as_index_set(indices, n, name)             # names non-whole values too


def _pattern(C):
    """(rows, cols, values) of the stored entries of the CSR matrix ``C``, explicit zeros too."""
    return np.repeat(np.arange(C.shape[0]), np.diff(C.indptr)), C.indices.astype(np.int64), C.data


def _two_ring_pairs(rows, cols, n):
    """Directed pairs (i, j), j within two edges of i, i != j, sorted by i then j."""
    P = sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n))
    P2 = (P @ P + P).tocsr()
    P2.setdiag(0)
    P2.eliminate_zeros()
    P2.sort_indices()
    r = np.repeat(np.arange(n), np.diff(P2.indptr))
    return r, P2.indices.astype(np.int64)


def _positions_in(idx, n):
    """``pos[v]`` = position of vertex ``v`` in ``idx``, -1 where absent; shape (n,)."""
    pos = np.full(n, -1, dtype=np.int64)
    pos[idx] = np.arange(idx.size)
    return pos


def _anchored_components(a, b, n, anchors):
    """Label the graph with edges (a, b); True per vertex whose component holds an anchor."""
    G = sp.csr_matrix((np.ones(a.size, dtype=np.int8), (a, b)), shape=(n, n))
    count, labels = connected_components(G, directed=False)
    anchored = np.zeros(count, dtype=bool)
    anchored[labels[anchors]] = True
    return anchored[labels]


def _detail_islands(rows, cols, cvals, free, rank, n):
    """Free vertices whose detail the coefficients cannot determine, shape (n,) bool.

    ``C`` is invariant under any linear map of the detail, so a group of free vertices whose
    coefficient rows reach no known detail (through non-zero coefficients, across flat vertices
    whose rows are zero) has its detail fixed only up to a 3x3 linear map: the square system is
    singular there (e.g. a bump in a flat plane). Such islands keep their rest detail.
    """
    active = free & (rank > 0)
    if not active.any():
        return np.zeros(n, dtype=bool)
    # links from an active row to an active or a known vertex (flat free vertices are D = 0)
    k = active[rows] & (cvals != 0) & (active[cols] | ~free[cols])
    anchored = _anchored_components(rows[k], cols[k], n, np.flatnonzero(~free))
    return active & ~anchored


def _check_pieces_detail_constrained(F, in_roi, dc):
    """UndeterminedEditError if a connected piece of the mesh lies wholly inside the roi with one
    or two detail constraints: ``C`` is invariant under any linear map of the detail, and one or
    two given details fix only 3 or 6 of its 9 unknowns (the rest check missed it: a second
    piece with one detail constraint came back 0.03-0.2 % of the diagonal off at rest, and
    accepted). A piece with none is named by the reach check; a single piece as the whole roi
    by the constructor's own message."""
    labels, count = vertex_components(F, in_roi.size)
    outside = np.bincount(labels[~in_roi], minlength=count) > 0
    given = np.bincount(labels[dc], minlength=count)
    short = np.flatnonzero(~outside & (given > 0) & (given < 3))
    if not short.size:
        return
    first = int(np.flatnonzero(labels == short[0])[0])
    pieces = counted(short.size, "piece", verb="lie") if short.size > 1 else "a piece of the mesh lies"
    raise UndeterminedEditError(
        f"{pieces} wholly inside the edited region with only {counted(int(given[short[0]]), 'detail constraint')} (e.g. "
        f"the piece containing vertex {first}): its details are determined only up to a linear map "
        "(9 unknowns, 3 per constrained detail).",
        "Constrain the details of at least three vertices of each such piece (e.g. its handles), or leave "
        "part of it outside the roi.", parameter="detail_constrained", count=int(short.size), first=[first])


def _check_reached(rows, cols, free, n, what, name):
    """Raise if a connected region of free vertices touches no constrained (or exterior) vertex."""
    if not free.any():
        return
    k = free[rows]
    anchored = _anchored_components(rows[k], cols[k], n, np.flatnonzero(~free))
    lost = np.flatnonzero(free & ~anchored)
    if lost.size:
        G = sp.csr_matrix((np.ones(int(k.sum()), dtype=np.int8), (rows[k], cols[k])), shape=(n, n))
        _, labels = connected_components(G, directed=False)
        regions = np.unique(labels[lost])
        example = [int(lost[np.flatnonzero(labels[lost] == c)[0]]) for c in regions[:3]]
        raise UndeterminedEditError(
            f"{regions.size} connected free {'region touches' if regions.size == 1 else 'regions touch'} no "
            f"{what} constraint (e.g. the {'region' if regions.size == 1 else 'regions'} containing vertex "
            f"{', '.join(map(str, example))}); their {what}s are undetermined.",
            f"Add a vertex of each region to {name}, or shrink the roi.", parameter=name,
            count=int(regions.size), first=example)


def square_curvature_system(D, in_roi, free_d, fd, dc, at_fd, at_dc, rows, cols, cvals):
    """The paper's linear-system form: (I - C)_uu D_u = C_uk D_k over the free rows (square,
    not symmetric). The paper's implementation minimized |(I - C) D|^2 over all rows instead;
    through normal equations that squares a condition number of up to 1e14 (docs/guide/editing.md).
    Returns the matrix ``(I - C)_uu``, ``C_uk`` and the constant term."""
    r_in = free_d[rows]
    both = r_in & free_d[cols]
    M = sp.csr_matrix((np.concatenate([-cvals[both], np.ones(fd.size)]),
                       (np.concatenate([at_fd[rows[both]], np.arange(fd.size)]),
                        np.concatenate([at_fd[cols[both]], np.arange(fd.size)]))),
                      shape=(fd.size, fd.size))
    to_dc = r_in & (at_dc[cols] >= 0)
    C_dc = sp.csr_matrix((cvals[to_dc], (at_fd[rows[to_dc]], at_dc[cols[to_dc]])),
                         shape=(fd.size, dc.size))
    # constant term: the exterior details as in V (C_u,ext D_ext), plus the rest detail's
    # residual (I - C) D kept as it is: rank-deficient rings (a grid's valence-2 corners, flat
    # regions) do not reproduce their detail, and (I - C)_uu amplified that into a rest shape
    # 5 diagonals off with 8 handles. Together: D_u - C_u,roi D_roi at rest, so the rest
    # state solves the system exactly
    inside = r_in & in_roi[cols]
    w = cvals[inside][:, None] * D[cols[inside]]
    d_const = D[fd] - np.stack([np.bincount(at_fd[rows[inside]], weights=w[:, k], minlength=fd.size)
                                for k in range(3)], axis=1)
    return M, C_dc, d_const


def stacked_curvature_system(D, in_roi, fd, dc, at_fd, at_dc, rel1, rel2):
    """Least squares over the region's rows of both (I - C1) and (I - C2): normal equations
    ``(A_u^T A_u) D_u = -A_u^T (A_dc D_dc + A_ext D_ext)``, symmetric positive definite.
    Returns ``A_u``, ``A_u^T``, ``A_dc`` and ``b_rest``."""
    n = D.shape[0]
    roi = np.flatnonzero(in_roi)
    at_roi = _positions_in(roi, n)
    r_parts, c_parts, v_parts = [], [], []
    for k, (r, c, v) in enumerate((rel1, rel2)):
        keep = in_roi[r]
        r_parts += [k * roi.size + at_roi[r[keep]], k * roi.size + np.arange(roi.size)]
        c_parts += [c[keep], roi]
        v_parts += [-v[keep], np.ones(roi.size)]
    mr, mc, mv = np.concatenate(r_parts), np.concatenate(c_parts), np.concatenate(v_parts)
    m = 2 * roi.size
    k = at_fd[mc] >= 0
    Au = sp.csr_matrix((mv[k], (mr[k], at_fd[mc[k]])), shape=(m, fd.size))
    k = at_dc[mc] >= 0
    Bdc = sp.csr_matrix((mv[k], (mr[k], at_dc[mc[k]])), shape=(m, dc.size))
    AuT = Au.T.tocsr()
    # the least squares |A_u D_u - b| with b = b_rest - A_dc D_dc: b_rest holds the exterior
    # details as in V and the rest residual of every stacked row, kept as it is (see
    # square_curvature_system), so that the rest state solves it exactly. Au and its transpose are
    # kept for the corrected semi-normal refinement (CurvatureEditor._curvature_solve): the normal equations
    # square the coefficients' condition number (fandisk, 3 handles: the rest shape 7e-3 ...
    # 3e-2 of the diagonal off without it)
    return Au, AuT, Bdc, Au @ D[fd] + Bdc @ D[dc]


def embedding_system(L, V, in_roi, pc, rows, cols, fd, dc, detail, all_rows):
    """E_Q over the rows that involve the free positions (``all_rows``: normal equations) or the
    free rows: the editor's embedding state (a dict of its attributes) and the matrix to factor."""
    n = V.shape[0]
    free_p = in_roi.copy()
    free_p[pc] = False
    _check_reached(rows, cols, free_p, n, "position", "position_constrained")
    fp = np.flatnonzero(free_p)
    touch = free_p.copy()
    if all_rows:
        touch[cols[free_p[rows]]] = True
    R = np.flatnonzero(touch)                              # rows of E_Q that involve fp
    Lc = L.tocoo()
    li, lj, lv = Lc.row, Lc.col, Lc.data
    at_R, at_fp, at_pc = _positions_in(R, n), _positions_in(fp, n), _positions_in(pc, n)
    in_R = at_R[li] >= 0
    k = in_R & (at_fp[lj] >= 0)
    A = sp.csr_matrix((lv[k], (at_R[li[k]], at_fp[lj[k]])), shape=(R.size, fp.size))
    k = in_R & (at_pc[lj] >= 0)
    L_pc = sp.csr_matrix((lv[k], (at_R[li[k]], at_pc[lj[k]])), shape=(R.size, pc.size))
    # positions about a centre inside the constraints: large coordinates (UTM, ECEF) do not
    # cancel in the right-hand side (L 1 = 0: the solution moves with the centre)
    centre = bbox_centre(V[pc] if pc.size else V)
    k = in_R & ~in_roi[lj]                                 # exterior positions stay as in V
    w = lv[k][:, None] * (V[lj[k]] - centre)
    rhs_const = -np.stack([np.bincount(at_R[li[k]], weights=w[:, c], minlength=R.size)
                           for c in range(3)], axis=1)
    # sum of each row's exterior weights: moves rhs_const to another centre (see _solve)
    exterior_weight = np.bincount(at_R[li[k]], weights=lv[k], minlength=R.size)
    A_T = A.T.tocsr()
    # where each row of R gets its detail from: solved (fd), given (dc) or rest (exterior)
    R_fd = at_R[fd] >= 0
    R_fd_at = at_R[fd][R_fd]
    R_dc = at_R[dc] >= 0
    R_dc_at = at_R[dc][R_dc]
    D_R_rest = detail[R].copy()
    if all_rows:                                           # normal equations of E_Q
        system, A_kept = A_T @ A, A
    else:                                                  # square: L_ff X_f = D_f - L_fc X_c
        system, A_T, A_kept = A, None, None
    parts = dict(_fp=fp, _pc=pc, _R=R, _L_pc=L_pc, _centre=centre, _rhs_const=rhs_const,
                 _exterior_weight=exterior_weight, _A_T=A_T, _A=A_kept, _R_fd=R_fd, _R_fd_at=R_fd_at,
                 _R_dc=R_dc, _R_dc_at=R_dc_at, _D_R_rest=D_R_rest)
    return parts, system
