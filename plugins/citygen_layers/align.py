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

import bisect
import heapq
import itertools
import math
import operator
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from operator import attrgetter, not_, or_

import numpy as np

from citygen_layers.words import Letter

#: A column: per row ``(start, end)`` letter indices; ``start == end`` is epsilon.
Column = tuple[tuple[int, int], ...]
#: An edge of the ADN: ``(phi, symbols, column, size, next state)``.
Edge = tuple[float, int, Column, float, tuple[int, ...]]


@dataclass
class Budget:
    """Node expansions (deterministic) and a CPU-time deadline of this process (safety net; other processes on
    a loaded machine do not move it) shared by one solve."""

    expansions: int
    deadline: float
    used: int = 0
    timed_out: bool = False

    def spend(self) -> bool:
        if self.used >= self.expansions:
            return False
        if self.used % 256 == 0 and time.process_time() > self.deadline:
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


#: Letters per row whose ends propose target column sizes (longer columns come from the other rows).
LOOKAHEAD = 2
TOL = 1e-9


class NetworkMemo:
    """The rows of the alignment networks of one direction solve, shared between its searches (reusing the
    alignment work across candidates and mu rounds, §5.2). The candidates of a direction mostly differ in a few
    words (a counter value, a sampled size), so most rows of a matrix recur with the same word at the same index;
    such a row's prefix sums and its memos of substrings, target choices and entries are built once, and so is
    a word's transparent split."""

    def __init__(self) -> None:
        self.rows: dict[tuple, _Row] = {}
        #: the same rows by the identities of their letters (no letter hashing for a word met before; the rows
        #: keep their words, so the identities stay unique)
        self.by_ids: dict[tuple, _Row] = {}
        #: transparent splits of the words (``splits.split_transparent``)
        self.splits: dict[tuple, tuple] = {}


class _Row:
    """Row ``r`` of a network: prefix sums and flag counts of its word, where epsilon may be inserted, the ends of
    the runs of letters of equal transparency, the rows above it (bit set), and per start letter ``a`` and bound
    ``end`` on the substring ends: the substring sizes, the target sizes the row proposes, its entries per
    substring end and its choices per target. Everything is a function of ``(r, word, parents, upper)``."""

    __slots__ = ("bit", "clear", "cum", "eps_ok", "nonopaque", "runend", "runs", "solid", "starts", "unocc", "upper",
                 "word")

    def __init__(self, r: int, word: Sequence[Letter], parents: Sequence[int], upper: int) -> None:
        def count(flags) -> list[int]:
            """Prefix counts of a letter flag (C-level maps: the networks are rebuilt per candidate)."""
            return list(itertools.accumulate(flags, initial=0))

        w = self.word = tuple(word)
        size, opaque, clear = attrgetter("size"), attrgetter("opaque"), attrgetter("transparent")
        self.bit = 1 << r
        self.upper = upper
        self.cum = list(itertools.accumulate(map(size, w), initial=0.0))
        self.nonopaque = count(map(not_, map(opaque, w)))
        self.unocc = count(map(attrgetter("unoccludable"), w))
        self.solid = count(map(not_, map(or_, map(clear, w), map(opaque, w))))
        self.clear = count(map(clear, w))
        pa = list(parents)
        att = [x.attached for x in w]
        # no insertion next to an attached letter, nor inside a split transparent letter (§5.2)
        self.eps_ok = [not ((p > 0 and att[p - 1]) or (p < len(w) and att[p]) or
                            (0 < p < len(w) and pa[p - 1] == pa[p])) for p in range(len(w) + 1)]
        ends = list(range(len(w) + 1))
        for i in range(len(w) - 1, -1, -1):
            ends[i] = ends[i + 1] if i + 1 < len(w) and w[i + 1].transparent == w[i].transparent else i + 1
        self.runend = ends
        self.starts: dict[tuple[int, int], tuple[list[float], list[float], dict, dict]] = {}
        #: per start letter, its start up to the end of its run (filled on first use); None at the word's end
        self.runs: list = [False] * len(w) + [None]

    def start(self, a: int, end: int, whole: bool = False) -> tuple[list[float], list[float], dict, dict]:
        """From letter ``a`` with substrings ending at most at ``end``: the substring sizes, the target sizes the
        row proposes, and memos of its entries per substring end and of its choices per target. With ``whole``
        (``end`` is a prealigned column's end) the substring up to ``end`` proposes its size too: a control
        letter's whole content is a column of its own, however many letters it has."""
        key = (a, end, whole)
        row = self.starts.get(key)
        if row is None:
            c, b = self.cum, self.cum[a]
            seg = [c[j] - b for j in range(a + 1, end + 1)]
            proposed = seg[:LOOKAHEAD] + seg[-1:] if whole and len(seg) > LOOKAHEAD else seg[:LOOKAHEAD]
            row = self.starts[key] = (seg, [round(x * 1e9) / 1e9 for x in proposed], {}, {})
        return row

    def run(self, a: int) -> tuple[list[float], list[float], dict, dict]:
        """``start(a, runend[a])``, kept in ``runs``."""
        start = self.runs[a] = self.start(a, self.runend[a])
        return start

    def choose(self, a: int, start: tuple, t: float) -> tuple[int, int, int, int]:
        """For target ``t``: the substring end nearest to it, then the ends just below and just above it, then
        the nearest end if it matches the target exactly (else epsilon, where allowed); memoised in ``start``."""
        seg = start[0]
        last = len(seg) - 1
        first = a + 1
        i = bisect.bisect_left(seg, t - TOL)
        if i <= last and seg[i] <= t + TOL:    # an end within the tolerance: lo = hi = near
            near = lo = hi = i
        else:
            hi = i if i < last else last
            lo = i - 1 if i > 0 else 0
            near = lo if t - seg[lo] <= seg[hi] - t else hi
        strict = first + near if not self.eps_ok[a] or abs(seg[near] - t) <= TOL else a
        pick = start[3][t] = (first + near, first + lo, first + hi, strict)
        return pick

    def entry(self, a: int, e: int) -> tuple | None:
        """What entry ``(a, e)`` brings to a column: ``(size, size, opaque bit, solid bit, rows one of which
        must be opaque (-1: any), rows none of which may be solid)``, the sizes -inf and inf for epsilon (so that
        it is neither the largest nor the smallest); None when the entry alone breaks a constraint (epsilon beside
        an attached letter or with no upper row, transparent mixed with other letters)."""
        upper = self.upper
        if e == a:
            return (-math.inf, math.inf, 0, 0, upper, 0) if upper and self.eps_ok[a] else None
        clear = self.clear[e] - self.clear[a]
        if 0 < clear < e - a:
            return None
        bit = self.bit
        size = self.cum[e] - self.cum[a]
        return (size, size, bit if self.nonopaque[e] == self.nonopaque[a] else 0,
                bit if self.solid[e] > self.solid[a] else 0, -1,
                upper if self.unocc[e] > self.unocc[a] else 0)


