"""A thin ctypes binding of MKL PARDISO for :mod:`sparse_solver` (factor once, solve many times).

pypardiso supplies the MKL runtime and finds it; its solver object is not used for the calls
themselves because it converts the index arrays to one-based copies on every call (~5 ms per
right-hand side column at 100k unknowns, as much as the back-substitution of ``L_ff``) and
offers no way to keep them. Here the arrays are handed to MKL once converted, zero-based
(``iparm[34] = 1``), and kept alive as long as the factor.
"""

import ctypes
import os
import threading

import numpy as np

#: From this many unknowns PARDISO orders with parallel METIS (``iparm[1] = 3``).
PARALLEL_ORDERING = 50_000

_INT_P = ctypes.POINTER(ctypes.c_int32)
_INT32_MAX = 2**31 - 1
_pardiso_function = None


def _library_path():
    """Path of the MKL runtime that pypardiso located: importing it builds one solver (``ps``);
    a fresh solver looks again where that attribute is missing."""
    import pypardiso

    if os.environ.get("PYPARDISO_MKL_RT"):
        return os.environ["PYPARDISO_MKL_RT"]
    solver = getattr(pypardiso, "ps", None) or pypardiso.PyPardisoSolver()
    path = getattr(getattr(solver, "libmkl", None), "_name", None)
    if not path:
        raise PardisoError("pypardiso found no MKL runtime (mkl_rt); reinstall pypardiso and mkl, "
                           "or choose another solver backend")
    return path


def _use_32_bit_indices(library):
    """Fix the MKL runtime to its LP64 interface (32-bit MKL_INT), the one these bindings pass:
    with ``MKL_INTERFACE_LAYER=ILP64`` in the environment mkl_rt reads every integer argument as
    64 bits and PARDISO crashed the process. Must run before the first MKL call (it is
    process-wide, so once is enough for both bindings)."""
    set_layer = library.MKL_Set_Interface_Layer
    set_layer.argtypes, set_layer.restype = [ctypes.c_int], ctypes.c_int
    if set_layer(0) != 0:                              # 0: MKL_INTERFACE_LP64
        raise PardisoError("the MKL runtime is fixed to its 64-bit integer interface (ILP64); unset "
                           "MKL_INTERFACE_LAYER or choose another solver backend")


def _function():
    global _pardiso_function
    if _pardiso_function is None:
        library = ctypes.CDLL(_library_path())
        _use_32_bit_indices(library)
        fn = library.pardiso
        fn.argtypes = [ctypes.POINTER(ctypes.c_int64)] + [_INT_P] * 5 + [ctypes.c_void_p, _INT_P, _INT_P,
                                                                         _INT_P, _INT_P, _INT_P, _INT_P,
                                                                         ctypes.c_void_p, ctypes.c_void_p, _INT_P]
        fn.restype = None
        _pardiso_function = fn
    return _pardiso_function


class PardisoError(RuntimeError):
    """PARDISO returned a nonzero error code."""


class PardisoSizeError(PardisoError):
    """The matrix needs 64-bit indices, which this binding (MKL's 32-bit interface) cannot pass."""


