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


def _grow(index: LayoutIndex, boxes: np.ndarray, direction: int) -> list[Box | None]:
    """Each box grown by the strip of terminals adjacent to one side (0 right, 1 left, 2 up, 3 down) when the
    strip lies within the side and its far edges align (Fig. 7); None where it cannot grow."""
    X0, Y0, X1, Y1 = index.X0[None, :], index.Y0[None, :], index.X1[None, :], index.Y1[None, :]
    x0, y0, x1, y1 = (boxes[:, k, None] for k in range(4))
    if direction == 0:
        m, lo, hi, far, a, b = (X0 == x1) & (Y0 < y1) & (Y1 > y0), Y0, Y1, X1, y0, y1
    elif direction == 1:
        m, lo, hi, far, a, b = (X1 == x0) & (Y0 < y1) & (Y1 > y0), Y0, Y1, X0, y0, y1
    elif direction == 2:
        m, lo, hi, far, a, b = (Y0 == y1) & (X0 < x1) & (X1 > x0), X0, X1, Y1, x0, x1
    else:
        m, lo, hi, far, a, b = (Y1 == y0) & (X0 < x1) & (X1 > x0), X0, X1, Y0, x0, x1
    big = np.iinfo(np.int64).max
    fmin = np.where(m, far, big).min(axis=1)
    fmax = np.where(m, far, -big).max(axis=1)
    ok = m.any(axis=1) & (fmin == fmax) & (np.where(m, lo, big).min(axis=1) >= a[:, 0]) \
        & (np.where(m, hi, -big).max(axis=1) <= b[:, 0])
    out: list[Box | None] = []
    for k, (bx0, by0, bx1, by1) in enumerate(boxes.tolist()):
        if not ok[k]:
            out.append(None)
            continue
        f = int(fmin[k])
        out.append(((bx0, by0, f, by1), (f, by0, bx1, by1), (bx0, by0, bx1, f), (bx0, f, bx1, by1))[direction])
    return out


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
            for new in _grow(index, np.array(groups[sig], dtype=np.int64), direction):
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