class _Words:
    """The alignment decision network of one matrix (forward, or on the reversed words for the backward search).

    Words are short and matrices have few rows, so a node's edges are built in plain Python (numpy's per-call
    overhead dominated on such tiny arrays) and memoised per state: the depth-first search and the Dijkstra
    search of one alignment visit many of the same nodes. The rows (:class:`_Row`) come from ``memo`` when
    given, so the searches of a direction solve share them."""

    def __init__(self, words: Sequence[Sequence[Letter]], above: np.ndarray,
                 parents: Sequence[Sequence[int]] | None = None, fence: Sequence[tuple[int, ...]] = (),
                 memo: NetworkMemo | None = None, cutoff: float = math.inf) -> None:
        self.m = len(words)
        #: columns with a larger Phi are left out: no search of this network could take them (see ``align``)
        self.cutoff = cutoff
        self.n = tuple(len(w) for w in words)
        #: prealigned column ends (the last is ``n``): no column of this network crosses one of them
        self.fence = tuple(fence)
        parents = parents or [range(len(w)) for w in words]
        # per row r, the bit set of the rows above it (above[h, r])
        uppers = [sum(1 << h for h, flag in enumerate(column) if flag)
                  for column in np.asarray(above, dtype=bool).T.tolist()]
        shared, by_ids = (memo.rows, memo.by_ids) if memo is not None else ({}, {})
        self.rows: list[_Row] = []
        for r, (word, pa, upper) in enumerate(zip(words, parents, uppers)):
            pa = tuple(pa)
            ids = (r, tuple(map(id, word)), pa, upper)
            row = by_ids.get(ids)
            if row is None:
                key = (r, tuple(word), pa, upper)
                row = shared.get(key)
                if row is None:
                    row = shared[key] = _Row(r, word, pa, upper)
                by_ids[(r, tuple(map(id, row.word)), pa, upper)] = row
            self.rows.append(row)
        self.cum = [row.cum for row in self.rows]
        self._runs = [row.runs for row in self.rows]
        self.total = [c[-1] for c in self.cum]
        self._edges: dict[tuple[int, ...], list[Edge]] = {}

    def rest(self, state: tuple[int, ...]) -> float:
        """The largest remaining word size after ``state`` (the size bound of the searches)."""
        return max(map(operator.sub, self.total, map(list.__getitem__, self.cum, state)))

    def edges(self, state: tuple[int, ...]) -> list[Edge]:
        """Valid outgoing columns of ``state`` as ``(phi, symbols, column, size, next state)`` (memoised per
        state)."""
        out = self._edges.get(state)
        if out is None:
            out = self._edges[state] = self._build(state)
        return out

    def _cap(self, p: tuple[int, ...]) -> tuple[int, ...]:
        """Where the columns leaving ``p`` must end at the latest: the end of the current prealigned column."""
        return next((b for b in self.fence if any(x < y for x, y in zip(p, b))), self.n)

    def _build(self, p: tuple[int, ...]) -> list[Edge]:
        n = self._cap(p)
        if n is self.n:    # no prealigned column: every row's substrings run to the end of the run (Row.runs)
            starts = list(map(list.__getitem__, self._runs, p))
            if False in starts:
                starts = [start if start is not False else row.run(a) for row, a, start in zip(self.rows, p, starts)]
        else:
            starts = [row.start(a, min(row.runend[a], b), b <= row.runend[a]) if a < b else None
                      for row, a, b in zip(self.rows, p, n)]
        found = set()
        for start in starts:
            if start is not None:
                found.update(start[1])
        if not found:
            return []
        targets = sorted(found)
        # per row, the choices of every target (Row.choose), all nearest ends first, then those below, above and
        # the strict ones
        choices = []
        for row, a, start in zip(self.rows, p, starts):
            if start is None:
                choices.append((a,) * (4 * len(targets)))
                continue
            known = start[3]
            picks = [known.get(t) or row.choose(a, start, t) for t in targets]
            choices.append(list(itertools.chain.from_iterable(zip(*picks))))
        # distinct columns, each in the place of its last proposal
        columns = list(dict.fromkeys(reversed(list(zip(*choices)))))[::-1]
        entries = []
        for row, a, start, ends in zip(self.rows, p, starts, choices):
            known = start[2] if start is not None else {}
            for e in set(ends).difference(known):
                known[e] = row.entry(a, e)
            entries.append(known)
        out = []
        before = sum(p)
        cutoff = self.cutoff
        for ends in columns:
            column = list(map(dict.__getitem__, entries, ends))
            if None not in column:
                scored = self._column(p, before, ends, column, cutoff)
                if scored is not None:
                    out.append(scored)
        return out

    @staticmethod
    def _column(p: tuple[int, ...], before: int, ends: tuple[int, ...], column: Sequence[tuple],
                cutoff: float = math.inf) -> Edge | None:
        """``(phi, symbols, column, size, ends)``: Phi (Eq. 9) and size of a column of valid entries (``before`` is
        ``sum(p)``), or None when it breaks a column constraint: an opaque entry in every column, epsilon only
        below an opaque entry of an upper layer, unoccludable letters covered only by transparent or opaque
        entries; None too when Phi exceeds ``cutoff`` (checked first: most columns do)."""
        tops, bottoms, opaque_bits, solid_bits, needs, guards = zip(*column)
        hi = max(tops)
        phi = hi - min(bottoms)
        if phi > cutoff:
            return None
        opaque = sum(opaque_bits)    # one bit per row: the sum is the union
        # (no opaque entry also rejects the all-epsilon column)
        if not opaque or not all(map(opaque.__and__, needs)):
            return None
        solid = sum(solid_bits)
        if solid and any(map(solid.__and__, guards)):
            return None
        # some entry is opaque, so not epsilon: hi and the smallest size are finite
        return phi, sum(ends) - before, tuple(zip(p, ends)), hi, ends

    def score(self, col: Column) -> tuple[float, int, float] | None:
        """``(phi, symbols, size)`` of one column, or None when a column constraint fails."""
        p, ends = tuple(a for a, _ in col), tuple(b for _, b in col)
        column = [row.entry(a, e) for row, (a, e) in zip(self.rows, col)]
        out = None if None in column else self._column(p, sum(p), ends, column)
        return (out[0], out[1], out[3]) if out else None


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
    for phi, nsym, col, csize, nxt in words.edges(state):
        g = dist[state] + phi
        if g > bound + 1e-9:
            continue
        s = size[state] + csize
        if s + words.rest(nxt) > canvas + mu + 1e-9:
            continue
        if nxt not in dist or g < dist[nxt] - 1e-12:
            dist[nxt], size[nxt], parent[nxt] = g, s, (state, col)
            seq[0] += 1
            heapq.heappush(heap, _Entry((g, ncols - 1, nsym, seq[0]), nxt))
    return state


