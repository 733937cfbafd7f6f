"""MKL's sparse BLAS product (used for the rows="all" normal matrix with PARDISO)."""

import importlib

import numpy as np
import pytest
import scipy.sparse as sp

from curvdetail import Reconstructor, available_backends, curvature_detail
from curvdetail.curvature import boundary_vertices
from curvdetail.curvature.testing import grid

reconstruct_module = importlib.import_module("curvdetail.curvature.reconstruct")

pytestmark = pytest.mark.skipif("pardiso" not in available_backends(),
                                reason="the MKL runtime comes with pypardiso (x86-64)")


def test_gram_upper_is_the_upper_triangle_of_the_product():
    from curvdetail.curvature._mkl_sparse import gram_upper

    rng = np.random.default_rng(0)
    A = sp.random(300, 200, density=0.03, random_state=rng, format="csr")
    A = sp.vstack([A, sp.csr_matrix((5, 200))]).tocsr()          # rows with no entries
    A.indices = A.indices.copy()
    for r in range(A.shape[0]):                                   # unsorted rows in the input
        A.indices[A.indptr[r]:A.indptr[r + 1]] = A.indices[A.indptr[r]:A.indptr[r + 1]][::-1]
        A.data[A.indptr[r]:A.indptr[r + 1]] = A.data[A.indptr[r]:A.indptr[r + 1]][::-1]
    A.has_sorted_indices = False
    C = gram_upper(A)
    expected = sp.triu(A @ A.T).toarray()
    assert C.shape == (305, 305)
    assert np.abs(C.toarray() - expected).max() <= 1e-15 * np.abs(expected).max()
    assert all(np.all(np.diff(C.indices[C.indptr[r]:C.indptr[r + 1]]) > 0) for r in range(305))
    rows = np.repeat(np.arange(305), np.diff(C.indptr))
    assert np.all(C.indices >= rows)


def test_gram_upper_sums_duplicate_entries_and_leaves_its_input_alone():
    from curvdetail.curvature._mkl_sparse import gram_upper

    A = sp.csr_matrix((np.array([1.0, 2.0, 3.0]), np.array([1, 0, 1]), np.array([0, 3])), shape=(1, 2))
    stored = (A.indices.copy(), A.data.copy())
    assert gram_upper(A).toarray().tolist() == [[2.0 ** 2 + (1.0 + 3.0) ** 2]]       # the row is (2, 4)
    assert np.array_equal(A.indices, stored[0]) and np.array_equal(A.data, stored[1])


def test_gram_upper_of_an_empty_matrix():
    from curvdetail.curvature._mkl_sparse import gram_upper

    assert gram_upper(sp.csr_matrix((4, 3))).shape == (4, 4)
    assert gram_upper(sp.csr_matrix((4, 3))).nnz == 0


def test_rows_all_with_the_mkl_product_solves_like_scipys(monkeypatch):
    V, F = grid(40, 40)
    V[:, 2] = np.sin(3 * V[:, 0]) * V[:, 1] ** 2
    b = boundary_vertices(F)
    D = curvature_detail(V, F)
    monkeypatch.setattr(reconstruct_module, "MKL_GRAM_MIN_FREE", 10 ** 9)
    plain = Reconstructor(V, F, b, backend="pardiso")
    monkeypatch.setattr(reconstruct_module, "MKL_GRAM_MIN_FREE", 1)
    mkl = Reconstructor(V, F, b, backend="pardiso")
    assert mkl._upper and not plain._upper
    X1, X2 = plain.solve(1.5 * D, 1.5 * V[b]), mkl.solve(1.5 * D, 1.5 * V[b])
    assert np.array_equal(X1, X2)                                 # the same values, bit for bit
    assert np.abs(X2 - 1.5 * V).max() < 1e-12


def test_rows_all_falls_back_to_scipys_product_where_mkl_refuses(monkeypatch):
    from curvdetail.curvature import _mkl_sparse

    def refuse(A):
        raise _mkl_sparse.MklSparseError("MKL sparse BLAS: mkl_sparse_syrk returned status 2")

    monkeypatch.setattr(reconstruct_module, "MKL_GRAM_MIN_FREE", 1)
    monkeypatch.setattr(_mkl_sparse, "gram_upper", refuse)
    V, F = grid(12, 12)
    V[:, 2] = V[:, 0] * V[:, 1]
    b = boundary_vertices(F)
    rec = Reconstructor(V, F, b, backend="pardiso")
    assert not rec._upper
    assert np.abs(rec.solve(curvature_detail(V, F), V[b]) - V).max() < 1e-12


def test_a_missing_or_old_mkl_runtime_is_a_mkl_sparse_error(monkeypatch):
    from curvdetail.curvature import _mkl_sparse

    monkeypatch.setattr(_mkl_sparse, "_library", None)
    monkeypatch.setattr(_mkl_sparse, "_library_path", lambda: "/nonexistent/libmkl_rt.so")
    with pytest.raises(_mkl_sparse.MklSparseError, match="MKL's sparse BLAS is not available"):
        _mkl_sparse.gram_upper(sp.eye(3, format="csr"))
    # and Reconstructor goes on with SciPy's product
    monkeypatch.setattr(reconstruct_module, "MKL_GRAM_MIN_FREE", 1)
    V, F = grid(12, 12)
    V[:, 2] = V[:, 0] ** 2
    b = boundary_vertices(F)
    rec = Reconstructor(V, F, b, backend="pardiso")
    assert not rec._upper and np.abs(rec.solve(curvature_detail(V, F), V[b]) - V).max() < 1e-12


def test_the_bindings_pass_32_bit_indices_even_with_mkl_interface_layer_ilp64():
    # with MKL_INTERFACE_LAYER=ILP64 mkl_rt read the int32 arguments as 64-bit: PARDISO crashed
    # the process and mkl_sparse_syrk refused (status 5); the bindings now fix the LP64 layer
    import os
    import subprocess
    import sys

    script = """
import numpy as np, scipy.sparse as sp
from curvdetail.curvature._mkl_sparse import gram_upper
from curvdetail.curvature.sparse_solver import factorize
A = sp.random(40, 30, density=0.2, random_state=1, format="csr") + sp.eye(40, 30, format="csr")
print(abs(gram_upper(A) - sp.triu(A @ A.T)).max())
M = (A @ A.T + sp.eye(40)).tocsr()
x = np.arange(40.0)
print(np.abs(factorize(M, backend="pardiso").solve(M @ x) - x).max())
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120,
                          env={**os.environ, "MKL_INTERFACE_LAYER": "ILP64"})
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    syrk, solve = map(float, done.stdout.split())
    assert syrk < 1e-12 and solve < 1e-9
