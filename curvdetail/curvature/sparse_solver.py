"""Sparse direct solver backends behind one interface: factor once, back-substitute many times.

Backends, chosen automatically in this order where installed:

``"pardiso"``  Intel MKL PARDISO (x86-64; the MKL runtime comes with ``pypardiso``, the calls go
               through the small ctypes binding in ``_pardiso``). Fastest and leanest here.
``"cholmod"``  SuiteSparse CHOLMOD through ``scikit-sparse`` (symmetric positive definite only).
``"splu"``     SciPy's SuperLU with ``MMD_AT_PLUS_A`` ordering and symmetric mode (everywhere).
``"banded"``   LAPACK's banded Cholesky (``scipy.linalg.cholesky_banded``) in reverse
               Cuthill-McKee order (everywhere; symmetric positive definite, small systems).

``"auto"`` takes SuperLU for small systems (under ``SMALL_SYSTEM_NNZ`` stored entries, or
``SMALL_SYSTEM`` unknowns where only the size is known; see there), and among those the banded
Cholesky for small symmetric systems with dense rows (see ``BANDED_MAX_SIZE``; where that meets a
non-positive pivot, SuperLU takes over). The choice can be
overridden per call (``backend="splu"``) or for the whole process with the
environment variable ``CURVDETAIL_SOLVER``. All backends agree to ~1e-12 relative on the
systems used here.

A :class:`Factorization` refactors new values on the same pattern (:meth:`Factorization.refactor`:
PARDISO keeps its ordering and symbolic analysis), and a :class:`PendingFactorization` starts
PARDISO's analysis from the pattern alone while the caller computes the values.
"""

import os

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ._validate import shown_choice
from .errors import CurvdetailError, counted

BACKENDS = ("pardiso", "cholmod", "splu", "banded")

#: Number of numeric factorizations performed in this process (a solver that promises
#: back-substitution only can be checked against it).
factorization_count = 0


class SolverError(CurvdetailError):
    """A backend was requested that is unknown or not installed, or a factorization failed."""


def _has_pardiso():
    try:
        import pypardiso  # noqa: F401
    except Exception:
        return False
    return True


def _has_cholmod():
    try:
        from sksparse import cholmod  # noqa: F401
    except Exception:
        return False
    return True


def available_backends():
    """Names of the installed backends, fastest first; ``"splu"`` and ``"banded"`` are always there.

    Takes no parameters. Whether ``"pardiso"`` (``pypardiso``) and ``"cholmod"``
    (``scikit-sparse``) are listed depends on what imports on this machine; ``"auto"`` is not a
    backend name and is never listed.

    Returns
    -------
    names : list of str   a subset of :data:`BACKENDS`, in its order: ``"pardiso"``, ``"cholmod"``
                          where installed, then always ``"splu"`` and ``"banded"``

    Examples
    --------
    >>> available_backends()[-2:]
    ['splu', 'banded']
    """
    found = []
    if _has_pardiso():
        found.append("pardiso")
    if _has_cholmod():
        found.append("cholmod")
    found += ["splu", "banded"]
    return found


#: Below this many unknowns ``"auto"`` picks SuperLU. Measured on 2 cores (factor + one solve of
#: 3 right-hand sides, grid Laplacians): the free-row system ``L_ff`` at 4.9k / 10k / 20k / 40k
#: unknowns takes 0.017 / 0.043 / 0.117 / 0.289 s with SuperLU and 0.036 / 0.051 / 0.105 /
#: 0.225 s with PARDISO; the ``L^T L`` system 0.045 / 0.120 / 0.322 / 0.826 s and 0.038 / 0.075 /
#: 0.168 / 0.344 s. Below ~5k both take a few milliseconds. (PARDISO's former ~0.2 s fixed cost
#: per factorization was pypardiso's library look-up, now done once per process.)
SMALL_SYSTEM = 5000

