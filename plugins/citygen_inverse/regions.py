"""The extractor's view of a layout: terminals on an integer grid and regions identified by their content.

A *region* is an axis-aligned box exactly tiled by terminals (wu2014 §3.1). Two regions with the same content up
to translation share a *signature* (an interned integer), so they share one grammar symbol and one rule.
Coordinates are quantised to ``quantum`` metres (1e-7 of the facade size) so equality is exact.

*Free extents*: as in wu2014 §3.1 terminal symbols are materials (label and depth), their sizes being set by the
parent rule. The same holds for a region all of whose terminals span its full width (a vertical stack): no rule
inside it fixes its width, so stacks that differ only in width share one signature and one rule (likewise for
height). Likewise a region that is an exact periodic sequence of >= 2 tiles along an axis is derived by one
``repeat`` rule whatever the count, so its signature is (axis, tile length, tile signature) (``periodic=True``;
off by default because a writer that expands repeats to the input's count, the ``linear`` mode, cannot share
them). With ``free_extents=False`` signatures are strictly translational (sizes included).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from citygen.errors import LayoutError
from citygen.layout import FacadeLayout, check_partition

Box = tuple[int, int, int, int]  # x0, y0, x1, y1 on the integer grid


@dataclass(frozen=True)
class TerminalKind:
    """A terminal symbol: label, depth and size (identical regions share a symbol)."""

    label: str | None
    depth: float
    w: int
    h: int


@dataclass(frozen=True)
class SigInfo:
    """A region signature: its representative box, terminal count and (for one terminal) its kind index."""

    box: Box
    n: int
    terminal: int | None
    period: tuple[int, int] | None = None  # (axis, tile length): a repeat of >= 2 tiles, shared by any count


class LayoutIndex:
    """Terminals of one or more layouts (placed side by side) with region lookup by box."""

    def __init__(self, layouts: list[FacadeLayout], free_extents: bool = True, periodic: bool = False) -> None:
        self.free_extents = free_extents
        self.periodic = periodic
        if not layouts:
            raise LayoutError("no layout to extract from")
        for k, layout in enumerate(layouts):
            problems = check_partition(layout)
            if problems:
                raise LayoutError("not a partition: " + "; ".join(problems[:3]), where=f"layout {k}",
                                  hint="grammar extraction needs terminals that tile the facade exactly")
        scale = max(max(lay.width, lay.height) for lay in layouts)
        self.quantum = 10.0 ** np.floor(np.log10(1e-7 * scale))  # a decimal step: decimal inputs stay exact
        rows, kinds, self.roots, offset = [], [], [], 0
        for layout in layouts:
            w, h = self.q(layout.width), self.q(layout.height)
            self.roots.append((offset, 0, offset + w, h))
            for t in layout.terminals():
                if t.w <= 0 or t.h <= 0:
                    raise LayoutError(f"terminal {t.symbol} at ({t.x:g}, {t.y:g}) has zero size",
                                      hint="remove zero-size regions before extraction")
                x0, y0 = offset + self.q(t.x), self.q(t.y)
                rows.append((x0, y0, offset + self.q(t.x + t.w), self.q(t.y + t.h)))
                kinds.append((t.label, t.depth))
            offset += w + max(w // 10, 1)  # a gap: no region spans two facades
        arr = np.array(rows, dtype=np.int64)
        self.X0, self.Y0, self.X1, self.Y1 = arr.T.copy()
        self.kinds: list[TerminalKind] = []
        kind_ids: dict[TerminalKind, int] = {}
        materials: dict[tuple, int] = {}
        sym, mat = [], []
        for (label, depth), (x0, y0, x1, y1) in zip(kinds, rows):
            kind = TerminalKind(label, depth, x1 - x0, y1 - y0)
            sym.append(kind_ids.setdefault(kind, len(kind_ids)))
            mat.append(materials.setdefault((label, depth), len(materials)))
            if len(kind_ids) > len(self.kinds):
                self.kinds.append(kind)
        self.sym = np.array(sym, dtype=np.int64)
        self.material = np.array(mat, dtype=np.int64)
        self.sigs: list[SigInfo] = [SigInfo((0, 0, 0, 0), 0, None)]  # id 0: the empty dummy
        self._sig_ids: dict[bytes, int] = {}
        self._boxes: dict[Box, int] = {}

    def q(self, v: float) -> int:
        return int(round(v / self.quantum))

    def inside(self, box: Box) -> np.ndarray:
        x0, y0, x1, y1 = box
        return np.flatnonzero((self.X0 >= x0) & (self.X1 <= x1) & (self.Y0 >= y0) & (self.Y1 <= y1))

    def sig(self, box: Box) -> int:
        """Signature id of the region ``box`` (which must be exactly tiled; -1 when it is not)."""
        found = self._boxes.get(box)
        if found is not None:
            return found
        idx = self.inside(box)
        x0, y0, x1, y1 = box
        area = int(np.sum((self.X1[idx] - self.X0[idx]) * (self.Y1[idx] - self.Y0[idx])))
        if idx.size == 0 or area != (x1 - x0) * (y1 - y0):
            self._boxes[box] = -1
            return -1
        X0, Y0, X1, Y1 = self.X0[idx] - x0, self.Y0[idx] - y0, self.X1[idx] - x0, self.Y1[idx] - y0
        free_w = self.free_extents and bool(np.all((X0 == 0) & (X1 == x1 - x0)))
        free_h = self.free_extents and bool(np.all((Y0 == 0) & (Y1 == y1 - y0)))
        w, h = (-1 if free_w else x1 - x0), (-1 if free_h else y1 - y0)
        if free_w:
            X1 = np.zeros_like(X1)
        if free_h:
            Y1 = np.zeros_like(Y1)
        rel = np.stack([self.material[idx], X0, Y0, X1, Y1], axis=1)
        period = None
        if self.periodic and idx.size > 1:
            for axis, free in ((0, free_w), (1, free_h)):
                p = None if free else _period(rel, axis, (x1 - x0, y1 - y0)[axis])
                if p is not None:
                    tile = (x0, y0, x0 + p, y1) if axis == 0 else (x0, y0, x1, y0 + p)
                    period = (axis, p)
                    key = np.array([-2 - axis, p, self.sig(tile)]).tobytes()
                    break
        if period is None:
            rel = rel[np.lexsort(rel.T[::-1])]
            key = np.concatenate([[w, h], rel.ravel()]).tobytes()
        sid = self._sig_ids.get(key)
        if sid is None:
            sid = len(self.sigs)
            self._sig_ids[key] = sid
            self.sigs.append(SigInfo(box, int(idx.size), int(self.sym[idx[0]]) if idx.size == 1 else None, period))
        self._boxes[box] = sid
        return sid

    def cuts(self, box: Box, axis: int) -> np.ndarray:
        """Valid split lines of ``box`` along ``axis`` (0 = x): interior edges no terminal inside crosses."""
        idx = self.inside(box)
        lo, hi = (self.X0[idx], self.X1[idx]) if axis == 0 else (self.Y0[idx], self.Y1[idx])
        cand = np.unique(lo)
        cand = cand[cand > box[axis]]
        if cand.size == 0:
            return cand
        crossed = np.any((lo[:, None] < cand[None, :]) & (hi[:, None] > cand[None, :]), axis=0)
        return cand[~crossed]


def _period(rel: np.ndarray, axis: int, length: int) -> int | None:
    """Smallest tile length ``p`` (``length / p >= 2``) such that the content is ``length / p`` identical tiles."""
    lo, hi = rel[:, 1 + axis], rel[:, 3 + axis]
    n = rel.shape[0]
    cand = np.unique(lo[(lo > 0) & (2 * lo <= length)])
    cand = cand[length % cand == 0]
    if cand.size == 0:
        return None
    cand = cand[np.searchsorted(np.sort(lo), cand) * (length // cand) == n]  # a tile holds n / k terminals
    for p in cand.tolist():
        k = length // p
        if np.any(lo // p != (hi - 1) // p):
            continue
        first = rel[lo < p]
        shifted = rel.copy()
        tile = lo // p
        shifted[:, 1 + axis] -= tile * p
        shifted[:, 3 + axis] -= tile * p
        shifted = shifted[np.lexsort(shifted.T[::-1])]
        first = np.repeat(first[np.lexsort(first.T[::-1])], k, axis=0)
        if first.shape == shifted.shape and np.array_equal(first, shifted):
            return int(p)
    return None
