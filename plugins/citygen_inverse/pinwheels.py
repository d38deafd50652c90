"""Pinwheels opened into splits: a block no straight line separates (wu2014 §6.3) is cut along a line that crosses
only walls and bands, so a size-independent grammar needs no ``grid`` rule there.

An exact grammar must keep every terminal, so the extractor explains a pinwheel with one ``grid`` rule listing
its cells (67-133 items on some CMP facades). A size-independent grammar only has to keep the label map: cutting
a wall or a molding in two changes no pixel. :func:`open_pinwheels` cuts the layout recursively like a guillotine
(all free lines first); where none is free it takes the terminal edge whose line crosses only ``CUTTABLE``
terminals -- fewest crossed, then fewest pieces thinner than ``THIN`` made, then nearest the block's middle --
and cuts them. Blocks whose every line crosses an opening stay pinwheels (and grids).
"""
from __future__ import annotations

from dataclasses import replace

from citygen.layout import FacadeLayout, Region

#: Labels a cut may cross (cutting them changes no label).
CUTTABLE = frozenset({"wall", "molding", "cornice", "ledge", "deco", "frame", "sill", "none", ""})
#: Pieces thinner than this (metres) are avoided when choosing a line.
THIN = 0.05
EPS = 1e-9


def open_pinwheels(layout: FacadeLayout) -> FacadeLayout:
    """``layout`` with pinwheel blocks cut open where walls and bands allow (module doc); same label map."""
    ts = _open(list(layout.terminals()), 0.0, 0.0, float(layout.width), float(layout.height))
    return FacadeLayout(layout.width, layout.height, replace(layout.root, children=tuple(ts)), meta=layout.meta)


def _open(ts: list[Region], x0: float, y0: float, x1: float, y1: float) -> list[Region]:
    if len(ts) <= 1:
        return ts
    for axis in (1, 0):
        free = [c for c in _lines(ts, axis, x0, y0, x1, y1) if not _crossed(ts, axis, c)]
        if free:
            return _split(ts, axis, free, x0, y0, x1, y1)
    best = None
    for axis in (1, 0):
        lo, hi = (y0, y1) if axis else (x0, x1)
        for c in _lines(ts, axis, x0, y0, x1, y1):
            crossed = _crossed(ts, axis, c)
            if any((t.label or "") not in CUTTABLE for t in crossed):
                continue
            thin = sum(1 for t in crossed for piece in _sides(t, axis, c) if piece < THIN)
            key = (len(crossed), thin, abs(c - 0.5 * (lo + hi)))
            if best is None or key < best[0]:
                best = (key, axis, c)
    if best is None:
        return ts
    _, axis, c = best
    cut = []
    for t in ts:
        if t in _crossed([t], axis, c):
            a, b = _halves(t, axis, c)
            cut += [a, b]
        else:
            cut.append(t)
    return _split(cut, axis, [c], x0, y0, x1, y1)


def _lines(ts: list[Region], axis: int, x0: float, y0: float, x1: float, y1: float) -> list[float]:
    lo, hi = (y0, y1) if axis else (x0, x1)
    edges = {t.y if axis else t.x for t in ts} | {(t.y + t.h) if axis else (t.x + t.w) for t in ts}
    return sorted(e for e in edges if lo + EPS < e < hi - EPS)


def _crossed(ts: list[Region], axis: int, c: float) -> list[Region]:
    return [t for t in ts if ((t.y < c - EPS < c + EPS < t.y + t.h) if axis else (t.x < c - EPS < c + EPS < t.x + t.w))]


def _sides(t: Region, axis: int, c: float) -> tuple[float, float]:
    return (c - t.y, t.y + t.h - c) if axis else (c - t.x, t.x + t.w - c)


def _halves(t: Region, axis: int, c: float) -> tuple[Region, Region]:
    if axis:
        return replace(t, h=c - t.y), replace(t, y=c, h=t.y + t.h - c)
    return replace(t, w=c - t.x), replace(t, x=c, w=t.x + t.w - c)


def _split(ts: list[Region], axis: int, cuts: list[float], x0: float, y0: float, x1: float, y1: float
           ) -> list[Region]:
    lo, hi = (y0, y1) if axis else (x0, x1)
    bounds = [lo, *cuts, hi]
    out: list[Region] = []
    for a, b in zip(bounds, bounds[1:]):
        part = [t for t in ts if a - EPS <= (t.y if axis else t.x) and (t.y + t.h if axis else t.x + t.w) <= b + EPS]
        out += _open(part, x0, a, x1, b) if axis else _open(part, a, y0, b, y1)
    return out