#: ``"auto"`` factors a small symmetric system (one it would give to SuperLU) with the banded
#: Cholesky when it has at most this many unknowns and at least ``BANDED_MIN_ROW_ENTRIES`` stored
#: entries a row: the normal equations ``L^T L`` (2-ring rows, ~19 entries) fill SuperLU's factors
#: much more than a narrow band does. Measured (factor, 2 cores): ``L^T L`` of grids at 873 / 1849
#: / 3364 / 5329 unknowns 3.6 / 6.1 / 13 / 26 ms banded against 6.1 / 12.7 / 28 / 59 ms SuperLU;
#: the sparser ``L_ff`` (7 a row) is faster with SuperLU (1849 unknowns: 5.9 against 7.8 ms).
BANDED_MAX_SIZE = 6000
BANDED_MIN_ROW_ENTRIES = 12

#: An explicitly requested banded factorization whose band would take more memory than this
#: is refused (the band grows with the square root of the size on a mesh).
BANDED_MAX_BYTES = 1 << 30

#: Below this many stored entries ``"auto"`` picks SuperLU (used when the matrix is at hand). The
#: crossover moves with the host: in the measurements above (2026-11-22) it sat near 1e5 entries
#: for both systems; on an AMD EPYC host (2026-11-30; grid / cube-sphere, factor + solve, ms)
#: ``L_ff`` at 4.8k unknowns (33k entries) took 14 / 33 with SuperLU and 14 / 18 with PARDISO, at
#: 9.6k (66k) 36 / 65 and 35 / 36; ``L^T L`` at 4.8k (88k) 42 / 58 SuperLU, 27 / 35 PARDISO and
#: 18 / 61 banded. 50k entries splits the difference (``L_ff``: ~7k unknowns, ``L^T L``: ~2.6k);
#: either way, below it the choice is worth milliseconds.
SMALL_SYSTEM_NNZ = 50_000


#: What ``"auto"`` picks, in a line (for parameter descriptions and help texts).
AUTO_RULE = (f"auto = SuperLU (or the banded Cholesky for small normal equations) below "
             f"{SMALL_SYSTEM_NNZ:,} stored entries, else the first installed of PARDISO, CHOLMOD, SuperLU")


def resolve_backend(backend="auto", *, symmetric=True, size=None, nnz=None):
    """Turn ``"auto"`` (or the ``CURVDETAIL_SOLVER`` setting) into an installed backend name."""
    if isinstance(backend, str):
        backend = backend.strip().lower()         # "PARDISO" too, as the filters' choices are taken
    elif backend is not None:                     # an array would meet ``in`` below element-wise
        raise SolverError(f"backend={shown_choice(backend)} is not a solver backend; choose one of "
                          f"{', '.join(BACKENDS)} or 'auto'.")
    source = ""
    if backend in (None, "auto"):
        backend = (os.environ.get("CURVDETAIL_SOLVER", "auto") or "auto").strip().lower()
        source = " (from the environment variable CURVDETAIL_SOLVER)" if backend != "auto" else ""
    if backend == "auto":
        small = nnz < SMALL_SYSTEM_NNZ if nnz is not None else (size is not None and size < SMALL_SYSTEM)
        if small:
            dense_rows = (nnz is not None and size is not None and 0 < size <= BANDED_MAX_SIZE
                          and nnz >= BANDED_MIN_ROW_ENTRIES * size)
            return "banded" if symmetric and dense_rows else "splu"
        for name in available_backends():
            if name in ("cholmod", "banded") and not symmetric:
                continue
            return name
    if backend not in BACKENDS:
        raise SolverError(f"unknown solver backend {backend!r}{source}", parameter="backend", value=backend,
                          hint=f"choose one of {', '.join(BACKENDS)} or 'auto'")
    if backend not in available_backends():
        hint = {"pardiso": "pip install pypardiso (x86-64 only)",
                "cholmod": "install SuiteSparse (apt install libsuitesparse-dev) and pip install scikit-sparse"}
        raise SolverError(f"solver backend {backend!r}{source} is not installed", parameter="backend",
                          value=backend, hint=f"{hint[backend]}, or use 'auto'")
    if backend in ("cholmod", "banded") and not symmetric:
        name = {"cholmod": "CHOLMOD", "banded": "The banded Cholesky"}[backend]
        raise SolverError(f"{name} factors symmetric positive definite matrices only", parameter="backend",
                          value=backend, hint="use 'pardiso' or 'splu'")
    return backend


