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
    """Padded prefix sums and flag counts of the words of one matrix (forward, or reversed for the backward
    search), so the edges of a node are scored for all candidate columns at once."""

    #: Letters per row whose ends propose target column sizes (longer columns come from the other rows).
    LOOKAHEAD = 2

    def __init__(self, words: Sequence[Sequence[Letter]], above: np.ndarray,
                 parents: Sequence[Sequence[int]] | None = None) -> None:
        self.m = len(words)
        self.n = np.array([len(w) for w in words], dtype=np.int64)
        width = int(self.n.max(initial=0)) + 1
        parents = parents or [range(len(w)) for w in words]

        def table(values, fill):
            out = np.full((self.m, width), fill, dtype=float)
            for r, row in enumerate(values):
                out[r, :len(row)] = row
                out[r, len(row):] = row[-1] if len(row) else fill
            return out

        def prefix(pred):
            return table([np.concatenate([[0], np.cumsum([bool(pred(x)) for x in w])]) for w in words], 0)

        self.cum = table([np.concatenate([[0.0], np.cumsum([x.size for x in w])]) for w in words], 0.0)
        self.total = self.cum[np.arange(self.m), self.n]
        self.nonopaque = prefix(lambda x: not x.opaque)
        self.unocc = prefix(lambda x: x.unoccludable)
        self.solid = prefix(lambda x: not (x.transparent or x.opaque))
        self.clear = prefix(lambda x: x.transparent)
        self.eps_ok = np.zeros((self.m, width), dtype=bool)
        self.runend = np.zeros((self.m, width), dtype=np.int64)
        for r, w in enumerate(words):
            pa = list(parents[r])
            att = [x.attached for x in w]
            for p in range(len(w) + 1):
                # no insertion next to an attached letter, nor inside a split transparent letter (§5.2)
                inner = 0 < p < len(w) and pa[p - 1] == pa[p]
                self.eps_ok[r, p] = not ((p > 0 and att[p - 1]) or (p < len(w) and att[p]) or inner)
            ends = np.arange(width)
            for i in range(len(w) - 1, -1, -1):
                ends[i] = ends[i + 1] if i + 1 < len(w) and w[i + 1].transparent == w[i].transparent else i + 1
            self.runend[r] = np.minimum(ends, len(w))
        self.above = above.astype(float)
        self.rows = np.arange(self.m)

    def edges(self, state: tuple[int, ...], mu: float) -> list[tuple[float, int, Column, float]]:
        """Valid outgoing columns of ``state`` as ``(phi, symbols, column, size)``."""
        p = np.asarray(state, dtype=np.int64)
        active = np.flatnonzero(p < self.n)
        base = self.cum[self.rows, p]
        targets = []
        for r in active:
            stop = min(int(self.runend[r, p[r]]), int(p[r]) + self.LOOKAHEAD)
            targets.append(self.cum[r, p[r] + 1:stop + 1] - base[r])
        if not targets:
            return []
        t = np.sort(np.round(np.concatenate(targets), 9))
        t = t[np.concatenate([[True], np.diff(t) > 0])]
        tol = 1e-9
        choices = []
        for r in range(self.m):
            if p[r] >= self.n[r]:
                choices.append(np.tile(p[r], (3, t.size)))
                continue
            seg = self.cum[r, p[r] + 1:self.runend[r, p[r]] + 1] - base[r]
            i = np.searchsorted(seg, t - tol)
            hi = np.minimum(i, seg.size - 1)
            lo = np.where((i < seg.size) & (seg[hi] <= t + tol), hi, np.maximum(i - 1, 0))
            near = np.where(t - seg[lo] <= seg[hi] - t, lo, hi)
            choices.append(p[r] + 1 + np.stack([near, lo, hi]))
        ends = np.stack(choices, axis=-1).reshape(-1, self.m)          # (3 * targets, m)
        near = ends[:t.size]
        exact = np.abs(self.cum[self.rows, near] - base - t[:, None]) <= tol
        strict = np.where(exact | ~self.eps_ok[self.rows, p], near, p)
        ends = np.vstack([ends, strict])
        keep = list({row.tobytes(): k for k, row in enumerate(ends)}.values())
        return self._score(p, ends[sorted(keep)])

    def _score(self, p: np.ndarray, ends: np.ndarray) -> list[tuple[float, int, Column, float]]:
        """Column error Phi (Eq. 9), size and symbol count of candidate columns; drops those that break the
        column constraints: an opaque entry in every column, epsilon only below an opaque entry of an upper
        layer and never beside an attached letter, unoccludable letters covered only by transparent or opaque
        entries; transparent letters separated from the others (edges() never proposes such entries)."""
        rows = self.rows
        eps = ends == p
        clear = self.clear[rows, ends] - self.clear[rows, p]
        mixed = (clear > 0) & (clear < ends - p)
        sums = self.cum[rows, ends] - self.cum[rows, p]
        opaque = ~eps & (self.nonopaque[rows, ends] == self.nonopaque[rows, p])
        covered = (opaque.astype(float) @ self.above) > 0
        ok = ~np.all(eps, axis=1) & np.any(opaque, axis=1) & ~np.any(mixed, axis=1)
        ok &= np.all(~eps | (covered & self.eps_ok[rows, p]), axis=1)
        unocc = ~eps & (self.unocc[rows, ends] > self.unocc[rows, p])
        solid = ~eps & (self.solid[rows, ends] > self.solid[rows, p])
        ok &= ~np.any(unocc & ((solid.astype(float) @ self.above) > 0), axis=1)
        if not ok.any():
            return []
        ends, eps, sums = ends[ok], eps[ok], sums[ok]
        hi = np.where(eps, -np.inf, sums).max(axis=1)
        lo = np.where(eps, np.inf, sums).min(axis=1)
        nsym = (ends - p).sum(axis=1)
        return [(float(hi[k] - lo[k]), int(nsym[k]), tuple(zip(p.tolist(), ends[k].tolist())), float(hi[k]))
                for k in range(ends.shape[0])]

    def score(self, col: Column) -> tuple[float, int, float] | None:
        """``(phi, symbols, size)`` of one column, or None when a column constraint fails."""
        p = np.array([a for a, _ in col], dtype=np.int64)
        ends = np.array([[b for _, b in col]], dtype=np.int64)
        out = self._score(p, ends)
        return (out[0][0], out[0][1], out[0][3]) if out else None


