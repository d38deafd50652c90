"""The sizing QP of bao2013 §7.2: ``argmin sum (x_i - xbar_i)^2`` under the newly active linear constraints.

Solved with the Goldfarb-Idnani dual active-set method (``quadprog``, as in the paper); the choice is measured
in ``benchmarks/relayout_qp.py``. Problems are tiny (one variable per element of one arrangement) and dense, so
the solver is called directly on dense arrays rather than through :func:`citygen.qp.solve_qp`, which would
rebuild and regularise them on every call.
"""
from __future__ import annotations

import numpy as np
import quadprog


def solve_sizes(xbar: np.ndarray, lo: np.ndarray, hi: np.ndarray, eq: np.ndarray, eq_rhs: np.ndarray,
                le: np.ndarray, le_rhs: np.ndarray) -> np.ndarray | None:
    """Sizes closest to ``xbar`` with ``lo <= x <= hi``, ``eq @ x = eq_rhs``, ``le @ x <= le_rhs``; None if
    infeasible. ``eq`` and ``le`` are ``(m, n)`` arrays."""
    n = xbar.size
    eye = np.eye(n)
    C = np.vstack([eq, -le, eye, -eye]).T
    b = np.concatenate([eq_rhs, -le_rhs, lo, -hi])
    try:
        x = quadprog.solve_qp(eye, xbar, C, b, eq.shape[0])[0]
    except ValueError:  # inconsistent constraints, or linearly dependent equality rows
        if eq.shape[0] < 2:
            return None
        keep = _independent_rows(eq, eq_rhs)
        if keep.size == eq.shape[0]:
            return None
        C = np.vstack([eq[keep], -le, eye, -eye]).T
        b = np.concatenate([eq_rhs[keep], -le_rhs, lo, -hi])
        try:
            x = quadprog.solve_qp(eye, xbar, C, b, keep.size)[0]
        except ValueError:
            return None
    tol = 1e-7 * (1.0 + float(np.max(np.abs(b), initial=0.0)))
    if eq.shape[0] and np.max(np.abs(eq @ x - eq_rhs)) > tol:
        return None
    if np.any(x < lo - tol) or np.any(x > hi + tol) or (le.shape[0] and np.any(le @ x > le_rhs + tol)):
        return None
    return np.clip(x, lo, hi)


def _independent_rows(eq: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Indices of a maximal linearly independent subset of the equality rows (pivoted QR)."""
    from scipy.linalg import qr

    aug = np.column_stack([eq, rhs])
    _, r, piv = qr(aug.T, pivoting=True, mode="economic")
    diag = np.abs(np.diag(r))
    rank = int(np.sum(diag > 1e-9 * max(1.0, float(diag[0]) if diag.size else 1.0)))
    return np.sort(piv[:rank])
