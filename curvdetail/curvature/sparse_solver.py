"""Sparse direct solvers behind one interface: factor once, back-substitute many times.

``"pardiso"``  Intel MKL PARDISO through ``pypardiso`` (x86-64).
``"cholmod"``  SuiteSparse CHOLMOD through ``scikit-sparse`` (symmetric positive definite only).
``"splu"``     SciPy's SuperLU (everywhere).

``"auto"`` (also the environment variable ``CURVDETAIL_SOLVER``, which a named backend
overrides) takes SuperLU below ``SMALL_SYSTEM_NNZ`` stored entries and otherwise the first
installed of PARDISO, CHOLMOD (symmetric systems only) and SuperLU. SuperLU runs on one thread:
below that size MKL's threads do not pay, and on a busy machine they make a re-solve many times
slower (docs/results/small_solves.md).
"""

import os
import threading
import weakref

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .errors import CurvdetailError

BACKENDS = ("pardiso", "cholmod", "splu")

#: Below this many stored entries (a ~15k-vertex Laplacian) ``"auto"`` takes SuperLU: one thread,
#: as fast as PARDISO there on an idle machine and many times faster beside busy processes
#: (docs/results/small_solves.md); from a 20k-vertex Laplacian PARDISO's threads pay.
SMALL_SYSTEM_NNZ = 100_000

#: What ``"auto"`` picks, in a line (for parameter descriptions and help texts).
AUTO_RULE = (f"auto = SuperLU below {SMALL_SYSTEM_NNZ:,} stored entries, else the first installed of "
             "PARDISO, CHOLMOD, SuperLU")

#: PARDISO's settings (1-based iparm numbers): METIS ordering, no iterative refinement, pivot
#: perturbation 1e-8 / 1e-13, scaling and matching for nonsymmetric matrices; symmetric ones
#: get the two-level factorization with the parallel forward/backward solve.
_IPARM = {True: {1: 1, 8: 0, 10: 8, 11: 0, 13: 0, 24: 1, 25: 2},
          False: {1: 1, 8: 0, 10: 13, 11: 1, 13: 1, 24: 0, 25: 0}}

#: From this many unknowns PARDISO orders with parallel METIS (iparm 2 = 3).
PARALLEL_ORDERING = 50_000

#: Number of numeric factorizations in this process (for tests of back-substitution only).
factorization_count = 0


class SolverError(CurvdetailError):
    """A backend that is unknown or not installed, or a factorization or solve that failed."""


def _installed(module):
    try:
        __import__(module)
    except Exception:
        return False
    return True


def available_backends():
    """Names of the installed backends, in `BACKENDS` order; ``"splu"`` is always there.

    Examples
    --------
    >>> available_backends()[-1]
    'splu'
    """
    return [name for name, module in zip(BACKENDS, ("pypardiso", "sksparse.cholmod", "scipy"))
            if _installed(module)]


def _requested(backend):
    """``(name, where)``: ``backend`` lower-cased and ``"backend"``, or for ``"auto"`` the setting
    of ``CURVDETAIL_SOLVER`` and that name where it is set."""
    if backend is not None and not isinstance(backend, str):
        raise SolverError(f"backend={backend!r} ({type(backend).__name__}, not a single str) is not a "
                          "solver backend", parameter="backend", value=backend,
                          hint=f"choose one of {', '.join(BACKENDS)} or 'auto'.")
    backend = (backend or "auto").strip().lower()
    setting = os.environ.get("CURVDETAIL_SOLVER", "").strip().lower()
    if backend == "auto" and setting:
        return setting, "CURVDETAIL_SOLVER"
    return backend, "backend"


def resolve_backend(backend="auto", *, symmetric=True, nnz=None):
    """The installed backend that ``backend`` names or ``"auto"`` picks for ``nnz`` stored entries
    (None: many); SolverError (``parameter``: ``"backend"`` or ``"CURVDETAIL_SOLVER"``) if none."""
    name, where = _requested(backend)
    if name == "auto":
        if nnz is not None and nnz < SMALL_SYSTEM_NNZ:
            return "splu"
        return next(b for b in available_backends() if symmetric or b != "cholmod")
    if name not in BACKENDS:
        raise SolverError(f"unknown solver backend {name!r}", parameter=where, value=name,
                          hint=f"choose one of {', '.join(BACKENDS)} or 'auto'.")
    if name not in available_backends():
        install = {"pardiso": "pip install pypardiso (x86-64 only)",
                   "cholmod": "install SuiteSparse and pip install scikit-sparse"}[name]
        raise SolverError(f"solver backend {name!r} is not installed", parameter=where, value=name,
                          hint=f"{install}, or use backend='auto'.")
    if name == "cholmod" and not symmetric:
        raise SolverError("CHOLMOD factors symmetric positive definite matrices only", parameter=where,
                          value=name, hint="use 'pardiso' or 'splu'.")
    return name


