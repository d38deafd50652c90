"""Symmetry detection (wu2014 §4.3): exhaustive, hash-based growing of repeated regions in four directions.

Starting from every terminal that occurs at least twice, each repeated region is grown left, right, down and up
by the strip of terminals adjacent to that side when their far edges align (Fig. 7); a grown region that still
occurs two or more times enters the hash table (signature -> instances) and is grown in turn.
"""
from __future__ import annotations

from collections import defaultdict, deque
from dataclasses import dataclass

import numpy as np

from citygen_inverse.regions import Box, LayoutIndex


@dataclass(frozen=True)
class RepeatedRegions:
    """Instances of repeated regions as arrays: boxes ``(m, 4)``, terminal count ``a`` and group ``o``."""

    boxes: np.ndarray
    terminals: np.ndarray
    occurrences: np.ndarray
    group: np.ndarray

    @property
    def importance(self) -> np.ndarray:
        """wu2014 §4.7: f(a, o) = (a - 1)(o - 1) per instance."""
        return (self.terminals - 1) * (self.occurrences - 1)


def _grow(index: LayoutIndex, box: Box, direction: int) -> Box | None:
    x0, y0, x1, y1 = box
    X0, Y0, X1, Y1 = index.X0, index.Y0, index.X1, index.Y1
    if direction == 0:    # right
        m = (X0 == x1) & (Y0 < y1) & (Y1 > y0)
        lo, hi, far = Y0[m], Y1[m], X1[m]
    elif direction == 1:  # left
        m = (X1 == x0) & (Y0 < y1) & (Y1 > y0)
        lo, hi, far = Y0[m], Y1[m], X0[m]
    elif direction == 2:  # up
        m = (Y0 == y1) & (X0 < x1) & (X1 > x0)
        lo, hi, far = X0[m], X1[m], Y1[m]
    else:                 # down
        m = (Y1 == y0) & (X0 < x1) & (X1 > x0)
        lo, hi, far = X0[m], X1[m], Y0[m]
    if far.size == 0 or np.any(far != far[0]):
        return None
    a, b = (y0, y1) if direction < 2 else (x0, x1)
    if lo.min() < a or hi.max() > b:
        return None
    f = int(far[0])
    return ((x0, y0, f, y1), (f, y0, x1, y1), (x0, y0, x1, f), (x0, f, x1, y1))[direction]


def detect_symmetry(index: LayoutIndex, max_groups: int = 1500) -> RepeatedRegions:
    """All repeated regions reachable by growing (capped at ``max_groups`` signatures)."""
    table: dict[int, list[Box]] = defaultdict(list)
    for k in range(index.X0.size):
        box = (int(index.X0[k]), int(index.Y0[k]), int(index.X1[k]), int(index.Y1[k]))
        table[index.sig(box)].append(box)
    groups = {s: boxes for s, boxes in table.items() if len(boxes) >= 2}
    queue = deque(sorted(groups))
    while queue and len(groups) < max_groups:
        sig = queue.popleft()
        for direction in range(4):
            grown: dict[int, list[Box]] = defaultdict(list)
            for box in groups[sig]:
                new = _grow(index, box, direction)
                if new is not None:
                    grown[index.sig(new)].append(new)
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
