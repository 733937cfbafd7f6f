"""sparse_solver: every installed backend solves, agrees, factors once; choice and errors."""

import platform

import numpy as np
import pytest
import scipy.sparse as sp

from curvdetail import available_backends
from curvdetail.curvature import _pardiso, sparse_solver
from curvdetail.curvature.sparse_solver import SolverError, factorize, resolve_backend
from curvdetail.curvature.testing import grid
from curvdetail.curvature.cotan_laplacian import cotan_laplacian

from conftest import every_backend


def _spd_system(nx=30):
    """Free-row block of a grid Laplacian (SPD) and a known solution."""
    V, F = grid(nx, nx)
    V[:, 2] = np.sin(3 * V[:, 0]) * V[:, 1]
    L = cotan_laplacian(V, F)
    inner = np.flatnonzero((V[:, 0] > 0) & (V[:, 0] < 1) & (V[:, 1] > 0) & (V[:, 1] < 1))
    A = L[inner][:, inner]
    x = np.random.default_rng(3).normal(size=(inner.size, 3))
    return A, x


@pytest.mark.skipif(platform.machine() not in ("x86_64", "AMD64"),
                    reason="pypardiso is a dependency on x86-64 only")
def test_pardiso_is_available_where_it_is_a_dependency():
    # a broken MKL runtime would otherwise drop "pardiso" from every backend-parametrized test
    # without a word (available_backends() leaves out what fails to import)
    assert "pardiso" in available_backends()


@pytest.mark.parametrize("backend", every_backend())
def test_solves_an_spd_system_to_rounding(backend):
    A, x = _spd_system()
    fac = factorize(A, symmetric=True, backend=backend)
    assert fac.backend == backend
    # cond(A) ~ 1e3 here: the error is ~1e-13 relative
    assert np.abs(fac.solve(A @ x) - x).max() < 1e-10 * np.abs(x).max()


@pytest.mark.parametrize("backend", every_backend(exclude=("cholmod", "banded")))
def test_solves_a_nonsymmetric_system(backend):
    A, x = _spd_system()
    A = (A + sp.diags(np.linspace(0, 0.5, A.shape[0])) @ abs(sp.triu(A, 1))).tocsr()
    fac = factorize(A, symmetric=False, backend=backend)
    assert np.abs(fac.solve(A @ x) - x).max() < 1e-10 * np.abs(x).max()


@pytest.mark.parametrize("backend", every_backend())
def test_backends_agree_with_a_dense_solve(backend):
    # the reference is numpy's dense LU, not one of the backends (splu against itself cannot fail)
    A, x = _spd_system(45)
    b = A @ x
    ref = np.linalg.solve(A.toarray(), b)
    assert np.abs(factorize(A, backend=backend).solve(b) - ref).max() < 1e-9 * np.abs(ref).max()


@pytest.mark.skipif("pardiso" not in available_backends(), reason="PARDISO (pypardiso) not installed")
@pytest.mark.parametrize("symmetric", [True, False])
def test_pardiso_parallel_ordering_solves_the_same(monkeypatch, symmetric):
    # large systems are ordered with parallel METIS; lower the threshold to take that path here
    A, x = _spd_system()
    monkeypatch.setattr(_pardiso, "PARALLEL_ORDERING", 10)
    fac = factorize(A, symmetric=symmetric, backend="pardiso")
    assert fac._pardiso.iparm[1] == 3
    assert np.abs(fac.solve(A @ x) - x).max() < 1e-10 * np.abs(x).max()
    assert np.abs(fac.solve(np.asfortranarray(A @ x)) - x).max() < 1e-10 * np.abs(x).max()


@pytest.mark.parametrize("backend", every_backend())
def test_solve_keeps_the_shape_of_the_right_hand_side(backend):
    A, x = _spd_system(12)
    fac = factorize(A, backend=backend)
    assert fac.solve(A @ x[:, 0]).shape == (A.shape[0],)
    assert fac.solve(A @ x).shape == x.shape
    assert fac.solve(np.zeros((A.shape[0], 0))).shape == (A.shape[0], 0)


