"""Symmetry detection (wu2014 §4.3): exhaustive, hash-based growing of repeated regions in four directions.

Starting from every terminal that occurs at least twice, each repeated region is grown left, right, down and up
by the strip of terminals adjacent to that side when their far edges align (Fig. 7); a grown region that still
occurs two or more times enters the hash table (signature -> instances) and is grown in turn.
"""
from __future__ import annotations

from bisect import bisect_left, bisect_right
from collections import defaultdict
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from citygen_inverse.regions import LayoutIndex


@dataclass(frozen=True)
class RepeatedRegions:
    """Instances of repeated regions as arrays: boxes ``(m, 4)``, terminal count ``a`` and group ``o``."""

    boxes: np.ndarray
    terminals: np.ndarray
    occurrences: np.ndarray
    group: np.ndarray

    def within(self, box: tuple[int, int, int, int]) -> np.ndarray:
        """Indices of the instances inside ``box`` (the box itself included, when it is an instance)."""
        (xs, ys), (x0, y0, x1, y1) = self._containment
        return (x0[bisect_left(xs, box[0])] & y0[bisect_left(ys, box[1])] &
                x1[bisect_right(xs, box[2])] & y1[bisect_right(ys, box[3])]).nonzero()[0]

    @cached_property
    def _containment(self) -> tuple[tuple[list[int], list[int]], tuple[np.ndarray, ...]]:
        """The instances' distinct x and y lines, and per side a table: row r holds which instances have their
        x0 (y0) at line r or beyond, or their x1 (y1) before line r."""
        lines = [np.unique(self.boxes[:, axis::2]) for axis in (0, 1)]
        tables = []
        for k in range(4):
            rank, rows = np.searchsorted(lines[k % 2], self.boxes[:, k]), np.arange(lines[k % 2].size + 1)[:, None]
            tables.append(rank[None, :] >= rows if k < 2 else rank[None, :] < rows)
        return (lines[0].tolist(), lines[1].tolist()), tuple(tables)

    @cached_property
    def importance(self) -> np.ndarray:
        """wu2014 §4.7: f(a, o) = (a - 1)(o - 1) per instance."""
        return (self.terminals - 1) * (self.occurrences - 1)


