"""sparse_solver: every installed backend solves, agrees, factors once; choice and errors."""

import platform

import numpy as np
import pytest
import scipy.sparse as sp

from curvdetail import available_backends
from curvdetail.curvature import sparse_solver
from curvdetail.curvature.sparse_solver import SolverError, factorize, resolve_backend
from curvdetail.curvature.testing import grid
from curvdetail.curvature.cotan_laplacian import cotan_laplacian

from conftest import every_backend

_needs_pardiso = pytest.mark.skipif("pardiso" not in available_backends(), reason="PARDISO (pypardiso) not installed")


def _spd_system(nx=30):
    """Free-row block of a grid Laplacian (SPD) and a known solution."""
    V, F = grid(nx, nx)
    V[:, 2] = np.sin(3 * V[:, 0]) * V[:, 1]
    L = cotan_laplacian(V, F)
    inner = np.flatnonzero((V[:, 0] > 0) & (V[:, 0] < 1) & (V[:, 1] > 0) & (V[:, 1] < 1))
    A = L[inner][:, inner].tocsr()
    x = np.random.default_rng(3).normal(size=(inner.size, 3))
    return A, x


def _nonsymmetric(A):
    return (A + sp.diags(np.linspace(0, 0.5, A.shape[0])) @ abs(sp.triu(A, 1))).tocsr()


@pytest.mark.skipif(platform.machine() not in ("x86_64", "AMD64"),
                    reason="pypardiso is a dependency on x86-64 only")
def test_pardiso_is_available_where_it_is_a_dependency():
    # a broken MKL runtime would otherwise drop "pardiso" from every backend-parametrized test
    assert "pardiso" in available_backends()


@pytest.mark.parametrize("backend", every_backend())
def test_solves_an_spd_system_to_rounding(backend):
    A, x = _spd_system()
    fac = factorize(A, symmetric=True, backend=backend)
    assert fac.backend == backend
    # cond(A) ~ 1e3 here: the error is ~1e-13 relative
    assert np.abs(fac.solve(A @ x) - x).max() < 1e-10 * np.abs(x).max()


@pytest.mark.parametrize("backend", every_backend(exclude=("cholmod",)))
def test_solves_a_nonsymmetric_system(backend):
    A, x = _spd_system()
    A = _nonsymmetric(A)
    fac = factorize(A, symmetric=False, backend=backend)
    assert np.abs(fac.solve(A @ x) - x).max() < 1e-10 * np.abs(x).max()


@pytest.mark.parametrize("backend", every_backend())
def test_backends_agree_with_a_dense_solve(backend):
    # the reference is numpy's dense LU, not one of the backends
    A, x = _spd_system(45)
    b = A @ x
    ref = np.linalg.solve(A.toarray(), b)
    assert np.abs(factorize(A, backend=backend).solve(b) - ref).max() < 1e-9 * np.abs(ref).max()


@_needs_pardiso
@pytest.mark.parametrize("symmetric", [True, False])
def test_pardiso_parallel_ordering_solves_the_same(monkeypatch, symmetric):
    # large systems are ordered with parallel METIS; lower the threshold to take that path here
    monkeypatch.setattr(sparse_solver, "PARALLEL_ORDERING", 10)
    A, x = _spd_system()
    A = A if symmetric else _nonsymmetric(A)
    fac = factorize(A, symmetric=symmetric, backend="pardiso")
    assert fac._pardiso.iparm[1] == 3
    assert np.abs(fac.solve(A @ x) - x).max() < 1e-9 * np.abs(x).max()


@pytest.mark.parametrize("backend", every_backend())
def test_solve_keeps_the_shape_and_takes_any_layout_of_the_right_hand_side(backend):
    A, x = _spd_system(12)
    fac = factorize(A, backend=backend)
    n = A.shape[0]
    assert fac.solve(A @ x[:, 0]).shape == (n,)
    assert fac.solve(np.zeros((n, 0))).shape == (n, 0)
    # float32, Fortran order and read-only are all fine
    b = np.asfortranarray((A @ x).astype(np.float32))
    b.flags.writeable = False
    assert np.abs(fac.solve(b) - x).max() < 1e-4 * np.abs(x).max()


