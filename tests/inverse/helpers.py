"""Shared helpers: random layouts (guillotine partitions with pinwheels) and the round-trip check."""
from __future__ import annotations

import numpy as np

from citygen.layout import FacadeLayout, Region
from citygen_inverse.verify import mismatches

LABELS = ("wall", "window", "sill", "door")


def random_layout(rng: np.random.Generator, width: float = 12.0, height: float = 9.0, depth: int = 4,
                  pinwheel: float = 0.2) -> FacadeLayout:
    """A random guillotine partition on a 0.5 m lattice, with some blocks replaced by a 5-piece pinwheel (whose
    pieces may be split further)."""
    out: list[Region] = []

    def rec(x, y, w, h, d):
        if d == 0 or (w <= 1.0 and h <= 1.0) or rng.random() < 0.15:
            out.append(Region(x, y, w, h, "T", LABELS[rng.integers(len(LABELS))]))
            return
        if w >= 2.0 and h >= 2.0 and rng.random() < pinwheel:
            a, b = 0.5 * rng.integers(1, int(w / 0.5)), 0.5 * rng.integers(1, int(h / 0.5))
            c, e = 0.5 * rng.integers(1, int(w / 0.5)), 0.5 * rng.integers(1, int(h / 0.5))
            if a < c and b < e:  # pinwheel: four arms around a centre, no straight cut
                pieces = [(x, y, c, b), (x + c, y, w - c, e), (x + a, y + e, w - a, h - e), (x, y + b, a, h - b),
                          (x + a, y + b, c - a, e - b)]
                for k, p in enumerate(pieces):
                    if rng.random() < 0.5:  # an arm or the centre split further
                        rec(*p, d - 1)
                    else:
                        out.append(Region(*p, "T", LABELS[k % len(LABELS)]))
                return
        axis = 0 if (w > h if rng.random() < 0.7 else rng.random() < 0.5) else 1
        extent = w if axis == 0 else h
        if extent < 1.0:
            axis, extent = 1 - axis, (h if axis == 0 else w)
        if extent < 1.0:
            out.append(Region(x, y, w, h, "T", "wall"))
            return
        n = int(extent / 0.5)
        cut = 0.5 * rng.integers(1, n)
        if rng.random() < 0.4:  # a repeated pattern: equal slices with identical content
            k = int(rng.integers(2, 4))
            if n % k == 0:
                step = extent / k
                before = len(out)
                rec(x, y, step if axis == 0 else w, step if axis == 1 else h, d - 1)
                tile = out[before:]
                for i in range(1, k):
                    dx, dy = (i * step, 0) if axis == 0 else (0, i * step)
                    out.extend(t.translated(dx, dy) for t in tile)
                return
        if axis == 0:
            rec(x, y, cut, h, d - 1)
            rec(x + cut, y, w - cut, h, d - 1)
        else:
            rec(x, y, w, cut, d - 1)
            rec(x, y + cut, w, h - cut, d - 1)

    rec(0.0, 0.0, width, height, depth)
    return FacadeLayout(width, height, Region(0.0, 0.0, width, height, "Facade", children=tuple(out)))


def assert_reproduces(text: str, layout: FacadeLayout) -> None:
    """Deriving ``text`` at the layout's size gives every terminal rectangle and label (tol 1e-6 of the size)."""
    problems = mismatches(text, layout)
    assert not problems, "; ".join(problems)
