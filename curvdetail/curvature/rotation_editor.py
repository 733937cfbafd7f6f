"""Rotation-aware curvature-detail editing: the rest details turn with their neighbourhoods."""

import collections

import numpy as np
import scipy.sparse as sp

from ._editor_checks import _check_reached, _index_set, region_mask
from .checks import as_count, as_positive_number, as_values, check_bool
from .cotan_laplacian import checked_cotan_laplacian, laplacian_product
from .errors import ConstraintError
from .geometry import bbox_centre, bbox_diagonal
from .sparse_solver import factorize, resolve_backend

#: Default stopping tolerance: the largest vertex move over the last `RotationAwareEditor.stop_window`
#: iterations, over the bbox diagonal.
DEFAULT_TOL = 1e-4
#: Default cap on the number of iterations of `RotationAwareEditor.solve`.
DEFAULT_MAX_ITERATIONS = 500


class RotationAwareEditor:
    """Edit a mesh by its curvature detail, turning each rest detail with its neighbourhood.

    The result minimizes, over the free positions ``X`` and one rotation ``R_i`` (times a scale
    ``s_i`` with ``scaling=True``, else ``s_i = 1``) per vertex, the energy

        ``E(X, R) = sum_{i in S} sum_{j ~ i} w_ij |(x_i - x_j) - s_i R_i (v_i - v_j)|^2``

    with ``w_ij = max(-L_ij, 0)`` the cotangent weights of the rest mesh ``V`` clamped at zero (a
    negative weight makes ``E`` unbounded below) and ``S`` the vertices with a free vertex in
    their closed one-ring (the as-rigid-as-possible energy of Sorkine & Alexa 2007).
    `solve` alternates two steps, each minimizing ``E`` exactly over its variables:

    - local: every ``R_i`` in closed form, the rotation nearest the 3x3 covariance
      ``sum_j w_ij (x_i - x_j) (v_i - v_j)^T`` (all vertices at once, reflections excluded);
    - global: the embedding ``(L X)_f = B_f`` over the free vertices ``f`` (``L`` with the
      weights ``w``), with the turned rest details ``B_i = sum_j w_ij (s_i R_i + s_j R_j) / 2
      (v_i - v_j)``; where the neighbourhood turns as one, ``B_i = s R D_i``.

    Steps are Anderson-accelerated (`anderson_memory`); an accelerated step is kept only
    where it lowers ``E`` (else the plain step is taken, and the next step is plain too), so
    ``E`` never increases from one iteration to the next (``energies``). The rotations start
    at the best-fit rotation of the handles (rest to given positions), blended towards the
    identity at the fixed part by a harmonic weight, so a rigid motion of every handle with
    ``roi=None`` is reproduced in the first iteration. The iterations stop when no vertex has
    moved more than ``tol`` times the bbox diagonal over the last `stop_window` (10) iterations
    (since the start, in the first ones: a cold start takes at least 11), or after
    ``max_iterations``. ``tol`` bounds that move, which is close to the distance to the minimum
    where the iteration converges at a steady rate (one step's move is not, where the rate is
    slow), but not along a nearly flat valley of ``E``, where the result can lie farther (see
    docs/guide/editing.md). The constructor does all factoring; an iteration of `solve` is one
    back-substitution plus the batched local fits.

    Parameters
    ----------
    V : (n, 3) float array
        Rest positions.
    F : (m, 3) int array
        Triangles.
    handles : (p,) int array or (n,) bool mask
        Vertices whose positions are given to `solve`, inside ``roi``.
    roi : (r,) int array or (n,) bool mask, optional
        Region of interest; vertices outside keep their rest positions. None: the whole mesh.
    scaling : bool
        Fit a uniform scale with each rotation (as-similar-as-possible), else rotations only.
    tol : float
        Stopping tolerance: the largest vertex move over the last `stop_window` iterations, over
        the bbox diagonal of ``V``.
    max_iterations : int
        Most iterations of `solve`.
    backend : str
        Sparse solver backend ("auto" or one of `available_backends`).

    Attributes
    ----------
    detail : (n, 3) float array
        Rest detail ``D_i = sum_j w_ij (v_i - v_j)``: the curvature detail ``L V`` wherever no
        weight was clamped.
    iterations : int
        Iterations of the last `solve` (global steps).
    converged : bool
        Whether the last `solve` met ``tol`` within ``max_iterations``.
    energies : list of float
        ``E`` after each local step of the last `solve`; non-increasing up to rounding.
    backend : str
        Solver backend of the embedding.

    Raises
    ------
    MeshError
        If the mesh is malformed.
    ConstraintError
        If ``handles`` or ``roi`` are out of range or repeated, ``roi`` is empty, a handle lies
        outside it, or the whole mesh is the region and there is no handle.
    UndeterminedEditError
        If a connected free region touches no handle and no fixed vertex.
    ValueError
        If ``scaling``, ``tol`` or ``max_iterations`` is not a valid value.

    Examples
    --------
    >>> import numpy as np
    >>> from curvdetail.curvature.testing import grid
    >>> V, F = grid(12, 12)
    >>> h = np.flatnonzero(V[:, 0] > 0.9)
    >>> ed = RotationAwareEditor(V, F, h, roi=np.flatnonzero(V[:, 0] > 0.1))
    >>> X = ed.solve(V[h] + [0, 0, 0.3])
    >>> bool(np.allclose(X[h, 2], 0.3)), ed.converged
    (True, True)
    """

    #: Anderson acceleration of the iterations: how many earlier steps it combines (0: off)
    anderson_memory = 5
    #: How many iterations back the stopping test measures the move (fewer at the start of a solve)
    stop_window = 10

    def __init__(self, V, F, handles, *, roi=None, scaling=False, tol=DEFAULT_TOL,
                 max_iterations=DEFAULT_MAX_ITERATIONS, backend="auto"):
        self.scaling = check_bool(scaling, "scaling")
        self.tol = as_positive_number(tol, "tol")
        self.max_iterations = as_count(max_iterations, "max_iterations")
        resolve_backend(backend)
        V, F, L = checked_cotan_laplacian(V, F)
        n = V.shape[0]
        self.V, self.F, self.n = V.copy(), F.copy(), n
        pc = _index_set(handles, n, "handles", "positions")
        in_roi = region_mask(n, roi, (("handles", pc),))
        if in_roi.all() and pc.size == 0:
            raise ConstraintError("handles is empty and the roi is the whole mesh: the result is only "
                                  "determined up to a rigid motion", parameter="handles", count=0,
                                  hint="give at least one handle per connected piece, or a smaller roi")
        free = in_roi.copy()
        free[pc] = False
        L = L.tocsr()
        L.sort_indices()
        rows = np.repeat(np.arange(n), np.diff(L.indptr))
        off = rows != L.indices
        # non-negative cotangent weights: a negative one (an obtuse pair of opposite angles) makes
        # E unbounded below, and the benchmark plane folded 3,649 triangles with them
        rows, cols, w = rows[off], L.indices[off], np.maximum(-L.data[off], 0.0)
        L = sp.csr_matrix((np.concatenate([-w, np.bincount(rows, weights=w, minlength=n)]),
                           (np.concatenate([rows, np.arange(n)]), np.concatenate([cols, np.arange(n)]))),
                          shape=(n, n)).tocsr()
        _check_reached(rows, cols, free, n, "position", "handles")
        self.position_constrained, self.roi = pc, np.flatnonzero(in_roi)
        self.diagonal = bbox_diagonal(V)
        fp = np.flatnonzero(free)
        # S: the vertices whose one-ring holds a free vertex (their rotations enter E's free part)
        in_s = free.copy()
        in_s[cols[free[rows]]] = True
        s_idx = np.flatnonzero(in_s)
        at_s = np.full(n, -1, dtype=np.int64)
        at_s[s_idx] = np.arange(s_idx.size)
        k = in_s[rows]                                     # CSR order: sorted by row
        self._s, self._fp, self._pc = s_idx, fp, pc
        self.detail = laplacian_product(L, V)              # sum_j w_ij (v_i - v_j)
        ei, ej, we = rows[k], cols[k], w[k]                # the edges from S
        rest_e = V[ei] - V[ej]
        at_rows = at_s[ei]
        # the covariances are one product with X: row c s + i holds D_i[c] at column i and
        # -w_ij (v_i - v_j)[c] at j, so that it gives sum_j w_ij (v_i - v_j)[c] (x_i - x_j)
        ns = s_idx.size
        c_rows = np.concatenate([at_rows, np.arange(ns)])
        c_vals = np.concatenate([-we[:, None] * rest_e, self.detail[s_idx]])
        self._cov_rows = sp.csr_matrix((c_vals.T.ravel(), (np.concatenate([c_rows + c * ns for c in range(3)]),
                                                           np.tile(np.concatenate([ej, s_idx]), 3))), shape=(3 * ns, n))
        # the edges i < j of E, weighted w_ij times how many of i, j are in S
        times = np.where(rows < cols, in_s[rows].astype(float) + in_s[cols], 0.0)
        half = times > 0
        self._edges = (rows[half], cols[half], w[half] * times[half])
        self._rest_sq = np.bincount(at_rows, weights=we * np.einsum("ij,ij->i", rest_e, rest_e), minlength=ns)
        # the global step's turned details: B = T R for R (3, 3, s) as rows c s + j: R_j[:, c]; row
        # f of T holds w_fj (v_f - v_j)[c] / 2 at column c s + j and D_f[c] / 2 at c s + f
        kf = free[ei]
        at_f = np.full(n, -1, dtype=np.int64)
        at_f[fp] = np.arange(fp.size)
        t_rows = np.concatenate([at_f[ei[kf]], np.arange(fp.size)])
        t_cols = np.concatenate([at_s[ej[kf]], at_s[fp]])
        t_vals = np.concatenate([we[kf, None] * rest_e[kf], self.detail[fp]])
        self._turn = sp.csr_matrix((0.5 * t_vals.T.ravel(),
                                    (np.tile(t_rows, 3), np.concatenate([t_cols + c * ns for c in range(3)]))),
                                   shape=(fp.size, 3 * ns))
        L_free = L[fp]
        self._L_pc = L_free[:, pc].tocsr()
        outside = ~in_roi
        self._L_out_V = L_free[:, outside] @ V[outside]    # the exterior stays at rest
        self._L_out_sum = np.asarray(L_free[:, outside].sum(axis=1)).ravel()
        self._embed = factorize(L_free[:, fp].tocsc(), symmetric=True, backend=backend) if fp.size else None
        self.backend = self._embed.backend if self._embed is not None else "none"
        # harmonic blend weight per vertex of S: 1 at the handles, 0 outside the roi (the start
        # of the rotations: the handles' turn, blended towards the fixed part)
        phi = np.zeros(n)
        phi[pc] = 1.0
        if fp.size:
            phi[fp] = self._embed.solve(-(self._L_pc @ np.ones(pc.size)))
        self._blend = np.clip(phi[s_idx], 0.0, 1.0)
        self.iterations, self.converged, self.energies = 0, True, []

    def solve(self, positions=None, *, initial=None):
        """Edited positions for the handles at ``positions``, by alternating local and global steps.

        Parameters
        ----------
        positions : (p, 3) float array, optional
            Positions of ``handles`` (row r for vertex ``handles[r]``); None: rest positions.
        initial : (n, 3) float array, optional
            A start for the rotations (e.g. the previous result of an interactive edit); None
            starts from the handles' best-fit rotation.

        Returns
        -------
        X : (n, 3) float array
            ``X[handles] == positions`` exactly; vertices outside the roi at rest exactly.

        Raises
        ------
        ConstraintError
            If ``positions`` or ``initial`` is not of the right shape of finite numbers.
        """
        Xk = self.V[self._pc] if positions is None else as_values(positions, self._pc.size, "positions")
        # everything about a centre among the handles (large coordinates do not cancel)
        centre = bbox_centre(Xk) if Xk.size else bbox_centre(self.V)
        X = self.V - centre
        X[self._pc] = Xk - centre
        if initial is not None:
            X[self._fp] = as_values(initial, self.n, "initial")[self._fp] - centre
            R, energy = self._local(X)
        else:
            R = _blended_rotations(_best_rotation(self.V[self._pc], Xk), self._blend).transpose(1, 2, 0)
            energy = None
        self.energies = [] if energy is None else [energy]
        self.iterations, self.converged = 0, self._embed is None
        const = -(self._L_pc @ X[self._pc]) - (self._L_out_V - self._L_out_sum[:, None] * centre)
        fp, accel, plain = self._fp, _Anderson(self.anderson_memory), False
        # the start and the iterates since, the last stop_window + 1 kept: the stop tests the move over them
        recent = collections.deque([X[fp]], maxlen=self.stop_window + 1)
        while self._embed is not None and self.iterations < self.max_iterations:
            x = recent[-1]                                    # X[fp]
            g = self._embed.solve(self._turned_details(R) + const)
            self.iterations += 1
            step = g
            if energy is not None and self.anderson_memory:   # (g, g - x): a sample of the map x -> g
                accel.add(g.ravel(), (g - x).ravel())
                if not plain and accel.dF:
                    step = accel.step().reshape(g.shape)
            X[fp] = step
            R_step, E_step = self._local(X)
            # the plain step never increases E; after it, the next step is plain too (an
            # accelerated step right after a rejected one is mostly rejected again)
            plain = step is not g and not E_step <= energy
            if plain:
                X[fp] = g
                R_step, E_step = self._local(X)
            R, energy = R_step, E_step
            self.energies.append(energy)
            recent.append(X[fp])                              # a copy (fancy index)
            if np.abs(recent[-1] - recent[0]).max() < self.tol * self.diagonal:
                self.converged = True
                break
        X += centre
        X[self._pc] = Xk                                      # exactly, as given
        outside = np.ones(self.n, dtype=bool)
        outside[self.roi] = False
        X[outside] = self.V[outside]
        return X

    def _local(self, X):
        """Rotations (scaled with ``scaling``), shape (3, 3, s), of every vertex of S fitted to X,
        and E(X, R). ``X`` about a centre near the mesh (the sums below cancel large coordinates)."""
        ns = self._s.size
        # cov[a, c, i] = sum_j w_ij (x_i - x_j)[a] (v_i - v_j)[c], C order (every entry a contiguous row)
        cov = np.ascontiguousarray((self._cov_rows @ X).reshape(3, ns, 3).transpose(2, 0, 1))
        R = _closest_rotations(cov)
        fit = np.einsum("ijk,ijk->k", R, cov)                # trace(R_i^T cov_i)
        i, j, w = self._edges
        d = np.take(X, i, axis=0) - np.take(X, j, axis=0)
        def_sq = np.einsum("ij,ij,i->", d, d, w)             # sum_i sum_j w_ij |x_i - x_j|^2
        if self.scaling:
            s = np.maximum(fit, 0.0) / np.maximum(self._rest_sq, np.finfo(float).tiny)
            R *= s
            energy = def_sq - np.sum(2 * s * fit - s * s * self._rest_sq)
        else:
            energy = def_sq - np.sum(2 * fit - self._rest_sq)
        return R, float(energy)

    def _turned_details(self, R):
        """``B_f = sum_j w_fj (R_f + R_j) / 2 (v_f - v_j) = (R_f D_f + sum_j R_j w_fj (v_f - v_j)) / 2``
        over the free rows, for R (3, 3, s) (scaled with ``scaling``)."""
        return self._turn @ R.transpose(1, 2, 0).reshape(-1, 3)


