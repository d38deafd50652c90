"""The equality-constrained QP's KKT system (citygen.qp)."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from citygen.qp import _kkt_matrix, solve_eq_qp


def _random_blocks(seed: int) -> tuple[sp.csc_matrix, sp.csc_matrix]:
    rng = np.random.default_rng(seed)
    n, m = int(rng.integers(1, 30)), int(rng.integers(1, 20))
    D = sp.random(n + 5, n, density=0.3, random_state=seed, format="csr")
    Ps = sp.csc_matrix(2.0 * (D.T @ D)) + 1e-9 * sp.identity(n, format="csc")   # unsorted indices, as in a solve
    # duplicates, explicit zeros and empty rows/columns in the constraints
    k = int(rng.integers(0, 3 * n))
    rows, cols = rng.integers(0, m, k), rng.integers(0, n, k)
    vals = rng.choice([0.0, 1.0, -1.0, 0.1, 2.5], k)
    if seed % 2:    # non-canonical: unsorted, duplicate row indices within a column
        order = np.argsort(cols, kind="stable")
        indptr = np.searchsorted(cols[order], np.arange(n + 1))
        As = sp.csc_matrix((vals[order], rows[order], indptr), shape=(m, n))
    else:
        As = sp.csc_matrix((vals, (rows, cols)), shape=(m, n))
    return Ps, As


@pytest.mark.parametrize("seed", range(40))
def test_kkt_matrix_is_bmat_exactly(seed):
    """Regression (layer-stack speed-up): the directly assembled KKT matrix has bmat's arrays bit for bit, so
    the LU factorisation and every solve are unchanged."""
    Ps, As = _random_blocks(seed)
    expected = sp.bmat([[Ps, As.T], [As, -1e-9 * sp.identity(As.shape[0])]], format="csc")
    got = _kkt_matrix(Ps, As, 1e-9)
    assert np.array_equal(got.indptr, expected.indptr)
    assert np.array_equal(got.indices, expected.indices)
    assert got.data.tobytes() == expected.data.tobytes()


def test_kkt_matrix_sums_duplicate_constraint_entries():
    Ps = sp.identity(2, format="csc")
    As = sp.csc_matrix((np.array([1.0, 2.0, 3.0]), np.array([0, 0, 0]), np.array([0, 2, 3])), shape=(1, 2))
    K = _kkt_matrix(Ps, As, 0.5).toarray()
    assert K.tolist() == [[1.0, 0.0, 3.0], [0.0, 1.0, 3.0], [3.0, 3.0, -0.5]]


def test_solve_eq_qp_meets_equalities():
    P = sp.identity(3, format="csc")
    q = np.array([-1.0, -2.0, -3.0])
    A = sp.csr_matrix(np.array([[1.0, 1.0, 1.0]]))
    res = solve_eq_qp(P, q, A, np.array([3.0]))
    assert res.success
    assert np.allclose(res.x, [0.0, 1.0, 2.0], atol=1e-6)
