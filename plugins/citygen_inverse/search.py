"""Grammar search (wu2014 §4.1-4.5, §4.7): greedy, importance sampling and approximate dynamic programming.

One *iteration* builds a complete deterministic grammar top-down: non-terminal regions without a rule are taken
bottom to top, left to right (only the first instance of a signature is split; later instances reuse its rule),
and one action (rule) is chosen for each. *Greedy* takes the action of least heuristic H (Eq. 5); *importance
sampling* draws from softmax(-H); *ADP* explores with probability epsilon (0.9, decaying exponentially to 0.01
over the run, or over each cycle of ``CYCLE`` iterations of a longer run: a cycle ends like a whole run, with one
exploiting iteration, so a run of k cycles begins with the one-cycle run and is never worse) and otherwise
exploits the value function approximation: min_a C(a) + sum of V(child) over the successors that have no rule
yet, V being the best known cost of the sub-grammar a region introduced, stored per region with its best action
(§4.5). Iterations protect a random non-overlapping set of important repeated regions
(f(a, o) = (a-1)(o-1), §4.7) from being cut. The best grammar over all iterations is returned; ADP's first
iteration is the greedy one, so ADP is never worse than greedy.
"""
from __future__ import annotations

import heapq
import math
import time
from bisect import bisect_right
from dataclasses import dataclass

import numpy as np

from citygen.rng import derive_rng
from citygen_inverse.actions import Action, Candidates, CostModel, region_actions
from citygen_inverse.exact import solve_exact
from citygen_inverse.regions import LayoutIndex
from citygen_inverse.symmetry import RepeatedRegions, detect_symmetry

METHODS = ("greedy", "is", "adp", "exact")
CYCLE = 2000  # ADP's epsilon schedule restarts after this many iterations (longer runs are never worse)
EXACT_SECONDS = 20.0  # method exact: the integer program's time limit when the run has none
_NO_KIDS: frozenset[int] = frozenset()


@dataclass(frozen=True)
class SearchResult:
    """The best grammar found: ``rules`` maps region signature -> chosen action."""

    rules: dict[int, Action]
    cost: float
    iterations: int
    seconds: float
    history: tuple[float, ...]
    bound: float | None = None  # method exact: a lower bound on every grammar's cost over the candidate rules
    optimal: bool = False  # method exact: the grammar is proven the cheapest over the candidate rules
    stopped: bool = False  # method exact: the integer program was stopped by the time limit