class _Anderson:
    """Anderson acceleration (Walker & Ni 2011) from the samples ``(g_k, f_k = g_k - x_k)`` of
    the last ``memory + 1`` steps: `step` is ``g - dG gamma`` with ``gamma`` minimizing
    ``|f - dF gamma|``, from the normal equations of its few unknowns (a poor step is refused by
    the energy test). The differences and their Gram matrix are kept, one new row a sample."""

    def __init__(self, memory):
        self.memory, self.last, self.dG, self.dF, self.gram = memory, None, [], [], np.zeros((0, 0))

    def add(self, g, f):
        if self.last is not None:
            self.dG = (self.dG + [g - self.last[0]])[-self.memory:]
            self.dF = (self.dF + [f - self.last[1]])[-self.memory:]
            row = np.array([np.einsum("i,i->", self.dF[-1], d) for d in self.dF])
            k = row.size
            gram = np.empty((k, k))
            gram[:-1, :-1] = self.gram[1:, 1:] if self.gram.shape[0] == k else self.gram
            gram[-1], gram[:, -1] = row, row
            self.gram = gram
        self.last = (g, f)

    def step(self):
        g, f = self.last
        gamma = np.linalg.lstsq(self.gram, np.array([np.einsum("i,i->", d, f) for d in self.dF]), rcond=None)[0]
        out = g.copy()
        for c, d in zip(gamma, self.dG):
            out -= c * d
        return out


