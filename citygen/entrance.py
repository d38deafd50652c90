"""The door budget's safety net: make a layout carry exactly the doors its request asks for.

Ruleset kinds are expected to place the building's one entrance themselves (the request says where). When a
ruleset cannot -- a grammar extracted from a photo, a layer stack without a door symbol -- :func:`enforce_entrance`
repairs the layout generically and says what it did, so the building still gets exactly one door:

* a face that must not have a door gets its doors turned into plain wall;
* the entrance face keeps the door nearest its centre;
* an entrance face without a door gets one carved into its ground floor where it clips the least opening area;
  regions the door overlaps are cut into the rectangles around it (openings that are cut become wall), so the
  terminals still partition the face (in a layer stack: the door goes into the front layer, every other layer
  keeps an unlabelled, occluded region in its place).
"""
from __future__ import annotations

import operator
from dataclasses import replace

import numpy as np

from citygen.layout import FLOOR_BOUND_LABELS, FacadeLayout, Region
from citygen.request import FacadeRequest

DOOR_WIDTH = 1.2
DOOR_HEIGHT = 2.3
DOOR_DEPTH = -0.25


def enforce_entrance(layout: FacadeLayout, request: FacadeRequest) -> tuple[FacadeLayout, str | None]:
    """``layout`` with exactly ``int(request.entrance)`` doors, and a note when a repair was needed."""
    doors = [r for r in layout.leaves if r.label == "door"] if "door" in layout.leaf_labels[0] else []
    wanted = 1 if request.entrance else 0
    if len(doors) == wanted:
        return layout, None
    if doors:
        centre = layout.width / 2
        keep = min(doors, key=lambda r: abs(r.x + r.w / 2 - centre)) if wanted else None
        drop = {id(r) for r in doors if r is not keep}
        root = _map_terminals(layout.root, lambda r: [replace(r, label="wall", depth=0.0, asset=None, key=None)]
                              if id(r) in drop else [r])
        return replace(layout, root=root), f"turned {len(drop)} extra door(s) into wall"
    door = _door_rect(layout, request)
    if door is None:
        return layout, "entrance face has no room for a door"
    x0, y0, x1, y1 = door
    root = _map_terminals(layout.root, lambda r: _cut(r, door))
    hole = Region(x=x0, y=y0, w=x1 - x0, h=y1 - y0, symbol="Entrance", label="door", depth=DOOR_DEPTH)
    layers = root.children
    if layers and all(c.layer is not None for c in layers):  # a layer stack: the door in the front layer,
        last = len(layers) - 1                             # the hole in the others occluded (no label)
        root = replace(root, key=None, children=tuple(
            replace(c, key=None, children=(*c.children, replace(hole, layer=c.layer, **({} if i == last else
                                                                                     {"label": None, "depth": 0.0}))))
            for i, c in enumerate(layers)))
    else:
        root = replace(root, children=(*root.children, hole), key=None)
    return replace(layout, root=root), f"carved an entrance door at x={x0:.2f}..{x1:.2f}"


def _map_terminals(region: Region, fn) -> Region:
    """``region`` with every terminal replaced by ``fn(terminal)`` (a list: itself, a changed region without its
    ``key``, pieces, or none). A subtree that changes loses its key (the module hint of a subtree whose copies
    elsewhere in the building stay as they were); the others stay the same objects."""

    def walk(r: Region) -> list[Region]:
        if r.children:
            children = tuple(c for child in r.children for c in walk(child))
            if len(children) == len(r.children) and all(map(operator.is_, children, r.children)):
                return [r]
            return [replace(r, children=children, key=None)] if children else []
        pieces = fn(r)
        if len(pieces) <= 1:
            return pieces
        return [replace(r, label=None, depth=0.0, children=tuple(pieces), key=None)]

    result = walk(region)
    return result[0] if result else replace(region, children=())


def _door_rect(layout: FacadeLayout, request: FacadeRequest) -> tuple[float, float, float, float] | None:
    left, right = request.corner_widths
    usable = layout.width - left - right
    ground = request.floor_lines[1] if len(request.floor_lines) > 1 else layout.height
    width = min(DOOR_WIDTH, 0.8 * usable)
    height = min(DOOR_HEIGHT, ground - 0.3 if ground > 2.0 else 0.85 * ground)
    if width < 0.6 or height < 1.5:
        return None
    terminals = [r for r in layout.leaves if r.y < height]
    centres = {layout.width / 2, *(r.x + r.w / 2 for r in terminals)}
    lo, hi = left + width / 2, layout.width - right - width / 2
    best, best_score = None, np.inf
    for cx in sorted(np.clip(list(centres), lo, hi)):
        x0, x1 = cx - width / 2, cx + width / 2
        clipped = sum(max(0.0, min(r.x + r.w, x1) - max(r.x, x0)) * max(0.0, min(r.y + r.h, height) - r.y)
                      for r in terminals if r.label in FLOOR_BOUND_LABELS or r.label == "door")
        score = clipped + 1e-3 * abs(cx - layout.width / 2)
        if score < best_score:
            best, best_score = (x0, 0.0, x1, height), score
    return best


def _cut(region: Region, rect: tuple[float, float, float, float]) -> list[Region]:
    """``region`` minus ``rect`` as up to four rectangles (left, right, below, above)."""
    x0, y0, x1, y1 = rect
    rx0, ry0, rx1, ry1 = region.x, region.y, region.x + region.w, region.y + region.h
    if min(rx1, x1) - max(rx0, x0) <= 1e-9 or min(ry1, y1) - max(ry0, y0) <= 1e-9:
        return [region]
    opening = region.label in FLOOR_BOUND_LABELS
    base = replace(region, label="wall", depth=0.0, asset=None, material=None) if opening else region
    cx0, cx1 = max(rx0, x0), min(rx1, x1)
    boxes = [(rx0, ry0, x0, ry1), (x1, ry0, rx1, ry1), (cx0, ry0, cx1, y0), (cx0, y1, cx1, ry1)]
    return [replace(base, x=a, y=b, w=c - a, h=d - b, key=None) for a, b, c, d in boxes
            if c - a > 1e-9 and d - b > 1e-9]
