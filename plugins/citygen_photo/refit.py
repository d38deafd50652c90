"""Carry a refined window box (``photo.refine_box``, full resolution) into the photo's FacadeLayout.

A side of a window terminal lies on a split line of its tile's region tree. The side moves to its refined
position by moving that line: the line separates an ancestor ``A`` of the window (the highest one, below the
tile, that still has the side on its boundary) from the sibling ``N`` beside it, and every terminal of ``A`` and
of ``N`` on the line moves with it. The move is made only if those terminals are wall (or the window's own
terminals, for a window made of several) and each keeps at least ``least`` metres, so the layout stays a
partition and nothing but the window and the wall around it changes; otherwise the side keeps its work-image
position. In the common tile (wall | strip (wall / window / wall) | wall, ``photo_tiles.box_split``) all four
sides move: the left and right walls absorb the horizontal change, the strip's top and bottom walls the vertical.
"""
from __future__ import annotations

from dataclasses import replace

from citygen.layout import Region

Path = tuple[int, ...]
Box = tuple[float, float, float, float]  # x0, y0, x1, y1 in metres, y up
#: Sides: (index into a Box, the opposite side).
SIDES = {"L": (0, "R"), "B": (1, "T"), "R": (2, "L"), "T": (3, "B")}


def edge(region: Region, side: str) -> float:
    return {"L": region.x, "B": region.y, "R": region.x + region.w, "T": region.y + region.h}[side]


def at(root: Region, path: Path) -> Region:
    for k in path:
        root = root.children[k]
    return root


def carry(root: Region, members: list[Path], old: Box, new: Box, tile_depth: int, least: float,
          eps: float) -> tuple[Region, int, int]:
    """``root`` with the sides of the window made of the terminals ``members`` (paths from ``root``; their
    bounding box is ``old``) moved to ``new`` where the tile's structure allows (see the module docstring).
    Returns the new root, the number of sides moved and of sides that differed."""
    moved = wanted = 0
    for side, (k, _) in SIDES.items():
        if abs(new[k] - old[k]) <= eps:
            continue
        wanted += 1
        on_side = [p for p in members if abs(edge(at(root, p), side) - old[k]) <= eps]
        ok = bool(on_side)
        for p in on_side:
            if abs(edge(at(root, p), side) - new[k]) <= eps:
                continue  # moved with another terminal of the window
            step = _move(root, p, side, new[k], set(members), tile_depth, least, eps)
            if step is None:
                ok = False
                continue
            root = step
        moved += ok
    return root, moved, wanted


def _move(root: Region, path: Path, side: str, value: float, members: set[Path], tile_depth: int, least: float,
          eps: float) -> Region | None:
    """Move the line under ``side`` of the terminal at ``path`` to ``value``, or None when it is not safe."""
    line = edge(at(root, path), side)
    k = len(path)
    while k > tile_depth and abs(edge(at(root, path[:k - 1]), side) - line) <= eps:
        k -= 1  # the side is the parent's side too: the line lies higher up
    if k <= tile_depth:
        return None  # the tile's own boundary
    a, parent = path[:k], at(root, path[:k - 1])
    opposite = SIDES[side][1]
    near = [n for n, c in enumerate(parent.children) if abs(edge(c, opposite) - line) <= eps
            and _overlap(c, at(root, a), side) > eps]
    if len(near) != 1:
        return None
    n = path[:k - 1] + (near[0],)
    for p, s, allowed in ((a, side, members), (n, opposite, set())):
        for q, t in _on_line(at(root, p), p, s, line, eps):
            if t.label != "wall" and q not in allowed:
                return None
            far = edge(t, SIDES[s][1])
            if abs(far - value) < least or (far - value) * (far - line) <= 0:
                return None
    root = _replace(root, a, lambda r: _shift(r, side, line, value, eps))
    return _replace(root, n, lambda r: _shift(r, opposite, line, value, eps))


def _overlap(a: Region, b: Region, side: str) -> float:
    """Length along the line shared by ``a`` and ``b`` (a sibling beside ``b`` at the line, not diagonal)."""
    if side in "LR":
        return min(a.y + a.h, b.y + b.h) - max(a.y, b.y)
    return min(a.x + a.w, b.x + b.w) - max(a.x, b.x)


def _on_line(region: Region, path: Path, side: str, line: float, eps: float):
    """(path, terminal) of the terminals of ``region`` whose ``side`` lies on ``line``."""
    if abs(edge(region, side) - line) > eps:
        return
    if not region.children:
        yield path, region
    for k, c in enumerate(region.children):
        yield from _on_line(c, path + (k,), side, line, eps)


def _shift(region: Region, side: str, line: float, value: float, eps: float) -> Region:
    """``region`` with every side ``side`` on ``line`` (its own and its descendants') moved to ``value``."""
    if abs(edge(region, side) - line) > eps:
        return region
    children = tuple(_shift(c, side, line, value, eps) for c in region.children)
    if side == "L":
        return replace(region, x=value, w=region.x + region.w - value, children=children)
    if side == "R":
        return replace(region, w=value - region.x, children=children)
    if side == "B":
        return replace(region, y=value, h=region.y + region.h - value, children=children)
    return replace(region, h=value - region.y, children=children)


def _replace(root: Region, path: Path, fn) -> Region:
    if not path:
        return fn(root)
    children = list(root.children)
    children[path[0]] = _replace(children[path[0]], path[1:], fn)
    return replace(root, children=tuple(children))
