"""Symmetry detection (wu2014 §4.3): the batched growing against a plain per-instance reference."""
from collections import defaultdict, deque
from pathlib import Path

import numpy as np
import pytest

from citygen_inverse.cmp import import_cmp
from citygen_inverse.regions import LayoutIndex
from citygen_inverse.symmetry import detect_symmetry

from .helpers import random_layout

DATA = Path(__file__).resolve().parents[1] / "data" / "inverse"


def _grow(index, box, direction):
    """Brute force over all terminals: ``box`` grown by the adjacent strip, with the strip's content."""
    x0, y0, x1, y1 = box
    X0, Y0, X1, Y1, mat = index.X0, index.Y0, index.X1, index.Y1, index.material
    line, (a, b) = (x1, x0, y1, y0)[direction], ((y0, y1) if direction < 2 else (x0, x1))
    near, start, end, far = ((X0, Y0, Y1, X1), (X1, Y0, Y1, X0), (Y0, X0, X1, Y1), (Y1, X0, X1, Y0))[direction]
    ks = np.flatnonzero((near == line) & (start < b) & (end > a))
    ks = ks[np.argsort(start[ks])]
    if ks.size == 0 or start[ks[0]] != a or end[ks[-1]] != b or np.any(far[ks] != far[ks[0]]):
        return None
    f = int(far[ks[0]])
    strip = (f - line, *((int(mat[k]), int(start[k]) - a) for k in ks))
    return ((x0, y0, f, y1), (f, y0, x1, y1), (x0, y0, x1, f), (x0, f, x1, y1))[direction], strip


def _reference(index, max_groups):
    table = defaultdict(list)
    for k in range(index.X0.size):
        box = (int(index.X0[k]), int(index.Y0[k]), int(index.X1[k]), int(index.Y1[k]))
        table[index.sig(box)].append(box)
    groups = {s: boxes for s, boxes in table.items() if len(boxes) >= 2}
    queue = deque(sorted(groups))
    while queue and len(groups) < max_groups:
        sig = queue.popleft()
        for direction in range(4):
            same = defaultdict(list)
            for box in groups[sig]:
                found = _grow(index, box, direction)
                if found is not None:
                    same[(box[2] - box[0], box[3] - box[1], found[1])].append(found[0])
            grown = defaultdict(list)
            for boxes in same.values():
                grown[index.sig(boxes[0])].extend(boxes)
            for new_sig, boxes in grown.items():
                if new_sig > 0 and len(boxes) >= 2 and new_sig not in groups:
                    groups[new_sig] = boxes
                    queue.append(new_sig)
    return [(s, box) for s in groups for box in groups[s]]


def _layouts():
    rng = np.random.default_rng(7)
    yield from (random_layout(rng) for _ in range(6))
    yield from (import_cmp(xml) for xml in sorted(DATA.glob("*.xml"))[:2])


@pytest.mark.parametrize("dense", [True, False])
@pytest.mark.parametrize("max_groups", [1500, 12])
def test_batched_growing_matches_per_instance_reference(max_groups, dense, monkeypatch):
    """Same groups, instances and order as growing one instance at a time (also when the cap stops early), with
    the side table's keys found in a dense table or (large grids) by binary search."""
    from citygen_inverse.symmetry import _Sides
    monkeypatch.setattr(_Sides, "DENSE", _Sides.DENSE if dense else 0)
    for layout in _layouts():
        found = detect_symmetry(LayoutIndex([layout], periodic=True), max_groups)
        expected = _reference(LayoutIndex([layout], periodic=True), max_groups)
        assert [(int(s), tuple(b)) for s, b in zip(found.group, found.boxes.tolist())] == expected