@dataclass(order=True)
class _Entry:
    key: tuple
    state: tuple[int, ...] = field(compare=False)


def _search_step(words: _Words, heap: list, dist: dict, size: dict, parent: dict, mu: float, canvas: float,
                 budget: Budget, seq: list[int], bound: float) -> tuple[int, ...] | None:
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
        if g > bound + 1e-9:
            continue
        nxt = tuple(b for _, b in col)
        s = size[state] + csize
        rest = float(np.max(words.total - words.cum[words.rows, nxt]))
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
    if start == goal:
        return Alignment((), 0.0, 0.0)
    found = _descend(fwd, goal, canvas, mu, budget)
    if found is not None and found[2]:
        return found[0]
    bound = mu if found is None else found[0].error - 1e-9
    best: tuple[float, tuple[int, ...]] | None = None
    turn = 0
    while all(s["heap"] for s in sides) and not budget.exhausted:
        if best is not None and sides[0]["heap"][0].key[0] + sides[1]["heap"][0].key[0] >= best[0] - 1e-12:
            break
        side, other = sides[turn], sides[1 - turn]
        settled = _search_step(side["words"], side["heap"], side["dist"], side["size"], side["parent"], mu, canvas,
                               budget, side["seq"], bound)
        if settled is not None:
            mirror = tuple(int(n) - p for n, p in zip(fwd.n, settled))
            if mirror in other["dist"]:
                total = side["dist"][settled] + other["dist"][mirror]
                fsize = side["size"][settled] + other["size"][mirror]
                if total <= mu + 1e-9 and fsize <= canvas + mu + 1e-9 and (best is None or total < best[0] - 1e-12):
                    best = (total, settled if turn == 0 else mirror)
        turn = 1 - turn
    if best is None:
        return None if found is None else found[0]
    meet = best[1]
    forward = _path(sides[0]["parent"], meet)
    back = _path(sides[1]["parent"], tuple(int(n) - p for n, p in zip(fwd.n, meet)))
    columns = list(forward)
    for col in reversed(back):   # reversed-word columns back to forward indices
        columns.append(tuple((int(n) - b, int(n) - a) for n, (a, b) in zip(fwd.n, col)))
    size = sum(max(fwd.cum[r, b] - fwd.cum[r, a] for r, (a, b) in enumerate(c)) for c in columns)
    return Alignment(tuple(columns), best[0], size)


class _Stop(Exception):
    pass


def _descend(words: _Words, goal: tuple[int, ...], canvas: float, mu: float, budget: Budget,
             share: float = 0.5, improve: float = 1.0) -> tuple[Alignment, float, bool] | None:
    """Depth-first branch and bound over the ADN, cheapest edge first, ties to fewer symbols (the paper's
    informed depth-first search with a transposition table of visited nodes). Anytime: the first alignment with
    ``Omega <= mu`` is improved for ``improve`` times the expansions it took, then returned as
    ``(alignment, error, complete)``; ``complete`` means the search space was exhausted (the result is optimal)."""
    best: list = [mu + 1e-9, None]
    table: dict[tuple[int, ...], float] = {}
    start = budget.used
    cap = [budget.used + max(int(share * (budget.expansions - budget.used)), 1)]
    path: list[Column] = []

    def visit(state: tuple[int, ...], g: float, size: float) -> None:
        if state == goal:
            if g < best[0] - 1e-12:
                if best[1] is None:
                    cap[0] = min(cap[0], budget.used + int(improve * (budget.used - start)) + 1)
                best[0], best[1] = g, (tuple(path), size)
            return
        if budget.used >= cap[0] or not budget.spend():
            raise _Stop
        for phi, _, col, csize in sorted(words.edges(state, mu), key=lambda e: (e[0], e[1])):
            g2 = g + phi
            if g2 >= best[0] - 1e-12:
                break
            nxt = tuple(b for _, b in col)
            s2 = size + csize
            if s2 + float(np.max(words.total - words.cum[words.rows, nxt])) > canvas + mu + 1e-9:
                continue
            if table.get(nxt, np.inf) <= g2 + 1e-12:
                continue
            table[nxt] = g2
            path.append(col)
            visit(nxt, g2, s2)
            path.pop()

    complete = True
    try:
        visit(tuple(0 for _ in goal), 0.0, 0.0)
    except _Stop:
        complete = False
    if best[1] is None:
        return None
    columns, size = best[1]
    return Alignment(columns, best[0], size), best[0], complete


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
            sums = [fwd.cum[r, b] - fwd.cum[r, a] for r, (a, b) in enumerate(col) if b > a]
            phi, csize = max(sums) - min(sums), max(sums)
            violations.append(f"column {len(columns)}: no column satisfies the alignment constraints; "
                              "the rest of every word forms one column")
        columns.append(col)
        error += phi
        size += csize
        state = tuple(b for _, b in col)
    return Alignment(tuple(columns), error, size, tuple(violations))
