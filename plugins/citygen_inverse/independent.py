"""Scene-ready size-independent grammars (wu2014 §5) with alignment kept by construction (the aim of Fig. 12).

The input facade is cut into *floor slabs* at lines no terminal crosses, one slab per row of openings (windows,
doors, shops). The slabs are extracted jointly (wu2014 §6.1: identical slabs and regions share rules) and written
in the ``linear`` size mode (every size relative, repeats written out), so a slab derived at any size is the input
slab scaled along x and y. The facade rule follows the building's floor lines::

    Facade --> floors { 0: GroundFloor | -1: TopRow | 1: Floor1Row | *: Floor2Row }
    GroundFloor --> case entrance: EntranceRow  else: GroundRow
    Floor2Row --> repeat(x) { ~8.59: Floor2 }

Every floor is a ``repeat`` of its whole slab with the input width as tile, so all floors of a face get the same
tile count and edges aligned in the input stay aligned (columns across floors, edges of sibling regions), while a
wide face gets more bays instead of stretched windows. ``EntranceRow`` picks by the face width the split of the
same tiles with exactly one ``GroundDoor`` tile in the middle; every other slab has no door (extra and upper-floor
doors become windows), so a face has one door in its ground floor exactly when the request asks for an entrance.
Faces narrower than half a tile get ``<Slab>Narrow`` instead: one opening per floor at its input size, centred.
"""
from __future__ import annotations

import math
import re
from collections import Counter
from dataclasses import replace

import numpy as np

import citygen_split
from citygen.errors import LayoutError
from citygen.gcpause import cyclic_gc_paused
from citygen.layout import FLOOR_BOUND_LABELS, FacadeLayout, Region, check_partition
from citygen.plausible import OPENING_LABELS
from citygen_inverse.actions import CostModel
from citygen_inverse.emit import GrammarWriter, _num
from citygen_inverse.extract import Extraction
from citygen_inverse.regions import LayoutIndex
from citygen_inverse.search import GrammarSearch

ROW_LABELS = frozenset({"window", "door", "shop"})
#: Faces up to this width (metres) keep the entrance tile aligned with the tiles of the other floors.
MAX_ALIGNED_WIDTH = 100.0
_RESERVED = frozenset({"Facade", "GroundFloor", "EntranceRow"})


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


def _as_layout(width: float, height: float, ts: list[Region]) -> FacadeLayout:
    return FacadeLayout(width, height, Region(0.0, 0.0, width, height, "Slab", children=tuple(ts)))


def _no_doors(ts: list[Region], keep: Region | None = None) -> list[Region]:
    """Doors other than ``keep`` become windows of the same depth."""
    return [replace(t, label="window", symbol="Window") if t.label == "door" and t is not keep else t for t in ts]


#: A carved door: its width (metres, at most half the slab) and its height as a share of the ground slab, so
#: the door stays a door (>= 1.9 m) on any ground floor of 2.4 m or more whatever the input slab's height.
DOOR_WIDTH = 1.2
DOOR_SHARE = 0.8


def _with_door(ts: list[Region], width: float, height: float) -> list[Region]:
    """The ground slab with exactly one door: the input's largest (most central on ties), else one carved
    (:func:`_carve_door`)."""
    doors = [t for t in ts if t.label == "door"]
    if doors:
        main = max(doors, key=lambda t: (round(t.w * t.h, 9), -abs(t.x + 0.5 * t.w - 0.5 * width)))
        return _no_doors(ts, keep=main)
    return _carve_door(ts, width, height)