def _closest_rotations(C, tol=1e-7, max_steps=20):
    """The rotations ``R_k`` maximizing ``trace(R_k^T C_k)``, for ``C`` of shape (3, 3, k)
    (matrix index first, so that every entry is a contiguous row); the SVD solution
    ``U diag(1, 1, d) W^T``, ``d = det(U) det(W)``. Returns shape (3, 3, k).

    ``C + cof(C)`` (``C`` scaled to unit Frobenius norm) is ``U diag(s1 + d s2 s3, s2 + d s1 s3,
    s3 + d s1 s2) W^T``: where its first two entries are positive and the third has the sign of
    ``d`` (always for ``d = 1``, rank 2 included), its determinant is positive and its orthogonal
    polar factor is the answer, found by scaled Newton steps ``X <- (g X + X^-T / g) / 2`` until
    no entry moves more than ``tol`` (the error is then about ``tol^2``). The rest (a factor that
    is no rotation, or a start whose determinant is rounding: rank 1) goes through
    `_closest_rotations_eigh`."""
    if C.shape[2] == 0:                                  # no vertex to fit (every roi vertex a handle)
        return C.copy()
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        X = C / np.sqrt(np.einsum("ijk,ijk->k", C, C))
        X += _cofactor(X)
        for step_number in range(max_steps):
            cof = _cofactor(X)                               # det(X) X^-T
            det = np.einsum("ik,ik->k", X[:, 0], cof[:, 0])
            if step_number == 0:
                # det(C + cof(C)) below 1e-15 (rank 1, a one-ring on a line: rounding, up to
                # 1e-17) makes the Newton steps' X^-T rounding: the eigen path takes it
                start = det
            g = np.sqrt(np.sqrt(np.einsum("ijk,ijk->k", cof, cof) / np.einsum("ijk,ijk->k", X, X)) / np.abs(det))
            step = 0.5 * (g * X + cof / (g * det))
            change = np.abs(step - X)
            X = step
            if np.fmax.reduce(change, axis=None) < tol:     # NaN (a singular X) ignored, caught by det
                break
        bad = ~((det > 0) & (start > 1e-15))
        if not np.fmax.reduce(change, axis=None) < tol:
            bad |= ~(change.reshape(9, -1).max(axis=0) < tol)
    if bad.any():
        X[:, :, bad] = _closest_rotations_eigh(C[:, :, bad].transpose(2, 0, 1)).transpose(1, 2, 0)
    return X


