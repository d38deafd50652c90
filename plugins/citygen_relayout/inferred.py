"""Default constraints of a model built from a layout (``layout "file.json"``), for what its author leaves unsaid.

A model written by hand states its sequences and size ranges; one built from an imported layout should vary
without them (issue 21): the automatic segmentation (:mod:`citygen_relayout.hierarchy`) gives storeys and bays,
and these defaults turn its structure into bao2013 §5.2 repetitions and generous size ranges:

* the facade repeats each storey above the ground with the gap band before it (``Ground (Gap Storey)+ Top``), so
  storey counts follow the building's floors;
* a row (x-split) repeats each run of a repeated unit of one to three children holding a bay
  (``Wall (Bay Pier)+ Bay Wall``: the unit occurs twice or more in the input; plain walls match each other and
  so do window bays), so bay counts vary and a door between two runs stays between bays, where the input had
  it, never at the facade's end;
* a row holding one door bay in its middle whose children read the same from both ends by kind is
  ``symmetric`` (mirror positions share their symbols), so the door stays centred as in the input;
* a door-bearing child of a row may also be one of the row's opening bays (``{DoorBay Bay}``), once per row
  (``freq ... 1..1``): a face without entrance takes a window bay there (the door budget of §9.1 relaxes it);
* size ranges: openings 50-150 % of their input size (never below the plausibility minimums, doors at least
  1.9 m tall, no other labelled terminal a sliver), walls and bands 25-300 %, composites from 40 % up to what
  their content allows, storeys 40-160 % of their height, the top band 25-125 %, gaps 0.05-2 m, the parts of
  rows without openings (moldings, wall bands) as wide as needed, so faces far from the input size and storeys
  of other heights fit; the minimum sizes of openings hold on both axes (:attr:`Model.terminal_min`), whichever
  axis their parent splits.

Every default yields to what the model file states for that composite or symbol.
"""
from __future__ import annotations

from collections.abc import Mapping

from citygen.plausible import DEFAULT_RULES, OPENING_LABELS
from citygen_relayout import generators as gen
from citygen_relayout.hierarchy import Segmentation
from citygen_relayout.model import Frequency, SizeRange, Symbol

#: (low, high) fractions of the input size by kind of symbol, and sigma of the initial-size distribution.
OPENING_RANGE = (0.5, 1.5)
PLAIN_RANGE = (0.25, 3.0)
COMPOSITE_RANGE = (0.4, 20.0)  # the upper bound: in effect what the content allows
STOREY_RANGE = (0.4, 1.6)
TOP_RANGE = (0.25, 1.25)  # the top band may shrink into the top storey, not grow into storeys of its own
GAP_RANGE = (0.05, 2.0)  # metres: a gap band absorbs the top band's height in every storey pitch
SIGMA = 0.1
_MAX_UNIT = 3


def opening_bearing(name: str, symbols: Mapping[str, Symbol], memo: dict[str, bool] | None = None) -> bool:
    """Whether ``name`` is or holds an opening (window, door, shop, balcony)."""
    memo = {} if memo is None else memo
    if name not in memo:
        sym = symbols[name]
        memo[name] = sym.label in OPENING_LABELS if sym.is_terminal else \
            any(opening_bearing(c, symbols, memo) for c in sym.children)
    return memo[name]


def holds_label(name: str, label: str, symbols: Mapping[str, Symbol]) -> bool:
    sym = symbols[name]
    return sym.label == label if sym.is_terminal else any(holds_label(c, label, symbols) for c in sym.children)


def sequences(sym: Symbol, symbols: Mapping[str, Symbol], segmentation: Segmentation) -> list:
    """Default sequences of composite ``sym`` (see the module doc)."""
    if sym.name == segmentation.root and segmentation.storeys:
        return gen.repetition(_storey_pattern(sym.children, segmentation.storeys, segmentation.gaps))
    if sym.split == "x":
        return gen.repetition(_row_pattern(sym.children, symbols))
    return gen.replication(tuple(frozenset({c}) for c in sym.children))