def _carve_door(ts: list[Region], width: float, height: float) -> list[Region]:
    """A door ``DOOR_WIDTH`` wide and ``DOOR_SHARE`` of the slab tall, standing on the ground, where it covers
    the least of the slab's openings and leaves no terminal pieces thinner than 0.15 m (nearest the middle on
    ties); the terminals it covers are cut around it (the slab stays a partition)."""
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
    out = [Region(dx, 0.0, dw, dh, "Door", "door", depth=-0.3)]
    for t in ts:
        if not (t.x < dx + dw - 1e-9 and t.x + t.w > dx + 1e-9 and t.y < dh - 1e-9):
            out.append(t)
            continue
        a, b = max(t.x, dx), min(t.x + t.w, dx + dw)
        pieces = [replace(t, w=a - t.x), replace(t, x=b, w=t.x + t.w - b),
                  replace(t, x=a, y=dh, w=b - a, h=t.y + t.h - dh)]
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
    out = [_as_layout(layout.width, gh, _with_door(ground, layout.width, gh)),
           _as_layout(layout.width, gh, _no_doors(ground))]
    names = ["GroundDoor", "Ground"]
    for k, (ts, h) in enumerate(upper, start=1):
        out.append(_as_layout(layout.width, h, _no_doors(ts)))
        names.append("Top" if k == len(upper) and k > 1 else f"Floor{k}")
    return out, names


@cyclic_gc_paused()
def extract_size_independent(layout: FacadeLayout, method: str = "adp", iterations: int = 2000, seed: int = 0,
                             model: CostModel = CostModel(), time_limit: float | None = None,
                             header: tuple[str, ...] = ()) -> Extraction:
    """A grammar for ``layout`` that derives on any face under the building's floor lines, entrance and corners.

    ``cost`` and ``rules`` are those of the written file (``citygen grammar cost``), not of the joint search.
    """
    slabs, names = slab_layouts(layout)
    index = LayoutIndex(slabs)
    result = GrammarSearch(index, model).run(method, iterations, seed, time_limit)
    roots = [index.sig(b) for b in index.roots]
    writer = GrammarWriter(index, result.rules, names, reserved=_RESERVED | {f"{n}Row" for n in names})
    sym = [writer.names[r] for r in roots]  # identical slabs share the first one's name
    W = _num(layout.width)
    rules = [f"Facade --> floors {{ {_selectors(sym)} }}",
             f"GroundFloor --> case entrance: EntranceRow  else: {sym[1]}Row",
             _entrance(sym[0], f"{sym[1]}Row", layout.width)]
    first = dict(zip(reversed(sym), reversed(slabs)))  # each name's first slab
    narrow: list[str] = []
    for s in dict.fromkeys(sym[1:]):
        rules.append(f"{s}Row --> case width < {_num(0.5 * layout.width)}: {s}Narrow\n"
                     f"    else: repeat(x) {{ ~{W}: {s} }}")
        narrow += _narrow(s, first[s], ROW_LABELS - {"door"}, entrance=False)
    narrow += _narrow(sym[0], first[sym[0]], frozenset({"door"}), entrance=True)
    body = "\n".join(_merge_identical(rules + writer.rule_lines("linear") + narrow)) + "\n"
    grammar = citygen_split.parse(body, "<size-independent>")
    cost = citygen_split.grammar_cost(grammar, model.split, model.repeat)
    count = sum(1 for r in grammar.rules if type(r.body).__name__ != "Terminal")
    lines = [*(f"# {h}" for h in header),
             f"# size-independent grammar (wu2014 §5) extracted by citygen grammar extract, method {method}, "
             f"{result.iterations} iterations, seed {seed}",
             f"# {int(index.X0.size)} terminals in {len(slabs) - 1} floor slabs; cost {cost:.1f} "
             f"(split {model.split}, repeat {model.repeat}); {count} rules",
             f"@size {W} {_num(layout.height)}"]
    text = "\n".join(lines) + "\n" + body
    return Extraction(text, text, cost, count, result.seconds, result.iterations, int(index.X0.size), method)