@pytest.mark.parametrize("backend", every_backend())
def test_upper_triangle_input_solves_like_the_whole_matrix(backend):
    A, x = _spd_system(30)
    fac = factorize(sp.triu(A, format="csr"), backend=backend, upper=True)
    assert fac.backend == backend
    assert np.abs(fac.solve(A @ x) - x).max() < 1e-9 * np.abs(x).max()


def test_upper_triangle_input_needs_a_symmetric_matrix():
    A, _ = _spd_system(5)
    with pytest.raises(SolverError) as e:
        factorize(sp.triu(A), symmetric=False, upper=True)
    assert e.value.parameter == "upper"


@_needs_pardiso
def test_pardiso_refuses_an_empty_row_instead_of_crashing():
    A = sp.csr_matrix(np.diag([2.0, 0.0, 3.0]))
    A.eliminate_zeros()
    with pytest.raises(SolverError) as e:
        factorize(A, backend="pardiso")
    assert e.value.parameter == "A"


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


@_needs_pardiso
def test_dropping_a_pardiso_factorization_releases_mkls_memory(monkeypatch):
    import gc

    import pypardiso

    released = []
    monkeypatch.setattr(pypardiso.PyPardisoSolver, "free_memory",
                        lambda self, everything=False: released.append((self, everything)))
    A, x = _spd_system(12)
    fac = factorize(A, backend="pardiso")
    fac.solve(A @ x)
    solver = fac._pardiso
    del fac
    gc.collect()
    assert (solver, True) in released


def test_auto_picks_splu_below_the_small_system_size(monkeypatch):
    monkeypatch.delenv("CURVDETAIL_SOLVER", raising=False)
    small = sparse_solver.SMALL_SYSTEM_NNZ - 1
    assert resolve_backend("auto", nnz=small) == "splu"
    assert resolve_backend("auto", nnz=small + 1) == available_backends()[0]
    assert resolve_backend("auto") == available_backends()[0]            # size unknown: a large one
    A, _ = _spd_system(12)
    assert factorize(A).backend == "splu"
    # CHOLMOD is passed over for a nonsymmetric system
    monkeypatch.setattr(sparse_solver, "available_backends", lambda: ["cholmod", "splu"])
    assert resolve_backend("auto", symmetric=True) == "cholmod"
    assert resolve_backend("auto", symmetric=False) == "splu"


@pytest.mark.parametrize("nx, expected", [(100, "splu"), (141, None), (200, None)])
def test_auto_solves_a_10k_vertex_laplacian_single_threaded_and_a_20k_one_with_the_first_backend(
        monkeypatch, nx, expected):
    # docs/results/small_solves.md: at 10k vertices SuperLU's one thread re-solves as fast as
    # PARDISO on an idle machine and ~13x faster beside two busy processes; from 20k PARDISO wins
    monkeypatch.delenv("CURVDETAIL_SOLVER", raising=False)
    V, F = grid(nx, nx)
    inner = np.flatnonzero((V[:, 0] > 0) & (V[:, 0] < 1) & (V[:, 1] > 0) & (V[:, 1] < 1))
    A = cotan_laplacian(V, F)[inner][:, inner]
    assert resolve_backend("auto", nnz=A.nnz) == (expected or available_backends()[0])


def test_environment_variable_overrides_auto_and_a_named_backend_overrides_it(monkeypatch):
    monkeypatch.setenv("CURVDETAIL_SOLVER", " SPLU")
    assert resolve_backend("auto") == resolve_backend(None) == "splu"
    monkeypatch.setenv("CURVDETAIL_SOLVER", "auto")
    assert resolve_backend("auto", nnz=10) == "splu"
    monkeypatch.setenv("CURVDETAIL_SOLVER", "umfpack")
    assert resolve_backend("splu") == "splu"
    with pytest.raises(SolverError) as e:                 # where the name came from
        resolve_backend("auto")
    assert e.value.parameter == "CURVDETAIL_SOLVER" and e.value.value == "umfpack"


