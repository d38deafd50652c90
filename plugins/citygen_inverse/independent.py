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
from bisect import bisect_right
from collections import Counter
from dataclasses import replace

import numpy as np

import citygen_split
from citygen.errors import LayoutError
from citygen.gcpause import cyclic_gc_paused
from citygen.layout import FLOOR_BOUND_LABELS, FacadeLayout, Region, check_partition
from citygen.plausible import OPENING_LABELS
from citygen_inverse.actions import CostModel
from citygen_inverse.bays import Bays, clipped, crosses, find_bays
from citygen_inverse.emit import GrammarWriter, _num
from citygen_inverse.extract import Extraction
from citygen_inverse.pinwheels import open_pinwheels
from citygen_inverse.regions import LayoutIndex
from citygen_inverse.search import GrammarSearch

ROW_LABELS = frozenset({"window", "door", "shop"})
#: Faces up to this width (metres) keep the entrance tile aligned with the tiles of the other floors.
MAX_ALIGNED_WIDTH = 100.0
_RESERVED = frozenset({"Facade", "GroundFloor", "EntranceRow", "EntranceBays", "EntranceTiles", "NarrowWall"})
#: Labels a bay boundary through the ground slab must not cut.
DOOR_LABELS = frozenset({"door", "shop", "window"})
EPS = 1e-9


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
#: An input door at least this share of the ground slab tall keeps its height.
DOOR_TALL = 0.7


def _with_door(ts: list[Region], width: float, height: float) -> list[Region]:
    """The ground slab with exactly one door standing on the ground: the input's largest (most central on ties),
    reaching down to the ground and, when lower than ``DOOR_TALL`` of the slab, up to ``DOOR_SHARE`` of it where no
    opening is in the way (a CMP door
    above steps, or 2 m tall in a 6 m ground floor, was a floating door or a hatch at 3-4 m ground floors); else
    one carved (:func:`_carve_door`)."""
    doors = [t for t in ts if t.label == "door"]
    if not doors:
        return _carve_door(ts, width, height)
    main = max(doors, key=lambda t: (round(t.w * t.h, 9), -abs(t.x + 0.5 * t.w - 0.5 * width)))
    ts = _no_doors(ts, keep=main)
    top = main.y + main.h
    above = [t.y for t in ts if t.label in OPENING_LABELS and t is not main and t.y >= top - 1e-9
             and t.x < main.x + main.w - 1e-9 and t.x + t.w > main.x + 1e-9]
    if top < DOOR_TALL * height:
        top = max(top, min([DOOR_SHARE * height, *above]))
    return _carve(ts, replace(main, y=0.0, h=top)) if main.y > 0 or top > main.y + main.h else ts


def _carve_door(ts: list[Region], width: float, height: float) -> list[Region]:
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
    out = [_as_layout(layout.width, gh, _with_door(ground, layout.width, gh)),
           _as_layout(layout.width, gh, _no_doors(ground))]
    names = ["GroundDoor", "Ground"]
    for k, (ts, h) in enumerate(upper, start=1):
        out.append(_as_layout(layout.width, h, _no_doors(ts)))
        names.append("Top" if k == len(upper) and k > 1 else f"Floor{k}")
    return out, names