def symmetric(sym: Symbol, symbols: Mapping[str, Symbol]) -> bool:
    """A row holding a door whose children read the same from both ends by kind (plain walls alike, window bays
    alike) with the door in the middle: it is laid out symmetric, so the door stays centred."""
    if sym.split != "x" or len(sym.children) % 2 == 0:
        return False
    doors = frozenset(c for c in sym.children if holds_label(c, "door", symbols))
    keys = _kinds(sym.children, symbols, doors)
    return bool(doors) and sym.children[len(keys) // 2] in doors and sum(c in doors for c in sym.children) == 1 \
        and keys == keys[::-1]


def frequencies(sym: Symbol, symbols: Mapping[str, Symbol]) -> list[Frequency]:
    """One door per row that holds the door (a row with a door-bearing child offered in place of a bay)."""
    if sym.split != "x":
        return []
    doors = frozenset(c for c in sym.children if holds_label(c, "door", symbols))
    if not doors or not _bays(sym.children, symbols, doors):
        return []
    return [Frequency(doors, 1, 1, text=f"freq {sym.name} {{{' '.join(sorted(doors))}}} 1..1 (default)")]


def size_range(sym: Symbol, axis: str, role: str | None = None) -> SizeRange:
    """Default size range of ``sym`` along ``axis`` (see the module doc); ``role``: ``storey``, ``gap`` or
    ``top`` for the facade's storeys, the wall bands between them and the top band; ``band`` for a part of a row
    without openings (it stretches with the facade's width)."""
    base = sym.extent[0 if axis == "x" else 1]
    if role == "gap" and axis == "y":
        return SizeRange(min(GAP_RANGE[0], base), max(GAP_RANGE[1], 3 * base), base, SIGMA * max(base, 1.0))
    if role == "storey" and axis == "y":
        lo, hi = STOREY_RANGE
    elif role == "top" and axis == "y":
        lo, hi = TOP_RANGE
    elif role == "band" and axis == "x":
        lo, hi = PLAIN_RANGE[0], COMPOSITE_RANGE[1]
    elif not sym.is_terminal:
        lo, hi = COMPOSITE_RANGE
    elif sym.label in OPENING_LABELS:
        lo, hi = OPENING_RANGE
    else:
        lo, hi = PLAIN_RANGE
    low = lo * base
    if sym.is_terminal and sym.label and sym.label not in DEFAULT_RULES.thin_labels:
        low = max(low, 2 * DEFAULT_RULES.sliver)
    if sym.is_terminal and sym.label in DEFAULT_RULES.min_size:
        least = DEFAULT_RULES.min_size[sym.label][0 if axis == "x" else 1]
        if sym.label == "door" and axis == "y":
            least = max(least, DEFAULT_RULES.door_min_height)
        low = max(low, least)
    high = max(hi * base, low)
    return SizeRange(low, high, min(max(base, low), high), SIGMA * base)


def terminal_minimums(symbols: Mapping[str, Symbol]) -> dict[tuple[str, str], float]:
    """The plausible minimum extents of opening terminals on both axes (doors at least 1.9 m tall), and of every
    other labelled terminal not thin by nature (no slivers), whichever axis their parent splits."""
    rules = DEFAULT_RULES
    out: dict[tuple[str, str], float] = {}
    for sym in symbols.values():
        if not sym.is_terminal or not sym.label:
            continue
        for k, axis in enumerate("xy"):
            if sym.label in rules.min_size:
                least = rules.min_size[sym.label][k]
                if sym.label == "door" and axis == "y":
                    least = max(least, rules.door_min_height)
            elif sym.label in rules.thin_labels:
                continue
            else:
                least = rules.sliver
            out[(sym.name, axis)] = least
    return out


def _storey_pattern(children: tuple[str, ...], storeys: tuple[str, ...], gaps: tuple[str, ...]) -> gen.Node:
    """Each storey above the ground, with the gap band before it, repeats: ``Ground (Gap Storey)+ Top``."""
    units: list[tuple[str, ...]] = []
    k = 0
    while k < len(children):
        if children[k] in gaps and k + 1 < len(children) and children[k + 1] in storeys:
            units.append(children[k:k + 2])
            k += 2
        else:
            units.append(children[k:k + 1])
            k += 1
    parts: list[gen.Node] = []
    for j, unit in enumerate(units):
        if j and units[j - 1] == unit and unit[-1] in storeys:
            continue
        seq = gen.Node("seq", parts=tuple(gen.Node("item", item=frozenset({c})) for c in unit))
        parts.append(gen.Node("+", parts=(seq,)) if unit[-1] in storeys else seq)
    return gen.Node("seq", parts=tuple(parts))


def _kinds(children: tuple[str, ...], symbols: Mapping[str, Symbol], doors: frozenset[str]) -> list[str]:
    """Children by kind: ``wall`` (a plain wall terminal), ``bay`` (an opening bay without door), ``door`` (the
    door bay), else the symbol itself."""
    bays = set(_bays(children, symbols, doors))
    return ["door" if c in doors else "wall" if symbols[c].is_terminal and symbols[c].label == "wall"
            else "bay" if c in bays else c for c in children]


def _bays(children: tuple[str, ...], symbols: Mapping[str, Symbol], doors: frozenset[str]) -> list[str]:
    """The row's opening bays without a door, most frequent first."""
    counts: dict[str, int] = {}
    for c in children:
        if c not in doors and opening_bearing(c, symbols):
            counts[c] = counts.get(c, 0) + 1
    return sorted(counts, key=lambda c: -counts[c])


def _row_pattern(children: tuple[str, ...], symbols: Mapping[str, Symbol]) -> gen.Node:
    """Runs of a repeated unit become ``(unit)+``; units match by kind (plain walls alike, window bays alike), and a
    run's items are the symbols found at that place of the unit. A door-bearing child may also be the row's
    commonest bay."""
    doors = frozenset(c for c in children if holds_label(c, "door", symbols))
    bays = _bays(children, symbols, doors)
    keys = _kinds(children, symbols, doors)
    if symmetric(Symbol("?", (0.0, 0.0), split="x", children=children), symbols):
        # mirror positions take each other's symbols, so the row reads the same from both ends
        children = tuple("|".join(sorted({a, b})) for a, b in zip(children, reversed(children)))

    def item(names) -> gen.Node:
        names = {part for name in names for part in name.split("|")}
        if names & doors and bays:
            names.add(bays[0])
        return gen.Node("item", item=frozenset(names))

    parts: list[gen.Node] = []
    i, n = 0, len(children)
    while i < n:
        best_len, best_reps = 1, 1
        for size in range(1, _MAX_UNIT + 1):
            unit = keys[i:i + size]
            if len(unit) < size or "door" in unit or "bay" not in unit:
                continue
            reps = 1
            while keys[i + reps * size:i + (reps + 1) * size] == unit:
                reps += 1
            if reps >= 2 and reps * size > best_len * best_reps:
                best_len, best_reps = size, reps
        if best_reps >= 2:
            run = children[i:i + best_len * best_reps]
            unit = tuple(item(run[k::best_len]) for k in range(best_len))
            parts.append(gen.Node("+", parts=(gen.Node("seq", parts=unit),)))
            i += best_len * best_reps
        else:
            parts.append(item((children[i],)))
            i += 1
    return gen.Node("seq", parts=tuple(parts))
