"""Alignment (§5.2): shortest path through the alignment decision network (ADN).

A state is the tuple of positions reached in every word of the matrix; an edge consumes one substring per word
(possibly the empty string epsilon) and forms one column. Edges are weighted by the column error Phi (Eq. 9),
so a path's weight is the alignment error Omega. Outgoing edges are generated per target column size: for every
size some word can consume next, each word takes the substring closest to it (the dynamic programme that makes
edge evaluation ``O(n log m)``), or epsilon. Edges that break the four column constraints are dropped. Ties of
equal weight prefer fewer symbols per column (more partitions). The search is bidirectional (reflective
symmetry, §5.2): the backward search is the forward search on the reversed words.
"""
from __future__ import annotations

import heapq
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from citygen_layers.words import Letter

#: A column: per row ``(start, end)`` letter indices; ``start == end`` is epsilon.
Column = tuple[tuple[int, int], ...]


@dataclass
class Budget:
    """Node expansions (deterministic) and a wall-clock deadline (safety net) shared by one solve."""

    expansions: int
    deadline: float
    used: int = 0
    timed_out: bool = False

    def spend(self) -> bool:
        if self.used >= self.expansions:
            return False
        if self.used % 256 == 0 and time.perf_counter() > self.deadline:
            self.timed_out = True
            return False
        self.used += 1
        return True

    @property
    def exhausted(self) -> bool:
        return self.used >= self.expansions or self.timed_out


@dataclass(frozen=True)
class Alignment:
    """An alignment matrix (paper's A): columns over the rows, with its error Omega and total size."""

    columns: tuple[Column, ...]
    error: float
    size: float
    violations: tuple[str, ...] = ()


class _Words:
    """Per-row prefix sums and flag counts of one direction of a matrix (forward or reversed words)."""

    def __init__(self, words: Sequence[Sequence[Letter]], above: np.ndarray,
                 parents: Sequence[Sequence[int]] | None = None) -> None:
        self.m = len(words)
        self.n = np.array([len(w) for w in words])
        self.cum = [np.concatenate([[0.0], np.cumsum([x.size for x in w])]) for w in words]
        self.total = np.array([c[-1] for c in self.cum])

        def counts(pred):
            return [np.concatenate([[0], np.cumsum([bool(pred(x)) for x in w])]) for w in words]

        self.nonopaque = counts(lambda x: not x.opaque)
        self.unocc = counts(lambda x: x.unoccludable)
        self.solid = counts(lambda x: not (x.transparent or x.opaque))
        self.attached = [np.array([x.attached for x in w] + [False]) for w in words]
        parents = parents or [range(len(w)) for w in words]
        self.inner = [np.array([False] + [a == b for a, b in zip(pa[:-1], pa[1:])] + [False])
                      for pa in (list(p) for p in parents)]
        self.runend = []
        for w in words:
            ends = np.zeros(len(w) + 1, dtype=int)
            ends[len(w)] = len(w)
            for i in range(len(w) - 1, -1, -1):
                ends[i] = ends[i + 1] if i + 1 < len(w) and w[i + 1].transparent == w[i].transparent else i + 1
            self.runend.append(ends)
        self.above = above

    def eps_allowed(self, r: int, p: int) -> bool:
        """No insertion next to an attached letter (the fourth column constraint, pairwise)."""
        att = self.attached[r]
        return not ((p > 0 and att[p - 1]) or (p < self.n[r] and att[p]) or self.inner[r][p])

    def edges(self, state: tuple[int, ...], mu: float) -> list[tuple[float, int, Column, float]]:
        """Valid outgoing columns of ``state`` as ``(phi, symbols, column, size)``."""
        active = [r for r in range(self.m) if state[r] < self.n[r]]
        targets: set[float] = set()
        spans = {}
        for r in active:
            p = state[r]
            seg = self.cum[r][p + 1:self.runend[r][p] + 1] - self.cum[r][p]
            spans[r] = seg
            targets.update(np.round(seg, 9).tolist())
        out: dict[Column, tuple[float, int, float]] = {}
        tol = 1e-9
        for target in sorted(targets):
            near: dict[int, tuple[int, float]] = {}
            lower: dict[int, tuple[int, float]] = {}
            upper: dict[int, tuple[int, float]] = {}
            for r in active:
                seg = spans[r]
                i = int(np.searchsorted(seg, target - tol))
                hi = min(i, seg.size - 1)
                lo = i if i < seg.size and seg[i] <= target + tol else max(i - 1, 0)
                upper[r] = (state[r] + hi + 1, float(seg[hi]))
                lower[r] = (state[r] + lo + 1, float(seg[lo]))
                near[r] = lower[r] if target - lower[r][1] <= upper[r][1] - target else upper[r]
            for choice, strict in ((near, False), (lower, False), (upper, False), (near, True)):
                column = []
                for r in range(self.m):
                    p = state[r]
                    if r in choice and not (strict and abs(choice[r][1] - target) > tol and self.eps_allowed(r, p)):
                        column.append((p, choice[r][0]))
                    else:
                        column.append((p, p))
                col = tuple(column)
                if col in out or all(a == b for a, b in col):
                    continue
                scored = self.score(col)
                if scored is not None:
                    out[col] = scored
        return [(phi, nsym, col, size) for col, (phi, nsym, size) in out.items()]

    def score(self, col: Column) -> tuple[float, int, float] | None:
        """``(phi, symbols, size)`` of a column, or None when a column constraint fails."""
        sums = []
        opaque_row = False
        nsym = 0
        for r, (a, b) in enumerate(col):
            if a == b:
                if not self.eps_allowed(r, a):
                    return None
                continue
            nsym += b - a
            sums.append(self.cum[r][b] - self.cum[r][a])
            if self.nonopaque[r][b] == self.nonopaque[r][a]:
                opaque_row = True
            if self.unocc[r][b] > self.unocc[r][a]:
                for h in np.flatnonzero(self.above[:, r]):
                    ha, hb = col[h]
                    if ha != hb and self.solid[h][hb] > self.solid[h][ha]:
                        return None
        if not opaque_row:
            return None
        return max(sums) - min(sums), nsym, max(sums)