def _chosen_automatically(backend):
    """True if ``backend`` leaves the choice to :func:`resolve_backend` (no name, no setting)."""
    if isinstance(backend, str):
        backend = backend.strip().lower()
    return backend in (None, "auto") and \
        (os.environ.get("CURVDETAIL_SOLVER", "auto") or "auto").strip().lower() == "auto"


def _refuse_empty_rows(indptr):
    """MKL PARDISO crashes on a row without stored entries instead of failing: refuse it."""
    counts = np.diff(indptr)
    if not counts.all():
        row = int(np.flatnonzero(counts == 0)[0])
        raise SolverError(f"the matrix is singular: row {row} has no stored entries.")


def _upper_triangle(A):
    """Upper triangle (diagonal included) of a CSR matrix with sorted indices, as CSR; a mask on
    the stored entries, ~2x faster than ``scipy.sparse.triu`` (which goes through COO)."""
    n = A.shape[0]
    rows = np.repeat(np.arange(n, dtype=A.indices.dtype), np.diff(A.indptr))
    keep = A.indices >= rows
    indptr = np.zeros(n + 1, dtype=A.indptr.dtype)
    np.cumsum(np.bincount(rows[keep], minlength=n), out=indptr[1:])
    return sp.csr_matrix((A.data[keep], A.indices[keep], indptr), shape=A.shape)