class PardisoFactor:
    """PARDISO's factors of one CSR matrix; ``solve(b)`` back-substitutes only.

    Parameters
    ----------
    M : (n, n) scipy.sparse.csr_matrix with sorted indices; for ``symmetric=True`` its upper
        triangle only, diagonal included (PARDISO's storage for symmetric matrices)
    symmetric : bool   real symmetric positive definite (mtype 2) or real nonsymmetric (mtype 11)
    analyze_only : bool   stop after the symbolic analysis; :meth:`factor_values` finishes
    """

    def __init__(self, M, *, symmetric, analyze_only=False):
        n = M.shape[0]
        nnz = int(M.indptr[-1]) if len(M.indptr) else 0
        if max(n, nnz) > _INT32_MAX:                   # the int32 copies below would wrap around
            raise PardisoSizeError(f"a matrix with {n} rows and {nnz} stored entries needs 64-bit indices, "
                                   "which this PARDISO binding does not pass; use backend='splu' or 'cholmod'")
        # kept referenced: PARDISO reads them again in every solve
        self._data = np.ascontiguousarray(M.data, dtype=np.float64)
        self._indptr = np.ascontiguousarray(M.indptr, dtype=np.int32)
        self._indices = np.ascontiguousarray(M.indices, dtype=np.int32)
        self._n = n
        self._mtype = 2 if symmetric else 11
        self._pt = np.zeros(64, dtype=np.int64)
        self._perm = np.zeros(0, dtype=np.int32)
        iparm = np.zeros(64, dtype=np.int32)
        iparm[0] = 1    # use the values below instead of all defaults
        # nested-dissection ordering: METIS, or its OpenMP version above PARALLEL_ORDERING unknowns
        # (factor of L_ff at 1M: 7.3 -> 5.1 s, of L^T L: 12.6 -> 9.9 s, same fill and solve time;
        # at 10k it costs 0.02 s more)
        iparm[1] = 3 if n >= PARALLEL_ORDERING else 2
        iparm[7] = 0    # no iterative refinement: it triples the re-solve time for nothing here
        iparm[9] = 8 if symmetric else 13   # pivot perturbation 1e-8 / 1e-13
        iparm[10] = 0 if symmetric else 1   # scaling (nonsymmetric only)
        iparm[12] = 0 if symmetric else 1   # weighted matching (nonsymmetric only)
        # two-level factorization: with the classic one (0), solving three columns in one call
        # took 0.10 s at 100k unknowns and 1.0 s at 1M, slower than three one-column calls (0.06 /
        # 0.32 s); with this one the three-column call takes 0.045 / 0.25 s, the factorization
        # the same time (kept to the symmetric case, the one measured)
        iparm[23] = 1 if symmetric else 0
        # parallel forward/backward solve for the two-level factorization: three columns of the
        # normal matrix at 100k unknowns 0.040 -> 0.036 s (the same at 1M)
        iparm[24] = 2 if symmetric else 0
        iparm[34] = 1   # zero-based indices
        self.iparm = iparm
        # PARDISO's handle (pt), iparm and the solve's work arrays are one state that every phase
        # reads and writes: two threads in it at once corrupt it (two threads solving with one
        # shared Reconstructor crashed the process in phase 33). MKL releases the GIL, so each
        # factor serializes its own calls; different factors still run in parallel.
        self._lock = threading.Lock()
        self._holds_memory = True                     # from the first call on, even a failed one
        self._factored = False                        # numeric factors ready for phase 33
        # 11: ordering and symbolic analysis (reads the pattern only); 12: both phases
        self._call(11 if analyze_only else 12, np.zeros(n), np.zeros(n))
        self._factored = not analyze_only

    def factor_values(self, data):
        """Numeric factorization (phase 22) with ``data``, the values of the analysed pattern in
        its order."""
        data = np.ascontiguousarray(data, dtype=np.float64)
        with self._lock:                               # a solve in another thread reads _data
            if data.shape != self._indices.shape:     # MKL would read past the end of the array
                raise PardisoError(f"{data.size} values for a pattern of {self._indices.size} entries")
            if not self._holds_memory:
                raise PardisoError("the factor was freed; factor the matrix again")
            self._data = data
            self._factored = False                     # a failed phase 22 leaves no usable factors
            self._call_unlocked(22, np.zeros(self._n), np.zeros(self._n))
            self._factored = True

    def _call(self, phase, b, x, columns=1):
        """One PARDISO call with this factor's handle, one thread at a time (see ``_lock``)."""
        with self._lock:
            if not self._holds_memory:                 # MKL would read the released handle
                raise PardisoError("the factor was freed; factor the matrix again")
            if phase == 33 and not self._factored:     # MKL crashed solving with the analysis only
                raise PardisoError("the matrix has no numeric factorization (it has not run or it "
                                   "failed); factor the matrix again")
            self._call_unlocked(phase, b, x, columns)

    def _call_unlocked(self, phase, b, x, columns=1):
        error = ctypes.c_int32(0)
        one = ctypes.c_int32(1)
        _function()(self._pt.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)), ctypes.byref(one),
                    ctypes.byref(one), ctypes.byref(ctypes.c_int32(self._mtype)),
                    ctypes.byref(ctypes.c_int32(phase)), ctypes.byref(ctypes.c_int32(self._n)),
                    self._data.ctypes.data, self._indptr.ctypes.data_as(_INT_P),
                    self._indices.ctypes.data_as(_INT_P), self._perm.ctypes.data_as(_INT_P),
                    ctypes.byref(ctypes.c_int32(columns)), self.iparm.ctypes.data_as(_INT_P),
                    ctypes.byref(ctypes.c_int32(0)), b.ctypes.data, x.ctypes.data, ctypes.byref(error))
        if error.value != 0:
            raise PardisoError(f"PARDISO error {error.value}")

    def solve(self, b):
        """Solve for ``b`` of shape (n,) or (n, k); the k columns go to MKL in one call, in the
        column-major layout it wants."""
        if b.ndim == 1:
            x = np.empty(self._n)
            self._call(33, np.ascontiguousarray(b, dtype=np.float64), x)
            return x
        x = np.empty((b.shape[1], self._n))            # x.T: (n, k) column-major
        if b.shape[1]:
            self._call(33, np.ascontiguousarray(b.T, dtype=np.float64), x, columns=b.shape[1])
        return x.T

    def free(self):
        """Release MKL's memory for this factor (also done when the object is collected)."""
        lock = getattr(self, "_lock", None)
        if lock is None:                               # __init__ failed before the first call
            return
        with lock:
            if self._holds_memory:
                self._holds_memory = False
                self._call_unlocked(-1, np.zeros(0), np.zeros(0))

    def __del__(self):
        try:
            self.free()
        except Exception:
            pass
