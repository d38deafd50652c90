"""Least squares with linear equality and inequality constraints (§5.3), solved exactly.

``min ||D x - d||^2  s.t.  A x = b,  G x <= h``. The equality-only problem is solved through its sparse KKT
system (:func:`citygen.qp.solve_eq_qp`); when its optimum violates an inequality, the equalities are eliminated
(``x = x0 + N z`` with ``N`` a null-space basis, which also tolerates redundant rows) and the inequality QP goes
to a dual active-set method, as the paper's [Bjo88]: DAQP, with an iteration limit. Goldfarb--Idnani's
(quadprog) cycled without end, in C and beyond any budget, on systems whose storey bands and least sizes are
active together (terraced house 14 x 25.5 m).
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

import daqp

from citygen.qp import QPResult, solve_eq_qp

REG = 1e-9
#: Active-set iterations before a system counts as unsolved (the systems have tens of variables).
ITER_LIMIT = 2000


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
    Gz = np.ascontiguousarray(Gd0 @ N)
    upper = h - Gd0 @ x0
    z, _, flag, _ = daqp.solve(Pz + 1e-8 * np.eye(Pz.shape[0]), qz, Gz, upper, np.full(upper.size, -1e30),
                               np.zeros(upper.size, dtype=np.int32), iter_limit=ITER_LIMIT)
    if flag != 1:
        return QPResult(np.full(n, np.nan), False, "infeasible", f"DAQP exit flag {flag}")
    x = x0 + N @ z
    return QPResult(x, True, "solved", "optimal (active set)", float(np.sum((Dd @ x - d) ** 2)))
