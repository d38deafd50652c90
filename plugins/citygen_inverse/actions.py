"""Candidate rules for a region (the actions of wu2014 §4.1) and the splitting heuristic of §4.4.

Along each axis a region's valid split lines cut it into *atoms*; every split rule groups consecutive atoms.
Candidates are: every atom its own child; for each repeated region inside (§4.3) the grouping that keeps its
instances whole; the same with runs of identical groups merged into one child (which a repeat rule then
explains). Each grouping is written with the cheapest operator that fits its child sequence: ``repeat`` (periodic),
``repeatABA`` (A B A ... A), ``symsplit`` (odd palindrome) or ``split``. A region no line separates (a pinwheel,
wu2014 §6.3) gets a ``grid`` rule over its guillotine blocks.
"""
from __future__ import annotations

import math
from bisect import bisect_left, bisect_right
from collections import Counter
from dataclasses import dataclass
from functools import lru_cache
from itertools import compress
from operator import eq

import numpy as np

from citygen_inverse.regions import Box, LayoutIndex
from citygen_inverse.symmetry import RepeatedRegions


@dataclass(frozen=True)
class CostModel:
    """wu2014 Eq. 1-2 operator costs (symsplit/grid/floors priced like split, repeatABA like repeat)."""

    split: float = 0.1
    repeat: float = 0.5
    lambda1: float = 1.0
    lambda2: float = 1.0

    def __post_init__(self) -> None:
        for name in ("split", "repeat", "lambda1", "lambda2"):
            value = getattr(self, name)
            if not value >= 0 or value == float("inf"):  # (NaN fails both tests)
                raise ValueError(f"cost model: {name} must be a finite number >= 0, got {value!r}")


@dataclass(frozen=True)
class Action:
    """A rule ``sym -> op alpha`` for one region signature.

    ``items`` are ``(sig, relative box)`` of the successors written in the rule (for ``repeat`` one tile, for
    ``repeatABA`` A then B, for ``symsplit`` the first half and the centre, for ``grid`` every cell region);
    ``children`` the distinct non-terminal successor signatures with a relative box of one instance each;
    ``cuts`` the interior split lines (relative, along ``axis``) used by protection.
    """

    op: str
    axis: int
    items: tuple[tuple[int, Box], ...]
    children: tuple[tuple[int, Box], ...]
    cost: float
    heuristic: float
    cuts: tuple[int, ...]
    grid_lines: tuple[tuple[int, ...], tuple[int, ...]] = ((), ())