class Factorization:
    """A factored square sparse matrix. ``solve(b)`` back-substitutes only.

    Parameters
    ----------
    A : (n, n) scipy.sparse matrix
    symmetric : bool   True if A is symmetric positive definite (uses a Cholesky-type factorization)
    backend : str      ``"auto"``, ``"pardiso"``, ``"cholmod"``, ``"splu"`` or ``"banded"``
    upper : bool       True if ``A`` holds only the upper triangle (diagonal included) of the
                       symmetric matrix: PARDISO takes it as it is, which saves extracting it
    """

    def __init__(self, A, *, symmetric=True, backend="auto", upper=False, _analysis=None):
        global factorization_count
        A = sp.csr_matrix(A, dtype=np.float64)
        if A.shape[0] != A.shape[1]:
            raise SolverError(f"cannot factor a non-square matrix of shape {A.shape}.")
        if upper and not symmetric:
            raise SolverError("upper=True stores half of a symmetric matrix; pass the whole matrix "
                              "with symmetric=False.")
        self.shape = A.shape
        self.symmetric = bool(symmetric)
        self.upper = bool(upper)
        full_nnz = 2 * A.nnz - A.shape[0] if upper else A.nnz     # as stored in full (about)
        self.backend = resolve_backend(backend, symmetric=symmetric, size=A.shape[0], nnz=full_nnz)
        self._automatic = _chosen_automatically(backend)    # may another backend take over?
        self._partial_pivoting = False                        # SuperLU's, once it took over from PARDISO
        factorization_count += 1
        # PARDISO's ordering and symbolic analysis of A's pattern, where a PendingFactorization
        # has run them already; refactor reuses the same
        self._pardiso = _analysis
        if A.shape[0] == 0:
            self._solve = lambda b: np.zeros_like(b)
            return
        A.sort_indices()
        self._pattern = (A.indptr.copy(), A.indices.copy())    # for refactor
        try:
            getattr(self, "_factor_" + self.backend)(self._as_backend_wants(A))
        except SolverError:
            # the banded Cholesky stops at the first non-positive pivot; a symmetric matrix that is
            # only semi-definite in floating point (a curvature stage with an undetermined mode)
            # still has an LU factorization. "auto" takes it; a named backend reports the failure.
            if self.backend != "banded" or not _chosen_automatically(backend):
                raise
            self.backend = "splu"
            self._factor_splu(self._as_backend_wants(A))      # the whole matrix, also from upper=True

    def _as_backend_wants(self, A):
        """``A`` (sorted) as the backend takes it: the whole matrix, except PARDISO's triangle."""
        if self.upper and self.backend != "pardiso":
            A = (A + sp.triu(A, k=1, format="csr").T).tocsr()     # the other backends take it whole
            A.sort_indices()
        return A

    def refactor(self, A):
        """Factor new values that have the sparsity pattern of the matrix factored first.

        PARDISO keeps its fill-reducing ordering and symbolic analysis and redoes only the
        numeric factorization (at 1M unknowns ~1.5 s of a 5-6 s factorization); the other
        backends factor afresh. For iterations whose matrix changes only in its values, such
        as :func:`minimal_surface`.

        Parameters
        ----------
        A : (n, n) scipy.sparse matrix   same shape, stored pattern and ``upper`` convention as
                                         the first matrix (explicit zeros count as stored)

        Raises
        ------
        SolverError   the shape or the stored pattern differs, or the factorization fails
        """
        global factorization_count
        A = sp.csr_matrix(A, dtype=np.float64)
        if A.shape != self.shape:
            raise SolverError(f"refactor needs a matrix of shape {self.shape}, not {A.shape}; "
                              "use factorize for a new system.")
        if A.shape[0] == 0:
            factorization_count += 1
            return
        A.sort_indices()
        if not (np.array_equal(A.indptr, self._pattern[0]) and np.array_equal(A.indices, self._pattern[1])):
            raise SolverError("refactor needs the stored sparsity pattern of the first matrix (explicit "
                              "zeros included); use factorize for a system with another pattern.")
        factorization_count += 1
        try:
            getattr(self, "_factor_" + self.backend)(self._as_backend_wants(A))
        except BaseException:
            # the old factors are not of this matrix, and PARDISO's are half overwritten (a solve
            # after a failed refactor returned neither matrix's solution): refuse to solve
            self._solve = _after_failed_refactor
            raise

    # -- backends ---------------------------------------------------------------------------
    def _factor_pardiso(self, A):
        from ._pardiso import PardisoError, PardisoFactor, PardisoSizeError

        M = A if (self.upper or not self.symmetric) else _upper_triangle(A)
        _refuse_empty_rows(M.indptr)
        try:
            if self._pardiso is None:
                self._pardiso = PardisoFactor(M, symmetric=self.symmetric)
            else:                              # analysed before (pattern checked): numeric phase only
                self._pardiso.factor_values(M.data)
        except PardisoSizeError as exc:
            raise SolverError(f"{exc}.") from None
        except PardisoError as exc:
            raise SolverError(f"PARDISO could not factor the matrix ({exc}); it may be singular.") from None
        self._solve = self._pardiso.solve
        perturbed = int(self._pardiso.iparm[13])
        if perturbed and not self.symmetric:
            self._replace_perturbed_pardiso(A, perturbed)

    def _replace_perturbed_pardiso(self, A, perturbed):
        """PARDISO's nonsymmetric factorization pivots statically: a pivot below 1e-13 of the
        (scaled, matched) matrix is replaced by that size (``iparm[13]`` counts them), so the
        factors are of a nearby matrix, and its two automatic refinement steps do not make up for
        it on a nearly singular one (a 50 x 50 one: 14 % off the dense solution, SuperLU 9e-5).
        ``"auto"`` factors such a matrix again with SuperLU's partial pivoting; a named PARDISO
        reports it. Ordinary matrices never get here (the CurvatureEditor's (I - C) systems of ten
        test meshes: no perturbed pivot), so their solves cost nothing more."""
        self._pardiso.free()
        self._pardiso = None
        if not self._automatic:
            raise SolverError(f"PARDISO had to perturb {counted(perturbed, 'pivot')} of this "
                              "nonsymmetric matrix: it is singular or nearly so, and the solution would be off by "
                              "more than rounding. Use backend='splu' (LU with partial pivoting) or 'auto'.")
        self.backend = "splu"
        self._partial_pivoting = True
        self._factor_splu(A)

    def _factor_cholmod(self, A):
        from sksparse import cholmod

        try:
            if hasattr(cholmod, "cho_factor"):
                # scikit-sparse >= 0.5: cho_factor -> CholeskyFactor with .solve(b); it wants a
                # csc_array with sorted indices (``cholesky`` now returns the factor matrix)
                M = sp.csc_array(A)
                M.sort_indices()
                self._solve = cholmod.cho_factor(M).solve
            else:
                # scikit-sparse 0.4: cholesky -> Factor, called as factor(b) to solve A x = b
                self._solve = cholmod.cholesky(A.tocsc())
        except Exception as exc:
            raise SolverError(f"CHOLMOD could not factor the matrix ({exc}); it is not positive definite.") from None

    def _factor_banded(self, A):
        from scipy.linalg import LinAlgError, cho_solve_banded, cholesky_banded
        from scipy.sparse.csgraph import reverse_cuthill_mckee

        n = A.shape[0]
        A.sort_indices()
        p = reverse_cuthill_mckee(A, symmetric_mode=True)
        at = np.empty(n, dtype=np.int64)
        at[p] = np.arange(n)                   # new index of each old one
        B = A.tocoo()
        rows, cols = at[B.row], at[B.col]
        upper = cols >= rows
        rows, cols = rows[upper], cols[upper]
        width = int((cols - rows).max())
        if (width + 1) * n * 8 > BANDED_MAX_BYTES:
            raise SolverError(f"the banded Cholesky would need {(width + 1) * n * 8 / 2**30:.1f} GB for a band "
                              f"of width {width} over {n} unknowns; use 'auto', 'pardiso' or 'splu'.")
        band = np.zeros((width + 1, n))        # LAPACK upper band storage: A[i, j] at [w + i - j, j]
        band[width + rows - cols, cols] = B.data[upper]
        try:
            factor = cholesky_banded(band, lower=False, overwrite_ab=True, check_finite=False)
        except LinAlgError as exc:
            raise SolverError(f"the banded Cholesky could not factor the matrix ({exc}); it is not "
                              "positive definite.") from None

        def solve(b):
            x = np.empty_like(b)
            x[p] = cho_solve_banded((factor, False), b[p], check_finite=False)
            return x

        self._solve = solve

    def _factor_splu(self, A):
        try:
            if self._partial_pivoting:         # a nonsymmetric matrix PARDISO could not pivot
                lu = spla.splu(A.tocsc(), permc_spec="COLAMD")
            else:
                lu = spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                               options={"SymmetricMode": True})
        except RuntimeError as exc:
            raise SolverError(f"SuperLU could not factor the matrix ({exc}); it is singular.") from None
        self._solve = lu.solve

    # -- use --------------------------------------------------------------------------------
    def solve(self, b):
        """Solve ``A x = b`` by back-substitution with the stored factors.

        Parameters
        ----------
        b : (n,) or (n, k) float array

        Returns
        -------
        x : array of the shape of ``b``
        """
        if np.iscomplexobj(b):                 # the cast below would drop the imaginary part
            raise SolverError("the right-hand side is complex; solve its real and imaginary parts "
                              "separately.")
        b = np.asarray(b, dtype=np.float64)
        if b.ndim not in (1, 2):
            raise SolverError(f"the right-hand side has shape {b.shape}; pass one column (n,) or "
                              "k columns (n, k).")
        if b.shape[0] != self.shape[0]:
            raise SolverError(f"right-hand side has {b.shape[0]} rows; the matrix has {self.shape[0]}.")
        x = np.asarray(self._solve(b), dtype=np.float64).reshape(b.shape)
        if not np.all(np.isfinite(x)):
            raise SolverError("the solve produced NaN or infinite values: the matrix is singular or "
                              "numerically degenerate (check for collapsed triangles).")
        return x


