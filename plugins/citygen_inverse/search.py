"""Grammar search (wu2014 §4.1-4.5, §4.7): greedy, importance sampling and approximate dynamic programming.

One *iteration* builds a complete deterministic grammar top-down: non-terminal regions without a rule are taken
bottom to top, left to right (only the first instance of a signature is split; later instances reuse its rule),
and one action (rule) is chosen for each. *Greedy* takes the action of least heuristic H (Eq. 5); *importance
sampling* draws from softmax(-H); *ADP* explores with probability epsilon (0.9, decaying exponentially) and
otherwise exploits the value function approximation: min_a C(a) + sum of V(child) over the successors that have
no rule yet, V being the best known cost of the sub-grammar a region introduced, stored per region with its
best action (§4.5). Iterations protect a random non-overlapping set of important repeated regions
(f(a, o) = (a-1)(o-1), §4.7) from being cut. The best grammar over all iterations is returned; ADP's first
iteration is the greedy one, so ADP is never worse than greedy.
"""
from __future__ import annotations

import heapq
import time
from dataclasses import dataclass

import numpy as np

from citygen.rng import derive_rng
from citygen_inverse.actions import Action, CostModel, region_actions
from citygen_inverse.regions import LayoutIndex
from citygen_inverse.symmetry import RepeatedRegions, detect_symmetry

METHODS = ("greedy", "is", "adp")


@dataclass(frozen=True)
class SearchResult:
    """The best grammar found: ``rules`` maps region signature -> chosen action."""

    rules: dict[int, Action]
    cost: float
    iterations: int
    seconds: float
    history: tuple[float, ...]