def _narrow(name: str, slab: FacadeLayout, labels: frozenset[str], entrance: bool) -> list[str]:
    """``<name>Narrow``: the slab on a face narrower than half its tile, where squeezing the tile would give
    slivers of windows: plain wall with the slab's most common opening of ``labels`` once in the middle at its
    input size (input height profile kept), or wall alone when the face cannot hold it. The entrance variant
    always has its door, narrowed with the face when needed."""
    ts = [t for t in slab.terminals() if t.label in labels]
    if not ts:
        return [f"{name}Narrow --> NarrowWall", "NarrowWall --> terminal(wall)"]
    sizes = Counter((round(t.w, 3), round(t.h, 3)) for t in ts)
    t = min(ts, key=lambda t: (-sizes[round(t.w, 3), round(t.h, 3)], abs(t.x + 0.5 * t.w - 0.5 * slab.width)))
    depth = f", depth: {_num(t.depth)}" if t.depth else ""
    ys = [("NarrowWall", t.y), (f"{name}Opening", t.h), ("NarrowWall", slab.height - t.y - t.h)]
    pane = " | ".join(f"'{_num(h)}: {sym}" for sym, h in ys if h > 1e-9 * slab.height)
    fits = f"split(x) {{ '1: NarrowWall | {_num(t.w)}: {name}Pane | '1: NarrowWall }}"
    if entrance:  # the door stays, narrowed with the face
        small, least = f"split(x) {{ '1: NarrowWall | '8: {name}Pane | '1: NarrowWall }}", t.w + 0.4
    else:  # a window needs piers beside it: at least 0.8 m and its own width of wall in all
        small, least = "NarrowWall", max(t.w + 0.8, 2 * t.w)
    return [f"{name}Narrow --> case width < {_num(least)}: {small}\n    else: {fits}",
            f"{name}Pane --> split(y) {{ {pane} }}",
            f"{name}Opening --> terminal({t.label}{depth})",
            "NarrowWall --> terminal(wall)"]


def _merge_identical(lines: list[str]) -> list[str]:
    """Merge symbols whose rules read the same (regions of one content but other sizes: in the linear mode a
    region's size comes from its parent), until no two rules are alike."""
    while True:
        first: dict[str, str] = {}
        alias: dict[str, str] = {}
        for line in lines:
            name, body = line.split(" --> ", 1)
            alias[name] = first.setdefault(body, name)
        alias = {a: b for a, b in alias.items() if a != b}
        if not alias:
            return lines
        pattern = re.compile(r"\b(" + "|".join(map(re.escape, alias)) + r")\b")
        lines = [pattern.sub(lambda m: alias[m.group(1)], line) for line in lines
                 if line.split(" --> ", 1)[0] not in alias]


def _selectors(sym: list[str]) -> str:
    """``floors`` items: ground, top, the input's own middle floors, and ``*`` the most frequent middle floor."""
    upper = sym[2:]
    if not upper:
        return f"0: GroundFloor | *: {sym[1]}Row"
    middle = upper[:-1] or upper
    star = Counter(middle).most_common(1)[0][0]
    parts = ["0: GroundFloor"]
    if len(upper) > 1 and upper[-1] != star:
        parts.append(f"-1: {upper[-1]}Row")
    parts += [f"{k}: {s}Row" for k, s in enumerate(upper[:-1], start=1) if s != star]
    parts.append(f"*: {star}Row")
    return " | ".join(parts)


def _entrance(door: str, row: str, width: float) -> str:
    """``EntranceRow``: as many slab tiles as ``repeat`` would place (n = round(L / W)), the middle one with the
    door, so the ground floor's tiles line up with the other floors' (for faces up to MAX_ALIGNED_WIDTH)."""
    top = max(1, math.ceil(MAX_ALIGNED_WIDTH / width + 0.5))
    alts = [f"case width < {_num(0.5 * width)}: {door}Narrow"]
    for n in range(1, top + 1):
        left = (n - 1) // 2
        right = n - 1 - left
        items = ([f"'{left}: {row}"] if left else []) + [f"'1: {door}"] + ([f"'{right}: {row}"] if right else [])
        body = door if n == 1 else f"split(x) {{ {' | '.join(items)} }}"
        alts.append(body if n == top else f"case width < {_num((n + 0.5) * width)}: {body}")
    return "EntranceRow --> " + "\n    ".join(alts[:-1]) + "\n    else: " + alts[-1]
