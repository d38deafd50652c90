"""Derivation: apply a grammar to a facade request and produce the FacadeLayout region tree.

Non-terminal symbols become inner regions with their children; terminal rules become labelled leaves. Every
split places its last item exactly at the parent's edge, so the leaves partition the face for any size.
"""
from __future__ import annotations

import functools
import itertools
import operator
import os
from bisect import bisect_right
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from citygen.errors import RulesetError
from citygen.layout import FacadeLayout, Region
from citygen.request import FacadeRequest
from citygen_split.ast import (
    Case, Choice, Floors, Grammar, Grid, Item, Rename, Repeat, RepeatABA, Rule, SimpleBody, Split, SymSplit,
    Terminal,
)
from citygen_split.expr import evaluate
from citygen_split.sizes import aba_count, place, preferred_length, repeat_count, resolve

PLUGIN_ID = "split"
_WALL = Terminal("wall")
#: Deepest derivation allowed (a rule that splits into itself without shrinking hits this).
MAX_DEPTH = 200
#: Most regions one face's derivation may make. A real facade makes a few thousand (a 100 m long, 10 storey face of
#: the shipped apartment grammar ~3,000), a 10 km long one ~300,000 -- which the builder would then turn into
#: geometry and the stage writer into prims, for minutes and gigabytes: past this the face is too large for the
#: grammar's sizes (:class:`FaceTooLarge`).
MAX_REGIONS = 100_000


class FaceTooLarge(RulesetError):
    """A derivation that would make more than :data:`MAX_REGIONS` regions (a 10 km long facade, a repeat of tiny
    tiles): the face is too large for the grammar's sizes. Not the grammar's error:
    :func:`~citygen_split.alternatives.derive_plausible` makes the face a plain wall with a ``too-large`` finding,
    so the building's fallback ruleset takes over."""


#: A choice point of a derivation: the rule's symbol and the region's size (regions of one symbol and size choose
#: alike, so the translation cache stays valid).
PointKey = tuple[str, float, float]


def point_key(symbol: str, w: float, h: float) -> PointKey:
    return (symbol, round(w, 6), round(h, 6))


class Subtrees:
    """The :attr:`~citygen_split.ast.Grammar.face_invariant` subtrees derived on the faces of one building, for its
    next faces. Such a subtree derives alike on every face given its symbol, size and floor, and at the same place
    to the last bit: so a later face that needs one where an earlier face had it (the storeys of opposite faces of
    equal width) places a copy of it instead of deriving it again, and its layout is the one it would derive.
    A face's subtrees are offered when its derivation completes, and only by derivations without forced
    alternatives. A copy does not note the choice points inside it (:attr:`_Derivation.partial`)."""

    def __init__(self, grammar: Grammar) -> None:
        self.grammar = grammar
        #: (region, its size in regions, its first terminal's position and its terminal count in the arrays of
        #: the derivation that made it, that derivation) by (symbol, width, height, floor or -1, x, y)
        self.derived: dict[tuple[str, float, float, int, float, float],
                           tuple[Region, int, int, int, _Derivation]] = {}
        #: per key of :attr:`derived` copied: its terminals' rectangles in tree order, their distinct sources (in
        #: order of first use) and the index of each terminal's source among them
        self.blocks: dict[tuple[str, float, float, int, float, float],
                          tuple[list[list[float]], list[Region], list[int]]] = {}

    def block(self, place: tuple[str, float, float, int, float, float]
              ) -> tuple[list[list[float]], list[Region], list[int]]:
        """The terminals of the subtree at ``place`` (a key of :attr:`derived`), read once from its derivation's
        arrays."""
        made = self.blocks.get(place)
        if made is None:
            _, _, first, n, origin = self.derived[place]
            rects, sources, index = origin.arrays
            of = index[first:first + n].tolist()
            distinct = {i: k for k, i in enumerate(dict.fromkeys(of))}
            made = self.blocks[place] = (rects[first:first + n].tolist(), [sources[i] for i in distinct],
                                         list(map(distinct.__getitem__, of)))
        return made


