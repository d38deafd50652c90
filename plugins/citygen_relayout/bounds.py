"""Static extent bounds of every symbol: the smallest (and largest) size a region can take along each axis.

Along its split axis a composite needs the cheapest arrangement its sequences accept (shortest path through the
cover automaton, each child costing its minimum size); across it, every child spans the whole extent, so it needs
the arrangement whose largest child minimum is smallest (bottleneck path). Maxima are the longest paths
(infinite when a repetition loop is reachable). Used to prune successors whose minimum cannot fit and to reject an
impossible target size up front with the reason (bao2013 §9.3 cannot tell; we can for these bounds).
"""
from __future__ import annotations

import heapq
import math

from citygen_relayout.model import END

_STATE_LIMIT = 20000


def extent_bounds(model, automata, door: dict[str, bool], relax_doors: bool) -> tuple[dict, dict]:
    """``(minimum, maximum)`` dicts keyed by ``(symbol, axis)``; with ``relax_doors`` frequency minimums of
    door-bearing symbols are ignored, as on a face without entrance."""
    lo: dict[tuple[str, str], float] = {}
    hi: dict[tuple[str, str], float] = {}

    def need(name: str, axis: str) -> tuple[float, float]:
        key = (name, axis)
        if key not in lo:
            sym = model.symbols[name]
            if sym.is_terminal:
                lo[key], hi[key] = model.terminal_min.get(key, 0.0), math.inf
            else:
                kids = list(dict.fromkeys(sym.children))
                if sym.split == axis:
                    cost = {c: max(model.sizes[(c, axis)].lo, need(c, axis)[0]) for c in kids}
                    gain = {c: min(model.sizes[(c, axis)].hi, need(c, axis)[1]) for c in kids}
                    lo[key] = _path(automata[name], cost, lambda a, b: a + b)
                    hi[key] = _longest(automata[name], gain)
                else:
                    cost = {c: need(c, axis)[0] for c in kids}
                    mandatory = [need(next(iter(f.members)), axis)[0] for f in model.rules[name].frequencies
                                 if len(f.members) == 1 and f.lo >= 1 and not f.relative
                                 and not (relax_doors and door[next(iter(f.members))])]
                    lo[key] = max(_path(automata[name], cost, max), *mandatory, 0.0)
                    hi[key] = math.inf
        return lo[key], hi[key]

    for name in model.symbols:
        need(name, "x")
        need(name, "y")
    return lo, hi


def _path(auto, cost: dict[str, float], combine) -> float:
    """Cheapest accepted arrangement under ``combine`` (sum or max) of child costs; 0 if the search is too big."""
    start = auto.start
    best = {start: 0.0}
    heap = [(0.0, 0, start)]
    tie = 1
    while heap:
        d, _, state = heapq.heappop(heap)
        if d > best.get(state, math.inf):
            continue
        if auto.step(state, END) is not None:
            return d
        for c, w in cost.items():
            nxt = auto.step(state, c)
            if nxt is None:
                continue
            nd = combine(d, w)
            if nd < best.get(nxt, math.inf):
                if len(best) > _STATE_LIMIT:
                    return 0.0
                best[nxt] = nd
                heapq.heappush(heap, (nd, tie, nxt))
                tie += 1
    return math.inf  # no accepted arrangement at all


def _longest(auto, gain: dict[str, float]) -> float:
    """Longest accepted arrangement; infinite when a loop of positive gain can be taken."""
    memo: dict[object, float] = {}
    onstack: set = set()

    def visit(state, depth: int) -> float:
        if state in memo:
            return memo[state]
        if state in onstack or depth > 400 or len(memo) > _STATE_LIMIT:
            return math.inf
        onstack.add(state)
        best = 0.0 if auto.step(state, END) is not None else -math.inf
        for c, w in gain.items():
            nxt = auto.step(state, c)
            if nxt is not None:
                best = max(best, w + visit(nxt, depth + 1))
                if best == math.inf:
                    break
        onstack.discard(state)
        memo[state] = best
        return best

    return visit(auto.start, 0)
