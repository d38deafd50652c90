"""Least squares with linear equality and inequality constraints (§5.3), solved exactly.

``min ||D x - d||^2  s.t.  A x = b,  G x <= h``. The equality-only problem is solved through its sparse KKT
system (:func:`citygen.qp.solve_eq_qp`); when its optimum violates an inequality, the equalities are eliminated
(``x = x0 + N z`` with ``N`` a null-space basis, which also tolerates redundant rows) and the inequality QP goes
to Goldfarb--Idnani's active-set method (:func:`citygen.qp.solve_qp`, quadprog), as the paper's [Bjo88].
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from citygen.qp import QPResult, solve_eq_qp, solve_qp

REG = 1e-9


def solve_lsq(D: sp.csr_matrix, d: np.ndarray, A: sp.csr_matrix, b: np.ndarray, G: sp.csr_matrix,
              h: np.ndarray, tol: float = 1e-7) -> QPResult:
    n = D.shape[1]
    P = 2.0 * (D.T @ D)
    q = -2.0 * (D.T @ d)
    first = solve_eq_qp(P, q, A, b, regularization=REG)
    if first.success and (G.shape[0] == 0 or np.all(G @ first.x <= h + tol)):
        return first
    Ad = A.toarray()
    x0, *_ = np.linalg.lstsq(Ad, b, rcond=None) if Ad.shape[0] else (np.zeros(n),)
    if Ad.shape[0] and np.max(np.abs(Ad @ x0 - b)) > tol * (1 + np.max(np.abs(b))):
        return QPResult(np.full(n, np.nan), False, "infeasible", "equality constraints are inconsistent")
    N = sla.null_space(Ad) if Ad.shape[0] else np.eye(n)
    Dd = D.toarray()
    Gd0 = G.toarray()
    if N.shape[1] == 0:   # the equalities fix every variable
        ok = bool(np.all(Gd0 @ x0 <= h + tol))
        return QPResult(x0, ok, "solved" if ok else "infeasible", "determined by the equalities",
                        float(np.sum((Dd @ x0 - d) ** 2)))
    DN = Dd @ N
    Pz = 2.0 * DN.T @ DN
    qz = -2.0 * DN.T @ (d - Dd @ x0)
    Gd = G.toarray()
    res = solve_qp(Pz, qz, G=Gd @ N, h=h - Gd @ x0, regularization=1e-8)
    if not res.success:
        return QPResult(np.full(n, np.nan), False, res.status, res.message)
    x = x0 + N @ res.x
    return QPResult(x, True, "solved", "optimal (active set)", float(np.sum((Dd @ x - d) ** 2)))