def align(words: Sequence[Sequence[Letter]], above: np.ndarray, canvas: float, mu: float,
          budget: Budget, parents: Sequence[Sequence[int]] | None = None,
          fence: Sequence[tuple[int, ...]] = (), memo: NetworkMemo | None = None) -> Alignment | None:
    """Best alignment with error ``Omega <= mu`` and size ``<= canvas + mu``, or None: a depth-first branch and
    bound over the forward network; when its anytime cut stops it early, a bidirectional Dijkstra search (which
    also sees the columns the backward network proposes). A depth-first search that exhausted the forward network
    is final (its optimum, or None): the bidirectional search would rarely find more and cost ~25 % of the
    expansions.

    ``parents`` maps the parts of split transparent letters to their letter (no hole may open inside one).
    ``fence`` lists the ends of prealigned columns (per row, the last is the word's end): the search is then
    restricted to columns inside them (prealignment of the control patterns, §5.2). ``memo`` shares the
    networks' rows with the other searches of a direction solve.
    """
    # Both searches skip columns with Phi > mu + 1e-9, since no path with error <= mu can take one: in the
    # depth-first search they sort after every cheaper column, beyond its cut at the best error (at most
    # mu + 1e-9), and the Dijkstra search drops them at its bound (at most mu) + 1e-9. So they are not built.
    cutoff = mu + 1e-9
    fwd = _Words(words, above, parents, fence, memo, cutoff)
    start = tuple(0 for _ in words)
    goal = tuple(int(n) for n in fwd.n)
    if start == goal:
        return Alignment((), 0.0, 0.0)
    found, complete = _descend(fwd, goal, canvas, mu, budget)
    if complete:  # the depth-first search exhausted the network: its result (or None) is final
        return found
    back_fence = [tuple(n - b for n, b in zip(fwd.n, ends)) for ends in reversed(fence[:-1])]
    bwd = _Words([tuple(reversed(w)) for w in words], above,
                 None if parents is None else [tuple(reversed(p)) for p in parents],
                 back_fence + [fwd.n] if fence else (), memo, cutoff)
    sides = []
    for side, origin in ((fwd, start), (bwd, start)):
        sides.append({"words": side, "dist": {origin: 0.0}, "size": {origin: 0.0}, "parent": {origin: None},
                      "heap": [_Entry((0.0, 0, 0, 0), origin)], "seq": [0]})
    bound = mu if found is None else found.error - 1e-9
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
        return found
    meet = best[1]
    forward = _path(sides[0]["parent"], meet)
    back = _path(sides[1]["parent"], tuple(int(n) - p for n, p in zip(fwd.n, meet)))
    columns = list(forward)
    for col in reversed(back):   # reversed-word columns back to forward indices
        columns.append(tuple((int(n) - b, int(n) - a) for n, (a, b) in zip(fwd.n, col)))
    size = sum(max(fwd.cum[r][b] - fwd.cum[r][a] for r, (a, b) in enumerate(c)) for c in columns)
    return Alignment(tuple(columns), best[0], size)