def derive(grammar: Grammar, request: FacadeRequest, alternatives: dict[PointKey, int] | None = None,
           subtrees: Subtrees | None = None) -> FacadeLayout:
    """The layout of ``grammar`` on ``request``'s face (see docs/grammar.md for the semantics).

    ``alternatives`` picks, per choice point, which alternative to take instead of the first (0): the k-th
    holding branch of a ``case`` (``else`` last), k fewer tiles of a ``repeat`` / ``repeatABA``, the k-th other
    alternative of a stochastic rule (see :mod:`citygen_split.alternatives`). ``subtrees``: those of the
    building's faces derived before (:class:`Subtrees`).
    """
    return _Derivation(grammar, request, alternatives=alternatives, subtrees=subtrees).run()


def explain(grammar: Grammar, request: FacadeRequest, alternatives: dict[PointKey, int] | None = None) -> str:
    """The derivation tree as indented text: symbol, size, position and the rule applied."""
    derivation = _Derivation(grammar, request, trace=True, alternatives=alternatives)
    derivation.run()
    return "\n".join(derivation.trace)


class _Derivation:
    def __init__(self, grammar: Grammar, request: FacadeRequest, trace: bool = False,
                 alternatives: dict[PointKey, int] | None = None, subtrees: Subtrees | None = None) -> None:
        if not (request.width > 0 and request.height > 0):
            raise RulesetError(f"facade size {request.width} x {request.height} is not positive", plugin=PLUGIN_ID)
        self.grammar = grammar
        self.table = grammar.table
        self.request = request
        ctx = request.context
        self.face: dict[str, Any] = {
            "face_width": float(request.width), "face_height": float(request.height),
            "floor_count": request.floor_count, "entrance": bool(request.entrance),
            "street": bool(ctx.street_facing), "courtyard": bool(ctx.is_courtyard), "levels": ctx.levels,
        }
        self.attributes = ctx.attributes
        self.base = _folder(grammar.source)
        self.corners = _corner_widths(request)
        self.once: dict[str, int] = {}
        self.streams: dict[str, np.random.Generator] = {}
        self.count = 0
        self.trace: list[str] = []
        self.tracing = trace
        self.reusable = frozenset() if trace else grammar.translation_invariant
        self.floorless = frozenset() if trace else grammar.floor_invariant  # (cached with floor -1)
        #: Symbols whose subtrees' keys are scoped by the grammar, not by the face's seed: they derive alike on every
        #: face of the building, so the module search hashes each once per building (not when alternatives are
        #: forced: they are the face's own)
        self.shared = frozenset() if trace or alternatives else grammar.face_invariant
        self.scope = ("grammar", id(grammar))
        if subtrees is not None and subtrees.grammar is not grammar:
            raise ValueError("the subtrees of another grammar")
        #: The building's :class:`Subtrees` (None without shared symbols), what this face adds to them (as
        #: :attr:`Subtrees.derived`'s items), and whether a copy of another face's subtree was placed (its choice
        #: points are then not in :attr:`points`).
        self.subtrees = subtrees if subtrees is not None and self.shared else None
        self.offered: list[tuple[tuple[str, float, float, int, float, float], tuple[Region, int, int, int,
                                                                                   _Derivation]]] = []
        self.partial = False
        self.foreign: dict[int, int] = {}  # id of another face's source -> its index among :attr:`sources`
        #: (the terminals' rectangles, the sources and each terminal's source index, once :meth:`run` is done)
        self.arrays: tuple[np.ndarray, tuple[Region, ...], np.ndarray]
        #: (subtree, its size in regions, position of its first terminal, its terminal count, and for a terminal
        #: its index among :attr:`sources`) by (symbol, size, floor; -1 for a :attr:`floorless` symbol)
        self.cache: dict[tuple[str, float, float, int], tuple[Region, int, int, int, int]] = {}
        self.templates: dict[str, tuple[Terminal, dict[str, Any]]] = {}  # (body, its regions' fields)
        #: Fields of the terminal regions of reusable symbols whose rule is a plain terminal (the fast path of
        #: :meth:`terminal`; none when tracing, which derives every region).
        self.terminals = {} if trace else _terminal_fields(grammar, self.asset)
        #: The terminal regions made, in tree order (regions are made depth first, children in order), except
        #: those inside moved copies of subtrees, which are noted in :attr:`copies` instead.
        self.leaves: list[Region] = []
        #: The distinct terminals (:attr:`FacadeLayout.leaf_sources`: a repeated terminal is a moved copy of the
        #: first), in tree order, and the index of each of :attr:`leaves` among them.
        self.sources: list[Region] = []
        self.source_of: list[int] = []
        #: Per moved copy of a subtree: (terminals made before it, position of the original's first terminal,
        #: their count, dx, dy); positions count every terminal of the layout in tree order. A copy of another
        #: face's subtree has (its terminals' rectangles, their indices among :attr:`sources`) and None instead,
        #: and no move.
        self.copies: list[tuple[int, Any, int | None, float, float]] = []
        self.copied = 0  # terminals inside the copies so far
        self.alternatives = alternatives or {}
        #: Choice points met: key -> number of alternatives (the first included).
        self.points: dict[PointKey, int] = {}

    def run(self) -> FacadeLayout:
        r = self.request
        root = self.region(self.grammar.start, 0.0, 0.0, float(r.width), float(r.height), 0, 0, ())
        layout = FacadeLayout(width=float(r.width), height=float(r.height), root=root,
                              meta={"kind": PLUGIN_ID, "ruleset": self.grammar.source, "start": self.grammar.start})
        if not self.copies:  # (FacadeLayout.leaves, already known)
            layout.__dict__["leaves"] = tuple(self.leaves)
        rects, (sources, index) = _leaf_arrays(self.leaves, self.sources, self.source_of, self.copies)
        layout.__dict__["leaf_rects"], layout.__dict__["leaf_sources"] = rects, (sources, index)
        if self.subtrees is not None:
            self.arrays = rects, sources, index
            self.subtrees.derived.update(self.offered)  # (no place is offered twice: later faces copy it)
        return layout

    # ---- one region -----------------------------------------------------------------------------------------
    def region(self, symbol: str, x: float, y: float, w: float, h: float, floor: int, depth: int,
               chain: tuple[str, ...]) -> Region:
        if symbol in self.reusable:
            key = (symbol, w, h, -1 if symbol in self.floorless else floor)
            done = self.cache.get(key)
            if done is not None:  # regions of equal symbol, size and floor derive alike: a moved copy
                original, size, first, n, source = done
                self.count += size
                if self.count > MAX_REGIONS:
                    raise self.too_large(f"derivation went beyond {MAX_REGIONS} regions at {symbol}",
                                         self.grammar.source)
                dx, dy = x - original.x, y - original.y
                copy = original.moved(dx, dy)
                if n == 1 and not original.children:
                    self.leaves.append(copy)
                    self.source_of.append(source)
                else:
                    self.copies.append((len(self.leaves), first, n, dx, dy))
                    self.copied += n
                return copy
            if self.subtrees is not None and symbol in self.shared:
                place = (*key, x, y)
                if place in self.subtrees.derived:
                    return self.copied_from(place)
            before, first = self.count, len(self.leaves) + self.copied
            region = self.derive_region(symbol, x, y, w, h, floor, depth, chain)
            region.__dict__["key"] = hash((self.scope if symbol in self.shared else self.request.seed, key))
            # (copies share it: a module hint)
            n = len(self.leaves) + self.copied - first
            self.cache[key] = (region, self.count - before, first, n,
                               len(self.sources) - 1)  # (the source of a terminal region)
            if self.subtrees is not None and symbol in self.shared and region.children:
                self.offered.append(((*key, x, y), (region, self.count - before, first, n, self)))
            return region
        return self.derive_region(symbol, x, y, w, h, floor, depth, chain)

    def copied_from(self, place: tuple[str, float, float, int, float, float]) -> Region:
        """A copy of the subtree another face of the building derived at ``place`` (:attr:`Subtrees.derived`), noted
        like a subtree of this face (its terminals in :attr:`copies`, its sources among :attr:`sources`)."""
        region, size, _, n, _ = self.subtrees.derived[place]
        self.count += size
        if self.count > MAX_REGIONS:
            raise self.too_large(f"derivation went beyond {MAX_REGIONS} regions at {place[0]}", self.grammar.source)
        copy = region.moved(0.0, 0.0)
        rows, sources, codes = self.subtrees.block(place)
        foreign = self.foreign
        local = []
        for source in sources:
            k = foreign.get(id(source))
            if k is None:
                k = foreign[id(source)] = len(self.sources)
                self.sources.append(source)
            local.append(k)
        first = len(self.leaves) + self.copied
        self.copies.append((len(self.leaves), (rows, list(map(local.__getitem__, codes))), None, 0.0, 0.0))
        self.copied += n
        self.cache[place[:4]] = (copy, size, first, n, -1)  # (copies on this face are its own)
        self.partial = True
        return copy

    def derive_region(self, symbol: str, x: float, y: float, w: float, h: float, floor: int, depth: int,
                      chain: tuple[str, ...]) -> Region:
        self.count += 1
        rule = self.table.get(symbol)
        if depth > MAX_DEPTH:
            raise RulesetError(f"derivation of rule {symbol} went deeper than {MAX_DEPTH} levels", plugin=PLUGIN_ID,
                               where=rule.loc if rule else self.grammar.source,
                               hint="a rule probably splits into itself without its region getting smaller")
        if self.count > MAX_REGIONS:
            raise self.too_large(f"derivation of rule {symbol} went beyond {MAX_REGIONS} regions",
                                 rule.loc if rule else self.grammar.source)
        if rule is None:  # the built-in Corner strip
            self.note(depth, symbol, x, y, w, h, "corner strip, wall")
            return self.leaf(Region.fast(x, y, w, h, symbol, label="wall"))
        body = rule.body
        if isinstance(body, (Case, Choice)):
            body, how = self.select(rule, w, h, floor)
            if self.tracing:
                self.note(depth, symbol, x, y, w, h, how)
        elif self.tracing:
            self.note(depth, symbol, x, y, w, h, _describe(body))
        if isinstance(body, Terminal):
            return self.leaf(Region.stamped(self.template(symbol, body), x, y, w, h))
        if isinstance(body, Rename):
            if body.symbol in chain or body.symbol == symbol:
                cycle = " --> ".join((*chain, symbol, body.symbol))
                raise RulesetError(f"rename cycle {cycle}", where=rule.loc, plugin=PLUGIN_ID,
                                   hint="one of these rules must split or end in a terminal")
            child = self.region(body.symbol, x, y, w, h, floor, depth + 1, (*chain, symbol))
            return Region.fast(x, y, w, h, symbol, children=(child,))
        children = self.children(body, x, y, w, h, floor, depth + 1, rule)
        if not children:  # (a grid whose regions are all empty: an unlabelled terminal, as the tree reads it)
            return self.leaf(Region.fast(x, y, w, h, symbol))
        return Region.fast(x, y, w, h, symbol, children=tuple(children))

    def too_large(self, message: str, where: Any) -> FaceTooLarge:
        """The :class:`FaceTooLarge` of this face: ``message``, the face's size, what to check."""
        r = self.request
        return FaceTooLarge(f"{message} on a face of {r.width:g} x {r.height:g} m: too large for the grammar's sizes",
                            plugin=PLUGIN_ID, where=where,
                            hint="check the footprint's size and units (a facade kilometres long), or make the "
                                 "repeated sizes larger (tiles of a few centimetres)")

    def leaf(self, region: Region) -> Region:
        """``region``, a terminal, noted in :attr:`leaves` and :attr:`sources`."""
        self.leaves.append(region)
        self.source_of.append(len(self.sources))
        self.sources.append(region)
        return region

    def terminal(self, symbol: str, fields_: dict[str, Any], x: float, y: float, w: float, h: float,
                 floor: int, depth: int) -> Region:
        """``region(symbol, ...)`` for a reusable ``symbol`` whose rule is a plain terminal with the region fields
        ``fields_``: the same regions, keys and counts without the general path's dispatch."""
        count = self.count
        if depth > MAX_DEPTH or count >= MAX_REGIONS:  # (the general path raises the error)
            return self.region(symbol, x, y, w, h, floor, depth, ())
        self.count = count + 1
        key = (symbol, w, h, -1)  # (a plain terminal reads no floor)
        done = self.cache.get(key)
        region = _new(Region)
        if done is not None:  # (:func:`_moved` of a terminal)
            original = done[0]
            copied = original.__dict__.copy()
            copied["x"] = original.x + (x - original.x)
            copied["y"] = original.y + (y - original.y)
            _set(region, "__dict__", copied)
            self.source_of.append(done[4])
        else:
            copied = fields_.copy()
            copied["x"] = x
            copied["y"] = y
            copied["w"] = w
            copied["h"] = h
            copied["key"] = hash((self.scope if symbol in self.shared else self.request.seed, key))
            _set(region, "__dict__", copied)
            self.cache[key] = (region, 1, len(self.leaves) + self.copied, 1, len(self.sources))
            self.source_of.append(len(self.sources))
            self.sources.append(region)
        self.leaves.append(region)
        return region

    def template(self, symbol: str, body: Terminal) -> dict[str, Any]:
        """The fields of ``symbol``'s terminal regions (:meth:`Region.template`), made once per symbol and body."""
        made = self.templates.get(symbol)
        if made is None or made[0] is not body:
            made = self.templates[symbol] = (body, Region.template(
                symbol, label=body.label, depth=body.depth, material=body.material, asset=self.asset(body.asset)))
        return made[1]

    def note(self, depth: int, symbol: str, x: float, y: float, w: float, h: float, how: str) -> None:
        if self.tracing:
            self.trace.append(f"{'  ' * depth}{symbol} {w:.3f} x {h:.3f} at ({x:.3f}, {y:.3f}): {how}")

    def asset(self, path: str | None) -> str | None:
        if path is None or self.base is None or os.path.isabs(path):
            return path
        return os.path.normpath(self.base / path)

    # ---- choosing the body ----------------------------------------------------------------------------------
    def select(self, rule: Rule, w: float, h: float, floor: int) -> tuple[SimpleBody, str]:
        body = rule.body
        if isinstance(body, Case):
            env = {**self.face, "width": w, "height": h, "floor": floor}
            holds = (k for k, (cond, _) in enumerate(body.branches)
                     if evaluate(cond, env, self.attributes, rule.symbol))
            k = next(holds, len(body.branches))
            later = len(body.branches) - k - 1 + (body.otherwise is not None)  # at most this many alternatives
            for _ in range(self.alternative(rule.symbol, w, h, 1 + max(later, 0)) if later > 0 else 0):
                k = next(holds, len(body.branches))  # the next holding branch, else ``else``
            if k < len(body.branches):
                branch = body.branches[k][1]
                return branch, (f"case {k + 1}: {_describe(branch)}" if self.tracing else "")
            if body.otherwise is not None:
                return body.otherwise, (f"else: {_describe(body.otherwise)}" if self.tracing else "")
            return _WALL, "no case holds and no else: wall"
        if isinstance(body, Choice):
            n = len(body.alternatives)
            drawn = self.draw(rule.symbol, body)
            # alternative 0: the drawn one; j > 0: alternative j - 1 (else last) for every region of the point
            count = 1 + n + (body.otherwise is not None)
            j = (self.alternative(rule.symbol, w, h, count) if body.each else
                 self.alternative(rule.symbol, 0.0, 0.0, count))  # drawn once per face: one choice point
            k = drawn if j == 0 else j - 1
            chosen = body.alternatives[k][1] if k < n else body.otherwise
            assert chosen is not None
            if not self.tracing:
                return chosen, ""
            label = f"{body.alternatives[k][0]:g}%" if k < n else "else"
            return chosen, f"{'each ' if body.each else ''}choice {label}: {_describe(chosen)}"
        return body, (_describe(body) if self.tracing else "")  # type: ignore[return-value]

    def alternative(self, symbol: str, w: float, h: float, count: int) -> int:
        """Which of ``count`` alternatives the choice point of ``symbol`` on a ``w x h`` region takes."""
        if count < 2:
            return 0
        key = point_key(symbol, w, h)
        self.points[key] = count
        return min(self.alternatives.get(key, 0), count - 1)

    def draw(self, symbol: str, body: Choice) -> int:
        """Index of the alternative (len(alternatives) = else): once per symbol per face, or per region; drawn from
        the building's stream of the symbol, so every face of a building draws the same sequence (faces agree: the
        same style, the same floors with balconies)."""
        if not body.each and symbol in self.once:
            return self.once[symbol]
        stream = self.streams.get(symbol)
        if stream is None:
            stream = self.streams[symbol] = self.request.style_rng(PLUGIN_ID, symbol)
        u = 100.0 * float(stream.random())
        total = 0.0
        k = 0 if body.otherwise is None else len(body.alternatives)
        for i, (percent, _) in enumerate(body.alternatives):
            total += percent
            if u < total:
                k = i
                break
        if not body.each:
            self.once[symbol] = k
        return k

    # ---- operations -----------------------------------------------------------------------------------------
    def children(self, body: SimpleBody, x: float, y: float, w: float, h: float, floor: int,
                 depth: int, rule: Rule) -> list[Region]:
        if isinstance(body, Grid):
            return self.grid(body, x, y, w, h, floor, depth)
        if isinstance(body, Floors):
            return self.floors(body, x, y, w, h, depth)
        axis = body.axis  # type: ignore[union-attr]
        length = w if axis == "x" else h
        start = x if axis == "x" else y
        if isinstance(body, Split):
            items: Sequence[Item] = body.items
            extents = resolve(body.sizes, length, body.totals)
        elif isinstance(body, Repeat):
            tile = preferred_length(body.sizes)
            self.check_tiles(rule, tile, length)
            n = repeat_count(tile, length)
            n -= self.alternative(rule.symbol, w, h, n)
            extents = resolve(body.sizes, length / n, body.totals) * n
            items = body.items * n
        elif isinstance(body, RepeatABA):
            self.check_tiles(rule, preferred_length([body.a.size, body.b.size]), length)
            n = aba_count(preferred_length([body.a.size]), preferred_length([body.b.size]), length)
            n -= self.alternative(rule.symbol, w, h, max(n, 1))  # (never down to one A stretched over the region)
            items = [body.a, body.b] * n + [body.a]
            extents = resolve([i.size for i in items], length)
        else:
            assert isinstance(body, SymSplit)
            items = body.mirrored.items
            extents = resolve(body.mirrored.sizes, length, body.mirrored.totals)
        # (place(extents, start, length), inlined: the same arithmetic; ``if e < 0.0: e = 0.0`` is ``max(e, 0.0)``
        # bit for bit, -0.0 and NaN included)
        out = []
        region = self.region
        terminal = self.terminal
        terminals = self.terminals.get
        end = start + length
        pos = start
        last = len(extents) - 1
        for i, extent in enumerate(extents):
            if extent < 0.0:
                extent = 0.0
            if i == last or pos + extent > end:
                extent = end - pos
                if extent < 0.0:
                    extent = 0.0
            if extent > 0:
                symbol = items[i].symbol
                fields_ = terminals(symbol)
                if fields_ is not None:
                    if axis == "x":
                        out.append(terminal(symbol, fields_, pos, y, extent, h, floor, depth))
                    else:
                        out.append(terminal(symbol, fields_, x, pos, w, extent, floor, depth))
                elif axis == "x":
                    out.append(region(symbol, pos, y, extent, h, floor, depth, ()))
                else:
                    out.append(region(symbol, x, pos, w, extent, floor, depth, ()))
            pos = pos + extent
        return out

    def check_tiles(self, rule: Rule, tile: float, length: float) -> None:
        """Refuse a repeat whose tiles are so small that their count alone passes :data:`MAX_REGIONS`, before any is
        made."""
        if not length / tile <= MAX_REGIONS:
            raise self.too_large(f"repeat of rule {rule.symbol}: tiles of {tile:g} m would fill {length:g} m more "
                                 f"than {MAX_REGIONS} times", rule.loc)

    def grid(self, body: Grid, x: float, y: float, w: float, h: float, floor: int, depth: int) -> list[Region]:
        cols, rows = body.totals
        xs = [pos for pos, _ in place(resolve(body.cols, w, cols), x, w)] + [x + w]
        ys = [pos for pos, _ in place(resolve(body.rows, h, rows), y, h)] + [y + h]
        out = []
        for symbol, c0, r0, c1, r1 in body.regions:
            rw, rh = xs[c1] - xs[c0], ys[r1] - ys[r0]
            if rw > 0 and rh > 0:
                fields_ = self.terminals.get(symbol)
                if fields_ is not None:
                    out.append(self.terminal(symbol, fields_, xs[c0], ys[r0], rw, rh, floor, depth))
                else:
                    out.append(self.region(symbol, xs[c0], ys[r0], rw, rh, floor, depth, ()))
        return out

    def floors(self, body: Floors, x: float, y: float, w: float, h: float, depth: int) -> list[Region]:
        lines = self.request.floor_lines
        count = max(len(lines) - 1, 1)
        top = y + h
        cuts = [y, *(line for line in lines[1:-1] if y < line < top), top]
        face_w = float(self.request.width)
        cl, cr = self.corners
        left = min(max(cl - x, 0.0), w)
        right = min(max(x + w - (face_w - cr), 0.0), w - left)
        corner = self.terminals.get("Corner")
        out = []
        for lo, hi in zip(cuts[:-1], cuts[1:]):
            if hi - lo <= 0:
                continue
            k = min(max(bisect_right(lines, lo) - 1, 0), count - 1)
            symbol = next(i.symbol for i in body.items
                          if i.floor is None or i.floor == k or (i.floor < 0 and i.floor + count == k))
            if left > 0:
                out.append(self.region("Corner", x, lo, left, hi - lo, k, depth, ()) if corner is None else
                           self.terminal("Corner", corner, x, lo, left, hi - lo, k, depth))
            middle = (x + w - right if right > 0 else x + w) - (x + left)
            if middle > 0:
                out.append(self.region(symbol, x + left, lo, middle, hi - lo, k, depth, ()))
            if right > 0:
                out.append(self.region("Corner", x + w - right, lo, right, hi - lo, k, depth, ()) if corner is None
                           else self.terminal("Corner", corner, x + w - right, lo, right, hi - lo, k, depth))
        return out


