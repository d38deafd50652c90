"""Quadratic programs for the sizing steps of every ruleset kind.

``minimize 1/2 x'Px + q'x  s.t.  A x = b,  G x <= h``

Dense problems go to Goldfarb--Idnani (``quadprog``, as in bao2013); problems with only equality constraints are
solved exactly through their KKT system with a sparse LU (``scipy.sparse.linalg``), which is what the big
relayouts and layer stacks need. Every call returns a :class:`QPResult` (scipy's ``OptimizeResult`` style)
rather than raising on infeasibility.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import quadprog
import scipy.sparse as sp
import scipy.sparse.linalg as spla


@dataclass(frozen=True)
class QPResult:
    """Outcome of a QP: ``x`` is meaningful only when ``success``."""

    x: np.ndarray
    success: bool
    status: str
    message: str
    objective: float = float("nan")


def _dense(m: object | None, n: int) -> np.ndarray:
    if m is None:
        return np.zeros((0, n))
    if sp.issparse(m):
        return m.toarray()
    return np.atleast_2d(np.asarray(m, dtype=float)).reshape(-1, n)


def solve_qp(P: np.ndarray | sp.spmatrix, q: np.ndarray, A: np.ndarray | sp.spmatrix | None = None,
             b: np.ndarray | None = None, G: np.ndarray | sp.spmatrix | None = None,
             h: np.ndarray | None = None, *, regularization: float = 1e-9) -> QPResult:
    """Solve the QP; ``P`` is made strictly positive definite by ``regularization`` (quadprog requires it)."""
    q = np.asarray(q, dtype=float)
    n = q.size
    has_ineq = G is not None and (G.shape[0] if hasattr(G, "shape") else len(G)) > 0
    if not has_ineq:
        return solve_eq_qp(P, q, A, b, regularization=regularization)
    Pd = _dense(P, n) + regularization * np.eye(n)
    Ad, Gd = _dense(A, n), _dense(G, n)
    bd = np.zeros(0) if b is None else np.asarray(b, dtype=float).ravel()
    hd = np.asarray(h, dtype=float).ravel()
    C = np.vstack([Ad, -Gd]).T
    rhs = np.concatenate([bd, -hd])
    try:
        x, obj, *_ = quadprog.solve_qp(Pd, -q, C, rhs, Ad.shape[0])
    except ValueError as exc:  # quadprog signals infeasibility / non-PD matrices this way
        return QPResult(np.full(n, np.nan), False, "infeasible", str(exc))
    return QPResult(x, True, "solved", "optimal", float(obj))


def solve_eq_qp(P: np.ndarray | sp.spmatrix, q: np.ndarray, A: np.ndarray | sp.spmatrix | None = None,
                b: np.ndarray | None = None, *, regularization: float = 1e-9) -> QPResult:
    """Equality-constrained QP via the sparse KKT system ``[[P, A'], [A, -dI]] [x; y] = [-q; b]``.

    Redundant equality rows (common when constraints are generated per region) are tolerated through the small
    dual regularisation; an inconsistent system is reported, not raised.
    """
    q = np.asarray(q, dtype=float)
    n = q.size
    Ps = sp.csc_matrix(P) + regularization * sp.identity(n, format="csc")
    if A is None or A.shape[0] == 0:
        x = spla.spsolve(Ps, -q)
        return QPResult(np.atleast_1d(x), True, "solved", "optimal", float(0.5 * x @ (Ps @ x) + q @ x))
    As = sp.csc_matrix(A)
    bvec = np.asarray(b, dtype=float).ravel()
    K = _kkt_matrix(Ps, As, regularization)
    rhs = np.concatenate([-q, bvec])
    try:
        sol = spla.splu(K).solve(rhs)
    except RuntimeError as exc:
        return QPResult(np.full(n, np.nan), False, "singular", str(exc))
    x = sol[:n]
    residual = float(np.max(np.abs(As @ x - bvec), initial=0.0))
    scale = 1.0 + float(np.max(np.abs(bvec), initial=0.0))
    if not np.all(np.isfinite(x)) or residual > 1e-6 * scale:
        return QPResult(x, False, "infeasible", f"equality constraints inconsistent (residual {residual:.3g})")
    return QPResult(x, True, "solved", "optimal", float(0.5 * x @ (Ps @ x) + q @ x))


def _kkt_matrix(Ps: sp.csc_matrix, As: sp.csc_matrix, regularization: float) -> sp.csc_matrix:
    """``[[Ps, As'], [As, -dI]]`` in canonical CSC form: the arrays ``sp.bmat`` returns for it (so the same
    factorisation), assembled from index arrays without bmat's per-block conversions (3x faster on the
    small systems of layer stacks)."""
    n, m = Ps.shape[0], As.shape[0]
    if not As.has_canonical_format:
        As = As.copy()
        As.sum_duplicates()
    ps_cols = np.repeat(np.arange(n), np.diff(Ps.indptr))
    as_cols = np.repeat(np.arange(n), np.diff(As.indptr))
    diag = np.arange(n, n + m)
    cols = np.concatenate([ps_cols, as_cols, n + As.indices, diag])
    rows = np.concatenate([Ps.indices, n + As.indices, as_cols, diag])
    data = np.concatenate([Ps.data, As.data, As.data, np.full(m, -regularization)])
    order = np.lexsort((rows, cols))
    indptr = np.concatenate([[0], np.cumsum(np.bincount(cols, minlength=n + m))])
    return sp.csc_matrix((data[order], rows[order], indptr), shape=(n + m, n + m))
