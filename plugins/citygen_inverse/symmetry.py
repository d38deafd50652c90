"""Symmetry detection (wu2014 §4.3): exhaustive, hash-based growing of repeated regions in four directions.

Starting from every terminal that occurs at least twice, each repeated region is grown left, right, down and up
by the strip of terminals adjacent to that side when their far edges align (Fig. 7); a grown region that still
occurs two or more times enters the hash table (signature -> instances) and is grown in turn.
"""
from __future__ import annotations

from bisect import bisect_left, bisect_right
from collections import defaultdict, deque
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from citygen_inverse.regions import Box, LayoutIndex


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
    """Per side (0 right, 1 left, 2 up, 3 down) and line coordinate, the terminals touching that line from the
    outside, sorted along it: (starts, ends, far edges, materials) as lists for bisection."""

    def __init__(self, index: LayoutIndex) -> None:
        X0, Y0, X1, Y1 = (a.tolist() for a in (index.X0, index.Y0, index.X1, index.Y1))
        mat = index.material.tolist()
        spec = ((X0, Y0, Y1, X1), (X1, Y0, Y1, X0), (Y0, X0, X1, Y1), (Y1, X0, X1, Y0))
        self.sides: list[dict[int, tuple[list[int], list[int], list[int], list[int]]]] = []
        for line, start, end, far in spec:
            by_line: dict[int, list[int]] = defaultdict(list)
            for k, v in enumerate(line):
                by_line[v].append(k)
            side = {}
            for v, ks in by_line.items():
                ks.sort(key=start.__getitem__)
                side[v] = ([start[k] for k in ks], [end[k] for k in ks], [far[k] for k in ks], [mat[k] for k in ks])
            self.sides.append(side)

    def grow(self, box: Box, direction: int) -> tuple[Box, tuple] | None:
        """``box`` grown by the strip of terminals adjacent to one side when the strip exactly covers that side
        and its far edges align (Fig. 7), with a content key of the strip; None when it cannot grow."""
        x0, y0, x1, y1 = box
        line = (x1, x0, y1, y0)[direction]
        a, b = (y0, y1) if direction < 2 else (x0, x1)
        entry = self.sides[direction].get(line)
        if entry is None:
            return None
        starts, ends, fars, mats = entry
        i, j = bisect_right(ends, a), bisect_left(starts, b)
        if i >= j or starts[i] != a or ends[j - 1] != b:
            return None
        f = fars[i]
        for k in range(i + 1, j):
            if fars[k] != f or starts[k] != ends[k - 1]:
                return None
        strip = (f - line, *((mats[k], starts[k] - a) for k in range(i, j)))
        grown = ((x0, y0, f, y1), (f, y0, x1, y1), (x0, y0, x1, f), (x0, f, x1, y1))[direction]
        return grown, strip


def detect_symmetry(index: LayoutIndex, max_groups: int = 1500) -> RepeatedRegions:
    """All repeated regions reachable by growing (capped at ``max_groups`` signatures).

    Instances of one group that are grown by strips of identical content (and have the same size) have identical
    content, so only one of them is looked up in the signature table.
    """
    sides = _Sides(index)
    table: dict[int, list[Box]] = defaultdict(list)
    for k in range(index.X0.size):
        box = (int(index.X0[k]), int(index.Y0[k]), int(index.X1[k]), int(index.Y1[k]))
        table[index.sig(box)].append(box)
    groups = {s: boxes for s, boxes in table.items() if len(boxes) >= 2}
    queue = deque(sorted(groups))
    while queue and len(groups) < max_groups:
        sig = queue.popleft()
        for direction in range(4):
            same: dict[tuple, list[Box]] = defaultdict(list)
            for box in groups[sig]:
                found = sides.grow(box, direction)
                if found is not None:
                    same[(box[2] - box[0], box[3] - box[1], found[1])].append(found[0])
            grown: dict[int, list[Box]] = defaultdict(list)
            for boxes in same.values():
                grown[index.sig(boxes[0])].extend(boxes)
            for new_sig, boxes in grown.items():
                if new_sig > 0 and len(boxes) >= 2 and new_sig not in groups:
                    groups[new_sig] = boxes
                    queue.append(new_sig)
    multi = groups
    boxes = [box for s in multi for box in multi[s]]
    return RepeatedRegions(
        boxes=np.array(boxes, dtype=np.int64).reshape(-1, 4),
        terminals=np.array([index.sigs[s].n for s in multi for _ in multi[s]], dtype=np.int64),
        occurrences=np.array([len(multi[s]) for s in multi for _ in multi[s]], dtype=np.int64),
        group=np.array([s for s in multi for _ in multi[s]], dtype=np.int64))