def _pieces(slabs: list[FacadeLayout], names: list[str], has_door: bool
            ) -> tuple[Bays | None, bool, list[tuple[str, FacadeLayout]], list[tuple[str, ...]]]:
    """The layouts to extract and, per slab, the names of its pieces: ``(left, bay, right)`` (left/right may be
    "") for slabs that repeat the facade's bays (:func:`citygen_inverse.bays.find_bays`), ``(whole,)`` for the
    others. The ground slabs use the bays when they share them (no bay boundary through a door or shop); the
    door variant is then its door's piece (a bay, or a margin): ``GroundDoorBay``, ``GroundDoorLeft``, ..."""
    uppers = slabs[2:]
    bays = find_bays([slabs[1], *uppers]) if uppers else find_bays(slabs[1:2])
    ground = bays is not None and not (has_door and crosses(bays, slabs[0], DOOR_LABELS))  # else carved in a bay
    if bays is None and uppers:
        bays = find_bays(uppers)
    pieces: list[tuple[str, FacadeLayout]] = []
    parts: list[tuple[str, ...]] = []
    for k, (slab, name) in enumerate(zip(slabs, names)):
        if bays is None or (k < 2 and not ground):
            pieces.append((name, slab))
            parts.append((name,))
            continue
        left, bay, right = (clipped(slab, 0.0, bays.start), clipped(slab, bays.cuts[0], bays.cuts[1]),
                            clipped(slab, bays.end, slab.width))
        if k == 0:  # the door's piece, other pieces as in the ground slab without door
            door = next(t for t in slab.terminals() if t.label == "door")
            middle = door.x + 0.5 * door.w
            j = min(bisect_right(bays.cuts, middle) - 1, bays.count - 1)
            if not has_door:  # carved: into the middle bay
                c = bays.count // 2
                mid = clipped(slabs[1], bays.cuts[c], bays.cuts[c + 1])
                bay = _as_layout(mid.width, mid.height, _carve_door(mid.terminals(), mid.width, mid.height))
            elif middle < bays.start or middle >= bays.end:
                bay = left if middle < bays.start else right
            else:
                bay = clipped(slab, bays.cuts[j], bays.cuts[j + 1])
            where = "Left" if has_door and middle < bays.start else "Right" if has_door and middle >= bays.end \
                else "Bay"
            pieces.append((f"{name}{where}", bay))
            parts.append((where, f"{name}{where}"))
            continue
        named = (f"{name}Left" if bays.start > EPS * slab.width else "", f"{name}Bay",
                 f"{name}Right" if bays.end < (1 - EPS) * slab.width else "")
        for piece_name, piece in zip(named, (left, bay, right)):
            if piece_name:
                pieces.append((piece_name, piece))
        parts.append(named)
    return bays, ground, pieces, parts


@cyclic_gc_paused()
def extract_size_independent(layout: FacadeLayout, method: str = "adp", iterations: int = 2000, seed: int = 0,
                             model: CostModel = CostModel(), time_limit: float | None = None,
                             header: tuple[str, ...] = ()) -> Extraction:
    """A grammar for ``layout`` that derives on any face under the building's floor lines, entrance and corners.

    ``cost`` and ``rules`` are those of the written file (``citygen grammar cost``), not of the joint search.
    """
    slabs, names = slab_layouts(layout)
    bays, ground_bays, pieces, parts = _pieces(slabs, names, layout.count("door") > 0)
    index = LayoutIndex([open_pinwheels(piece) for _, piece in pieces])
    result = GrammarSearch(index, model).run(method, iterations, seed, time_limit)
    piece_names = [name for name, _ in pieces]
    reserved = {f"{n}{suffix}" for n in names for suffix in ("Row", "Bays", "Narrow", "Pane", "Opening")}
    writer = GrammarWriter(index, result.rules, piece_names, reserved=_RESERVED | reserved)
    written = {name: writer.names[index.sig(b)] for name, b in zip(piece_names, index.roots)}  # shared names
    W = layout.width
    # slabs of one content (all pieces alike) share a row, named after the first of them
    keys = [tuple(written.get(p, "") for p in part) for part in parts]
    row = [names[keys.index(key)] for key in keys]
    first = {row[k]: slabs[k] for k in reversed(range(len(slabs)))}
    rules = [f"Facade --> floors {{ {_selectors(row)} }}",
             f"GroundFloor --> case entrance: EntranceRow  else: {row[1]}Row"]
    narrow: list[str] = []
    for k in range(1, len(slabs)):
        if row[k] != names[k]:
            continue
        uses_bays = bays is not None and (k >= 2 or ground_bays)
        body = _row_body(keys[k], bays if uses_bays else None, W)
        least = (bays.start + W - bays.end + 0.75 * bays.tile) if uses_bays else 0.5 * W
        rules.append(f"{row[k]}Row --> case width >= {_num(least)}: {body}\n    else: {row[k]}Narrow")
        if uses_bays:
            rules.append(f"{keys[k][1]}s --> repeat(x) {{ ~{_num(bays.tile)}: {keys[k][1]} }}")
        narrow += _narrow(row[k], first[row[k]], ROW_LABELS - {"door"}, entrance=False)
    door = keys[0][-1]
    if bays is not None and ground_bays:
        where = parts[0][0]
        ground = keys[1]
        least = bays.start + W - bays.end + 0.75 * bays.tile
        if where == "Bay":
            middle = "'1: EntranceBays"
            rules.append(_entrance("EntranceBays", door, f"{ground[1]}s", bays.tile))
        else:
            middle = f"'1: {ground[1]}s"
        items = [f"{_num(bays.start)}: {door if where == 'Left' else ground[0]}" if ground[0] or where == "Left"
                 else "", middle,
                 f"{_num(W - bays.end)}: {door if where == 'Right' else ground[2]}" if ground[2] or where == "Right"
                 else ""]
        rules.append(f"EntranceRow --> case width >= {_num(least)}: split(x) {{ {' | '.join(i for i in items if i)} }}"
                     f"\n    else: {names[0]}Narrow")
    else:
        rules.append(f"EntranceRow --> case width >= {_num(0.5 * W)}: EntranceTiles\n    else: {names[0]}Narrow")
        rules.append(_entrance("EntranceTiles", door, f"{row[1]}Row", W))
    narrow += _narrow(names[0], slabs[0], frozenset({"door"}), entrance=True)
    lines_ = list(dict.fromkeys(rules + writer.rule_lines("linear") + narrow))
    body = "\n".join(_merge_identical(lines_)) + "\n"
    grammar = citygen_split.parse(body, "<size-independent>")
    cost = citygen_split.grammar_cost(grammar, model.split, model.repeat)
    count = sum(1 for r in grammar.rules if type(r.body).__name__ != "Terminal")
    repeat = (f"{bays.count} bays of {bays.tile:.2f} m between x = {bays.start:.2f} and {bays.end:.2f} m repeat"
              + ("" if ground_bays else " above the ground floor")) if bays else "no repeated bays: the slab repeats"
    lines = [*(f"# {h}" for h in header),
             f"# size-independent grammar (wu2014 §5) extracted by citygen grammar extract, method {method}, "
             f"{result.iterations} iterations, seed {seed}",
             f"# {int(index.X0.size)} terminals in {len(slabs) - 1} floor slabs ({repeat}); cost {cost:.1f} "
             f"(split {model.split}, repeat {model.repeat}); {count} rules",
             f"@size {_num(W)} {_num(layout.height)}"]
    text = "\n".join(lines) + "\n" + body
    return Extraction(text, text, cost, count, result.seconds, result.iterations, int(index.X0.size), method)