def _ops(seq: list[tuple[int, int]], model: CostModel) -> tuple[str, float, int]:
    """Cheapest operator for a child sequence of (signature, size along the axis): (op, cost, items written)."""
    k = len(seq)
    best = ("split", model.split + k, k)
    first = seq[0]
    for p in _divisors_below(k):
        if seq[p] == first and seq == seq[:p] * (k // p):
            if model.repeat + p < best[1]:
                best = ("repeat", model.repeat + p, p)
            break
    if k < 3 or k % 2 == 0 or seq[-1] != first:  # (A B A ... A and odd palindromes end as they start)
        return best
    if len(set(seq[0::2])) == 1 and len(set(seq[1::2])) == 1 and first != seq[1] and model.repeat + 2 < best[1]:
        best = ("repeatABA", model.repeat + 2, 2)
    if seq == seq[::-1] and model.split + (k + 1) // 2 < best[1]:
        best = ("symsplit", model.split + (k + 1) // 2, (k + 1) // 2)
    return best


@lru_cache(maxsize=None)
def _divisors_below(k: int) -> tuple[int, ...]:
    """The divisors of ``k`` below ``k``, smallest first."""
    return tuple(p for p in range(1, k) if k % p == 0)


SMALL = 48  # regions with at most this many repeated instances inside: plain Python (numpy's per-call cost dominates)


def region_actions(index: LayoutIndex, sig: int, sym: RepeatedRegions, model: CostModel,
                   max_groupings: int = 24, best_only: bool = False) -> Candidates:
    """Candidate rules for the region signature ``sig`` (its representative box); per axis at most
    ``max_groupings`` groupings from repeated regions (the most important first, f(a, o) of §4.7). With
    ``best_only``, only the first of least heuristic (see ``Candidates``)."""
    info = index.sigs[sig]
    box, n = info.box, info.n
    inside = sym.within(box)
    terms = sym.terminals.take(inside)
    proper = terms != n  # the region itself (the one instance inside with all its terminals) is not inside
    inside, terms = inside[proper], terms[proper]
    if info.period is not None:
        return _periodic(index, sig, model, sym.boxes.take(inside, 0), terms, best_only)
    actions = Candidates(index, box, model, best_only)
    instances = None
    lone = terms.size == 0 or terms.max() == 1  # only single terminals inside: no valid line cuts an instance
    if inside.size > SMALL and not lone:
        inst = sym.boxes.take(inside, 0)
        # the instances by repeated region (signature), and each region's f(a, o) (the same for all its instances)
        order = sym.group.take(inside).argsort(kind="stable")
        grp = sym.group.take(inside.take(order))
        starts = np.concatenate([[True], grp[1:] != grp[:-1]]).nonzero()[0]
        score = -sym.importance.take(inside.take(order.take(starts)))
    for axis in (0, 1):
        cuts = index.cuts(box, axis)
        if not cuts:
            continue
        bl = [box[axis], *cuts, box[axis + 2]]
        m = len(bl) - 1
        # line[k]: Eq. 5 cost of cutting at boundary k; per repeated region, the boundaries inside any of its
        # instances (which a grouping keeping every instance whole drops) as a bit mask, boundary k at bit
        # m - 1 - k, so that masks order as the rows of boundaries do: the distinct masks, in lexicographic order
        # (the first region's score), by f(a, o)
        if lone:  # (every mask is empty: the grouping it keeps is ``every``)
            line, rows = [0.0] * (m + 1), ()
        elif inside.size > SMALL and m <= 62:  # (a mask fits in int64)
            line, rows = _coverage(inst, terms, order, starts, score, axis, bl, n, max_groupings)
        else:
            if instances is None:
                group = sym.group.take(inside).tolist()
                instances = list(zip(sym.boxes.take(inside, 0).tolist(), terms.tolist(), group))
                scores = dict(zip(group, (-sym.importance.take(inside)).tolist()))
            line, rows = _small_coverage(instances, scores, axis, bl, n, max_groupings)
        every = tuple(range(1, m))
        groupings = {every}  # a grouping = the atom boundaries kept
        groupings.update(_kept(row, m, every) for row in rows)
        atom_sigs = [index.sig(_piece(box, axis, bl[k], bl[k + 1]), True) for k in range(m)]
        groupings.update(_repeated_runs([(s, bl[k + 1] - bl[k]) for k, s in enumerate(atom_sigs)]))
        piece = _Pieces(index, box, axis, bl, atom_sigs)
        if actions.bound is None:
            _add_all(actions, axis, bl, m, groupings, piece, line)
        else:
            _add_best(actions, axis, bl, m, groupings, piece, line)
    if not len(actions):
        for action in _grids(index, sig, sym, model, coarse=not best_only):
            actions.add_action(action)
        actions.greedy = len(actions) - 1  # (Eq. 5 ranks grids by their item count alone: see ``_grids``)
    return actions


def _small_coverage(instances: list[tuple[list[int], int, int]], score: dict[int, float], axis: int, bl: list[int],
                    n: int, max_groupings: int) -> tuple[list[float], list[int]]:
    """The line costs and the ranked masks of ``region_actions`` in plain Python, from the instances (box,
    terminals, group) and each group's score."""
    m = len(bl) - 1
    crossed = [0] * (m + 1)
    masks: dict[int, int] = {}
    for inst, terms, group in instances:
        lo, hi = bisect_right(bl, inst[axis]), bisect_left(bl, inst[axis + 2])  # boundaries lo..hi-1 inside
        for k in range(lo, hi):
            crossed[k] += terms
        masks[group] = masks.get(group, 0) | ((1 << (m - lo)) - (1 << (m - hi)))
    first: dict[int, int] = {}
    for group in sorted(masks):
        first.setdefault(masks[group], group)
    return [c / n for c in crossed], sorted(sorted(first), key=lambda r: score[first[r]])[:max_groupings]


def _coverage(inst: np.ndarray, terms: np.ndarray, order: np.ndarray, starts: np.ndarray, score: np.ndarray,
              axis: int, bl: list[int], n: int, max_groupings: int) -> tuple[list[float], list[int]]:
    """``_small_coverage`` with arrays: the instances in ``order`` of group, each group from ``starts`` with its
    ``score``; the terminals crossed at each boundary by a difference array (exact integer sums in float64)."""
    m = len(bl) - 1
    line, lo, hi = _line_costs(inst, terms, axis, bl, n)
    masks = np.bitwise_or.reduceat(((1 << (m - lo)) - (1 << (m - hi))).take(order), starts)
    by_mask = masks.argsort(kind="stable")  # each distinct mask's first group (np.unique's return_index, leaner)
    ranked = masks.take(by_mask)
    new = np.empty(ranked.size, dtype=bool)
    new[0] = True
    np.not_equal(ranked[1:], ranked[:-1], out=new[1:])
    first = by_mask.compress(new)
    top = first.take(score.take(first).argsort(kind="stable")[:max_groupings])
    return line, masks.take(top).tolist()


def _add_all(actions: Candidates, axis: int, bl: list[int], m: int, groupings, piece: _Pieces, line: list[float]
             ) -> None:
    """Every grouping's rule, then the rule with its runs of identical children merged, in order (once each)."""
    seen = set()
    for keep in groupings:
        edges = [0, *keep, m]
        sigs = [piece[ab] for ab in zip(edges, edges[1:])]
        merged = _merge_runs(piece, bl, edges, sigs) if any(map(eq, sigs, sigs[1:])) else None
        for e, sg in ((edges, sigs), merged) if merged else ((edges, sigs),):
            if len(e) < 3 or tuple(e) in seen:
                continue
            seen.add(tuple(e))
            actions.add(axis, bl, e, sg, line)


def _add_best(actions: Candidates, axis: int, bl: list[int], m: int, groupings, piece: _Pieces, line: list[float]
              ) -> None:
    """The rules of ``_add_all`` for a greedy run (``actions.bound`` set), which keeps the first of least H: the
    groupings are visited by a lower bound on H, known before any piece is looked up (the operator bound plus the
    line costs of the boundaries that no merge of equal-size neighbours can drop), and those that cannot win are
    never looked up. Each rule competes with its rank in ``_add_all``'s order (the first, when it comes twice), so
    the kept rule is the one ``_add_all`` keeps."""
    low, lam = actions.bound
    groupings = list(groupings)
    bounds = [low + lam * _kept_line_cost(keep, bl, m, line) for keep in groupings] if any(line) \
        else [low] * len(groupings)
    seen: dict[tuple[int, ...], int] = {}
    base = axis << 20
    for g in sorted(range(len(bounds)), key=bounds.__getitem__):
        bound, best = bounds[g], actions.best
        if best is not None:
            if bound > best[0]:
                break
            if bound == best[0] and base + 2 * g > best[1]:
                continue
        edges = [0, *groupings[g], m]
        sigs = [piece[ab] for ab in zip(edges, edges[1:])]
        merged = _merge_runs(piece, bl, edges, sigs) if any(map(eq, sigs, sigs[1:])) else None
        for rank, (e, sg) in enumerate(((edges, sigs), merged) if merged else ((edges, sigs),), base + 2 * g):
            key = tuple(e)
            if len(e) < 3 or seen.get(key, rank + 1) <= rank:
                continue
            seen[key] = rank
            actions.add(axis, bl, e, sg, line, rank=rank)


def _kept(row: int, m: int, every: tuple[int, ...]) -> tuple[int, ...]:
    """The boundaries 1..m-1 (``every``) whose bit (boundary k at bit m - 1 - k) is clear in ``row``, taken run by
    run of set bits (a row's set bits are the boundaries inside its instances: a few runs)."""
    if not row:
        return every
    kept: list[int] = []
    start = 0  # every[start] is the first boundary not yet decided
    while row:
        top = row.bit_length()  # the highest run of set bits: bits low..top-1, boundaries m-top..m-1-low
        low = (~row & ((1 << top) - 1)).bit_length()
        kept += every[start:m - top - 1]
        start = m - low - 1
        row &= (1 << low) - 1
    kept += every[start:]
    return tuple(kept)


def _kept_line_cost(keep: tuple[int, ...], bl: list[int], m: int, line: list[float]) -> float:
    """The line costs of the boundaries ``keep`` that no merge of equal-size neighbours can drop (boundary k
    between kept neighbours p, q goes when bl[k] - bl[p] == bl[q] - bl[k]), summed left to right."""
    s = 0
    if not keep:
        return s
    p, k = bl[0], keep[0]
    c = bl[k]
    for q in keep[1:]:
        d = bl[q]
        if c + c != p + d:
            s += line[k]
        p, k, c = c, q, d
    if c + c != p + bl[m]:
        s += line[k]
    return s


def _line_costs(inst: np.ndarray, terms: np.ndarray, axis: int, bl: list[int], n: int
                ) -> tuple[list[float], np.ndarray, np.ndarray]:
    """Eq. 5's cost of cutting at each boundary ``bl``: the terminals of the repeated instances it crosses over
    the region's ``n`` (a difference array: exact integer sums in float64); and per instance the range lo..hi-1 of
    the boundaries it crosses."""
    bounds = np.array(bl)
    lo = bounds.searchsorted(inst[:, axis], "right")
    hi = bounds.searchsorted(inst[:, axis + 2], "left")
    weights = terms.astype(float)
    crossed = (np.bincount(lo, weights, len(bl)) - np.bincount(hi, weights, len(bl))).cumsum()
    return (crossed / n).tolist(), lo, hi


def _periodic(index: LayoutIndex, sig: int, model: CostModel, inst: np.ndarray, terms: np.ndarray,
              best_only: bool) -> Candidates:
    """A periodic region (any tile count shares its signature) only gets ``repeat`` rules: over whole tiles, or
    over the tile's atoms written inline."""
    box = index.sigs[sig].box
    axis, p = index.sigs[sig].period
    cuts = index.cuts(box, axis)
    bl = [box[axis], *cuts, box[axis + 2]]
    line = _line_costs(inst, terms, axis, bl, index.sigs[sig].n)[0]
    tiles = [k for k, v in enumerate(bl) if (v - box[axis]) % p == 0]
    out = Candidates(index, box, model, best_only)
    for edges in (tiles, list(range(len(bl)))):
        sigs = [index.sig(_piece(box, axis, bl[a], bl[b]), True) for a, b in zip(edges, edges[1:])]
        out.add(axis, bl, edges, sigs, line, only="repeat")  # (always: for >= 2 tiles repeat is the cheapest)
        if len(tiles) == len(bl):
            break
    return out


def _repeated_runs(atoms: list[tuple[int, int]], limit: int = 16) -> list[tuple[int, ...]]:
    """Groupings that keep every occurrence of a repeated atom substring whole (1-D symmetry along the axis).

    Substrings are grown one atom at a time as integer ids (the id of the one an atom shorter, then the atom), from
    the starts whose shorter substring occurs more than once (no other can repeat)."""
    m = len(atoms)
    if m < 4:  # (no substring of two or more atoms occurs twice)
        return []
    ids: dict[tuple[int, int], int] = {}
    code = [ids.setdefault(a, len(ids)) for a in atoms]  # per start, the id of its substring of length 1
    width = len(ids)
    cur, live = code, range(m)
    found: list[tuple[int, int, list[int]]] = []  # (weight, length, occurrences kept whole)
    for length in range(2, m // 2 + 1):
        starts: dict[int, list[int]] = {}  # distinct substrings of this length, by first occurrence
        for i in live:
            if i <= m - length:
                starts.setdefault(cur[i] * width + code[i + length - 1], []).append(i)
        repeated = False
        cur, live = [0] * m, []
        for n, occ in enumerate(starts.values()):
            if len(occ) < 2:
                continue
            live += occ
            chosen, end = [], -1
            for i in occ:
                cur[i] = n
                if i >= end:
                    chosen.append(i)
                    end = i + length
            if len(chosen) >= 2:
                found.append(((length - 1) * (len(chosen) - 1), length, chosen))
                repeated = True
        if not repeated:  # a substring twice apart has its prefix twice apart: no longer one repeats either
            break
        live.sort()
    found.sort(key=lambda t: -t[0])
    out = []
    for _, length, chosen in found[:limit]:
        kept = [True] * m  # per boundary: not strictly inside a chosen occurrence
        inner = [False] * (length - 1)
        for i in chosen:
            kept[i + 1:i + length] = inner
        out.append(tuple(compress(range(1, m), kept[1:])))
    return out


def _piece(box: Box, axis: int, a: int, b: int) -> Box:
    """The slab of ``box`` from ``a`` to ``b`` along ``axis``: exactly tiled when ``box`` is and ``a``, ``b`` are
    its sides or valid cuts (so its signature is looked up with ``tiled``)."""
    return (int(a), box[1], int(b), box[3]) if axis == 0 else (box[0], int(a), box[2], int(b))


class _Pieces(dict):
    """Signatures of the pieces of ``box`` between atom boundaries ``(a, b)`` along ``axis``, each looked up once."""

    def __init__(self, index: LayoutIndex, box: Box, axis: int, bl: list[int], atom_sigs: list[int]) -> None:
        super().__init__(((k, k + 1), s) for k, s in enumerate(atom_sigs))
        self.index, self.box, self.axis, self.bl = index, box, axis, bl

    def __missing__(self, ab: tuple[int, int]) -> int:
        s = self[ab] = self.index.sig(_piece(self.box, self.axis, self.bl[ab[0]], self.bl[ab[1]]), True)
        return s


def _merge_runs(piece: _Pieces, bl: list[int], edges: list[int], sigs: list[int]) -> tuple[list[int], list[int]]:
    """Runs of identical consecutive children merged into one child (which a repeat rule then explains)."""
    out_e, out_s, start = [edges[0]], [], 0
    n = len(sigs)
    for k in range(1, n + 1):
        if k == n or sigs[k] != sigs[start] or \
                bl[edges[k + 1]] - bl[edges[k]] != bl[edges[start + 1]] - bl[edges[start]]:
            out_e.append(edges[k])
            out_s.append(piece[edges[start], edges[k]] if k - start > 1 else sigs[start])
            start = k
    return out_e, out_s


def _rel(box: Box, p: Box) -> Box:
    return (p[0] - box[0], p[1] - box[1], p[2] - box[0], p[3] - box[1])


class Candidates:
    """The candidate rules of one region in order: per candidate its cost C and heuristic H (Eq. 5), computed when
    it is added; the rule object (successor boxes, children, cuts) is built on first use, since a greedy run only
    uses the one it chooses. With ``best_only`` only the first candidate of least H is kept (all a greedy run
    needs): a candidate whose H cannot be below the best so far by a bound on its operator cost is not priced."""

    def __init__(self, index: LayoutIndex, box: Box, model: CostModel, best_only: bool = False) -> None:
        self.index, self.box, self.model = index, box, model
        # least operator cost of >= 2 children: split into 2, repeat of 1 tile (symsplit, repeatABA cost more)
        low = min(model.split + 2, model.repeat + 1)
        # with ``best_only``: any candidate's H >= bound[0] + bound[1] x its line cost
        self.bound = (model.lambda1 * low, model.lambda2) if best_only and model.lambda1 >= 0 <= model.lambda2 \
            else None
        self._best_only = best_only
        self.best: tuple[float, float] | None = None  # with ``best_only``: H and rank of the kept candidate
        self.cost: list[float] = []
        self.heuristic: list[float] = []
        self._specs: list[tuple] = []
        self.built: list[Action | None] = []  # per candidate its rule once built (``self[k]`` builds it)
        self.greedy: int | None = None  # the candidate a greedy run takes, where not the first of least H

    def __len__(self) -> int:
        return len(self.cost)

    def __getitem__(self, k: int) -> Action:
        action = self.built[k]
        if action is None:
            action = self.built[k] = _make(self.index, self.box, *self._specs[k])
        return action

    def __iter__(self):
        return (self[k] for k in range(len(self.cost)))

    def add(self, axis: int, bl: list[int], edges: list[int], sigs: list[int], line: list[float],
            only: str | None = None, rank: int | None = None) -> None:
        """The rule splitting the box at the atom boundaries ``edges`` (of the lines ``bl``) into ``sigs``;
        ``line`` the Eq. 5 cost of cutting at each boundary. With ``only``, kept when its operator is ``only``.
        With ``best_only``, ``rank`` orders candidates of equal H (default: after every one added before)."""
        line_cost = sum(map(line.__getitem__, edges[1:-1]))
        if self.bound is not None and self.heuristic and self.bound[0] + self.bound[1] * line_cost > self.best[0]:
            return
        op, cost, k = _ops([(s, bl[b] - bl[a]) for s, a, b in zip(sigs, edges, edges[1:])], self.model)
        if only is not None and op != only:
            return
        heuristic = self.model.lambda1 * cost + self.model.lambda2 * line_cost
        if self._best_only:
            if self.heuristic:
                if not (heuristic < self.best[0] or heuristic == self.best[0] and rank is not None
                        and rank < self.best[1]):
                    return
                self.cost.clear(), self.heuristic.clear(), self._specs.clear(), self.built.clear()
            self.best = (heuristic, math.inf if rank is None else rank)
        self.cost.append(cost)
        self.heuristic.append(heuristic)
        self._specs.append((axis, bl, edges, sigs, op, cost, k, heuristic))
        self.built.append(None)

    def add_action(self, action: Action) -> None:
        self.built.append(action)
        self.cost.append(action.cost)
        self.heuristic.append(action.heuristic)
        self._specs.append(None)

    def cut_lines(self) -> tuple[list[int], list[int], list[int], list[int]]:
        """Every split line of every candidate, without building the rules: the candidates that have lines (in
        order) and the offset of each one's first line, then per line its axis and position (absolute)."""
        owners, starts, axes, cuts = [], [], [], []
        for k, spec in enumerate(self._specs):
            if spec is None:
                action = self.built[k]
                axis, lines = action.axis, [c + self.box[action.axis] for c in action.cuts]
            else:
                axis, bl, edges = spec[0], spec[1], spec[2]
                lines = [bl[e] for e in edges[1:-1]]
            if lines:
                owners.append(k)
                starts.append(len(cuts))
                axes += [axis] * len(lines)
                cuts += lines
        return owners, starts, axes, cuts

    def kids(self, k: int) -> tuple[int, ...]:
        """The distinct non-terminal successor signatures of candidate ``k`` (its rule's ``children``)."""
        spec = self._specs[k]
        if spec is None:
            return tuple(c for c, _ in self[k].children)
        info = self.index.sigs
        return tuple(dict.fromkeys(s for s in spec[3] if info[s].n > 1))


def _make(index: LayoutIndex, box: Box, axis: int, bl: list[int], edges: list[int], sigs: list[int], op: str,
          cost: float, k: int, heuristic: float) -> Action:
    """The rule splitting ``box`` at the atom boundaries ``edges`` (of the lines ``bl``) into children ``sigs``."""
    ends = [bl[e] - bl[0] for e in edges]
    span = box[3] - box[1] if axis == 0 else box[2] - box[0]
    rels = [(a, 0, b, span) if axis == 0 else (0, a, span, b) for a, b in zip(ends, ends[1:])]
    children, seen, info = [], set(), index.sigs
    for s, r in zip(sigs, rels):
        if s not in seen and info[s].n > 1:
            seen.add(s)
            children.append((s, r))
    return Action(op, axis, tuple(zip(sigs[:k], rels[:k])), tuple(children), cost, heuristic, tuple(ends[1:-1]))


def _grids(index: LayoutIndex, sig: int, sym: RepeatedRegions, model: CostModel, coarse: bool = True
           ) -> list[Action]:
    """gridsplit (wu2014 §4.7) of a region that no single line separates (§6.3), coarse to fine (the distinct
    ones): its *guillotine blocks* (``_blocks``) as items, each a region of its own that split rules derive; the
    blocks that are repeated regions (§4.3) or occur twice, the others written out by their terminals; every
    terminal. Eq. 5 cannot rank them -- a coarser grid always has the lower H, though its blocks cost rules of
    their own -- so a greedy run takes the finest (every terminal, the only grid before) and ADP's value function
    (Eq. 4), which sees the blocks' sub-grammars, chooses among them. Without ``coarse``, only the finest."""
    box = index.sigs[sig].box
    idx = index.inside(box)
    terminals = list(zip(*(v.take(idx).tolist() for v in (index.X0, index.Y0, index.X1, index.Y1))))
    if not coarse:
        return [_grid(index, box, terminals, model)]
    blocks = min((_blocks(terminals, first) for first in (0, 1)), key=len)
    sigs = [index.sig(b, True) for b in blocks]
    repeated, count = set(sym.group.tolist()), Counter(sigs)
    kept = [b for b, s in zip(blocks, sigs) if index.sigs[s].n == 1 or s in repeated or count[s] > 1]
    hybrid = kept + [t for t in terminals if not any(_covers(b, t) for b in kept)]
    out, seen = [], set()
    for items in (blocks, hybrid, terminals):
        key = frozenset(items)
        if key not in seen:
            seen.add(key)
            out.append(_grid(index, box, items, model))
    return out


def _covers(b: Box, t: Box) -> bool:
    return b[0] <= t[0] and b[1] <= t[1] and t[2] <= b[2] and t[3] <= b[3]


def _grid(index: LayoutIndex, box: Box, pieces: list[Box], model: CostModel) -> Action:
    """The grid rule of ``box`` whose items are the tiled ``pieces`` (bottom to top, left to right) in the grid
    of their edges."""
    pieces = sorted(pieces, key=lambda b: (b[1], b[0]))
    items = tuple((index.sig(b, True), _rel(box, b)) for b in pieces)
    children, seen = [], set()
    for s, rel in items:
        if s not in seen and index.sigs[s].n > 1:
            seen.add(s)
            children.append((s, rel))
    xs = tuple(sorted({v - box[0] for b in pieces for v in (b[0], b[2])}))
    ys = tuple(sorted({v - box[1] for b in pieces for v in (b[1], b[3])}))
    cost = model.split + len(items)
    return Action("grid", 0, items, tuple(children), cost, model.lambda1 * cost, (), (xs, ys))


def _blocks(boxes: list[Box], first: int) -> list[Box]:
    """The boxes merged while two of them share a whole side, along axis ``first``, then the other, and again
    until none does: every block is then guillotine-cut (by the sides merged), and no two blocks form a rectangle.
    In a region no line separates the merging stops at five blocks or more (a pinwheel is the least)."""
    blocks = list(boxes)
    axis, still = first, 0
    while still < 2:  # (both axes tried without a merge)
        other = 1 - axis
        rows: dict[tuple[int, int], list[Box]] = {}  # per span across the axis, the blocks along it
        for b in blocks:
            rows.setdefault((b[other], b[other + 2]), []).append(b)
        merged: list[Box] = []
        for row in rows.values():
            row.sort(key=lambda b: b[axis])
            run = row[0]
            for b in row[1:]:
                if b[axis] == run[axis + 2]:  # abutting: one block
                    run = (run[0], run[1], b[2], run[3]) if axis == 0 else (run[0], run[1], run[2], b[3])
                else:
                    merged.append(run)
                    run = b
            merged.append(run)
        still = still + 1 if len(merged) == len(blocks) else 0
        blocks, axis = merged, other
    return blocks
