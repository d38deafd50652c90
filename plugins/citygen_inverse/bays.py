"""The repeated bays of a facade: the vertical strips that repeat on every floor slab (wu2014 §5: a size-independent
grammar grows by repeating what repeats, not by repeating the whole facade).

Bay boundaries are drawn through *piers*: x intervals that no opening, pillar or blind of any slab covers (a wall
or band crossing them -- string courses, moldings, long balconies -- is cut, its pieces repeat with the bays);
each boundary is the middle of its pier. The strips between consecutive boundaries are compared slab by slab on
a label raster (``RASTER`` samples in each slab, positions relative to the strip); a run of at least two
consecutive groups of strips that agree on at least ``agree`` of the samples, with widths within ``WIDTH_TOL``,
is a run of bays. The widest run wins. CMP facades are irregular: bays are an approximation where the layout
allows (the first bay stands for all of them), and a facade without such a run keeps repeating as a whole.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from citygen.layout import FacadeLayout, Region

#: Labels a bay boundary may cut (bands and wall); everything else is kept whole by the bays.
CUTTABLE = frozenset({"wall", "molding", "cornice", "ledge", "deco", "frame", "sill", "balcony", "none", ""})
#: Balconies are kept whole unless they span more than this share of the facade (a continuous balcony band).
BAND_SHARE = 0.4
#: Samples per slab (x, y) for comparing strips.
RASTER = (24, 12)
WIDTH_TOL = 0.1
#: A run must cover at least this share of the facade width.
MIN_COVER = 0.4


@dataclass(frozen=True)
class Bays:
    """``count`` bays from ``start`` to ``end`` (metres), each ``(end - start) / count`` wide in the grammar;
    ``cuts`` are the input's own boundaries (``count + 1`` of them)."""

    start: float
    end: float
    count: int
    cuts: tuple[float, ...]

    @property
    def tile(self) -> float:
        return (self.end - self.start) / self.count


def find_bays(slabs: Sequence[FacadeLayout], agree: float = 0.85) -> Bays | None:
    """The widest run of repeated bays common to all ``slabs`` (of one width), or None (module doc)."""
    width = float(slabs[0].width)
    cuts, piers = _piers(slabs, width)
    m = len(cuts) - 1
    best: Bays | None = None
    rasters: dict[tuple[int, int], list[np.ndarray]] = {}

    def raster(i: int, j: int) -> list[np.ndarray]:
        if (i, j) not in rasters:
            rasters[i, j] = [_raster(s, cuts[i], cuts[j]) for s in slabs]
        return rasters[i, j]

    for p in range(1, m // 2 + 1):
        for s in range(0, m - 2 * p + 1):
            tile = cuts[s + p] - cuts[s]
            k = 1
            while s + (k + 1) * p <= m:
                a, b = s + k * p, s + (k + 1) * p
                if abs(cuts[b] - cuts[a] - tile) > WIDTH_TOL * tile:
                    break
                score = np.mean([np.mean(u == v) for u, v in zip(raster(s, s + p), raster(a, b))])
                if score < agree:
                    break
                k += 1
            cover = cuts[s + k * p] - cuts[s]
            if k >= 2 and cover >= MIN_COVER * width and (best is None or cover > best.end - best.start + 1e-9):
                start, end = _outer(cuts, piers, s, p, k)
                best = Bays(start, end, k, (start, *cuts[s + p:s + k * p:p], end))
    return best


def crosses(bays: Bays, layout: FacadeLayout, labels: frozenset[str]) -> bool:
    """Whether a bay boundary (or the run's ends) crosses a terminal of ``labels`` in ``layout``."""
    eps = 1e-9 * max(layout.width, 1.0)
    return any(t.label in labels and t.x < c - eps < c + eps < t.x + t.w for t in layout.terminals() for c in bays.cuts)


def clipped(layout: FacadeLayout, a: float, b: float) -> FacadeLayout:
    """The part of ``layout`` between ``x = a`` and ``b`` as a layout of its own (terminals cut at the edges)."""
    eps = 1e-9 * max(layout.width, 1.0)
    ts = []
    for t in layout.terminals():
        lo, hi = max(t.x, a), min(t.x + t.w, b)
        if hi - lo > eps:
            ts.append(replace(t, x=lo - a, w=hi - lo, children=()))
    return FacadeLayout(b - a, layout.height, Region(0.0, 0.0, b - a, layout.height, "Slab", children=tuple(ts)))


def _piers(slabs: Sequence[FacadeLayout], width: float) -> tuple[list[float], list[tuple[float, float]]]:
    """Bay boundary candidates: 0, the middle of every pier and ``width``; and the pier (free x interval) each lies
    in."""
    kept = sorted((t.x, t.x + t.w) for s in slabs for t in s.terminals()
                  if (t.label or "") not in CUTTABLE or (t.label == "balcony" and t.w <= BAND_SHARE * width))
    cuts, piers, x = [0.0], [(0.0, 0.0)], 0.0
    for a, b in kept:
        if a > x + 1e-9:
            if x > 1e-9:
                cuts.append(0.5 * (x + a))
                piers.append((x, a))
            else:
                piers[0] = (0.0, a)
        x = max(x, b)
    cuts.append(width)
    piers.append((x, width) if x < width - 1e-9 else (width, width))
    return cuts, piers


def _outer(cuts: list[float], piers: list[tuple[float, float]], s: int, p: int, k: int) -> tuple[float, float]:
    """The run's outer boundaries: a bay's width (the median of the inner bays, else the wider end bay) away from
    the first and last inner boundary, within the end piers (pier middles make the end bays short where the run
    ends at a pilaster or a margin: their pier is only half a bay's)."""
    widths = [cuts[s + (i + 1) * p] - cuts[s + i * p] for i in range(k)]
    tile = float(np.median(widths[1:-1])) if k > 2 else max(widths)
    lo, hi = piers[s], piers[s + k * p]
    start = min(max(cuts[s + p] - tile, lo[0]), lo[1]) if lo[1] > lo[0] else cuts[s]
    end = min(max(cuts[s + (k - 1) * p] + tile, hi[0]), hi[1]) if hi[1] > hi[0] else cuts[s + k * p]
    return start, end


def _raster(slab: FacadeLayout, a: float, b: float) -> np.ndarray:
    nx, ny = RASTER
    xs = a + (np.arange(nx) + 0.5) / nx * (b - a)
    ys = (np.arange(ny) + 0.5) / ny * slab.height
    out = np.full((ny, nx), "", dtype=object)
    for t in slab.terminals():
        mx = (xs >= t.x) & (xs < t.x + t.w)
        my = (ys >= t.y) & (ys < t.y + t.h)
        if mx.any() and my.any():
            out[np.ix_(my, mx)] = f"{t.label}:{t.depth:g}"
    return out