class GrammarSearch:
    """Search state shared by all iterations: the layout index, repeated regions and per-signature actions."""

    def __init__(self, index: LayoutIndex, model: CostModel = CostModel(), max_groups: int = 1500) -> None:
        self.index = index
        self.model = model
        self.sym: RepeatedRegions = detect_symmetry(index, max_groups)
        self._actions: dict[int, list[Action]] = {}
        self._arrays: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = {}
        self.value: dict[int, float] = {}
        self.best_action: dict[int, int] = {}
        self.roots = [index.sig(box) for box in index.roots]
        imp = self.sym.importance.astype(float)
        self._important = np.flatnonzero(imp > 0)
        self._importance = imp[self._important]

    def actions(self, sig: int) -> list[Action]:
        acts = self._actions.get(sig)
        if acts is None:
            acts = region_actions(self.index, sig, self.sym, self.model)
            self._actions[sig] = acts
            cost = np.array([a.cost for a in acts])
            heur = np.array([a.heuristic for a in acts])
            kids = [[0] + [c for c, _ in a.children] for a in acts]
            offsets = np.cumsum([0] + [len(k) for k in kids[:-1]])
            self._arrays[sig] = (cost, heur, np.concatenate(kids).astype(np.int64), offsets)
        return acts

    def estimate(self, sig: int) -> float:
        """V for a region never completed: an optimistic guess from its terminal count."""
        return 1.0 + 0.25 * self.index.sigs[sig].n

    # ---- one iteration ---------------------------------------------------------------------------------------
    def iterate(self, choose, protected: np.ndarray) -> tuple[dict[int, int], float]:
        rules: dict[int, int] = {}
        intro: dict[int, int] = {}
        heap = [(box[1], box[0], sig, box[0], box[1]) for sig, box in zip(self.roots, self.index.roots)]
        heapq.heapify(heap)
        order = []
        while heap:
            _, _, sig, x, y = heapq.heappop(heap)
            if sig in rules or self.index.sigs[sig].n <= 1:
                continue
            acts = self.actions(sig)
            allowed = self._allowed(sig, acts, protected, x, y)
            k = choose(sig, acts, allowed, rules)
            rules[sig] = k
            order.append(sig)
            for child, rel in acts[k].children:
                if child not in rules:
                    intro.setdefault(child, sig)
                    heapq.heappush(heap, (y + rel[1], x + rel[0], child, x + rel[0], y + rel[1]))
        sub: dict[int, float] = {}
        for sig in reversed(order):
            sub[sig] = sub.get(sig, 0.0) + self._actions[sig][rules[sig]].cost
            parent = intro.get(sig)
            if parent is not None:
                sub[parent] = sub.get(parent, 0.0) + sub[sig]
        for sig in order:
            if sub[sig] < self.value.get(sig, np.inf):
                self.value[sig] = sub[sig]
                self.best_action[sig] = rules[sig]
        return rules, sum(self._actions[s][k].cost for s, k in rules.items())

    def _allowed(self, sig: int, acts: list[Action], protected: np.ndarray, x: int, y: int) -> np.ndarray:
        ok = np.ones(len(acts), dtype=bool)
        if protected.size == 0:
            return ok
        w, h = self.index.sigs[sig].box[2] - self.index.sigs[sig].box[0], \
            self.index.sigs[sig].box[3] - self.index.sigs[sig].box[1]
        p = protected - np.array([x, y, x, y])
        p = p[(p[:, 0] >= 0) & (p[:, 1] >= 0) & (p[:, 2] <= w) & (p[:, 3] <= h)
              & ~((p[:, 0] == 0) & (p[:, 1] == 0) & (p[:, 2] == w) & (p[:, 3] == h))]
        if p.size == 0:
            return ok
        for k, a in enumerate(acts):
            if a.cuts:
                c = np.asarray(a.cuts)
                ok[k] = not np.any((p[:, a.axis, None] < c) & (p[:, a.axis + 2, None] > c))
        return ok if ok.any() else np.ones(len(acts), dtype=bool)

    def _protect(self, rng: np.random.Generator, count: int = 6) -> np.ndarray:
        """A random non-overlapping set of important repeated-region instances (sampled by f(a, o))."""
        if self._important.size == 0:
            return np.zeros((0, 4), dtype=np.int64)
        keys = np.log(rng.random(self._important.size)) / self._importance  # weighted order (Efraimidis-Spirakis)
        chosen: list[np.ndarray] = []
        for k in self._important[np.argsort(-keys)]:
            b = self.sym.boxes[k]
            if all(b[2] <= c[0] or c[2] <= b[0] or b[3] <= c[1] or c[3] <= b[1] for c in chosen):
                chosen.append(b)
                if len(chosen) >= count:
                    break
        return np.array(chosen, dtype=np.int64).reshape(-1, 4)

    # ---- policies --------------------------------------------------------------------------------------------
    def _greedy(self, sig, acts, allowed, rules) -> int:
        heur = np.where(allowed, self._arrays[sig][1], np.inf)
        return int(np.argmin(heur))

    def _sample(self, rng):
        def choose(sig, acts, allowed, rules) -> int:
            heur = self._arrays[sig][1]
            logits = np.where(allowed, -(heur - heur[allowed].min()), -np.inf)
            p = np.exp(logits)
            return int(rng.choice(len(acts), p=p / p.sum()))
        return choose

    def _exploit(self, sig, acts, allowed, rules) -> int:
        cost, _, kids, offsets = self._arrays[sig]
        v = np.array([0.0 if (c == 0 or c in rules) else self.value.get(c, self.estimate(c)) for c in kids])
        total = cost + np.add.reduceat(v, offsets)
        best = self.best_action.get(sig)
        if best is not None and allowed[best]:
            total[best] -= 1e-9  # ties keep the best known action
        return int(np.argmin(np.where(allowed, total, np.inf)))

    def run(self, method: str = "adp", iterations: int = 2000, seed: int = 0,
            time_limit: float | None = None) -> SearchResult:
        if method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {method!r}")
        start = time.perf_counter()
        none = np.zeros((0, 4), dtype=np.int64)
        best_rules, best_cost = self.iterate(self._greedy, none)
        history = [best_cost]
        if method == "greedy":
            iterations = 1
        rng = derive_rng(seed, "citygen_inverse", method)
        sample = self._sample(rng)
        decay = (0.01 / 0.9) ** (1.0 / max(iterations, 1))
        done = 1
        for it in range(1, iterations):
            if time_limit is not None and time.perf_counter() - start > time_limit:
                break
            protected = self._protect(rng) if rng.random() < 0.5 else none
            if method == "is":
                policy = sample
            else:
                eps = 0.9 * decay ** it
                def policy(sig, acts, allowed, rules, eps=eps):
                    if rng.random() < eps:
                        return sample(sig, acts, allowed, rules)
                    return self._exploit(sig, acts, allowed, rules)
            rules, cost = self.iterate(policy, protected)
            done += 1
            if cost < best_cost - 1e-9:
                best_rules, best_cost = rules, cost
            history.append(best_cost)
        if method == "adp":
            rules, cost = self.iterate(self._exploit, none)
            if cost < best_cost - 1e-9:
                best_rules, best_cost = rules, cost
        chosen = {s: self._actions[s][k] for s, k in best_rules.items()}
        return SearchResult(chosen, best_cost, done, time.perf_counter() - start, tuple(history))
