"""Facade grids (dang2014 §3): general grids of non-overlapping elements arranged in rows and columns.

Elements are leaves chosen by label (all windows; windows and doors; ...). Columns are assigned left to right:
the next element joins the current column while it overlaps the column's first element -- we read "overlap" as
its centre lying within that element's extent, so a door spanning two window rows joins the lower row (Fig. 11)
instead of chaining both rows into one; rows likewise from the top.
A cell with no element holds a *phantom* (``None``). A grid is a *subgrid* of another when all its elements lie
inside one element of the other.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from citygen_safe.leaves import EPS, Facade


@dataclass(frozen=True)
class GridSpec:
    """A named grid: the labels whose leaves are its elements."""

    name: str
    labels: tuple[str, ...]


@dataclass(frozen=True)
class FacadeGrid:
    """A facade grid: ``cells[r][c]`` is a leaf index or None (a phantom); rows from the top, columns from the
    left. ``columns`` / ``rows`` hold each column's / row's (lo, hi) extent."""

    name: str
    cells: tuple[tuple[int | None, ...], ...]
    columns: tuple[tuple[float, float], ...]
    rows: tuple[tuple[float, float], ...]

    @property
    def elements(self) -> tuple[int, ...]:
        return tuple(i for row in self.cells for i in row if i is not None)

    def column(self, c: int) -> tuple[int | None, ...]:
        return tuple(row[c] for row in self.cells)

    def row(self, r: int) -> tuple[int | None, ...]:
        return self.cells[r]

    @property
    def phantoms(self) -> int:
        return sum(1 for row in self.cells for i in row if i is None)


def _assign(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, list[tuple[float, float]]]:
    """Index of the run (in increasing ``lo``, the members whose centre lies in the run's first interval) of
    every interval, and each run's extent."""
    order = np.argsort(lo, kind="stable")
    index = np.empty(lo.size, dtype=int)
    spans: list[tuple[float, float]] = []
    seed_hi = -np.inf
    for k in order:
        if spans and 0.5 * (lo[k] + hi[k]) < seed_hi - EPS:
            spans[-1] = (spans[-1][0], max(spans[-1][1], float(hi[k])))
        else:
            spans.append((float(lo[k]), float(hi[k])))
            seed_hi = float(hi[k])
        index[k] = len(spans) - 1
    return index, spans


def build_grid(facade: Facade, name: str, elements: list[int]) -> FacadeGrid | None:
    """The grid of ``elements`` (leaf indices), or None when it has none. Two elements falling into one cell keep
    the larger (a general grid holds one element per cell)."""
    if not elements:
        return None
    leaves = [facade.leaves[i] for i in elements]
    x0 = np.array([f.x for f in leaves])
    x1 = np.array([f.right for f in leaves])
    top = np.array([f.top for f in leaves])
    bottom = np.array([f.y for f in leaves])
    col, columns = _assign(x0, x1)
    row, rows_down = _assign(-top, -bottom)
    cells: list[list[int | None]] = [[None] * len(columns) for _ in rows_down]
    for k, i in enumerate(elements):
        held = cells[row[k]][col[k]]
        if held is None or facade.leaves[i].w * facade.leaves[i].h > facade.leaves[held].w * facade.leaves[held].h:
            cells[row[k]][col[k]] = i
    rows = tuple((-hi, -lo) for lo, hi in rows_down)
    return FacadeGrid(name, tuple(tuple(r) for r in cells), tuple(columns), rows)


def detect_grid(facade: Facade, spec: GridSpec) -> FacadeGrid | None:
    """The grid of every leaf carrying one of ``spec.labels``."""
    elements = [i for i, f in enumerate(facade.leaves) if f.label in spec.labels and f.w > EPS and f.h > EPS]
    return build_grid(facade, spec.name, elements)


def auto_specs(facade: Facade) -> tuple[GridSpec, ...]:
    """Grids detected from labels: one per opening label present (windows, doors, balconies, shops), and the
    windows-and-doors grid when both occur."""
    present = {f.label for f in facade.leaves}
    specs = [GridSpec(label, (label,)) for label in ("window", "door", "balcony", "shop") if label in present]
    if {"window", "door"} <= present:
        specs.append(GridSpec("window+door", ("window", "door")))
    return tuple(specs)


def subgrid_of(facade: Facade, inner: FacadeGrid, outer: FacadeGrid) -> bool:
    """True when every element of ``inner`` lies inside one element of ``outer`` (the hierarchy of grids)."""
    if set(inner.elements) & set(outer.elements):
        return False
    for o in outer.elements:
        box = facade.leaves[o]
        if all(box.x - EPS <= facade.leaves[i].x and facade.leaves[i].right <= box.right + EPS
               and box.y - EPS <= facade.leaves[i].y and facade.leaves[i].top <= box.top + EPS
               for i in inner.elements):
            return True
    return False
