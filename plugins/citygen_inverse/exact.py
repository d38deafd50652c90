"""The cheapest grammar over the candidate rules, as a 0-1 integer program (beyond wu2014).

wu2014 §4 searches with ADP because the space of grammars is too large to enumerate. Over citygen's candidate
rules -- the rules ADP chooses from (``actions.region_actions``) -- a grammar is a choice of one rule per signature
reachable from the facade, and its cost (Eq. 1) counts each chosen rule once however many regions share it.
With y_s = 1 when signature s has a rule and x_sa = 1 when that rule is candidate a::

    min  sum c_sa x_sa
    s.t. sum_a x_sa = y_s                      (a signature with a rule has exactly one)
         sum_{a: t successor of a} x_sa <= y_t  (a rule's non-terminal successors have rules)
         y_root = 1,  x binary

(the second row sums over the candidates of one signature: at most one is chosen, so this is valid and tighter
than one row per candidate). HiGHS (``scipy.optimize.milp``) solves it by branch and bound; its dual bound is a
lower bound on the cost of every grammar over these candidates, so a solution that meets it is optimal (within a
relative gap of 1e-7). A solve that ends is deterministic; one stopped by ``time_limit`` returns the best grammar
found so far, which may differ from machine to machine.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import Bounds, LinearConstraint, milp
from scipy.sparse import csr_matrix

from citygen_inverse.actions import Action


@dataclass(frozen=True)
class ExactResult:
    """The best grammar the solver found (``rules``: signature -> action, None when it found none), its cost, the
    lower bound on every grammar's cost over the candidates (0 when stopped before it had one) and whether the
    grammar is proven optimal."""

    rules: dict[int, Action] | None
    cost: float
    bound: float
    optimal: bool
    stopped: bool  # by the time limit


def solve_exact(search, time_limit: float | None) -> ExactResult:
    """The integer program over every candidate rule of every signature reachable from ``search``'s roots (a
    :class:`~citygen_inverse.search.GrammarSearch` whose candidates are complete, i.e. not a greedy run's)."""
    roots = [s for s in dict.fromkeys(search.roots) if search.index.sigs[s].n > 1]
    order, at = list(roots), {s: i for i, s in enumerate(roots)}
    first, owner, cost = [], [], []  # per signature its first candidate's column; per candidate its signature, C
    pair_rows: dict[tuple[int, int], int] = {}  # (signature, successor) -> row of the successor constraint
    succ_row, succ_col = [], []  # the successor rows each candidate enters
    for i, sig in enumerate(order):  # (grows while it runs: the successors' signatures are appended)
        acts = search.actions(sig)
        first.append(len(cost))
        for k in range(len(acts)):
            owner.append(i)
            cost.append(acts.cost[k])
            for kid in acts.kids(k):
                if kid not in at:
                    at[kid] = len(order)
                    order.append(kid)
                succ_row.append(pair_rows.setdefault((i, at[kid]), len(pair_rows)))
                succ_col.append(len(cost) - 1)
    n_sig, n_act, n_pair = len(order), len(cost), len(pair_rows)
    if n_sig == 0:
        return ExactResult({}, 0.0, 0.0, True, False)
    # variables: x (n_act) then y (n_sig); rows: one per signature (= 0), one per (signature, successor) (<= 0)
    pairs = np.array(list(pair_rows), dtype=np.int64).reshape(-1, 2)
    rows = np.concatenate([owner, np.arange(n_sig), n_sig + np.array(succ_row, dtype=np.int64),
                           n_sig + np.arange(n_pair)])
    cols = np.concatenate([np.arange(n_act), n_act + np.arange(n_sig), succ_col, n_act + pairs[:, 1]])
    vals = np.concatenate([np.ones(n_act), -np.ones(n_sig), np.ones(len(succ_col)), -np.ones(n_pair)])
    matrix = csr_matrix((vals, (rows, cols)), shape=(n_sig + n_pair, n_act + n_sig))
    lower = np.concatenate([np.zeros(n_sig), np.full(n_pair, -np.inf)])
    low_var = np.zeros(n_act + n_sig)
    low_var[n_act:n_act + len(roots)] = 1.0
    options: dict[str, float] = {"mip_rel_gap": 1e-7}
    if time_limit is not None:
        options["time_limit"] = time_limit
    res = milp(np.concatenate([cost, np.zeros(n_sig)]), integrality=np.r_[np.ones(n_act), np.zeros(n_sig)],
               bounds=Bounds(low_var, 1.0), constraints=LinearConstraint(matrix, lower, np.zeros(n_sig + n_pair)),
               options=options)
    bound, stopped = getattr(res, "mip_dual_bound", None), res.status == 1
    bound = 0.0 if bound is None else float(bound)  # (stopped before any bound: costs are >= 0)
    if res.x is None:
        return ExactResult(None, np.inf, bound, False, stopped)
    chosen = {order[owner[j]]: j - first[owner[j]] for j in np.flatnonzero(res.x[:n_act] > 0.5).tolist()}
    rules: dict[int, Action] = {}
    todo = list(roots)
    while todo:  # the rules reachable from the roots (an incumbent may hold rules nothing uses)
        sig = todo.pop()
        if sig not in rules:
            rules[sig] = action = search.actions(sig)[chosen[sig]]
            todo.extend(c for c, _ in action.children if c not in rules)
    total = sum(search.actions(sig).cost[chosen[sig]] for sig in rules)
    return ExactResult(rules, total, bound, res.status == 0, stopped)