class _Sides:
    """The terminals touching a box side from the outside, per side (0 right, 1 left, 2 up, 3 down) and line, in
    one table sorted by (side, line rank, start rank) with the same keys by end rank, *runs* (contiguous terminals
    of one side and line with one far edge) and prefix sums of a translation-covariant strip content hash
    sum_k R(material_k) P^start_k (mod 2^64, two lanes; P^v of the index's grid)."""

    MATERIAL = np.array([0xBF58476D1CE4E5B9, 0x94D049BB133111EB], dtype=np.uint64)  # R(material) per lane
    MIX = np.array([[0xA24BAED4963EE407, 0x9FB21C651E98DF25, 0xC13FA9A902A6328F, 0x91E10DA5C79E7B1D],
                    [0xE7037ED1A0B428DB, 0x8EBC6AF09C88C6E3, 0x589965CC75374CC3, 0x1D8E4E27C47D124F]], dtype=np.uint64)
    NEAR, START, END = [2, 0, 3, 1], [1, 1, 0, 0], [3, 3, 2, 2]  # per side: the box column of its line, a, b
    DENSE = 1 << 20

    def __init__(self, index: LayoutIndex) -> None:
        X0, Y0, X1, Y1 = index.X0, index.Y0, index.X1, index.Y1
        self.lines = (np.unique(np.concatenate([X0, X1])), np.unique(np.concatenate([Y0, Y1])))
        self.stride = max(v.size for v in self.lines) + 1
        ranks = [np.searchsorted(self.lines[k % 2], v) for k, v in enumerate((X0, Y0, X1, Y1))]
        cols = ((0, 1, 3, 2), (2, 1, 3, 0), (1, 0, 2, 3), (3, 0, 2, 1))  # per side: terminal's line, start, end, far
        key_start, key_end, far, at = [], [], [], []
        for d, (li, st, en, fa) in enumerate(cols):
            base = (d * self.stride + ranks[li]) * self.stride
            key_start.append(base + ranks[st])
            key_end.append(base + ranks[en])
            far.append((X0, Y0, X1, Y1)[fa])
            at.append(ranks[st] + (d // 2) * self.lines[1].size)  # index into the along-axis powers
        order = np.argsort(np.concatenate(key_start), kind="stable")
        self.by_start, self.by_end = np.concatenate(key_start)[order], np.concatenate(key_end)[order]
        self.far = np.concatenate(far)[order]
        new_run = np.ones(order.size, dtype=bool)
        new_run[1:] = (self.by_start[1:] // self.stride != self.by_start[:-1] // self.stride) | \
            (self.by_start[1:] != self.by_end[:-1]) | (self.far[1:] != self.far[:-1])
        self.run = np.cumsum(new_run)
        self.start_at = self.end_at = None  # a dense table of both sorted keys when small (a few MB at most)
        if 4 * self.stride ** 2 <= self.DENSE:
            self.start_at, self.end_at = np.full(4 * self.stride ** 2, -1), np.full(4 * self.stride ** 2, -1)
            self.start_at[self.by_start] = self.end_at[self.by_end] = np.arange(order.size)
        (ax, inv_ax), (ay, inv_ay) = index.grid_powers  # along y for sides 0 and 1, along x for 2 and 3
        at = np.concatenate(at)[order]
        power, self.inverse = np.concatenate([ay, ax], axis=1)[:, at], np.concatenate([inv_ay, inv_ax], axis=1)[:, at]
        mat = np.tile(index.material.astype(np.uint64) + np.uint64(1), 4)[order]
        self.prefix = np.zeros((power.shape[0], order.size + 1), dtype=np.uint64)
        np.cumsum(mat * self.MATERIAL[:, None] * power, axis=1, out=self.prefix[:, 1:])

    def grow(self, boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The rows of ``boxes`` that grow by the strip of terminals adjacent to one side (the strip exactly covers
        that side and its far edges align, Fig. 7), in every direction: per grown box its row, its direction,
        the grown box and two 64-bit hash lanes of (box size, strip thickness, terminal count, strip content)."""
        n = boxes.shape[0]
        ranks = np.stack([self.lines[k % 2].searchsorted(boxes[:, k]) for k in range(4)])  # (side, box)
        line = (np.arange(4)[:, None] * self.stride + ranks.take(self.NEAR, 0)) * self.stride  # (direction, box)
        qa, qb = (line + ranks.take(self.START, 0)).ravel(), (line + ranks.take(self.END, 0)).ravel()
        if self.start_at is not None:
            i, j = self.start_at.take(qa), self.end_at.take(qb)
            ok = ((i >= 0) & (i <= j) & (self.run.take(i) == self.run.take(j))).nonzero()[0]
        else:
            i = np.minimum(self.by_start.searchsorted(qa), self.by_start.size - 1)
            j = np.minimum(self.by_end.searchsorted(qb), self.by_end.size - 1)
            ok = ((self.by_start.take(i) == qa) & (self.by_end.take(j) == qb) & (i <= j) &
                  (self.run.take(i) == self.run.take(j))).nonzero()[0]
        i, j, (direction, rows) = i.take(ok), j.take(ok), np.divmod(ok, n)
        grown = boxes.take(rows, 0)  # (take: much faster than fancy indexing here)
        side, f = np.arange(0, 4 * ok.size, 4) + np.take(self.NEAR, direction), self.far.take(i)
        parts = np.column_stack([grown[:, 2] - grown[:, 0], grown[:, 3] - grown[:, 1],
                                 np.abs(f - grown.take(side)), j - i]).astype(np.uint64)
        grown.ravel()[side] = f
        hashes = (self.prefix.take(j + 1, 1) - self.prefix.take(i, 1)) * self.inverse.take(i, 1) + self.MIX @ parts.T
        return rows, direction, grown, hashes


def detect_symmetry(index: LayoutIndex, max_groups: int = 1500) -> RepeatedRegions:
    """All repeated regions reachable by growing (capped at ``max_groups`` signatures).

    Instances of one group that are grown by strips of identical content (and have the same size) have identical
    content, so only one of them is looked up in the signature table. The groups waiting in the queue are grown
    together (array operations over all their instances); their results are taken in queue order.
    """
    sides = _Sides(index)
    terminals = np.column_stack([index.X0, index.Y0, index.X1, index.Y1])
    table: dict[int, list[int]] = defaultdict(list)
    for k, s in enumerate(index.terminal_sigs()):
        table[s].append(k)
    groups = {s: terminals[rows] for s, rows in table.items() if len(rows) >= 2}
    queue = sorted(groups)
    while queue and len(groups) < max_groups:
        batch, queue = queue, []
        boxes = np.concatenate([groups[s] for s in batch])
        owner = np.repeat(np.arange(len(batch)), [len(groups[s]) for s in batch])
        starts, begin, size, firsts, grown = _same_strips(sides, boxes, owner, len(batch))
        sig = index.sig
        for g in range(len(batch)):
            if len(groups) >= max_groups:
                break
            lo, hi = starts[4 * g], starts[4 * g + 4]
            sigs = [sig(box, True) for box in firsts[lo:hi]]  # (in class order; grown boxes are tiled)
            if len(set(sigs)) == hi - lo:  # each class its own signature: a class of 2+ instances is a group
                for k, new_sig in zip(range(lo, hi), sigs):
                    if size[k] > 1 and new_sig > 0 and new_sig not in groups:
                        groups[new_sig] = grown[begin[k]:begin[k] + size[k]]
                        queue.append(new_sig)
                continue
            same: dict[tuple[int, int], list[int]] = {}  # classes of one direction with one signature merge
            for gd in range(4 * g, 4 * g + 4):
                for k in range(starts[gd], starts[gd + 1]):
                    same.setdefault((gd, sigs[k - lo]), []).append(k)
            for (_, new_sig), ks in same.items():
                if new_sig > 0 and (len(ks) > 1 or size[ks[0]] > 1) and new_sig not in groups:
                    groups[new_sig] = np.concatenate([grown[begin[k]:begin[k] + size[k]] for k in ks]) \
                        if len(ks) > 1 else grown[begin[ks[0]]:begin[ks[0]] + size[ks[0]]]
                    queue.append(new_sig)
    sizes = [len(instances) for instances in groups.values()]
    return RepeatedRegions(
        boxes=np.concatenate(list(groups.values())) if groups else np.zeros((0, 4), dtype=np.int64),
        terminals=np.repeat(np.array([index.sigs[s].n for s in groups], dtype=np.int64), sizes),
        occurrences=np.repeat(np.array(sizes, dtype=np.int64), sizes),
        group=np.repeat(np.array(list(groups), dtype=np.int64), sizes))


def _same_strips(sides: _Sides, boxes: np.ndarray, owner: np.ndarray, groups: int
                 ) -> tuple[list[int], list[int], list[int], list[tuple[int, ...]], np.ndarray]:
    """The instances of ``groups`` groups (``owner`` per row of ``boxes``) grown in every direction, in classes
    of equal group, direction, size and strip content (by a 128-bit hash). Returns per (group, direction) the
    range of its classes (``starts``, index ``4 group + direction``; a group's classes in order of their first
    instance), per class the start and size of its members (in instance order) in the grown boxes, which are
    sorted by class, and per class the first member."""
    rows, direction, grown, (h0, h1) = sides.grow(boxes)
    gd = owner.take(rows) * 4 + direction
    order = np.lexsort((h1, h0, gd))  # stable: equal keys stay in instance order
    gd, h0, h1, grown = gd.take(order), h0.take(order), h1.take(order), grown.take(order, 0)
    cut = np.ones(gd.size, dtype=bool)
    cut[1:] = (gd[1:] != gd[:-1]) | (h0[1:] != h0[:-1]) | (h1[1:] != h1[:-1])
    first = cut.nonzero()[0]
    classes = np.lexsort((order.take(first), gd.take(first)))
    begin = first.take(classes)
    starts = gd.take(begin).searchsorted(np.arange(4 * groups + 1)).tolist()
    size = (np.append(first[1:], gd.size) - first).take(classes)
    return starts, begin.tolist(), size.tolist(), list(map(tuple, grown.take(begin, 0).tolist())), grown