@pytest.mark.parametrize("name", ["SPLU", " splu", "Splu "])
def test_backend_names_are_case_insensitive(monkeypatch, name):
    monkeypatch.delenv("CURVDETAIL_SOLVER", raising=False)
    assert resolve_backend(name) == "splu"


@pytest.mark.parametrize("backend", [np.array(["splu"]), np.array(["splu", "pardiso"]), ["splu"], 3])
def test_a_backend_that_is_not_one_str_is_refused(backend):
    with pytest.raises(SolverError) as e:
        resolve_backend(backend)
    assert e.value.parameter == "backend" and e.value.value is backend


@pytest.mark.parametrize("name", ["umfpack", "banded", " Banded"])
def test_an_unknown_backend_name_is_refused(monkeypatch, name):
    monkeypatch.delenv("CURVDETAIL_SOLVER", raising=False)
    with pytest.raises(SolverError) as e:
        resolve_backend(name)
    assert e.value.parameter == "backend" and e.value.value == name.strip().lower()


def test_missing_backend_is_refused(monkeypatch):
    monkeypatch.setattr(sparse_solver, "available_backends", lambda: ["splu"])
    for name in ("pardiso", "cholmod"):
        with pytest.raises(SolverError) as e:
            resolve_backend(name)
        assert e.value.parameter == "backend" and e.value.value == name


def test_cholmod_is_refused_for_nonsymmetric_systems(monkeypatch):
    monkeypatch.setattr(sparse_solver, "available_backends", lambda: ["cholmod", "splu"])
    with pytest.raises(SolverError) as e:
        resolve_backend("cholmod", symmetric=False)
    assert e.value.parameter == "backend" and e.value.value == "cholmod"


@pytest.mark.parametrize("backend", every_backend())
def test_singular_matrix_is_reported_not_returned_as_nan(backend):
    A, _ = _spd_system(8)
    A = A.tolil()
    A[3, :] = 0.0
    A[:, 3] = 0.0
    with pytest.raises(SolverError):
        factorize(A.tocsr(), backend=backend).solve(np.ones(A.shape[0]))


def test_non_square_matrix_is_refused():
    with pytest.raises(SolverError) as e:
        factorize(sp.eye(3, 4))
    assert e.value.parameter == "A" and e.value.value == (3, 4)


@pytest.mark.parametrize("backend", every_backend())
@pytest.mark.parametrize("rhs", [lambda n: np.ones(5), lambda n: np.ones(n) * 1j, lambda n: 1.0,
                                 lambda n: np.ones((n, 2, 2))])
def test_solve_refuses_a_complex_or_misshapen_right_hand_side(backend, rhs):
    A, _ = _spd_system(8)
    b = rhs(A.shape[0])
    with pytest.raises(SolverError) as e:
        factorize(A, backend=backend).solve(b)
    assert e.value.parameter == "b" and e.value.value == np.shape(b)


def test_docstring_examples_run():
    import doctest

    result = doctest.testmod(sparse_solver, optionflags=doctest.ELLIPSIS)
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
    assert np.abs(fac.solve(B @ x) - x).max() < 1e-9 * np.abs(x).max()


@pytest.mark.parametrize("backend", every_backend())
def test_refactor_refuses_another_pattern_or_shape(backend):
    A, x = _spd_system(12)
    fac = factorize(A, backend=backend)
    other = (A + sp.eye(A.shape[0], k=5)).tocsr()
    for wrong in (other + other.T, sp.eye(3)):
        with pytest.raises(SolverError) as e:
            fac.refactor(wrong)
        assert e.value.parameter == "A"
    assert np.abs(fac.solve(A @ x) - x).max() < 1e-10 * np.abs(x).max()    # still the first factors