@pytest.mark.parametrize("backend", every_backend())
def test_upper_triangle_input_solves_like_the_whole_matrix(backend):
    A, x = _spd_system(30)
    b = A @ x
    U = sp.triu(A, format="csr")
    fac = factorize(U, backend=backend, upper=True)
    assert fac.backend == backend
    assert np.abs(fac.solve(b) - x).max() < 1e-9 * np.abs(x).max()


def test_upper_triangle_input_needs_a_symmetric_matrix():
    A, _ = _spd_system(5)
    with pytest.raises(SolverError, match="symmetric=False"):
        factorize(sp.triu(A), symmetric=False, upper=True)


@pytest.mark.skipif("pardiso" not in available_backends(), reason="PARDISO (pypardiso) not installed")
def test_pardiso_refuses_an_empty_row_instead_of_crashing():
    A = sp.csr_matrix(np.diag([2.0, 0.0, 3.0]))
    A.eliminate_zeros()
    with pytest.raises(SolverError, match="row 1 has no stored entries"):
        factorize(A, backend="pardiso")


def test_upper_triangle_matches_scipy_triu():
    A, _ = _spd_system(10)
    A = (A @ A).tocsr()
    A.sort_indices()
    U = sparse_solver._upper_triangle(A)
    assert (U != sp.triu(A, format="csr")).nnz == 0 and U.has_sorted_indices


def test_factorization_is_counted_once_and_solves_are_not():
    A, x = _spd_system(12)
    before = sparse_solver.factorization_count
    fac = factorize(A)
    for _ in range(5):
        fac.solve(A @ x)
    assert sparse_solver.factorization_count == before + 1


def test_auto_picks_splu_for_small_systems():
    assert resolve_backend("auto", size=sparse_solver.SMALL_SYSTEM - 1) == "splu"
    assert resolve_backend("auto", size=sparse_solver.SMALL_SYSTEM) == available_backends()[0]
    # where the matrix is known its stored entries decide
    assert resolve_backend("auto", size=10 ** 6, nnz=sparse_solver.SMALL_SYSTEM_NNZ - 1) == "splu"
    assert resolve_backend("auto", size=10, nnz=sparse_solver.SMALL_SYSTEM_NNZ) == available_backends()[0]
    A, _ = _spd_system(12)
    assert factorize(A).backend == "splu"


def _normal_equations(nx):
    """``L_f: L_f:^T`` of a grid (2-ring rows, ~19 stored entries each) and a known solution."""
    V, F = grid(nx, nx)
    V[:, 2] = np.sin(3 * V[:, 0]) * V[:, 1]
    L = cotan_laplacian(V, F)
    inner = np.flatnonzero((V[:, 0] > 0) & (V[:, 0] < 1) & (V[:, 1] > 0) & (V[:, 1] < 1))
    A = (L[inner] @ L[inner].T).tocsr()
    return A, np.random.default_rng(5).normal(size=(inner.size, 3))


def test_auto_picks_the_banded_cholesky_for_small_systems_with_dense_rows():
    A, x = _normal_equations(20)                  # 324 unknowns, ~17 entries a row
    assert A.nnz >= sparse_solver.BANDED_MIN_ROW_ENTRIES * A.shape[0]
    fac = factorize(A)
    assert fac.backend == "banded"
    ref = factorize(A, backend="splu").solve(A @ x)
    assert np.abs(fac.solve(A @ x) - ref).max() < 1e-9 * np.abs(ref).max()
    assert factorize(A, symmetric=False).backend == "splu"       # LU for a nonsymmetric system
    assert factorize(_spd_system(20)[0]).backend == "splu"       # 5-point rows: SuperLU is faster


def test_banded_cholesky_refuses_indefinite_and_oversized_systems(monkeypatch):
    A, _ = _spd_system(10)
    with pytest.raises(SolverError, match="not positive definite"):
        factorize(-A, backend="banded")
    monkeypatch.setattr(sparse_solver, "BANDED_MAX_BYTES", 1000)
    with pytest.raises(SolverError, match=r"would need .* GB for a band of width \d+ over \d+ unknowns"):
        factorize(A, backend="banded")