def _cofactor(A):
    """Cofactor matrices ``det(A) A^-T`` of (3, 3, k) ``A``."""
    out = np.empty_like(A)
    for i in range(3):
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        for j in range(3):
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            np.subtract(A[i1, j1] * A[i2, j2], A[i1, j2] * A[i2, j1], out=out[i, j])
    return out


def _closest_rotations_eigh(C):
    """`_closest_rotations` from the eigenvectors of ``C^T C`` (rank 2 included)."""
    _, W = np.linalg.eigh(np.swapaxes(C, 1, 2) @ C)          # ascending: W[..., 2] the largest
    w1, w2 = W[..., 2], W[..., 1]
    u1 = np.einsum("kij,kj->ki", C, w1)
    u1 /= np.maximum(np.linalg.norm(u1, axis=1), np.finfo(float).tiny)[:, None]
    u2 = np.einsum("kij,kj->ki", C, w2)
    u2 -= np.einsum("ki,ki->k", u1, u2)[:, None] * u1
    flat = ~(np.linalg.norm(u2, axis=1) > 1e-12 * np.linalg.norm(C, axis=(1, 2)))
    if flat.any():                      # rank 1: C w2 is rounding; any unit vector normal to u1 does
        u2[flat] = np.cross(u1[flat], np.eye(3)[np.argmin(np.abs(u1[flat]), axis=1)])
    u2 /= np.maximum(np.linalg.norm(u2, axis=1), np.finfo(float).tiny)[:, None]
    return (np.einsum("ki,kj->kij", u1, w1) + np.einsum("ki,kj->kij", u2, w2)
            + np.einsum("ki,kj->kij", np.cross(u1, u2), np.cross(w1, w2)))


def _blended_rotations(R, t):
    """``R`` turned by the fractions ``t`` (k,) of its angle about its own axis, shape (k, 3, 3)."""
    angle = np.arccos(np.clip((np.trace(R) - 1) / 2, -1.0, 1.0))
    axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if angle < 1e-12 or np.linalg.norm(axis) < 1e-12 * max(angle, 1.0):
        if angle < 1e-12:
            return np.broadcast_to(np.eye(3), (t.size, 3, 3))
        _, v = np.linalg.eigh(R + R.T)                    # a half turn: the axis is R's eigenvector 1
        axis = v[:, -1]
    axis = axis / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    a = (t * angle)[:, None, None]
    return np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * (K @ K)


def _best_rotation(P, Q):
    """The rotation ``R`` minimizing ``sum |(q - mean q) - R (p - mean p)|^2`` (Kabsch); the
    identity for fewer than three points."""
    if P.shape[0] < 3:
        return np.eye(3)
    U, _, Wt = np.linalg.svd((Q - Q.mean(0)).T @ (P - P.mean(0)))
    d = np.sign(np.linalg.det(U @ Wt)) or 1.0
    return U @ np.diag([1.0, 1.0, d]) @ Wt