#: The order of the depth-first search: cheapest column first, ties to fewer symbols.
PHI_SYMBOLS = operator.itemgetter(0, 1)


class _Stop(Exception):
    pass


def _descend(words: _Words, goal: tuple[int, ...], canvas: float, mu: float, budget: Budget,
             share: float = 0.5, improve: float = 1.0) -> tuple[Alignment | None, bool]:
    """Depth-first branch and bound over the ADN, cheapest edge first, ties to fewer symbols (the paper's
    informed depth-first search with a transposition table of visited nodes). Anytime: the first alignment with
    ``Omega <= mu`` is improved for ``improve`` times the expansions it took, then returned as
    ``(alignment or None, complete)``; ``complete`` means the search space was exhausted (the result is optimal,
    and None means that no alignment within ``mu`` exists)."""
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
        for phi, _, col, csize, nxt in sorted(words.edges(state), key=PHI_SYMBOLS):
            g2 = g + phi
            if g2 >= best[0] - 1e-12:
                break
            s2 = size + csize
            if s2 + words.rest(nxt) > canvas + mu + 1e-9:
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
    finally:
        # the recursive closure refers to itself: without this cycle break the network and its edge memo would
        # outlive the search until the cyclic collector runs (paused during a request, see plugin.generate)
        del visit
    if best[1] is None:
        return None, complete
    columns, size = best[1]
    return Alignment(columns, best[0], size), complete


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
        edges = fwd.edges(state)
        if edges:
            phi, _, col, csize, _ = min(edges, key=lambda e: (e[0] / max(e[3], 1e-9), e[1]))
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