def test_auto_falls_back_to_lu_where_the_banded_cholesky_meets_a_non_positive_pivot(monkeypatch):
    # a symmetric system with dense rows that is not positive definite: L^T L shifted past its
    # smallest eigenvalue. "auto" would take the banded Cholesky; it hands over to SuperLU.
    A, x = _normal_equations(20)
    smallest = np.linalg.eigvalsh(A.toarray())[:2]
    A = (A - sp.identity(A.shape[0]) * smallest.mean()).tocsr()
    for given, upper in ((A, False), (sp.triu(A, format="csr"), True)):
        fac = factorize(given, upper=upper)
        assert fac.backend == "splu"
        assert np.abs(fac.solve(A @ x) - x).max() < 1e-6 * np.abs(x).max()    # cond ~ 1e5
    upper = sp.triu(A, format="csr")
    upper.sort_indices()
    pending = sparse_solver.PendingFactorization(upper, backend="auto")
    assert pending.backend == "banded" and pending.finish(upper.data).backend == "splu"
    with pytest.raises(SolverError, match="not positive definite"):
        factorize(A, backend="banded")                  # a named backend reports it
    monkeypatch.setenv("CURVDETAIL_SOLVER", "banded")
    with pytest.raises(SolverError, match="not positive definite"):
        factorize(A)


def test_environment_variable_overrides_auto(monkeypatch):
    monkeypatch.setenv("CURVDETAIL_SOLVER", "splu")
    assert resolve_backend("auto", size=10 ** 6) == "splu"
    assert factorize(_normal_equations(20)[0]).backend == "splu"     # not swapped for banded
    monkeypatch.setenv("CURVDETAIL_SOLVER", "auto")
    assert factorize(_normal_equations(20)[0]).backend == "banded"   # "auto" spelled out is auto


@pytest.mark.parametrize("backend", [np.array(["splu"]), np.array(["splu", "pardiso"]), ["splu"], 3])
def test_a_backend_that_is_not_one_str_is_refused_as_such(backend):
    # ``in`` compared an array element-wise: numpy's "truth value ... is ambiguous" for two entries
    with pytest.raises(SolverError, match=r"backend=.* \((ndarray|list|int), not a single str\) is not a solver "
                                          r"backend; choose one of pardiso, cholmod, splu, banded or 'auto'"):
        resolve_backend(backend)


def test_unknown_backend_is_refused_with_the_choices():
    with pytest.raises(SolverError, match="unknown solver backend 'umfpack'.*pardiso, cholmod, splu, banded"):
        resolve_backend("umfpack")


def test_missing_backend_is_refused_with_the_install_hint(monkeypatch):
    monkeypatch.setattr(sparse_solver, "_has_cholmod", lambda: False)
    with pytest.raises(SolverError, match="'cholmod' is not installed; install SuiteSparse"):
        resolve_backend("cholmod")


def test_cholmod_is_refused_for_nonsymmetric_systems(monkeypatch):
    monkeypatch.setattr(sparse_solver, "_has_cholmod", lambda: True)
    with pytest.raises(SolverError, match="symmetric positive definite"):
        resolve_backend("cholmod", symmetric=False)
    with pytest.raises(SolverError, match="banded Cholesky factors symmetric positive definite"):
        resolve_backend("banded", symmetric=False)


def test_singular_matrix_is_reported_not_returned_as_nan():
    A, _ = _spd_system(8)
    A = A.tolil()
    A[3, :] = 0.0
    A[:, 3] = 0.0
    with pytest.raises(SolverError, match="singular"):
        factorize(A.tocsr(), backend="splu").solve(np.ones(A.shape[0]))


def test_non_square_matrix_is_refused():
    with pytest.raises(SolverError, match=r"non-square matrix of shape \(3, 4\)"):
        factorize(sp.eye(3, 4))


def test_right_hand_side_of_the_wrong_length_is_refused():
    A, _ = _spd_system(8)
    with pytest.raises(SolverError, match=f"right-hand side has 5 rows; the matrix has {A.shape[0]}"):
        factorize(A).solve(np.ones(5))


