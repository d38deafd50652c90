"""Benchmark of QP solvers on relayout sizing problems (bao2013 §7.2).

Problems have the structure the relayout generates: ``min ||x - xbar||^2`` with box bounds, a few equality rows
(alignment prefixes ``sum_{i<v} x_i + l x_v = y``, same-size sums) and the total-size row (``<=`` while
building, ``=`` on completion). Prints the median solve time per solver and size and the largest deviation of
each solver's solution from quadprog's. Solvers that are not installed are skipped.

    python benchmarks/relayout_qp.py
"""
from __future__ import annotations

import time

import numpy as np
import quadprog


def problems(n: int, count: int, rng: np.random.Generator) -> list[tuple]:
    out = []
    for _ in range(count):
        xbar = rng.uniform(0.5, 2.0, n)
        lo, hi = 0.7 * xbar, 1.6 * xbar
        total = float(np.sum(xbar) * rng.uniform(0.9, 1.2))
        m = min(3, n // 3)
        eq = np.zeros((m + 1, n))
        rhs = np.zeros(m + 1)
        for k in range(m):
            v = int(rng.integers(1, n))
            eq[k, :v] = 1.0
            eq[k, v] = 0.5
            rhs[k] = float(np.sum(xbar[:v]) + 0.5 * xbar[v]) * rng.uniform(0.97, 1.03)
        eq[m] = 1.0
        rhs[m] = total
        out.append((xbar, lo, hi, eq, rhs))
    return out


def solve_quadprog(xbar, lo, hi, eq, rhs):
    n = xbar.size
    eye = np.eye(n)
    C = np.vstack([eq, eye, -eye]).T
    b = np.concatenate([rhs, lo, -hi])
    try:
        return quadprog.solve_qp(eye, xbar, C, b, eq.shape[0])[0]
    except ValueError:
        return None


def solve_daqp(xbar, lo, hi, eq, rhs):
    import daqp
    n = xbar.size
    A = np.ascontiguousarray(eq)
    bupper = np.concatenate([hi, rhs])
    blower = np.concatenate([lo, rhs])
    sense = np.concatenate([np.zeros(n, dtype=np.int32), np.full(eq.shape[0], 5, dtype=np.int32)])
    x, _, flag, _ = daqp.solve(np.eye(n), -xbar, A, bupper, blower, sense)
    return x if flag == 1 else None


def solve_clarabel(xbar, lo, hi, eq, rhs):
    import clarabel
    import scipy.sparse as sp
    n = xbar.size
    A = sp.vstack([sp.csc_matrix(eq), sp.identity(n), -sp.identity(n)]).tocsc()
    b = np.concatenate([rhs, hi, -lo])
    cones = [clarabel.ZeroConeT(eq.shape[0]), clarabel.NonnegativeConeT(2 * n)]
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    sol = clarabel.DefaultSolver(sp.identity(n, format="csc"), -xbar, A, b, cones, settings).solve()
    return np.asarray(sol.x) if str(sol.status) == "Solved" else None


def solve_osqp(xbar, lo, hi, eq, rhs):
    import osqp
    import scipy.sparse as sp
    n = xbar.size
    A = sp.vstack([sp.csc_matrix(eq), sp.identity(n)]).tocsc()
    prob = osqp.OSQP()
    prob.setup(sp.identity(n, format="csc"), -xbar, A, np.concatenate([rhs, lo]), np.concatenate([rhs, hi]),
               verbose=False, eps_abs=1e-9, eps_rel=1e-9, polish=True)
    res = prob.solve()
    return res.x if res.info.status == "solved" else None


SOLVERS = {"quadprog": solve_quadprog, "daqp": solve_daqp, "clarabel": solve_clarabel, "osqp": solve_osqp}


def main() -> None:
    rng = np.random.default_rng(1)
    print(f"{'solver':10s} {'n':>4s} {'median us':>10s} {'max |x - x_quadprog|':>22s} {'failed':>7s}")
    for n in (5, 15, 40, 120):
        probs = problems(n, 200, rng)
        ref = [solve_quadprog(*p) for p in probs]
        for name, fn in SOLVERS.items():
            try:
                fn(*probs[0])
            except Exception as exc:  # not installed or API mismatch: report and go on
                print(f"{name:10s} {n:4d} skipped ({type(exc).__name__}: {exc})")
                continue
            times, dev, failed = [], 0.0, 0
            for p, r in zip(probs, ref):
                t = time.perf_counter()
                x = fn(*p)
                times.append(time.perf_counter() - t)
                if x is None or r is None:
                    failed += (x is None) != (r is None)
                    continue
                dev = max(dev, float(np.max(np.abs(np.asarray(x) - r))))
            print(f"{name:10s} {n:4d} {np.median(times) * 1e6:10.1f} {dev:22.2e} {failed:7d}")


if __name__ == "__main__":
    main()