class GrammarSearch:
    """Search state shared by all iterations: the layout index, repeated regions and per-signature actions.

    Per signature the actions are kept as plain lists (costs, non-terminal successors, greedy choice, softmax
    cumulative weights) because the per-region work is too small for numpy; protection is a bit mask over the
    important repeated instances per (signature, position).
    """

    def __init__(self, index: LayoutIndex, model: CostModel = CostModel(), max_groups: int = 800,
                 max_protected: int = 256) -> None:
        self.index = index
        self.model = model
        self.sym: RepeatedRegions = detect_symmetry(index, max_groups)
        self._actions: dict[int, Candidates] = {}
        self._cost: dict[int, list[float]] = {}
        self._kids: dict[int, list[tuple[int, ...]]] = {}
        self._greedy_k: dict[int, int] = {}
        self._cum: dict[int, list[float]] = {}
        self._weights: dict[int, list[float]] = {}
        self._masks: dict[tuple[int, int, int], tuple[list[int], int]] = {}
        self._kidset: dict[int, frozenset[int]] = {}
        self._parents: dict[int, list[int]] = {}
        self._exploited: dict[int, dict[frozenset[int], int]] = {}  # Eq. 4 choices, see _exploit
        self._best_only = False  # a greedy run keeps only each region's greedy action
        self.value: dict[int, float] = {}
        self.best_action: dict[int, int] = {}
        self.roots = [index.sig(box) for box in index.roots]
        imp = self.sym.importance.astype(float)
        order = np.argsort(-imp, kind="stable")[:max_protected]
        self._important = np.sort(order[imp[order] > 0])  # protection samples from the most important instances
        self._importance = imp[self._important]
        self._imp_boxes = self.sym.boxes[self._important]
        self._u: list[float] = []

    def actions(self, sig: int) -> Candidates:
        acts = self._actions.get(sig)
        if acts is None:
            acts = region_actions(self.index, sig, self.sym, self.model, best_only=self._best_only)
            self._actions[sig] = acts
            heur = acts.heuristic
            self._cost[sig] = acts.cost
            if not self._best_only:  # (successors for exploitation)
                self._kids[sig] = kids = [acts.kids(k) for k in range(len(acts))]
                self._kidset[sig] = kidset = frozenset(c for ks in kids for c in ks)
                for kid in kidset:
                    self._parents.setdefault(kid, []).append(sig)
            self._greedy_k[sig] = min(range(len(heur)), key=heur.__getitem__) if acts.greedy is None \
                else acts.greedy  # (the first least H, but for grids)
        return acts

    def _softmax(self, sig: int) -> list[float]:
        """Weights exp(-H) (scaled by the best) of a region's actions; their cumulative sums go to ``_cum``."""
        heur = self._actions[sig].heuristic
        low = min(heur)
        weights = self._weights[sig] = [math.exp(low - h) for h in heur]
        self._cum[sig] = list(np.cumsum(weights))
        return weights

    def estimate(self, sig: int) -> float:
        """V for a region never completed: an optimistic guess from its terminal count."""
        return 1.0 + 0.25 * self.index.sigs[sig].n

    # ---- one iteration ---------------------------------------------------------------------------------------
    def iterate(self, choose, protected: int) -> tuple[dict[int, int], float]:
        """One grammar, top-down; ``protected`` is a bit mask over the important repeated instances."""
        rules: dict[int, int] = {}
        intro: dict[int, int] = {}
        heap = [(box[1], box[0], sig) for sig, box in zip(self.roots, self.index.roots)
                if self.index.sigs[sig].n > 1]  # (successors in rules are always non-terminal)
        heapq.heapify(heap)
        order = []
        pop, push, actions = heapq.heappop, heapq.heappush, self._actions
        while heap:
            y, x, sig = pop(heap)
            if sig in rules:
                continue
            acts = actions.get(sig)
            if acts is None:
                acts = self.actions(sig)
            masks = None
            if protected:
                masks, cut = self._protection(sig, x, y)
                if not cut & protected or all(m & protected for m in masks):
                    masks = None  # no rule cuts a protected region, or every rule does (protection dropped here)
            k = choose(sig, masks, protected, rules)
            rules[sig] = k
            order.append(sig)
            for child, rel in (acts.built[k] or acts[k]).children:
                if child not in rules:
                    intro.setdefault(child, sig)
                    push(heap, (y + rel[1], x + rel[0], child))
        sub: dict[int, float] = {}
        total = 0.0
        for sig in reversed(order):
            c = self._cost[sig][rules[sig]]
            total += c
            sub[sig] = sub.get(sig, 0.0) + c
            parent = intro.get(sig)
            if parent is not None:
                sub[parent] = sub.get(parent, 0.0) + sub[sig]
        value, best, exploited, parents = self.value, self.best_action, self._exploited, self._parents
        for sig in order:
            if sub[sig] < value.get(sig, math.inf):
                value[sig] = sub[sig]
                best[sig] = rules[sig]
                exploited.pop(sig, None)
                for p in parents.get(sig, ()):
                    exploited.pop(p, None)
        return rules, total

    def _protection(self, sig: int, x: int, y: int) -> tuple[list[int], int]:
        """Per action, the bit mask of important instances strictly inside the region that its lines cut; and
        the union of those masks."""
        key = (sig, x, y)
        found = self._masks.get(key)
        if found is None:
            box = self.index.sigs[sig].box
            w, h = box[2] - box[0], box[3] - box[1]
            p = self._imp_boxes - np.array([x, y, x, y])
            inside = np.flatnonzero((p[:, 0] >= 0) & (p[:, 1] >= 0) & (p[:, 2] <= w) & (p[:, 3] <= h)
                                    & ~((p[:, 0] == 0) & (p[:, 1] == 0) & (p[:, 2] == w) & (p[:, 3] == h)))
            acts = self._actions[sig]
            masks = [0] * len(acts)
            owners, starts, axes, cuts = acts.cut_lines()
            if inside.size and owners:
                axes = np.array(axes)
                cuts = np.array(cuts) - np.take(box, axes)  # (relative to the box, as the instances are)
                q = p.take(inside, 0)
                lo, hi = q[:, axes], q[:, axes + 2]  # per instance, its extent along each line's axis
                hit = (lo < cuts) & (hi > cuts)  # instance x line: the line cuts the instance
                cut = np.zeros((len(acts), self._important.size), dtype=bool)
                cut[np.ix_(owners, inside)] = np.logical_or.reduceat(hit, starts, axis=1).T
                packed = np.packbits(cut, axis=1, bitorder="little")
                masks = [int.from_bytes(row.tobytes(), "little") for row in packed]
            any_mask = 0
            for m in masks:
                any_mask |= m
            self._masks[key] = found = (masks, any_mask)
        return found

    def _protect(self, rng: np.random.Generator, count: int = 6) -> int:
        """A random non-overlapping set of important repeated-region instances (sampled by f(a, o)), as a mask."""
        if self._important.size == 0:
            return 0
        keys = np.log(rng.random(self._important.size)) / self._importance  # weighted order (Efraimidis-Spirakis)
        chosen: list[np.ndarray] = []
        mask = 0
        for k in np.argsort(-keys).tolist():
            b = self._imp_boxes[k]
            if all(b[2] <= c[0] or c[2] <= b[0] or b[3] <= c[1] or c[3] <= b[1] for c in chosen):
                chosen.append(b)
                mask |= 1 << k
                if len(chosen) >= count:
                    break
        return mask

    # ---- policies --------------------------------------------------------------------------------------------
    def _greedy(self, sig, masks, protected, rules) -> int:
        k = self._greedy_k[sig]
        if masks is None or not masks[k] & protected:
            return k
        heur = self._actions[sig].heuristic
        return min((k for k in range(len(heur)) if not masks[k] & protected), key=heur.__getitem__)

    def _uniform(self, rng: np.random.Generator) -> float:
        if not self._u:
            self._u = rng.random(1024).tolist()
        return self._u.pop()

    def _sample(self, rng):
        def choose(sig, masks, protected, rules) -> int:
            weights = self._weights.get(sig) or self._softmax(sig)
            cum = self._cum[sig]
            if masks is None:
                return min(bisect_right(cum, self._uniform(rng) * cum[-1]), len(cum) - 1)
            w = [0.0 if m & protected else v for v, m in zip(weights, masks)]
            cum = list(np.cumsum(w))
            return min(bisect_right(cum, self._uniform(rng) * cum[-1]), len(cum) - 1)
        return choose

    def _exploit(self, sig, masks, protected, rules) -> int:
        """Eq. 4: min_a C(a) + sum of V over the successors that get a rule later (ties keep the best action).

        Unless something is protected the choice depends only on V and on which successors have a rule, so it is
        kept per set of those successors until V of the region or of a successor improves (``iterate`` drops it
        then)."""
        if masks is None:
            kids = self._kidset[sig]
            key = _NO_KIDS if rules.keys().isdisjoint(kids) else frozenset(rules.keys() & kids)
            memo = self._exploited.get(sig)
            if memo is None:
                memo = self._exploited[sig] = {}
            k = memo.get(key)
            if k is not None:
                return k
        value, sigs = self.value, self.index.sigs
        keep = self.best_action.get(sig)
        best_k, best_t = -1, math.inf
        for k, (c, kids) in enumerate(zip(self._cost[sig], self._kids[sig])):
            if masks is not None and masks[k] & protected:
                continue
            t = c - (1e-9 if k == keep else 0.0)
            for kid in kids:
                if kid not in rules:
                    v = value.get(kid)
                    t += v if v is not None else 1.0 + 0.25 * sigs[kid].n
            if t < best_t:
                best_k, best_t = k, t
        if masks is None:
            memo[key] = best_k
        return best_k

    def run(self, method: str = "adp", iterations: int = 2000, seed: int = 0,
            time_limit: float | None = None) -> SearchResult:
        """The best grammar of ``method``; ``exact`` is ADP followed by the integer program of ``exact.py``, the
        cheaper of the two being returned with the program's lower bound. ``time_limit`` (seconds) stops ADP's
        iterations and then the integer program (without one, the program stops after ``EXACT_SECONDS``)."""
        if method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {method!r}")
        if method != "greedy" and not iterations >= 1:
            raise ValueError(f"{method} needs at least 1 iteration, got {iterations!r}")
        start = time.perf_counter()
        exact, method = method == "exact", "adp" if method == "exact" else method
        if self._best_only != (method == "greedy"):  # (a search run again with another method starts afresh)
            for table in (self._actions, self._cost, self._kids, self._greedy_k, self._cum, self._weights,
                          self._masks, self._kidset, self._parents, self._exploited, self.value, self.best_action):
                table.clear()
            self._best_only = method == "greedy"
        best_rules, best_cost = self.iterate(self._greedy, 0)
        history = [best_cost]
        if method == "greedy":
            iterations = 1
        rng = derive_rng(seed, "citygen_inverse", method)
        self._u = []
        sample = self._sample(rng)
        cycle = min(iterations, CYCLE)
        decay = (0.01 / 0.9) ** (1.0 / cycle)
        done = 1
        for it in range(1, iterations):
            if time_limit is not None and time.perf_counter() - start > time_limit:
                break
            protected = self._protect(rng) if self._uniform(rng) < 0.5 else 0
            if method == "is":
                policy = sample
            else:
                eps = 0.9 * decay ** (it % cycle)
                def policy(sig, masks, protected, rules, eps=eps):
                    if self._uniform(rng) < eps:
                        return sample(sig, masks, protected, rules)
                    return self._exploit(sig, masks, protected, rules)
            rules, cost = self.iterate(policy, protected)
            done += 1
            if method == "adp" and (it + 1) % cycle == 0 and it + 1 < iterations:  # a cycle ends: exploit once
                exploited, exploited_cost = self.iterate(self._exploit, 0)
                if exploited_cost < cost:
                    rules, cost = exploited, exploited_cost
            if cost < best_cost - 1e-9:
                best_rules, best_cost = rules, cost
            history.append(best_cost)
        if method == "adp":
            rules, cost = self.iterate(self._exploit, 0)
            if cost < best_cost - 1e-9:
                best_rules, best_cost = rules, cost
        chosen = {s: self._actions[s][k] for s, k in best_rules.items()}
        if not exact:
            return SearchResult(chosen, best_cost, done, time.perf_counter() - start, tuple(history))
        left = EXACT_SECONDS if time_limit is None else max(time_limit - (time.perf_counter() - start), 1e-3)
        program = solve_exact(self, left)
        if program.rules is not None and program.cost < best_cost - 1e-9:
            chosen, best_cost = program.rules, program.cost
        return SearchResult(chosen, best_cost, done, time.perf_counter() - start, tuple(history), program.bound,
                            program.optimal or best_cost <= program.bound + 1e-7 * best_cost, program.stopped)