def test_docstring_examples_run():
    import doctest
    import importlib

    result = doctest.testmod(importlib.import_module("curvdetail.curvature.sparse_solver"), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0, result


@pytest.mark.parametrize("upper", [False, True])
@pytest.mark.parametrize("backend", every_backend())
def test_refactor_solves_like_a_fresh_factorization(backend, upper):
    A, x = _spd_system(30)
    B = (A + sp.diags(np.linspace(0.5, 2.0, A.shape[0]))).tocsr()    # same pattern, new values
    pick = (lambda M: sp.triu(M, format="csr")) if upper else (lambda M: M)
    fac = factorize(pick(A), backend=backend, upper=upper)
    before = sparse_solver.factorization_count
    fac.refactor(pick(B))
    assert sparse_solver.factorization_count == before + 1
    fresh = factorize(pick(B), backend=backend, upper=upper).solve(B @ x)
    assert np.abs(fac.solve(B @ x) - x).max() < 1e-9 * np.abs(x).max()
    assert np.abs(fac.solve(B @ x) - fresh).max() < 1e-9 * np.abs(x).max()


@pytest.mark.parametrize("backend", every_backend())
def test_refactor_refuses_another_pattern_or_shape(backend):
    A, _ = _spd_system(12)
    fac = factorize(A, backend=backend)
    other = (A + sp.eye(A.shape[0], k=5)).tocsr()
    with pytest.raises(SolverError, match="stored sparsity pattern"):
        fac.refactor(other + other.T)
    with pytest.raises(SolverError, match="shape"):
        fac.refactor(sp.eye(3))


@pytest.mark.parametrize("backend", every_backend())
def test_pending_factorization_finishes_like_factorize(backend):
    A, x = _spd_system(30)
    U = sp.triu(A, format="csr")
    U.sort_indices()
    pattern = sp.csr_matrix((np.zeros(U.nnz), U.indices, U.indptr), shape=U.shape)
    pending = sparse_solver.PendingFactorization(pattern, backend=backend)
    fac = pending.finish(U.data)
    assert fac.backend == backend
    assert np.abs(fac.solve(A @ x) - x).max() < 1e-9 * np.abs(x).max()
    # the same pattern with new values: accepted, and solved with the new values
    B = (A + sp.diags(np.linspace(0.5, 2.0, A.shape[0]))).tocsr()
    fac.refactor(sp.triu(B, format="csr"))
    assert np.abs(fac.solve(B @ x) - x).max() < 1e-9 * np.abs(x).max()
    assert np.abs(fac.solve(A @ x) - x).max() > 1e-3 * np.abs(x).max()       # not the old values


@pytest.mark.parametrize("backend", every_backend())
def test_cancelled_pending_factorization_frees_its_analysis(backend, monkeypatch):
    # nothing left behind: PARDISO's background analysis is freed once it ends; the other
    # backends have not started anything
    import threading

    freed, real_free = threading.Event(), _pardiso.PardisoFactor.free

    def spy(self):
        real_free(self)
        freed.set()

    monkeypatch.setattr(_pardiso.PardisoFactor, "free", spy)
    A, _ = _spd_system(30)
    pending = sparse_solver.PendingFactorization(sp.triu(A, format="csr"), backend=backend)
    analysis = pending._future
    assert (analysis is not None) == (backend == "pardiso")
    pending.cancel()
    assert pending._future is None
    if analysis is not None:
        assert freed.wait(10) and not analysis.result()._holds_memory
    else:
        assert not freed.is_set()


@pytest.mark.skipif("pardiso" not in available_backends(), reason="PARDISO (pypardiso) not installed")
def test_cancel_returns_at_once_and_the_analysis_frees_its_memory_when_it_ends(monkeypatch):
    import threading

    release, freed = threading.Event(), threading.Event()

    class SlowAnalysis:                       # stands in for PARDISO's ordering of a large matrix
        def __init__(self, M, *, symmetric, analyze_only=False):
            release.wait(10)

        def free(self):
            freed.set()

    monkeypatch.setattr(_pardiso, "PardisoFactor", SlowAnalysis)
    A, _ = _spd_system(10)
    pending = sparse_solver.PendingFactorization(sp.triu(A, format="csr"), backend="pardiso")
    pending.cancel()                          # while the analysis still runs
    assert not freed.is_set()
    release.set()
    assert freed.wait(10)


@pytest.mark.skipif("pardiso" not in available_backends(), reason="PARDISO (pypardiso) not installed")
def test_pending_factorization_refuses_an_empty_row():
    pattern = sp.csr_matrix((np.ones(2), [0, 2], [0, 1, 1, 2]), shape=(3, 3))
    with pytest.raises(SolverError, match="row 1 has no stored entries"):
        sparse_solver.PendingFactorization(pattern, backend="pardiso")


def test_unknown_backend_from_the_environment_names_the_variable(monkeypatch):
    # the user passed no backend: the message must say where the name came from
    monkeypatch.setenv("CURVDETAIL_SOLVER", "foo")
    with pytest.raises(SolverError, match=r"unknown solver backend 'foo' \(from the environment variable "
                                          r"CURVDETAIL_SOLVER\)"):
        resolve_backend("auto", size=10)
    monkeypatch.delenv("CURVDETAIL_SOLVER")
    with pytest.raises(SolverError, match=r"unknown solver backend 'foo'; choose one of"):
        resolve_backend("foo", size=10)


@pytest.mark.parametrize("name", ["SPLU", " splu", "Banded"])
def test_backend_names_are_case_insensitive(monkeypatch, name):
    monkeypatch.delenv("CURVDETAIL_SOLVER", raising=False)
    assert resolve_backend(name, size=10) == name.strip().lower()
    monkeypatch.setenv("CURVDETAIL_SOLVER", name)
    assert resolve_backend("AUTO", size=10) == name.strip().lower()


def _nearly_singular_nonsymmetric():
    """A 50 x 50 nonsymmetric matrix whose row 7 is twice row 3 plus 1e-13 on the diagonal
    (condition number 2e14), a right-hand side and numpy's dense solution."""
    A = (sp.random(50, 50, density=0.2, random_state=1) + 3.0 * sp.eye(50)).tolil()
    A[7, :] = A[3, :] * 2
    A[7, 7] += 1e-13
    A = A.tocsr()
    b = np.random.default_rng(0).normal(size=50)
    return A, b, np.linalg.solve(A.toarray(), b)


@pytest.mark.skipif("pardiso" not in available_backends(), reason="PARDISO (pypardiso) not installed")
def test_pardiso_perturbed_pivots_are_not_taken_for_a_solution(monkeypatch):
    # PARDISO replaced a pivot by 1e-13 (iparm[13] = 1) and its solution was 14 % off the dense one;
    # SuperLU's is 9e-5 off (cond 2e14: the problem's own sensitivity is ~0.05)
    A, b, dense = _nearly_singular_nonsymmetric()
    with pytest.raises(SolverError, match="PARDISO had to perturb 1 pivot of this nonsymmetric matrix: it is "
                                          "singular or nearly so.*backend='splu'"):
        factorize(A, symmetric=False, backend="pardiso")
    monkeypatch.delenv("CURVDETAIL_SOLVER", raising=False)
    monkeypatch.setattr(sparse_solver, "SMALL_SYSTEM_NNZ", 0)         # "auto" picks PARDISO first
    fac = factorize(A, symmetric=False)
    assert fac.backend == "splu"                                        # taken over, with pivoting
    assert np.abs(fac.solve(b) - dense).max() < 1e-3 * np.abs(dense).max()
    # refactoring: an ordinary matrix of the same pattern stays with PARDISO, the nearly singular one
    # goes to SuperLU again
    B = (A + 5.0 * sp.eye(50)).tocsr()
    fac = factorize(B, symmetric=False)
    assert fac.backend == "pardiso" and fac._pardiso.iparm[13] == 0
    fac.refactor(A)
    assert fac.backend == "splu"
    assert np.abs(fac.solve(b) - dense).max() < 1e-3 * np.abs(dense).max()
    fac.refactor(B)
    x = fac.solve(b)
    assert np.abs(B @ x - b).max() < 1e-11 * np.abs(b).max()


@pytest.mark.skipif("pardiso" not in available_backends(), reason="PARDISO (pypardiso) not installed")
def test_an_exactly_singular_nonsymmetric_matrix_is_refused_not_solved(monkeypatch):
    # row 7 = 2 row 3: PARDISO perturbed a pivot and returned entries of 4.6e13 with a residual of 0.37
    A, b, _ = _nearly_singular_nonsymmetric()
    A = A.tolil()
    A[7, 7] = 2 * A[3, 7]
    A = A.tocsr()
    monkeypatch.delenv("CURVDETAIL_SOLVER", raising=False)
    monkeypatch.setattr(sparse_solver, "SMALL_SYSTEM_NNZ", 0)
    with pytest.raises(SolverError, match="singular"):
        factorize(A, symmetric=False).solve(b)


# Child process for the shared-factor threading test: a crash (PARDISO's handle used by two
# threads at once segfaulted) then ends the child, not pytest. It prints the largest difference
# between the threaded and the serial solutions, relative to the solutions' size.
_SHARED_FACTOR_SCRIPT = """
import sys
from concurrent.futures import ThreadPoolExecutor
import numpy as np
from curvdetail.curvature.sparse_solver import factorize
from curvdetail.curvature.testing import grid
from curvdetail.curvature.cotan_laplacian import cotan_laplacian
V, F = grid(100, 100)
V[:, 2] = np.sin(5 * V[:, 0]) * V[:, 1]
L = cotan_laplacian(V, F)
inner = np.flatnonzero((V[:, 0] > 0) & (V[:, 0] < 1) & (V[:, 1] > 0) & (V[:, 1] < 1))
A = L[inner][:, inner].tocsr()
fac = factorize(A, symmetric=sys.argv[2] == "symmetric", backend=sys.argv[1])
rhs = [np.random.default_rng(k).normal(size=(A.shape[0], 1 + k % 3)) for k in range(4)]
serial = [fac.solve(b) for b in rhs]
with ThreadPoolExecutor(4) as pool:
    threaded = list(pool.map(lambda k: fac.solve(rhs[k % 4]), range(400)))
print(max(np.abs(x - serial[k % 4]).max() / np.abs(serial[k % 4]).max() for k, x in enumerate(threaded)))
"""


def _solve_in_threads_sharing_one_factor(backend, symmetric):
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", _SHARED_FACTOR_SCRIPT, backend,
                           "symmetric" if symmetric else "nonsymmetric"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    # the same factor and right-hand sides: the same answers, whichever thread solved them
    assert float(done.stdout.split()[-1]) < 1e-12


@pytest.mark.parametrize("backend", every_backend())
def test_threads_sharing_one_factorization_solve_as_serial_solves(backend):
    _solve_in_threads_sharing_one_factor(backend, symmetric=True)


@pytest.mark.parametrize("backend", every_backend(exclude=("cholmod", "banded")))
def test_threads_sharing_one_nonsymmetric_factorization_solve_as_serial_solves(backend):
    _solve_in_threads_sharing_one_factor(backend, symmetric=False)


_needs_pardiso = pytest.mark.skipif("pardiso" not in available_backends(), reason="PARDISO (pypardiso) not installed")


@pytest.mark.parametrize("backend", every_backend())
def test_a_failed_refactor_leaves_no_factors_to_solve_with(backend):
    # after a refactor that failed, neither the old factors (another matrix) nor PARDISO's half
    # overwritten ones (it returned a solution of neither matrix) may answer a solve
    A, x = _spd_system(12)
    A = sp.triu(A, format="csr") if backend == "pardiso" else A.tocsr()
    fac = factorize(A, backend=backend, upper=backend == "pardiso")
    singular = A.copy()
    singular.data = singular.data.copy()
    singular.data[(singular.tocoo().row == 0) | (singular.indices == 0)] = 0.0   # row and column 0
    with pytest.raises(SolverError):
        fac.refactor(singular)
    with pytest.raises(SolverError, match="last refactor failed"):
        fac.solve(x[:, 0])
    fac.refactor(A)                           # valid values make it usable again
    whole = A + sp.triu(A, k=1).T if backend == "pardiso" else A
    assert np.abs(fac.solve(whole @ x) - x).max() < 1e-9 * np.abs(x).max()


@pytest.mark.parametrize("backend", every_backend())
def test_solve_refuses_a_complex_or_misshapen_right_hand_side(backend):
    A, x = _spd_system(8)
    fac = factorize(A, backend=backend)
    n = A.shape[0]
    with pytest.raises(SolverError, match="complex"):          # was: imaginary part dropped silently
        fac.solve(np.ones(n) * 1j)
    with pytest.raises(SolverError, match=r"shape \(\)"):      # was: IndexError
        fac.solve(1.0)
    with pytest.raises(SolverError, match=r"\(n, k\)"):        # was: numpy's reshape error
        fac.solve(np.ones((n, 2, 2)))
    # float32, Fortran order, read-only and zero columns are all fine
    b = np.asfortranarray((A @ x).astype(np.float32))
    b.flags.writeable = False
    assert np.abs(fac.solve(b) - x).max() < 1e-4 * np.abs(x).max()
    assert fac.solve(np.ones((n, 0))).shape == (n, 0)


@_needs_pardiso
def test_pending_factorization_of_a_pattern_with_unsorted_rows_solves_like_factorize():
    # PARDISO needs sorted columns; an unsorted pattern was analysed as it came and the solution
    # was off by the size of the solution (6 x 6), or PARDISO never returned (this 10 x 10 grid:
    # hence a child process with a time limit)
    import subprocess
    import sys

    script = """
import numpy as np, scipy.sparse as sp
from curvdetail.curvature import cotan_laplacian, sparse_solver
from curvdetail.curvature.sparse_solver import SolverError
from curvdetail.curvature.testing import grid
V, F = grid(10, 10)
V[:, 2] = np.sin(3 * V[:, 0]) * V[:, 1]
L = cotan_laplacian(V, F)
inner = np.flatnonzero((V[:, 0] > 0) & (V[:, 0] < 1) & (V[:, 1] > 0) & (V[:, 1] < 1))
A = L[inner][:, inner]
x = np.random.default_rng(3).normal(size=(inner.size, 3))
U = sp.triu(A, format="csr")
U.sort_indices()
order = np.concatenate([np.arange(U.indptr[r], U.indptr[r + 1])[::-1] for r in range(U.shape[0])])
pattern = sp.csr_matrix((np.zeros(U.nnz), U.indices[order], U.indptr), shape=U.shape)
fac = sparse_solver.PendingFactorization(pattern, backend="pardiso").finish(U.data[order])
print(np.abs(fac.solve(A @ x) - x).max() / np.abs(x).max())
try:
    sparse_solver.PendingFactorization(pattern, backend="pardiso").finish(U.data[1:])
except SolverError as e:
    print(e)
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    error, refusal = done.stdout.strip().splitlines()
    assert float(error) < 1e-9
    assert refusal.startswith("finish needs ") and "values, one per stored entry of the pattern" in refusal


@_needs_pardiso
def test_pardiso_refuses_a_matrix_that_needs_64_bit_indices():
    # the int32 copy of an index array with an entry over 2**31 - 1 wrapped around: 2**32 + 1
    # stored entries became 1, and this 1 x 1 "matrix" was factored and solved without a word
    from types import SimpleNamespace

    M = SimpleNamespace(shape=(1, 1), data=np.array([2.0]), indices=np.array([0]),
                        indptr=np.array([0, 2**32 + 1], dtype=np.int64))
    with pytest.raises(_pardiso.PardisoSizeError, match="64-bit indices"):
        _pardiso.PardisoFactor(M, symmetric=True)


@_needs_pardiso
def test_pardiso_factor_without_numeric_factors_refuses_to_solve():
    # a failed numeric factorization (solving then returned neither matrix's solution) and an
    # analysis alone (solving then crashed the process, hence the child process)
    import subprocess
    import sys

    script = """
import numpy as np, scipy.sparse as sp
from curvdetail.curvature._pardiso import PardisoError, PardisoFactor
A = sp.triu(sp.diags([[-1.0] * 5, [3.0] * 6, [-1.0] * 5], [-1, 0, 1]), format="csr")
f = PardisoFactor(A, symmetric=True)
bad = A.data.copy()
bad[A.indices == np.repeat(np.arange(6), np.diff(A.indptr))] = [3, 3, -3, 3, 3, 3]
for make in (lambda: f.factor_values(bad), lambda: None):
    try:
        make()
    except PardisoError:
        pass
    try:
        f.solve(np.ones(6)); print("solved")
    except PardisoError as e:
        print("refused")
    f = PardisoFactor(A, symmetric=True, analyze_only=True)
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    assert done.stdout.split() == ["refused", "refused"]