_new = object.__new__
_set = object.__setattr__
_XYWH = operator.attrgetter("x", "y", "w", "h")


def _leaf_arrays(leaves: list[Region], sources: list[Region], source_of: list[int],
                 copies: list[tuple[int, Any, int | None, float, float]]
                 ) -> tuple[np.ndarray, tuple[tuple[Region, ...], np.ndarray]]:
    """:attr:`FacadeLayout.leaf_rects` and :attr:`FacadeLayout.leaf_sources` of a derivation: its own terminals
    ``leaves`` (with their distinct ``sources`` and the index of each one's source) and the terminals of its moved
    ``copies`` (:attr:`_Derivation.copies`: of this face's subtrees or of another face's), in tree order. A copied
    terminal is its original's ``x + dx``, ``y + dy`` (the same float additions as :meth:`Region.moved`)."""
    rows: list[Sequence[float]] = []
    source: list[int] = []
    done = 0
    for before, first, n, dx, dy in copies:
        if before > done:
            rows += map(_XYWH, leaves[done:before])
            source += source_of[done:before]
            done = before
        if n is None:  # (a copy of another face's subtree, in place: its rows and source indices)
            block, of_block = first
            rows += block
            source += of_block
            continue
        end = first + n
        rows += [(x + dx, y + dy, w, h) for x, y, w, h in rows[first:end]]
        source += source[first:end]
    rows += map(_XYWH, leaves[done:])
    source += source_of[done:]
    rects = np.fromiter(itertools.chain.from_iterable(rows), float, 4 * len(rows)).reshape(-1, 4)
    index = np.fromiter(source, np.intp, len(source))
    rects.flags.writeable = index.flags.writeable = False
    return rects, (tuple(sources), index)


