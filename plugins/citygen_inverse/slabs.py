"""Floor slabs of a facade layout for size-independent grammars: one slab per storey of the input, and the ground
slab with exactly one door of a door's size (docs/inverse.md, "Size-independent grammars for scenes", items 1-2).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from citygen.errors import LayoutError
from citygen.layout import FLOOR_BOUND_LABELS, FacadeLayout, Region, check_partition
from citygen.plausible import OPENING_LABELS

#: Labels whose rows make storeys.
ROW_LABELS = frozenset({"window", "door", "shop"})


def floor_cuts(layout: FacadeLayout) -> list[float]:
    """Heights that cut ``layout`` into floor slabs, one between each two consecutive rows of openings (openings
    overlapping in y form one row): the valid line (no terminal crosses it) in the gap nearest its middle, else
    the line in the gap that crosses the fewest terminals (floor-bound ones, windows or balconies, counting
    most), nearest the middle -- :func:`slab_layouts` cuts the terminals it crosses (a pilaster spanning three
    storeys becomes three pieces), so each storey of the input is a slab of its own and no storey is lost."""
    ts = layout.terminals()
    y0 = np.array([t.y for t in ts])
    y1 = np.array([t.y + t.h for t in ts])
    bound = np.array([t.label in FLOOR_BOUND_LABELS for t in ts], dtype=bool)
    eps = 1e-9 * max(layout.width, layout.height)
    rows: list[list[float]] = []
    for a, b in sorted((t.y, t.y + t.h) for t in ts if t.label in ROW_LABELS):
        if rows and a < rows[-1][1] - eps:
            rows[-1][1] = max(rows[-1][1], b)
        else:
            rows.append([a, b])
    lines = np.unique(np.concatenate([y0, y1]))
    cuts: list[float] = []
    for (_, top), (bottom, _) in zip(rows, rows[1:]):
        gap = lines[(lines >= top - eps) & (lines <= bottom + eps)]
        if not gap.size:
            continue
        crossed = (y0[None, :] < gap[:, None] - eps) & (y1[None, :] > gap[:, None] + eps)
        cost = crossed.sum(axis=1) + 100 * (crossed & bound[None, :]).sum(axis=1)
        middle = np.abs(gap - 0.5 * (top + bottom))
        cuts.append(float(gap[np.lexsort((middle, cost))[0]]))
    return cuts


def _slab(layout: FacadeLayout, lo: float, hi: float, eps: float) -> list[Region]:
    """The terminals between heights ``lo`` and ``hi``, moved down by ``lo``; terminals crossing ``lo`` or
    ``hi`` contribute the piece inside."""
    out = []
    for t in layout.terminals():
        a, b = max(t.y, lo), min(t.y + t.h, hi)
        if b - a > eps:
            out.append(replace(t, y=a - lo, h=b - a, children=()))
    return out


def as_layout(width: float, height: float, ts: list[Region]) -> FacadeLayout:
    return FacadeLayout(width, height, Region(0.0, 0.0, width, height, "Slab", children=tuple(ts)))


def _no_doors(ts: list[Region], keep: Region | None = None) -> list[Region]:
    """Doors other than ``keep`` become windows of the same depth."""
    return [replace(t, label="window", symbol="Window") if t.label == "door" and t is not keep else t for t in ts]


#: A carved door: its width (metres, at most half the slab) and its height as a share of the ground slab, so
#: the door stays a door (>= 1.9 m) on any ground floor of 2.4 m or more whatever the input slab's height.
DOOR_WIDTH = 1.2
DOOR_SHARE = 0.8
#: An input door at least this share of the ground slab tall keeps its height.
DOOR_TALL = 0.7


def _with_door(ts: list[Region], width: float, height: float) -> list[Region]:
    """The ground slab with exactly one door standing on the ground: the input's largest (most central on ties),
    reaching down to the ground and, when lower than ``DOOR_TALL`` of the slab, up to ``DOOR_SHARE`` of it where no
    opening is in the way (a CMP door
    above steps, or 2 m tall in a 6 m ground floor, was a floating door or a hatch at 3-4 m ground floors); else
    one carved (:func:`carve_door`)."""
    doors = [t for t in ts if t.label == "door"]
    if not doors:
        return carve_door(ts, width, height)
    main = max(doors, key=lambda t: (round(t.w * t.h, 9), -abs(t.x + 0.5 * t.w - 0.5 * width)))
    ts = _no_doors(ts, keep=main)
    top = main.y + main.h
    above = [t.y for t in ts if t.label in OPENING_LABELS and t is not main and t.y >= top - 1e-9
             and t.x < main.x + main.w - 1e-9 and t.x + t.w > main.x + 1e-9]
    if top < DOOR_TALL * height:
        top = max(top, min([DOOR_SHARE * height, *above]))
    return _carve(ts, replace(main, y=0.0, h=top)) if main.y > 0 or top > main.y + main.h else ts


def carve_door(ts: list[Region], width: float, height: float) -> list[Region]:
    """A door ``DOOR_WIDTH`` wide and ``DOOR_SHARE`` of the slab tall, standing on the ground, where it covers
    the least of the slab's openings and leaves no terminal pieces thinner than 0.15 m (nearest the middle on
    ties)."""
    dw, dh = min(DOOR_WIDTH, 0.5 * width), DOOR_SHARE * height
    edges = sorted({e for t in ts for e in (t.x, t.x + t.w)})
    starts = {min(max(x, 0.0), width - dw) for e in edges for x in (e, e - dw)} | {0.5 * (width - dw)}

    def score(x: float) -> tuple[float, int, float]:
        covered, thin = 0.0, 0
        for t in ts:
            ox = min(t.x + t.w, x + dw) - max(t.x, x)
            oy = min(t.y + t.h, dh) - t.y
            if ox > 1e-9 and oy > 1e-9:
                covered += ox * oy * (t.label in OPENING_LABELS)
                thin += sum(0 < piece < 0.15 for piece in (x - t.x, t.x + t.w - x - dw, t.y + t.h - dh))
        return (round(covered, 6), thin, abs(x + 0.5 * dw - 0.5 * width))

    dx = min(sorted(starts), key=score)
    return _carve(ts, Region(dx, 0.0, dw, dh, "Door", "door", depth=-0.3))


def _carve(ts: list[Region], door: Region) -> list[Region]:
    """``door`` (standing on the ground) placed over ``ts``: the terminals it covers are cut around it (left,
    right and above; a terminal inside it, such as the door it replaces, vanishes), so the slab stays a
    partition."""
    dx, dw, dh = door.x, door.w, door.h
    out = [door]
    for t in ts:
        if not (t.x < dx + dw - 1e-9 and t.x + t.w > dx + 1e-9 and t.y < dh - 1e-9):
            out.append(t)
            continue
        a, b = max(t.x, dx), min(t.x + t.w, dx + dw)
        top = max(t.y, dh)
        pieces = [replace(t, w=a - t.x), replace(t, x=b, w=t.x + t.w - b),
                  replace(t, x=a, y=top, w=b - a, h=t.y + t.h - top)]
        out += [p for p in pieces if p.w > 1e-9 and p.h > 1e-9]
    return out


def slab_layouts(layout: FacadeLayout) -> tuple[list[FacadeLayout], list[str]]:
    """The floor slabs as layouts with their root names: ``GroundDoor`` and ``Ground`` (the ground slab with one
    door and with none), then ``Floor1`` ... and ``Top`` for the slabs above (doors there become windows)."""
    problems = check_partition(layout)
    if problems:
        raise LayoutError("not a partition: " + "; ".join(problems[:3]),
                          hint="grammar extraction needs terminals that tile the facade exactly")
    eps = 1e-9 * max(layout.width, layout.height)
    edges = [0.0, *floor_cuts(layout), float(layout.height)]
    slabs = [(_slab(layout, lo, hi, eps), hi - lo) for lo, hi in zip(edges, edges[1:])]
    (ground, gh), upper = slabs[0], slabs[1:]
    out = [as_layout(layout.width, gh, _with_door(ground, layout.width, gh)),
           as_layout(layout.width, gh, _no_doors(ground))]
    names = ["GroundDoor", "Ground"]
    for k, (ts, h) in enumerate(upper, start=1):
        out.append(as_layout(layout.width, h, _no_doors(ts)))
        names.append("Top" if k == len(upper) and k > 1 else f"Floor{k}")
    return out, names
