"""Derived tables of a model used on the hot path of the relayout (built once per model, cached)."""
from __future__ import annotations

import math
import zlib
from dataclasses import dataclass

from citygen.layout import FLOOR_BOUND_LABELS, Region
from citygen_relayout.bounds import extent_bounds
from citygen_relayout.model import END, Model, Pattern, SizeRange
from citygen_relayout.sequences import CoverAutomaton


def scaled_bounds(lo: float, hi: float, relative: bool, size: float, input_size: float) -> tuple[int, int]:
    """Integer count bounds; relative bounds scale with ``size / input_size`` (§5.1 frequency, instances)."""
    if not relative:
        return int(math.ceil(lo - 1e-9)), int(math.floor(hi + 1e-9))
    r = size / input_size if input_size > 0 else 1.0
    return int(math.floor(lo * r + 1e-9)), max(int(math.ceil(hi * r - 1e-9)), int(math.floor(lo * r + 1e-9)))


@dataclass(frozen=True)
class PatternRef:
    """A constraint side: ``kind`` 'align' or 'same', constraint index, side 0/1."""

    kind: str
    index: int
    side: int
    pattern: Pattern


class Compiled:
    """Per-model tables: automata, size ranges, door-bearing, opening-holding and floor/corner-bound symbols,
    pattern index."""

    def __init__(self, model: Model) -> None:
        self.model = model
        self.automata = {name: CoverAutomaton(rules.sequences) for name, rules in model.rules.items()}
        self.reverse_automata = {name: a.reversed() for name, a in self.automata.items()
                                 if model.rules[name].symmetric}
        self.door: dict[str, bool] = {}
        self.bound: dict[tuple[str, str], bool] = {}
        for name in model.symbols:
            self._has_door(name)
            self._bound(name, "x")
            self._bound(name, "y")
        self.doorless: dict[str, bool] = {}
        self.opening: dict[str, bool] = {}
        self._door_ahead: dict[tuple, bool] = {}
        for name in model.symbols:
            self._doorless(name)
            self._has_opening(name)
        self.bounds = {relax: extent_bounds(model, self.automata, self.door, relax) for relax in (False, True)}
        self.min_extent, self.max_extent = self.bounds[False]
        self.patterns: list[PatternRef] = []
        for k, al in enumerate(model.alignments):
            self.patterns += [PatternRef("align", k, 0, al.a), PatternRef("align", k, 1, al.b)]
        for k, ss in enumerate(model.samesizes):
            self.patterns += [PatternRef("same", k, 0, ss.a), PatternRef("same", k, 1, ss.b)]
        self.by_last: dict[str, list[PatternRef]] = {}
        for ref in self.patterns:
            for sym in ref.pattern.items[-1]:
                self.by_last.setdefault(sym, []).append(ref)
        self.aligned_symbols = frozenset(s for al in model.alignments for p in (al.a, al.b) for s in p.body[0])
        self.composite = {name: not sym.is_terminal for name, sym in model.symbols.items()}
        # symbols that scope a constraint (``within``): the only ancestors a region needs to remember
        self.scoped = frozenset(c.within for c in (*model.alignments, *model.samesizes) if c.within)
        self._names: dict[tuple[str, int], str] = {}
        self._templates: dict[tuple[str, int], dict] = {}
        self.code = zlib.crc32(model.name.encode()) ^ (len(model.symbols) << 32)  # part of region module keys

    def names(self, element: tuple[str, int]) -> str:
        """Region name of an element: ``S`` for instance 0, ``S'k`` for instance k."""
        name = self._names.get(element)
        if name is None:
            name = self._names[element] = element[0] if not element[1] else f"{element[0]}'{element[1]}"
        return name

    def template(self, element: tuple[str, int]) -> dict:
        """``Region.template`` of a terminal element's regions (for ``Region.stamped``)."""
        found = self._templates.get(element)
        if found is None:
            sym = self.model.symbols[element[0]]
            found = self._templates[element] = Region.template(
                self.names(element), label=sym.label, depth=sym.depth, material=sym.material, asset=sym.asset)
        return found

    def size(self, symbol: str, axis: str) -> SizeRange:
        return self.model.sizes[(symbol, axis)]

    def _has_door(self, name: str) -> bool:
        if name not in self.door:
            sym = self.model.symbols[name]
            self.door[name] = sym.label == "door" if sym.is_terminal else \
                any([self._has_door(c) for c in sym.children])
        return self.door[name]

    def door_ahead(self, name: str, state) -> bool:
        """Whether some continuation of ``name``'s arrangement from automaton ``state`` holds a door-bearing
        child (breadth-first, memoised): a face that still owes its door prunes prefixes that cannot place it."""
        key = (name, state)
        found = self._door_ahead.get(key)
        if found is None:
            auto = self.automata[name]
            kids = list(dict.fromkeys(self.model.symbols[name].children))
            seen, frontier, found = {state}, [state], False
            while frontier and not found and len(seen) < 5000:
                here = frontier.pop()
                for c in kids:
                    nxt = auto.step(here, c)
                    if nxt is None:
                        continue
                    if self.door[c]:
                        found = True
                        break
                    if nxt not in seen:
                        seen.add(nxt)
                        frontier.append(nxt)
            found = found or len(seen) >= 5000
            self._door_ahead[key] = found
        return found

    def _has_opening(self, name: str) -> bool:
        """Whether ``name`` holds a floor-bound terminal (an opening) anywhere below: its floor matters."""
        if name not in self.opening:
            sym = self.model.symbols[name]
            self.opening[name] = sym.label in FLOOR_BOUND_LABELS if sym.is_terminal else \
                any([self._has_opening(c) for c in sym.children])
        return self.opening[name]

    def _doorless(self, name: str) -> bool:
        """Whether ``name`` has a valid arrangement without any door (breadth-first over automaton states)."""
        if name not in self.doorless:
            sym = self.model.symbols[name]
            if sym.is_terminal:
                self.doorless[name] = sym.label != "door"
            else:
                auto = self.automata[name]
                allowed = [c for c in dict.fromkeys(sym.children) if self._doorless(c)]
                seen, frontier, found = {auto.start}, [auto.start], False
                while frontier and not found and len(seen) < 5000:
                    state = frontier.pop()
                    if auto.step(state, END) is not None:
                        found = True
                    for c in allowed:
                        nxt = auto.step(state, c)
                        if nxt is not None and nxt not in seen:
                            seen.add(nxt)
                            frontier.append(nxt)
                self.doorless[name] = found
        return self.doorless[name]

    def _bound(self, name: str, axis: str) -> bool:
        """Whether a region of ``name`` arranged along ``axis`` has an opening spanning its whole extent on it.

        Such a region must itself stay within one floor (y) or out of the corner strips (x) of a request.
        """
        if (name, axis) not in self.bound:
            sym = self.model.symbols[name]
            self.bound[(name, axis)] = sym.label in FLOOR_BOUND_LABELS if sym.is_terminal else \
                sym.split != axis and any([self._bound(c, axis) for c in sym.children])
        return self.bound[(name, axis)]


_CACHE: dict[int, tuple[Model, Compiled]] = {}


def compile_model(model: Model) -> Compiled:
    """The (cached) tables of ``model``."""
    hit = _CACHE.get(id(model))
    if hit is None or hit[0] is not model:
        if len(_CACHE) > 64:
            _CACHE.clear()
        hit = _CACHE[id(model)] = (model, Compiled(model))
    return hit[1]
