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

Queries take constant time on the grid of all terminal edge lines (``_Grid``): memory and set-up grow with
(distinct x lines) x (distinct y lines), which regularised facades keep small (CMP: at most ~2,500 cells); a
layout beyond ``_Grid.MAX_CELLS`` is rejected.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from math import gcd
from typing import NamedTuple

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


class SigInfo(NamedTuple):
    """A region signature: its representative box, terminal count and (for one terminal) its kind index. (An
    immutable named tuple rather than a frozen dataclass: one is made per signature, ~1,400 in one extraction,
    and a tuple is made three times as fast.)"""

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
        edges, kinds, self.roots, offset = [], [], [], 0
        for layout in layouts:
            w, h = self.q(layout.width), self.q(layout.height)
            self.roots.append((offset, 0, offset + w, h))
            for t in layout.terminals():
                if t.w <= 0 or t.h <= 0:
                    raise LayoutError(f"terminal {t.symbol} at ({t.x:g}, {t.y:g}) has zero size",
                                      hint="remove zero-size regions before extraction")
                edges.append((offset, t.x, t.y, t.x + t.w, t.y + t.h))
                kinds.append((t.label, t.depth))
            offset += w + max(w // 10, 1)  # a gap: no region spans two facades
        e = np.array(edges, dtype=float)
        arr = np.rint(e[:, 1:] / self.quantum).astype(np.int64)  # as q(): round half to even
        arr[:, 0::2] += e[:, :1].astype(np.int64)
        rows = arr.tolist()
        self.X0, self.Y0, self.X1, self.Y1 = arr.T.copy()
        kind_ids: dict[tuple, int] = {}
        materials: dict[tuple, int] = {}
        sym, mat = [], []
        for (label, depth), (x0, y0, x1, y1) in zip(kinds, rows):
            sym.append(kind_ids.setdefault((label, depth, x1 - x0, y1 - y0), len(kind_ids)))
            mat.append(materials.setdefault((label, depth), len(materials)))
        self.kinds: list[TerminalKind] = [TerminalKind(*kind) for kind in kind_ids]
        self.sym = np.array(sym, dtype=np.int64)
        self.material = np.array(mat, dtype=np.int64)
        self.sigs: list[SigInfo] = [SigInfo((0, 0, 0, 0), 0, None)]  # id 0: the empty dummy
        self._sig_ids: dict[tuple, int] = {}
        self._boxes: dict[Box, int] = {}
        self._terminal_sigs: list[int] | None = None
        self._grid = _Grid(self)

    def q(self, v: float) -> int:
        return int(round(v / self.quantum))

    def inside(self, box: Box) -> np.ndarray:
        x0, y0, x1, y1 = box
        return np.flatnonzero((self.X0 >= x0) & (self.X1 <= x1) & (self.Y0 >= y0) & (self.Y1 <= y1))

    def sig(self, box: Box, tiled: bool = False) -> int:
        """Signature id of the region ``box`` (which must be exactly tiled; -1 when it is not). A caller that knows
        the box is tiled may say so (``tiled``), which skips the tiling test."""
        found = self._boxes.get(box)
        if found is not None:
            return found
        g = self._grid
        found = g.region(box, tiled)
        if found is None:
            self._boxes[box] = -1
            return -1
        cell, n, inner_x, inner_y = found
        free_w = self.free_extents and inner_x == 0
        free_h = self.free_extents and inner_y == 0
        variant = free_w + 2 * free_h
        key = None
        if self.periodic and n > 1:
            for axis, free in ((0, free_w), (1, free_h)):
                if free:
                    continue
                counts = _divisors(gcd(n, box[axis + 2] - box[axis]))
                p = g.period(box, cell, axis, variant, counts) if counts else None
                if p is not None:
                    x0, y0, x1, y1 = box
                    tile = (x0, y0, x0 + p, y1) if axis == 0 else (x0, y0, x1, y0 + p)
                    key = (-2 - axis, p, self.sig(tile))
                    break
        if key is None:
            key = (variant, *g.content(cell, variant))
        sid = self._sig_ids.get(key)
        if sid is None:
            sid = len(self.sigs)
            self._sig_ids[key] = sid
            self.sigs.append(SigInfo(box, n, int(self.sym[g.owner[cell[0]][cell[1]]]) if n == 1 else None,
                                     None if key[0] >= 0 else (-2 - key[0], key[1])))
        self._boxes[box] = sid
        return sid

    def terminal_sigs(self) -> list[int]:
        """``sig`` of every terminal's box, in terminal order (the same lookups, in the same order, the first time;
        later calls return the same list)."""
        if self._terminal_sigs is None:
            boxes = list(zip(self.X0.tolist(), self.Y0.tolist(), self.X1.tolist(), self.Y1.tolist()))
            if not self.free_extents:
                self._terminal_sigs = [self.sig(box) for box in boxes]
            else:
                first: dict[int, int] = {}  # with free extents a lone terminal's signature is its material's
                self._terminal_sigs = [first[mat] if mat in first else first.setdefault(mat, self.sig(box))
                                       for mat, box in zip(self.material.tolist(), boxes)]
                self._boxes.update(zip(boxes, self._terminal_sigs))  # (what a lookup of each box would find)
        return self._terminal_sigs

    @property
    def grid_powers(self) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
        """Per axis, (lanes, edge lines) arrays of the hash bases to the power of each line and their inverses."""
        return self._grid.powers

    def cuts(self, box: Box, axis: int) -> list[int]:
        """Valid split lines of the tiled ``box`` (a signature's) along ``axis`` (0 = x): interior edges no terminal
        inside crosses."""
        return self._grid.cuts(box, axis)


class _Grid:
    """Constant-time region queries on the grid of all terminal edges (``xs`` by ``ys`` lines).

    A box is exactly tiled when it covers no gap cell and a terminal edge runs along its whole boundary; edge
    counts come from prefix sums over the edge rasters. The content of a tiled box (terminal materials, sizes
    and positions relative to its corner) is identified by two 64-bit translation-covariant polynomial hashes
    sum_t R(t) A^(x_t - x0) B^(y_t - y0) (mod 2^64), each a 2D prefix sum over terminal corners: R(t) hashes
    (material, width, height), the width (height) dropped for a free-width (free-height) region.
    """

    MAX_CELLS = 1_000_000  # ~15 prefix tables of this many Python ints: ~0.5 GB

    LANES = ((0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F), (0xD6E8FEB86659FD93, 0xA0761D6478BD642F))
    MASK = (1 << 64) - 1

    def __init__(self, index: LayoutIndex) -> None:
        X0, Y0, X1, Y1 = index.X0, index.Y0, index.X1, index.Y1
        self.xs = np.unique(np.concatenate([X0, X1])).tolist()
        self.ys = np.unique(np.concatenate([Y0, Y1])).tolist()
        self.xi = {v: i for i, v in enumerate(self.xs)}
        self.yi = {v: j for j, v in enumerate(self.ys)}
        a0, b0 = np.searchsorted(self.xs, X0), np.searchsorted(self.ys, Y0)
        a1, b1 = np.searchsorted(self.xs, X1), np.searchsorted(self.ys, Y1)
        nx, ny = len(self.xs) - 1, len(self.ys) - 1
        if nx * ny > self.MAX_CELLS:
            raise LayoutError(f"{len(self.xs)} x {len(self.ys)} distinct edge lines: too irregular to index",
                              hint="regularise the layout (snap and align edges) before extraction")
        owner = np.full((nx + 2, ny + 2), -1, dtype=np.int64)  # padded by one cell on every side
        w, h = a1 - a0, b1 - b0
        k = np.repeat(np.arange(X0.size), w * h)  # every cell of every terminal
        start = np.repeat(np.cumsum(w * h) - w * h, w * h)
        cell = np.arange(k.size) - start  # row-major within the terminal: (cell // h, cell % h)
        owner[a0[k] + 1 + cell // h[k], b0[k] + 1 + cell % h[k]] = k
        self.owner = owner[1:-1, 1:-1].tolist()
        vert = owner[1:, 1:-1] != owner[:-1, 1:-1]  # (nx + 1, ny): an edge on line x_i along row j
        horz = owner[1:-1, 1:] != owner[1:-1, :-1]  # (nx, ny + 1)
        self.along = (_prefix1(vert), _prefix1(horz.T))  # per line, edge count along it
        self.interior = (_prefix2(vert), _prefix2(horz.T))  # per axis: line index, then the other axis
        gap = owner[1:-1, 1:-1] < 0
        self.gap = _prefix2(gap) if gap.any() else None  # (only joint extraction leaves gaps between facades)
        corner = np.zeros((nx, ny), dtype=np.int64)
        corner[a0, b0] = 1
        self.n = _prefix2(corner)
        variants = ((0, 0), (1, 0), (0, 1), (1, 1))  # (free width, free height): the size dropped from R(t)
        key = np.zeros(4 * X0.size, dtype=np.int64)  # (material, width, height) per variant and terminal
        for col in (np.tile(index.material, 4), np.concatenate([(X1 - X0) * (1 - fw) for fw, _ in variants]),
                    np.concatenate([(Y1 - Y0) * (1 - fh) for _, fh in variants])):
            values, code = np.unique(col, return_inverse=True)
            key = key * values.size + code
        _, kind = np.unique(key, return_inverse=True)
        lanes = len(self.LANES)
        r = np.random.default_rng(20140801).integers(0, 1 << 63, (kind.max() + 1, lanes), dtype=np.uint64)
        r = (r * np.uint64(2) + np.uint64(1))[kind].reshape(4, X0.size, lanes)
        A, B = ([lane[axis] for lane in self.LANES] for axis in (0, 1))
        # per axis (lanes, lines): A^x or B^y and its inverse (also the strip hashes of symmetry detection)
        self.powers = tuple((_upow(C, v), _upow([pow(c, -1, 1 << 64) for c in C], v))
                            for C, v in ((A, self.xs), (B, self.ys)))
        (_, inv_x), (_, inv_y) = self.powers
        self.inv = [(inv_x[k][:, None] * inv_y[k][None, :]).tolist() for k in range(lanes)]  # per lane, corner
        place = self.powers[0][0][:, a0] * self.powers[1][0][:, b0]  # (lanes, terminals)
        self.hash: list[list] = []  # per variant (free_w + 2 free_h) but the last, per lane: prefix sums
        for variant in range(3):
            val = np.zeros((lanes, nx, ny), dtype=np.uint64)
            val[:, a0, b0] = r[variant].T * place
            self.hash.append([_prefix2(v) for v in val])
        # free width and height: no interior edge either way, so a single terminal, whose content is its R(t)
        self.single = list(map(tuple, r[3].tolist()))

    def region(self, box: Box, tiled: bool = False) -> tuple[tuple[int, int, int, int], int, int, int] | None:
        """For an exactly tiled ``box`` (None otherwise): its grid indices, its terminal count and the terminal edge
        segments on lines strictly inside it, perpendicular to x and to y (prefix sums inlined: this is the
        signature lookup's hot path)."""
        xi, yi = self.xi, self.yi
        if tiled:
            i0, j0, i1, j1 = xi[box[0]], yi[box[1]], xi[box[2]], yi[box[3]]
        else:
            i0, j0, i1, j1 = xi.get(box[0]), yi.get(box[1]), xi.get(box[2]), yi.get(box[3])
            if i0 is None or j0 is None or i1 is None or j1 is None or i1 <= i0 or j1 <= j0:
                return None
            gap = self.gap
            if gap is not None and gap[i1][j1] - gap[i0][j1] - gap[i1][j0] + gap[i0][j0]:
                return None
            av, ah = self.along
            a, b = av[i0], av[i1]
            if a[j1] - a[j0] != j1 - j0 or b[j1] - b[j0] != j1 - j0:
                return None
            a, b = ah[j0], ah[j1]
            if a[i1] - a[i0] != i1 - i0 or b[i1] - b[i0] != i1 - i0:
                return None
        n, (vx, vy) = self.n, self.interior
        a, b = n[i0], n[i1]
        count = b[j1] - a[j1] - b[j0] + a[j0]
        if i1 > i0 + 1:
            a, b = vx[i0 + 1], vx[i1]
            inner_x = b[j1] - a[j1] - b[j0] + a[j0]
        else:
            inner_x = 0
        if j1 > j0 + 1:
            a, b = vy[j0 + 1], vy[j1]
            inner_y = b[i1] - a[i1] - b[i0] + a[i0]
        else:
            inner_y = 0
        return (i0, j0, i1, j1), count, inner_x, inner_y

    def content(self, cell: tuple[int, int, int, int], variant: int) -> tuple[int, int]:
        """The two content hashes of the tiled box on grid cells ``cell``, translated to its corner (``variant``:
        free width + 2 free height)."""
        if variant == 3:
            return self.single[self.owner[cell[0]][cell[1]]]
        t, u = self.hash[variant]
        a, b = self.inv
        i0, j0, i1, j1 = cell
        ti, tk, ui, uk = t[i0], t[i1], u[i0], u[i1]
        return ((tk[j1] - ti[j1] - tk[j0] + ti[j0]) * a[i0][j0] & self.MASK,
                (uk[j1] - ui[j1] - uk[j0] + ui[j0]) * b[i0][j0] & self.MASK)

    def period(self, box: Box, cell: tuple[int, int, int, int], axis: int, variant: int, counts: tuple[int, ...]
               ) -> int | None:
        """Smallest tile length ``p`` (``length / p >= 2``) such that the box is ``length / p`` identical tiles
        along ``axis``, trying the tile ``counts`` given (largest first: the smallest ``p`` first). ``k``
        identical tiles hold ``k`` times a tile's terminals, so the caller passes the counts that divide both the
        terminal count and the length."""
        start, length = box[axis], box[axis + 2] - box[axis]
        index = self.xi if axis == 0 else self.yi
        if axis == 0:
            i0, lo, i1, hi = cell
        else:
            lo, i0, hi, i1 = cell
        along = self.along[axis]
        span = hi - lo
        for count in counts:
            p = length // count
            if count > i1 - i0 or start + p not in index:  # (most boxes fail here: no line a tile away)
                continue
            tiles = [i0]
            for k in range(1, count):
                t = index.get(start + k * p)
                if t is None:
                    break
                a = along[t]
                if a[hi] - a[lo] != span:
                    break
                tiles.append(t)
            else:
                tiles.append(i1)
                first = None
                for a, b in zip(tiles, tiles[1:]):
                    h = self.content((a, lo, b, hi) if axis == 0 else (lo, a, hi, b), variant)
                    if first is None:
                        first = h
                    elif h != first:
                        break
                else:
                    return p
        return None

    def cuts(self, box: Box, axis: int) -> list[int]:
        cell = self.region(box, tiled=True)[0]
        i0, lo, i1, hi = (cell[0], cell[1], cell[2], cell[3]) if axis == 0 else (cell[1], cell[0], cell[3], cell[2])
        lines, along, span = (self.xs, self.along[0], hi - lo) if axis == 0 else (self.ys, self.along[1], hi - lo)
        return [lines[i] for i in range(i0 + 1, i1) if along[i][hi] - along[i][lo] == span]


@lru_cache(maxsize=None)
def _divisors(n: int) -> tuple[int, ...]:
    """The divisors ``k >= 2`` of ``n``, largest first."""
    return tuple(k for k in range(n, 1, -1) if n % k == 0)


def _upow(bases: list[int], exps: list[int]) -> np.ndarray:
    """base ** exps modulo 2^64 per base (rows): the product of one table entry per byte of the exponent (uint64
    arithmetic wraps)."""
    e = np.array(exps, dtype=np.uint64)
    top = int(e.max()) if e.size else 0
    tables = _byte_powers(tuple(bases), max(top.bit_length() + 7, 8) // 8)
    out = tables[0].take((e & np.uint64(255)).astype(np.intp), 1)
    for k in range(1, len(tables)):
        out *= tables[k].take(((e >> np.uint64(8 * k)) & np.uint64(255)).astype(np.intp), 1)
    return out


@lru_cache(maxsize=None)
def _byte_powers(bases: tuple[int, ...], nbytes: int) -> tuple[np.ndarray, ...]:
    """Per byte k < ``nbytes`` of an exponent, the table (bases, 256) of base ** (i * 256^k) modulo 2^64."""
    tables, step = [], np.array(bases, dtype=np.uint64)[:, None]
    for _ in range(nbytes):
        table = np.empty((len(bases), 256), dtype=np.uint64)
        table[:, 0] = 1
        table[:, 1:] = step
        np.multiply.accumulate(table, axis=1, out=table)
        tables.append(table)
        step = table[:, 255:] * table[:, 1:2]  # base ** (256^(k + 1))
    return tuple(tables)


def _prefix1(a: np.ndarray) -> list[list[int]]:
    """Prefix sums along the second axis with a leading zero: out[i][j] = a[i, :j].sum()."""
    out = np.zeros((a.shape[0], a.shape[1] + 1), dtype=np.int64)
    out[:, 1:] = np.cumsum(a, axis=1)
    return out.tolist()


def _prefix2(a: np.ndarray) -> list[list[int]]:
    """2D prefix sums with a leading zero row and column (uint64 sums wrap modulo 2^64)."""
    out = np.zeros((a.shape[0] + 1, a.shape[1] + 1), dtype=np.uint64 if a.dtype == np.uint64 else np.int64)
    out[1:, 1:] = np.cumsum(np.cumsum(a, axis=0, dtype=out.dtype), axis=1, dtype=out.dtype)
    return out.tolist()