def _terminal_fields(grammar: Grammar, asset: Callable[[str | None], str | None]) -> dict[str, dict[str, Any]]:
    """Per reusable symbol whose rule is a plain terminal, its regions' fields (:meth:`Region.template`), made
    once per grammar (``asset`` resolves the grammar's asset paths)."""
    made = _TERMINALS.get(id(grammar))
    if made is None or made[0] is not grammar:
        if len(_TERMINALS) > 256:
            _TERMINALS.clear()
        fields_ = {rule.symbol: Region.template(rule.symbol, label=rule.body.label, depth=rule.body.depth,
                                                material=rule.body.material, asset=asset(rule.body.asset))
                   for rule in grammar.table.values()
                   if isinstance(rule.body, Terminal) and rule.symbol in grammar.translation_invariant}
        if "Corner" not in grammar.table:  # (the built-in corner strip: wall)
            fields_["Corner"] = Region.template("Corner", label="wall")
        made = _TERMINALS[id(grammar)] = (grammar, fields_)
    return made[1]


#: ``id(grammar) -> (grammar, fields)`` of :func:`_terminal_fields`.
_TERMINALS: dict[int, tuple[Grammar, dict[str, dict[str, Any]]]] = {}


@functools.lru_cache(maxsize=256)
def _folder(source: str) -> Path | None:
    """The folder of a grammar file, against which its asset paths resolve (None for a grammar from text)."""
    return None if source.startswith("<") else Path(source).parent


def _corner_widths(request: FacadeRequest) -> tuple[float, float]:
    """The request's corner strips; if they leave no room, scaled to half the face (documented fallback)."""
    left, right = (max(float(c), 0.0) for c in request.corner_widths)
    if left + right >= request.width:
        scale = 0.5 * request.width / (left + right)
        return left * scale, right * scale
    return left, right


def _describe(body: SimpleBody) -> str:
    if isinstance(body, Terminal):
        return f"terminal {body.label or 'none'}"
    if isinstance(body, Rename):
        return f"rename to {body.symbol}"
    if isinstance(body, Grid):
        return f"grid {len(body.cols)} x {len(body.rows)}"
    if isinstance(body, Floors):
        return "floors"
    name = {Split: "split", Repeat: "repeat", RepeatABA: "repeatABA", SymSplit: "symsplit"}[type(body)]
    return f"{name}({body.axis})"