def _row_body(key: tuple[str, ...], bays: Bays | None, width: float) -> str:
    """A floor row: the whole slab repeated, or its margins at their input width around its repeated bays."""
    if bays is None:
        return f"repeat(x) {{ ~{_num(width)}: {key[0]} }}"
    left, bay, right = key
    if not left and not right:
        return f"{bay}s"
    items = ([f"{_num(bays.start)}: {left}"] if left else []) + [f"'1: {bay}s"] + (
        [f"{_num(width - bays.end)}: {right}"] if right else [])
    return f"split(x) {{ {' | '.join(items)} }}"


def _narrow(name: str, slab: FacadeLayout, labels: frozenset[str], entrance: bool) -> list[str]:
    """``<name>Narrow``: the slab on a face narrower than half its tile, where squeezing the tile would give
    slivers of windows: plain wall with the slab's most common opening of ``labels`` once in the middle at its
    input size (input height profile kept), or wall alone when the face cannot hold it (also the alternative the
    generator takes when the opening is implausible there). The entrance variant always has its door, narrowed
    with the face when needed."""
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
    return [f"{name}Narrow --> case width >= {_num(least)}: {fits}\n    else: {small}",
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


def _entrance(name: str, door: str, row: str, tile: float) -> str:
    """``name``: as many tiles as ``repeat`` would place (n = round(L / tile)), the middle one ``door``, so the
    ground floor's tiles line up with the other floors' (for faces up to MAX_ALIGNED_WIDTH)."""
    top = max(1, math.ceil(MAX_ALIGNED_WIDTH / tile + 0.5))
    alts: list[str] = []
    for n in range(1, top + 1):
        left = (n - 1) // 2
        right = n - 1 - left
        items = ([f"'{left}: {row}"] if left else []) + [f"'1: {door}"] + ([f"'{right}: {row}"] if right else [])
        body = door if n == 1 else f"split(x) {{ {' | '.join(items)} }}"
        alts.append(body if n == top else f"case width < {_num((n + 0.5) * tile)}: {body}")
    if len(alts) == 1:
        return f"{name} --> {alts[0]}"
    return f"{name} --> " + "\n    ".join(alts[:-1]) + "\n    else: " + alts[-1]