def _after_failed_refactor(b):
    raise SolverError("the last refactor failed, so no factors of a matrix are at hand; refactor "
                      "with valid values or factorize again.")


_background_pool = None


class PendingFactorization:
    """A symmetric positive definite factorization begun from the sparsity pattern alone.

    With PARDISO the fill-reducing ordering and symbolic analysis, about two thirds of a
    factorization at 1M unknowns, start at once in a background thread (MKL releases the GIL),
    so that the caller can compute the values meanwhile; :meth:`finish` then runs the numeric
    factorization. Other backends simply factor in :meth:`finish`.

    Parameters
    ----------
    pattern : (n, n) scipy.sparse.csr_matrix   upper triangle, diagonal included, with sorted
              indices; its values are ignored
    backend : str   as for :func:`factorize`
    """

    def __init__(self, pattern, *, backend="auto"):
        global _background_pool
        self._indptr, self._indices, self.shape = pattern.indptr, pattern.indices, pattern.shape
        n = self.shape[0]
        # PARDISO takes rows with sorted columns (unsorted ones gave a wrong solution silently);
        # finish puts the values given in the pattern's stored order into the sorted one
        self._order = None
        if n > 0 and not sp.csr_matrix(pattern).has_sorted_indices:
            rows = np.repeat(np.arange(n), np.diff(self._indptr))
            self._order = np.lexsort((self._indices, rows))
            self._indices = self._indices[self._order]
        self.backend = resolve_backend(backend, symmetric=True, size=n, nnz=2 * pattern.nnz - n)
        self._requested = backend              # "auto" stays "auto" for Factorization's fallback
        self._future = None
        if self.backend == "pardiso" and n > 0:
            from concurrent.futures import ThreadPoolExecutor

            from ._pardiso import PardisoFactor

            _refuse_empty_rows(self._indptr)
            if _background_pool is None:
                _background_pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="curvdetail-analysis")
            M = sp.csr_matrix((np.zeros(pattern.nnz), self._indices, self._indptr), shape=self.shape)
            self._future = _background_pool.submit(PardisoFactor, M, symmetric=True, analyze_only=True)

    def finish(self, data):
        """The :class:`Factorization` of the matrix with these values (in the pattern's stored
        order)."""
        data = np.asarray(data, dtype=np.float64)
        if data.shape != self._indices.shape:
            raise SolverError(f"finish needs {self._indices.size} values, one per stored entry of the "
                              f"pattern in its order, not an array of shape {data.shape}.")
        if self._order is not None:
            data = data[self._order]
        A = sp.csr_matrix((data, self._indices, self._indptr), shape=self.shape)
        A.has_sorted_indices = True
        if self._future is None:
            return Factorization(A, symmetric=True, backend=self._requested, upper=True)
        from ._pardiso import PardisoError

        future, self._future = self._future, None
        try:
            analysis = future.result()
        except PardisoError as exc:
            raise SolverError(f"PARDISO could not analyse the matrix ({exc}).") from None
        return Factorization(A, symmetric=True, backend="pardiso", upper=True, _analysis=analysis)

    def cancel(self):
        """Give up (after an error in the caller) without waiting: the background analysis, which
        cannot be interrupted (~4 s at 1M unknowns), releases its memory when it ends."""
        future, self._future = self._future, None
        if future is not None:
            future.add_done_callback(_free_analysis)


def _free_analysis(future):
    if future.exception() is None:
        future.result().free()


def factorize(A, *, symmetric=True, backend="auto", upper=False):
    """Factor ``A`` once; ``.solve(b)`` then back-substitutes. See :class:`Factorization`.

    Parameters
    ----------
    A : (n, n) scipy.sparse matrix
    symmetric : bool   True for a symmetric positive definite ``A`` (Cholesky-type factorization)
    backend : str      ``"auto"``, ``"pardiso"``, ``"cholmod"``, ``"splu"`` or ``"banded"``
    upper : bool       ``A`` is the upper triangle (diagonal included) of a symmetric matrix

    Returns
    -------
    Factorization   with ``.solve(b)``, ``.backend`` and ``.shape``

    Raises
    ------
    SolverError   unknown or uninstalled backend, non-square or singular matrix

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> A = sp.diags([[-1.0] * 3, [2.0] * 4, [-1.0] * 3], [-1, 0, 1])
    >>> fac = factorize(A)
    >>> x = fac.solve(np.ones(4))
    >>> bool(np.allclose(A @ x, 1.0))
    True
    """
    return Factorization(A, symmetric=symmetric, backend=backend, upper=upper)
