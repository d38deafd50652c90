"""The sizing QP of bao2013 §7.2: ``argmin sum w_i (x_i - xbar_i)^2`` under the newly active linear constraints.

The paper solves it with Goldfarb-Idnani (``quadprog`` here). ``benchmarks/relayout_qp.py`` measures it
against DAQP, a maintained dual active-set solver with native box bounds that also accepts linearly dependent
(consistent) equality rows; DAQP is the default (faster from ~15 variables on, equal below), quadprog stays
selectable (``METHOD``) for comparison. Problems are tiny and dense, so the solver is called on dense arrays
directly rather than through :func:`citygen.qp.solve_qp`, which would rebuild them on every call.
"""
from __future__ import annotations

import numpy as np

try:
    import daqp
except ImportError:  # pragma: no cover - daqp is a declared dependency; quadprog remains usable without it
    daqp = None
import quadprog

METHOD = "daqp" if daqp is not None else "quadprog"
_EQ = 5  # DAQP constraint sense: ACTIVE | IMMUTABLE (an equality)


def solve_sizes(xbar: np.ndarray, lo: np.ndarray, hi: np.ndarray, eq: np.ndarray, eq_rhs: np.ndarray,
                le: np.ndarray, le_rhs: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray | None:
    """Sizes closest to ``xbar`` with ``lo <= x <= hi``, ``eq @ x = eq_rhs``, ``le @ x <= le_rhs``; None if
    infeasible. ``eq`` and ``le`` are ``(m, n)`` arrays; ``weights`` (default 1) weight the squared deviations."""
    n = xbar.size
    w = np.ones(n) if weights is None else weights
    if np.any(lo > hi + 1e-12):
        return None
    x = _daqp(xbar, lo, hi, eq, eq_rhs, le, le_rhs, w) if METHOD == "daqp" else \
        _quadprog(xbar, lo, hi, eq, eq_rhs, le, le_rhs, w)
    if x is None:
        return None
    tol = 1e-7 * (1.0 + float(np.max(np.abs(eq_rhs), initial=0.0)) + float(np.max(np.abs(hi), initial=0.0)))
    if (eq.shape[0] and np.max(np.abs(eq @ x - eq_rhs)) > tol) or np.any(x < lo - tol) or np.any(x > hi + tol) \
            or (le.shape[0] and np.any(le @ x > le_rhs + tol)):
        return None
    return np.clip(x, lo, hi)


def _daqp(xbar, lo, hi, eq, eq_rhs, le, le_rhs, w) -> np.ndarray | None:
    n = xbar.size
    A = np.ascontiguousarray(np.vstack([eq, le]))
    upper = np.concatenate([hi, eq_rhs, le_rhs])
    lower = np.concatenate([lo, eq_rhs, np.full(le.shape[0], -1e30)])
    sense = np.zeros(n + A.shape[0], dtype=np.int32)
    sense[n:n + eq.shape[0]] = _EQ
    x, _, flag, _ = daqp.solve(np.diag(w), -w * xbar, A, upper, lower, sense)
    return x if flag == 1 else None


def _quadprog(xbar, lo, hi, eq, eq_rhs, le, le_rhs, w) -> np.ndarray | None:
    n = xbar.size
    eye = np.eye(n)
    C = np.vstack([eq, -le, eye, -eye]).T
    b = np.concatenate([eq_rhs, -le_rhs, lo, -hi])
    try:
        return quadprog.solve_qp(np.diag(w), w * xbar, C, b, eq.shape[0])[0]
    except ValueError:  # inconsistent constraints, or linearly dependent equality rows
        return None
