"""Symmetry detection (wu2014 §4.3): exhaustive, hash-based growing of repeated regions in four directions.

Starting from every terminal that occurs at least twice, each repeated region is grown left, right, down and up
by the strip of terminals adjacent to that side when their far edges align (Fig. 7); a grown region that still
occurs two or more times enters the hash table (signature -> instances) and is grown in turn.
"""
from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from citygen_inverse.regions import Box, LayoutIndex, _upow


@dataclass(frozen=True)
class RepeatedRegions:
    """Instances of repeated regions as arrays: boxes ``(m, 4)``, terminal count ``a`` and group ``o``."""

    boxes: np.ndarray
    terminals: np.ndarray
    occurrences: np.ndarray
    group: np.ndarray

    @cached_property
    def columns(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """x0, y0, x1, y1 of the instances as contiguous arrays (fast containment tests)."""
        return tuple(np.ascontiguousarray(self.boxes[:, k]) for k in range(4))

    @property
    def importance(self) -> np.ndarray:
        """wu2014 §4.7: f(a, o) = (a - 1)(o - 1) per instance."""
        return (self.terminals - 1) * (self.occurrences - 1)


class _Sides:
    """Per side (0 right, 1 left, 2 up, 3 down), the terminals touching a box side from the outside, as sorted
    arrays keyed by (line rank, start rank) and (line rank, end rank), with *runs* (contiguous terminals with one
    far edge) and prefix sums of a translation-covariant strip hash sum_k R(material_k) P^start_k (mod 2^64)."""

    LANES = ((0x9E3779B97F4A7C15, 0xBF58476D1CE4E5B9), (0xD6E8FEB86659FD93, 0x94D049BB133111EB))

    def __init__(self, index: LayoutIndex) -> None:
        X0, Y0, X1, Y1 = index.X0, index.Y0, index.X1, index.Y1
        self.lines = (np.unique(np.concatenate([X0, X1])), np.unique(np.concatenate([Y0, Y1])))
        self.stride = max(v.size for v in self.lines) + 1
        mat = index.material.astype(np.uint64) + np.uint64(1)
        powers = [[(_upow([p], v)[0], _upow([pow(p, -1, 1 << 64)], v)[0]) for _, p in self.LANES] for v in self.lines]
        spec = ((X0, Y0, Y1, X1), (X1, Y0, Y1, X0), (Y0, X0, X1, Y1), (Y1, X0, X1, Y0))
        self.sides = []
        for d, (line, start, end, far) in enumerate(spec):
            order = np.lexsort((start, line))
            line, start, end, far, m = line[order], start[order], end[order], far[order], mat[order]
            across, along = self.lines[d // 2], self.lines[1 - d // 2]
            rank = np.searchsorted(across, line) * self.stride
            new_run = np.ones(line.size, dtype=bool)
            new_run[1:] = (line[1:] != line[:-1]) | (start[1:] != end[:-1]) | (far[1:] != far[:-1])
            at = np.searchsorted(along, start)
            lanes = []
            for (r, p), (power, inverse) in zip(self.LANES, powers[1 - d // 2]):
                prefix = np.zeros(line.size + 1, dtype=np.uint64)
                np.cumsum(m * np.uint64(r) * power[at], out=prefix[1:])
                lanes.append((prefix, inverse[at]))
            self.sides.append((rank + at, rank + np.searchsorted(along, end), np.cumsum(new_run), line, far, lanes))

    def grow(self, boxes: np.ndarray, direction: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per box (rows of ``boxes``), whether it grows by the strip of terminals adjacent to one side (the strip
        exactly covers that side and its far edges align, Fig. 7): a mask, the grown boxes and a content key
        (thickness, terminal count, two hash lanes) of each strip, for the boxes that grow."""
        by_start, by_end, run, line, far, lanes = self.sides[direction]
        across, along = self.lines[direction // 2], self.lines[1 - direction // 2]
        side = boxes[:, (2, 0, 3, 1)[direction]]
        a, b = (boxes[:, 1], boxes[:, 3]) if direction < 2 else (boxes[:, 0], boxes[:, 2])
        rank = np.searchsorted(across, side) * self.stride
        qa, qb = rank + np.searchsorted(along, a), rank + np.searchsorted(along, b)
        i = np.minimum(np.searchsorted(by_start, qa), by_start.size - 1)
        j = np.minimum(np.searchsorted(by_end, qb), by_end.size - 1)
        ok = (by_start[i] == qa) & (by_end[j] == qb) & (i <= j) & (run[i] == run[j])
        i, j, side, boxes = i[ok], j[ok], side[ok], boxes[ok]
        f = far[i]
        grown = boxes.copy()
        grown[:, (2, 0, 3, 1)[direction]] = f
        key = np.empty((i.size, 4), dtype=np.int64)
        key[:, 0] = f - side
        key[:, 1] = j - i
        for k, (prefix, inverse) in enumerate(lanes):
            key[:, 2 + k] = ((prefix[j + 1] - prefix[i]) * inverse[i]).view(np.int64)
        return ok, grown, key


def detect_symmetry(index: LayoutIndex, max_groups: int = 1500) -> RepeatedRegions:
    """All repeated regions reachable by growing (capped at ``max_groups`` signatures).

    Instances of one group that are grown by strips of identical content (and have the same size) have identical
    content, so only one of them is looked up in the signature table. The groups waiting in the queue are grown
    together (array operations over all their instances); their results are taken in queue order.
    """
    sides = _Sides(index)
    table: dict[int, list[Box]] = defaultdict(list)
    for k in range(index.X0.size):
        box = (int(index.X0[k]), int(index.Y0[k]), int(index.X1[k]), int(index.Y1[k]))
        table[index.sig(box)].append(box)
    groups = {s: boxes for s, boxes in table.items() if len(boxes) >= 2}
    queue = sorted(groups)
    while queue and len(groups) < max_groups:
        batch, queue = queue, []
        sizes = [len(groups[s]) for s in batch]
        boxes = np.array([box for s in batch for box in groups[s]], dtype=np.int64)
        owner = np.repeat(np.arange(len(batch)), sizes)
        found = [_same_strips(sides, boxes, owner, len(batch), direction) for direction in range(4)]
        for g, sig in enumerate(batch):
            if len(groups) >= max_groups:
                break
            for starts, members, grown_boxes in found:
                grown: dict[int, list[Box]] = defaultdict(list)
                for k in range(starts[g], starts[g + 1]):
                    same = [tuple(grown_boxes[m]) for m in members[k]]
                    grown[index.sig(same[0])].extend(same)
                for new_sig, same in grown.items():
                    if new_sig > 0 and len(same) >= 2 and new_sig not in groups:
                        groups[new_sig] = same
                        queue.append(new_sig)
    multi = groups
    boxes = [box for s in multi for box in multi[s]]
    return RepeatedRegions(
        boxes=np.array(boxes, dtype=np.int64).reshape(-1, 4),
        terminals=np.array([index.sigs[s].n for s in multi for _ in multi[s]], dtype=np.int64),
        occurrences=np.array([len(multi[s]) for s in multi for _ in multi[s]], dtype=np.int64),
        group=np.array([s for s in multi for _ in multi[s]], dtype=np.int64))


def _same_strips(sides: _Sides, boxes: np.ndarray, owner: np.ndarray, groups: int, direction: int
                 ) -> tuple[list[int], list[list[int]], list[Box]]:
    """The instances of ``groups`` groups (``owner`` per row of ``boxes``) grown in one direction, in classes of
    equal group, size and strip content: per group the range of its classes (``starts``), per class the indices
    of its grown boxes in instance order (classes of a group ordered by their first instance), the grown boxes."""
    ok, grown, key = sides.grow(boxes, direction)
    owner, boxes = owner[ok], boxes[ok]
    cols = np.column_stack([owner, boxes[:, 2] - boxes[:, 0], boxes[:, 3] - boxes[:, 1], key])
    order = np.lexsort((np.arange(owner.size), *cols.T[::-1]))  # by group and class, then instance order
    cut = np.ones(owner.size, dtype=bool)
    cut[1:] = np.any(cols[order[1:]] != cols[order[:-1]], axis=1)
    first = np.flatnonzero(cut)
    classes = np.argsort(order[first], kind="stable")
    starts = np.searchsorted(owner[order[first[classes]]], np.arange(groups + 1)).tolist()
    order, bounds = order.tolist(), [*first.tolist(), owner.size]
    return starts, [order[bounds[c]:bounds[c + 1]] for c in classes.tolist()], grown.tolist()
