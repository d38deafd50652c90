"""Scene-ready size-independent grammars (wu2014 §5) with alignment kept by construction (the aim of Fig. 12).

The input facade is cut into *floor slabs*, one per storey (:mod:`citygen_inverse.slabs`, with the ground slab's
door), the slabs into margins and repeated *bays* where the facade has them (:mod:`citygen_inverse.bays`),
pinwheels are opened along walls (:mod:`citygen_inverse.pinwheels`), and the pieces are extracted jointly
(wu2014 §6.1: identical pieces and regions share rules) in the ``linear`` size mode (every size relative, repeats
written out), so a piece derived at any size is the input piece scaled along x and y. The facade rule follows the
building's floor lines::

    Facade --> floors { 0: GroundFloor | -1: TopRow | 1: Floor1Row | *: Floor2Row }
    GroundFloor --> case entrance: EntranceRow  else: GroundRow
    Floor2Row --> case width >= 3.9: split(x) { 0.6: Floor2Left | '1: Floor2Bays | 0.6: Floor2Right }
        else: Floor2Narrow
    Floor2Bays --> repeat(x) { ~2.5: Floor2Bay }

Every floor sharing the bays repeats its bay between margins of their input width (without bays: its whole slab,
tile = input width), so all floors of a face get the same tile count and edges aligned in the input stay aligned,
while a wide face gets more bays instead of stretched windows. ``EntranceRow`` writes out by the face width the
same tiles with the door's tile in the middle; every other slab has no door, so a face has one door in its ground
floor exactly when the request asks for an entrance. Faces too narrow for their tiles get ``<Slab>Narrow``: one
opening per floor at its input size, centred -- written as the later alternative of each row's ``case``, so the
``split`` kind's generator also takes it where squeezed tiles are implausible; there, on a face at least two
*pitches* wide (the facade's width over the openings of its typical storey), the opening repeats at that pitch
on every floor, so a wide face whose tiles do not fit its storeys keeps a row of windows per floor (not one
window in a blank wall) and its floors' columns stay aligned.
"""
from __future__ import annotations

import math
import re
from bisect import bisect_right
from collections import Counter

import citygen_split
from citygen.gcpause import cyclic_gc_paused
from citygen.layout import FacadeLayout
from citygen_inverse.actions import CostModel
from citygen_inverse.bays import Bays, clipped, crosses, find_bays
from citygen_inverse.emit import GrammarWriter, _num
from citygen_inverse.extract import Extraction
from citygen_inverse.pinwheels import open_pinwheels
from citygen_inverse.regions import LayoutIndex
from citygen_inverse.search import GrammarSearch
from citygen_inverse.slabs import ROW_LABELS, as_layout, carve_door, slab_layouts

#: Faces up to this width (metres) keep the entrance tile aligned with the tiles of the other floors.
MAX_ALIGNED_WIDTH = 100.0
_RESERVED = frozenset({"Facade", "GroundFloor", "EntranceRow", "EntranceBays", "EntranceTiles", "NarrowWall"})
#: Labels a bay boundary through the ground slab must not cut.
DOOR_LABELS = frozenset({"door", "shop", "window"})
EPS = 1e-9


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
                bay = as_layout(mid.width, mid.height, carve_door(mid.terminals(), mid.width, mid.height))
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
    reserved = {f"{n}{suffix}" for n in names for suffix in ("Row", "Bays", "Narrow", "NarrowBay", "Pane", "Opening")}
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
    pitch = _pitch(first[_star(row)], W)
    for k in range(1, len(slabs)):
        if row[k] != names[k]:
            continue
        uses_bays = bays is not None and (k >= 2 or ground_bays)
        body = _row_body(keys[k], bays if uses_bays else None, W)
        least = (bays.start + W - bays.end + 0.75 * bays.tile) if uses_bays else 0.5 * W
        rules.append(f"{row[k]}Row --> case width >= {_num(least)}: {body}\n    else: {row[k]}Narrow")
        if uses_bays:
            rules.append(f"{keys[k][1]}s --> repeat(x) {{ ~{_num(bays.tile)}: {keys[k][1]} }}")
        narrow += _narrow(row[k], first[row[k]], ROW_LABELS - {"door"}, entrance=False, pitch=pitch,
                          wide=max(least, 2 * pitch))
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


def _star(row: list[str]) -> str:
    """The slab name of the ``*`` floors (as :func:`_selectors` picks it): the typical storey."""
    upper = row[2:]
    return Counter(upper[:-1] or upper).most_common(1)[0][0] if upper else row[1]


def _pitch(slab: FacadeLayout, width: float) -> float:
    """The spacing of the openings of a typical storey: the facade's width over its windows and shops."""
    return width / max(1, sum(1 for t in slab.terminals() if t.label in ROW_LABELS - {"door"}))


def _narrow(name: str, slab: FacadeLayout, labels: frozenset[str], entrance: bool, pitch: float = math.inf,
            wide: float = math.inf) -> list[str]:
    """``<name>Narrow``: the slab on a face narrower than half its tile, where squeezing the tile would give
    slivers of windows: plain wall with the slab's most common opening of ``labels`` once in the middle at its
    input size (input height profile kept), or wall alone when the face cannot hold it (also the alternative the
    generator takes when the opening is implausible there). A face at least ``wide`` wide (only reached as the
    generator's alternative to squeezed tiles) repeats the opening in bays of about ``pitch``. The entrance
    variant always has its door, narrowed with the face when needed."""
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
    rows = [f"{name}Narrow --> case width >= {_num(least)}: {fits}\n    else: {small}"]
    if not entrance and pitch >= least and wide < math.inf:
        rows = [f"{name}Narrow --> case width >= {_num(wide)}: repeat(x) {{ ~{_num(pitch)}: {name}NarrowBay }}"
                f"\n    case width >= {_num(least)}: {fits}\n    else: {small}",
                f"{name}NarrowBay --> {fits}"]
    return [*rows,
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