@pytest.mark.parametrize("backend", every_backend())
def test_a_failed_refactor_leaves_no_factors_to_solve_with(backend):
    # neither the old factors (another matrix) nor PARDISO's half overwritten ones may answer
    A, x = _spd_system(12)
    fac = factorize(A, backend=backend)
    singular = A.copy()
    singular.data = np.where((singular.tocoo().row == 0) | (singular.indices == 0), 0.0, singular.data)
    with pytest.raises(SolverError):
        fac.refactor(singular)
        fac.solve(x)                 # PARDISO may factor it and find the NaNs in the solve
    with pytest.raises(SolverError):
        fac.solve(A @ x)
    fac.refactor(A)                  # valid values make it usable again
    assert np.abs(fac.solve(A @ x) - x).max() < 1e-9 * np.abs(x).max()


def _nearly_singular_nonsymmetric():
    """A 50 x 50 nonsymmetric matrix whose row 7 is twice row 3 plus 1e-13 on the diagonal
    (condition number 2e14), a right-hand side and numpy's dense solution."""
    A = (sp.random(50, 50, density=0.2, random_state=1) + 3.0 * sp.eye(50)).tolil()
    A[7, :] = A[3, :] * 2
    A[7, 7] += 1e-13
    A = A.tocsr()
    b = np.random.default_rng(0).normal(size=50)
    return A, b, np.linalg.solve(A.toarray(), b)


@_needs_pardiso
def test_pardiso_perturbed_pivots_are_not_taken_for_a_solution(monkeypatch):
    # PARDISO replaced a pivot by 1e-13 (iparm[13] = 1) and its solution was 14 % off the dense
    # one; SuperLU's with partial pivoting is 9e-5 off (cond 2e14: the problem's own sensitivity)
    A, b, dense = _nearly_singular_nonsymmetric()
    with pytest.raises(SolverError) as e:
        factorize(A, symmetric=False, backend="pardiso")
    assert e.value.count == 1 and e.value.parameter == "backend"
    monkeypatch.delenv("CURVDETAIL_SOLVER", raising=False)
    monkeypatch.setattr(sparse_solver, "SMALL_SYSTEM_NNZ", 0)         # "auto" picks PARDISO first
    fac = factorize(A, symmetric=False)
    assert fac.backend == "splu"
    assert np.abs(fac.solve(b) - dense).max() < 1e-3 * np.abs(dense).max()
    fac.refactor(A)                                                    # still with pivoting
    assert np.abs(fac.solve(b) - dense).max() < 1e-3 * np.abs(dense).max()
    B = (A + 5.0 * sp.eye(50)).tocsr()                                 # an ordinary matrix stays
    assert factorize(B, symmetric=False).backend == "pardiso"


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
V, F = grid(60, 60)
V[:, 2] = np.sin(5 * V[:, 0]) * V[:, 1]
L = cotan_laplacian(V, F)
inner = np.flatnonzero((V[:, 0] > 0) & (V[:, 0] < 1) & (V[:, 1] > 0) & (V[:, 1] < 1))
A = L[inner][:, inner].tocsr()
if sys.argv[2] == "nonsymmetric":
    A = (A + sp.diags(np.linspace(0, 0.5, A.shape[0])) @ abs(sp.triu(A, 1))).tocsr()
fac = factorize(A, symmetric=sys.argv[2] == "symmetric", backend=sys.argv[1])
rhs = [np.random.default_rng(k).normal(size=(A.shape[0], 1 + k % 3)) for k in range(4)]
serial = [fac.solve(b) for b in rhs]
with ThreadPoolExecutor(4) as pool:
    threaded = list(pool.map(lambda k: fac.solve(rhs[k % 4]), range(200)))
print(max(np.abs(x - serial[k % 4]).max() / np.abs(serial[k % 4]).max() for k, x in enumerate(threaded)))
""".replace("import numpy as np", "import numpy as np\nimport scipy.sparse as sp")


@pytest.mark.slow
@pytest.mark.parametrize("symmetric", [True, False])
@pytest.mark.parametrize("backend", every_backend(exclude=("cholmod",)))
def test_threads_sharing_one_factorization_solve_as_serial_solves(backend, symmetric):
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", _SHARED_FACTOR_SCRIPT, backend,
                           "symmetric" if symmetric else "nonsymmetric"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    # the same factor and right-hand sides: the same answers, whichever thread solved them
    assert float(done.stdout.split()[-1]) < 1e-12