@dataclass(order=True)
class _Entry:
    key: tuple
    state: tuple[int, ...] = field(compare=False)


def _search_step(words: _Words, heap: list, dist: dict, size: dict, parent: dict, mu: float, canvas: float,
                 budget: Budget, seq: list[int]) -> tuple[int, ...] | None:
    """Settle one node of a Dijkstra search; returns it (or None when the heap is empty / stale entry)."""
    entry = heapq.heappop(heap)
    state = entry.state
    if entry.key[0] > dist[state] + 1e-12:
        return None
    if not budget.spend():
        return None
    ncols = entry.key[1]
    for phi, nsym, col, csize in words.edges(state, mu):
        g = dist[state] + phi
        if g > mu + 1e-9:
            continue
        nxt = tuple(b for _, b in col)
        s = size[state] + csize
        rest = float(np.max(words.total - np.array([words.cum[r][nxt[r]] for r in range(words.m)])))
        if s + rest > canvas + mu + 1e-9:
            continue
        if nxt not in dist or g < dist[nxt] - 1e-12:
            dist[nxt], size[nxt], parent[nxt] = g, s, (state, col)
            seq[0] += 1
            heapq.heappush(heap, _Entry((g, ncols - 1, nsym, seq[0]), nxt))
    return state


def align(words: Sequence[Sequence[Letter]], above: np.ndarray, canvas: float, mu: float,
          budget: Budget, parents: Sequence[Sequence[int]] | None = None) -> Alignment | None:
    """Best alignment with error ``Omega <= mu`` and size ``<= canvas + mu`` (bidirectional Dijkstra), or None.

    ``parents`` maps the parts of split transparent letters to their letter (no hole may open inside one).
    """
    fwd = _Words(words, above, parents)
    bwd = _Words([tuple(reversed(w)) for w in words], above,
                 None if parents is None else [tuple(reversed(p)) for p in parents])
    start = tuple(0 for _ in words)
    goal = tuple(int(n) for n in fwd.n)
    sides = []
    for side, origin in ((fwd, start), (bwd, start)):
        sides.append({"words": side, "dist": {origin: 0.0}, "size": {origin: 0.0}, "parent": {origin: None},
                      "heap": [_Entry((0.0, 0, 0, 0), origin)], "seq": [0]})
    best: tuple[float, tuple[int, ...]] | None = None
    if start == goal:
        return Alignment((), 0.0, 0.0)
    turn = 0
    while all(s["heap"] for s in sides) and not budget.exhausted:
        if best is not None and sides[0]["heap"][0].key[0] + sides[1]["heap"][0].key[0] >= best[0] - 1e-12:
            break
        side, other = sides[turn], sides[1 - turn]
        settled = _search_step(side["words"], side["heap"], side["dist"], side["size"], side["parent"], mu, canvas,
                               budget, side["seq"])
        if settled is not None:
            mirror = tuple(int(n) - p for n, p in zip(fwd.n, settled))
            if mirror in other["dist"]:
                total = side["dist"][settled] + other["dist"][mirror]
                fsize = side["size"][settled] + other["size"][mirror]
                if total <= mu + 1e-9 and fsize <= canvas + mu + 1e-9 and (best is None or total < best[0] - 1e-12):
                    best = (total, settled if turn == 0 else mirror)
        turn = 1 - turn
    if best is None:
        return None
    meet = best[1]
    forward = _path(sides[0]["parent"], meet)
    back = _path(sides[1]["parent"], tuple(int(n) - p for n, p in zip(fwd.n, meet)))
    columns = list(forward)
    for col in reversed(back):   # reversed-word columns back to forward indices
        columns.append(tuple((int(n) - b, int(n) - a) for n, (a, b) in zip(fwd.n, col)))
    size = sum(fwd.score(c)[2] for c in columns)
    return Alignment(tuple(columns), best[0], size)


def _path(parent: dict, state: tuple[int, ...]) -> list[Column]:
    cols: list[Column] = []
    while parent[state] is not None:
        state, col = parent[state]
        cols.append(col)
    return cols[::-1]


def greedy_alignment(words: Sequence[Sequence[Letter]], above: np.ndarray) -> Alignment:
    """Best-effort fallback: cheapest valid column at each step, without backtracking; when no valid column
    exists, one column takes what is left of every word and the violated constraint is reported."""
    fwd = _Words(words, above)
    state = tuple(0 for _ in words)
    goal = tuple(int(n) for n in fwd.n)
    columns: list[Column] = []
    violations: list[str] = []
    error = size = 0.0
    while state != goal:
        edges = fwd.edges(state, float("inf"))
        if edges:
            phi, _, col, csize = min(edges, key=lambda e: (e[0] / max(e[3], 1e-9), e[1]))
        else:
            col = tuple((p, int(n)) for p, n in zip(state, fwd.n))
            sums = [fwd.cum[r][b] - fwd.cum[r][a] for r, (a, b) in enumerate(col) if b > a]
            phi, csize = max(sums) - min(sums), max(sums)
            violations.append(f"column {len(columns)}: no column satisfies the alignment constraints; "
                              "the rest of every word forms one column")
        columns.append(col)
        error += phi
        size += csize
        state = tuple(b for _, b in col)
    return Alignment(tuple(columns), error, size, tuple(violations))