def _chosen_automatically(backend):
    """True if ``backend`` leaves the choice to the ``"auto"`` rule (no name, no setting)."""
    return _requested(backend)[0] == "auto"


def _upper_triangle(A):
    """Upper triangle (diagonal included) of a CSR matrix with sorted indices, as CSR."""
    rows = np.repeat(np.arange(A.shape[0], dtype=A.indices.dtype), np.diff(A.indptr))
    keep = A.indices >= rows
    indptr = np.zeros(A.shape[0] + 1, dtype=A.indptr.dtype)
    np.cumsum(np.bincount(rows[keep], minlength=A.shape[0]), out=indptr[1:])
    return sp.csr_matrix((A.data[keep], A.indices[keep], indptr), shape=A.shape)


def _release(solver):
    """Free MKL's memory of a PARDISO solver (with the last reference to its Factorization)."""
    try:
        solver.free_memory(everything=True)
    except Exception:                          # a handle that never reached MKL (a refused matrix)
        pass


class Factorization:
    """A factored square sparse matrix; `solve` back-substitutes only. See `factorize`.

    Attributes
    ----------
    backend : str
        The backend that holds the factors.
    shape : (int, int)
    """

    def __init__(self, A, *, symmetric=True, backend="auto", upper=False):
        A = sp.csr_matrix(A, dtype=np.float64)
        if A.shape[0] != A.shape[1]:
            raise SolverError(f"cannot factor a non-square matrix of shape {A.shape}.", parameter="A",
                              value=A.shape)
        if upper and not symmetric:
            raise SolverError("upper=True stores half of a symmetric matrix", parameter="upper",
                              hint="pass the whole matrix with symmetric=False.")
        self.shape, self.symmetric, self.upper = A.shape, bool(symmetric), bool(upper)
        self.backend = resolve_backend(backend, symmetric=symmetric, nnz=2 * A.nnz - A.shape[0] if upper else A.nnz)
        self._automatic = _chosen_automatically(backend)
        self._pivoting = False                 # SuperLU's partial pivoting, once it took over from PARDISO
        self._lock = threading.Lock()          # pypardiso's solver object is not thread-safe
        A.sort_indices()
        self._pattern = (A.indptr.copy(), A.indices.copy())
        self._factor(A)

    def refactor(self, A):
        """Factor new values on the stored pattern of the first matrix (explicit zeros count);
        SolverError otherwise or where it fails (no solve until a refactor succeeds)."""
        A = sp.csr_matrix(A, dtype=np.float64)
        A.sort_indices()
        if A.shape != self.shape or not (np.array_equal(A.indptr, self._pattern[0])
                                         and np.array_equal(A.indices, self._pattern[1])):
            raise SolverError("refactor needs the shape and stored sparsity pattern of the first matrix",
                              parameter="A", hint="use factorize for another system.")
        try:
            with self._lock:
                self._factor(A)
        except BaseException:
            self._solve = None
            raise

    def _factor(self, A):
        global factorization_count
        factorization_count += 1
        if self.shape[0] == 0:
            self._solve = np.zeros_like
            return
        if self.upper and self.backend != "pardiso":             # the others take it whole
            A = (A + sp.triu(A, k=1, format="csr").T).tocsr()
        if self.backend == "pardiso":
            self._solve = self._factor_pardiso(A if self.upper or not self.symmetric else _upper_triangle(A))
        elif self.backend == "cholmod":
            self._solve = self._factor_cholmod(A)
        else:
            self._solve = self._factor_splu(A, self._pivoting)

    def _factor_pardiso(self, M):
        import pypardiso
        from pypardiso.pardiso_wrapper import PyPardisoError

        # pypardiso searches for MKL in every new solver object unless this is set
        os.environ.setdefault("PYPARDISO_MKL_RT", pypardiso.ps.libmkl._name)
        solver = getattr(self, "_pardiso", None)
        try:
            if solver is not None:                               # a refactor: numeric phase only
                solver.set_phase(22)
                solver._call_pardiso(M, np.zeros((M.shape[0], 1), order="F"))
            else:
                solver = pypardiso.PyPardisoSolver(mtype=2 if self.symmetric else 11)
                for i, value in {**_IPARM[self.symmetric], 2: 3 if M.shape[0] >= PARALLEL_ORDERING else 2}.items():
                    solver.set_iparm(i, value)
                weakref.finalize(self, _release, solver).atexit = False
                solver.factorize(M)
                solver.remove_stored_factorization()             # its copy of M: M is kept here
                self._pardiso = solver
        except (ValueError, PyPardisoError) as exc:    # ValueError: an empty row
            raise SolverError(f"PARDISO could not factor the matrix ({exc}); it may be singular.",
                              parameter="A") from None
        perturbed = int(solver.iparm[13])
        if perturbed and not self.symmetric:
            # static pivoting replaced tiny pivots (the factors are of a nearby matrix): "auto"
            # takes SuperLU's partial pivoting
            if not self._automatic:
                raise SolverError(f"PARDISO perturbed {perturbed} pivots of this nonsymmetric matrix: it is "
                                  "singular or nearly so", parameter="backend", value="pardiso", count=perturbed,
                                  hint="use backend='splu' (LU with partial pivoting) or 'auto'.")
            self.backend, self._pivoting = "splu", True
            return self._factor_splu(M, partial_pivoting=True)

        lock = self._lock                # not self: the factors go with the last reference to it

        def solve(b):
            with lock:                   # the cheap path pypardiso documents: phase 33 on the factors
                solver.set_phase(33)
                return solver._call_pardiso(M, np.asfortranarray(b))
        return solve

    @staticmethod
    def _factor_cholmod(A):
        from sksparse import cholmod

        try:
            if hasattr(cholmod, "cho_factor"):               # scikit-sparse >= 0.5
                M = sp.csc_array(A)
                M.sort_indices()
                return cholmod.cho_factor(M).solve
            return cholmod.cholesky(A.tocsc())                # 0.4: factor(b) solves
        except Exception as exc:
            raise SolverError(f"CHOLMOD could not factor the matrix ({exc}); it is not positive definite.",
                              parameter="A") from None

    @staticmethod
    def _factor_splu(A, partial_pivoting=False):
        try:
            if partial_pivoting:
                return spla.splu(A.tocsc(), permc_spec="COLAMD").solve
            return spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                             options={"SymmetricMode": True}).solve
        except RuntimeError as exc:
            raise SolverError(f"SuperLU could not factor the matrix ({exc}); it is singular.",
                              parameter="A") from None

    def solve(self, b):
        """Solve ``A x = b`` by back-substitution with the stored factors.

        Parameters
        ----------
        b : (n,) or (n, k) float array

        Returns
        -------
        x : float array of the shape of ``b``

        Raises
        ------
        SolverError
            If ``b`` is complex or misshapen, the solution is not finite or the last refactor failed.
        """
        if np.iscomplexobj(b) or np.ndim(b) not in (1, 2) or np.shape(b)[0] != self.shape[0]:
            raise SolverError(f"the right-hand side must be real of shape ({self.shape[0]},) or "
                              f"({self.shape[0]}, k).", parameter="b", value=np.shape(b))
        if self._solve is None:
            raise SolverError("the last refactor failed, so there are no factors to solve with",
                              hint="refactor with valid values or factorize again.")
        b = np.asarray(b, dtype=np.float64)
        if b.size == 0:                        # no columns (MKL refuses nrhs = 0)
            return np.zeros(b.shape)
        x = np.asarray(self._solve(b), dtype=np.float64).reshape(b.shape)
        if not np.all(np.isfinite(x)):
            raise SolverError("the solve produced NaN or infinite values: the matrix is singular or "
                              "numerically degenerate", hint="check for collapsed triangles.")
        return x


def factorize(A, *, symmetric=True, backend="auto", upper=False):
    """Factor ``A`` once; ``.solve(b)`` then back-substitutes.

    Parameters
    ----------
    A : (n, n) scipy.sparse matrix
    symmetric : bool
        True for a symmetric positive definite ``A``.
    backend : {"auto", "pardiso", "cholmod", "splu"}
        See the module.
    upper : bool
        ``A`` holds only the upper triangle (diagonal included) of a symmetric matrix.

    Returns
    -------
    Factorization
        With ``.solve(b)``, ``.refactor(A)``, ``.backend`` and ``.shape``.

    Raises
    ------
    SolverError
        If the backend is unknown or not installed, or ``A`` is non-square or singular.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> A = sp.diags([[-1.0] * 3, [2.0] * 4, [-1.0] * 3], [-1, 0, 1])
    >>> x = factorize(A).solve(np.ones(4))
    >>> bool(np.allclose(A @ x, 1.0))
    True
    """
    return Factorization(A, symmetric=symmetric, backend=backend, upper=upper)
