"""The sizing QP of bao2013 §7.2: ``argmin sum w_i (x_i - xbar_i)^2`` under the newly active linear constraints.

The paper solves it with Goldfarb-Idnani (``quadprog`` here). ``benchmarks/relayout_qp.py`` measures it
against DAQP, a maintained dual active-set solver with native box bounds that also accepts linearly dependent
(consistent) equality rows; DAQP is the default (faster from ~15 variables on, equal below), quadprog stays
selectable (``METHOD``) for comparison. Problems are tiny and dense, so the solver is called on dense arrays
directly rather than through :func:`citygen.qp.solve_qp`, which would rebuild them on every call.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

try:
    import daqp
except ImportError:  # pragma: no cover - daqp is a declared dependency; quadprog remains usable without it
    daqp = None
import quadprog

METHOD = "daqp" if daqp is not None else "quadprog"
_EQ = 5  # DAQP constraint sense: ACTIVE | IMMUTABLE (an equality)


def solve_sizes(xbar: np.ndarray, lo: Sequence[float], hi: Sequence[float], rows: Sequence[Sequence[float]],
                rhs: Sequence[float], eqs: int, weights: np.ndarray | None = None) -> np.ndarray | None:
    """Sizes closest to ``xbar`` with ``lo <= x <= hi`` and ``rows @ x = rhs`` for the first ``eqs`` rows,
    ``rows @ x <= rhs`` for the others; None if infeasible. ``rows`` is ``(m, n)`` (nested lists or an array);
    ``weights`` (default 1) weight the squared deviations. The problems are tiny (a few variables, a few dozen
    rows), so the bounds and the solution are checked in plain floats, which numpy would only slow down."""
    n = xbar.size
    w = np.ones(n) if weights is None else weights
    if any(a > b + 1e-12 for a, b in zip(lo, hi)):
        return None
    A = np.array(rows, dtype=float).reshape(-1, n)
    upper = np.array([*hi, *rhs], dtype=float)  # the bounds of x, then of the rows (DAQP's layout)
    lower = np.array([*lo, *rhs[:eqs], *[-1e30] * (len(rhs) - eqs)], dtype=float)
    x = _daqp(xbar, lower, upper, A, eqs, w) if METHOD == "daqp" else _quadprog(xbar, lower, upper, A, eqs, w)
    if x is None:
        return None
    tol = 1e-7 * (1.0 + max([0.0, *map(abs, rhs[:eqs])]) + max([0.0, *map(abs, hi)]))
    if any(v < a - tol or v > b + tol for v, a, b in zip(x.tolist(), lo, hi)):
        return None
    if eqs and any(abs(v - b) > tol for v, b in zip((A[:eqs] @ x).tolist(), rhs)):
        return None
    if eqs < len(rhs) and any(v > b + tol for v, b in zip((A[eqs:] @ x).tolist(), rhs[eqs:])):
        return None
    return x.clip(lower[:n], upper[:n])


def _daqp(xbar, lower, upper, A, eqs, w) -> np.ndarray | None:
    n = xbar.size
    sense = np.zeros(upper.size, dtype=np.int32)
    sense[n:n + eqs] = _EQ
    x, _, flag, _ = daqp.solve(np.diag(w), -w * xbar, A, upper, lower, sense)
    return x if flag == 1 else None


def _quadprog(xbar, lower, upper, A, eqs, w) -> np.ndarray | None:
    n = xbar.size
    eye = np.eye(n)
    C = np.vstack([A[:eqs], -A[eqs:], eye, -eye]).T
    b = np.concatenate([lower[n:n + eqs], -upper[n + eqs:], lower[:n], -upper[:n]])
    try:
        return quadprog.solve_qp(np.diag(w), w * xbar, C, b, eqs)[0]
    except ValueError:  # inconsistent constraints, or linearly dependent equality rows
        return None
