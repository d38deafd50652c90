"""The split grammar's abstract syntax tree: immutable frozen dataclasses.

Source locations are kept for error messages but excluded from equality, so ``parse(format_grammar(g)) == g``.
Names follow wu2014 §3.1: a rule ``sym -> op alpha`` maps a non-terminal symbol to an operation and a sequence
of successor symbols.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Literal, Union

from citygen.errors import SourceLocation
from citygen_split.gridspans import merge_cells
from citygen_split.sizes import totals as _totals

Axis = Literal["x", "y"]
SizeKind = Literal["abs", "rel", "float"]


@dataclass(frozen=True)
class Size:
    """A split size: ``abs`` metres, ``rel`` weight (``'w``) or ``float`` approximate metres (``~m``)."""

    kind: SizeKind
    value: float


@dataclass(frozen=True)
class Item:
    """One successor of a split: its size and symbol."""

    size: Size
    symbol: str
    loc: SourceLocation | None = field(default=None, compare=False, repr=False)


# ---- expressions -------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Const:
    value: float | bool | str


@dataclass(frozen=True)
class Var:
    name: str
    loc: SourceLocation | None = field(default=None, compare=False, repr=False)


@dataclass(frozen=True)
class Attr:
    """``attr("key")``: a footprint attribute as a string ("" when missing)."""

    key: str


@dataclass(frozen=True)
class Unary:
    op: Literal["-", "not"]
    operand: Expr


@dataclass(frozen=True)
class Binary:
    op: str
    left: Expr
    right: Expr
    loc: SourceLocation | None = field(default=None, compare=False, repr=False)  # of the operator


Expr = Union[Const, Var, Attr, Unary, Binary]


# ---- rule bodies --------------------------------------------------------------------------------------------

class _Sized:
    """The sizes of a split's items and their sums (:func:`citygen_split.sizes.totals`), worked out once per rule
    instead of once per region derived."""

    items: tuple[Item, ...]

    @cached_property
    def sizes(self) -> tuple[Size, ...]:
        return tuple(i.size for i in self.items)

    @cached_property
    def totals(self) -> tuple[float, float, float]:
        return _totals(self.sizes)


@dataclass(frozen=True)
class Split(_Sized):
    axis: Axis
    items: tuple[Item, ...]


@dataclass(frozen=True)
class Repeat(_Sized):
    axis: Axis
    items: tuple[Item, ...]


@dataclass(frozen=True)
class RepeatABA:
    """``A B A ... A`` with one more A than B (wu2014 §4.7)."""

    axis: Axis
    a: Item
    b: Item


@dataclass(frozen=True)
class SymSplit:
    """Mirrored split: items ``s1 .. sk`` give ``s1 .. sk-1 sk sk-1 .. s1`` (wu2014 §4.7)."""

    axis: Axis
    items: tuple[Item, ...]

    @cached_property
    def mirrored(self) -> Split:
        """The split this one stands for: ``s1 .. sk-1 sk sk-1 .. s1``."""
        return Split(self.axis, (*self.items, *reversed(self.items[:-1])))


@dataclass(frozen=True)
class Grid:
    """Split in x and y at once (wu2014 §4.7 gridsplit). ``cells`` are rows bottom first; ``<`` and ``v``
    continue the cell to the left / below."""

    cols: tuple[Size, ...]
    rows: tuple[Size, ...]
    cells: tuple[tuple[str, ...], ...]

    @cached_property
    def regions(self) -> tuple[tuple[str, int, int, int, int], ...]:
        """Merged regions as ``(symbol, col0, row0, col1, row1)`` (end-exclusive), bottom row first."""
        return merge_cells(self.cells)

    @cached_property
    def totals(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """The sums of the column sizes and of the row sizes (:func:`citygen_split.sizes.totals`)."""
        return _totals(self.cols), _totals(self.rows)


@dataclass(frozen=True)
class FloorItem:
    """A ``floors`` selector: floor index (negative counts from the top) or ``None`` for ``*``."""

    floor: int | None
    symbol: str
    loc: SourceLocation | None = field(default=None, compare=False, repr=False)


@dataclass(frozen=True)
class Floors:
    items: tuple[FloorItem, ...]


@dataclass(frozen=True)
class Terminal:
    label: str | None
    depth: float = 0.0
    material: str | None = None
    asset: str | None = None


@dataclass(frozen=True)
class Rename:
    symbol: str
    loc: SourceLocation | None = field(default=None, compare=False, repr=False)


SimpleBody = Union[Split, Repeat, RepeatABA, SymSplit, Grid, Floors, Terminal, Rename]


@dataclass(frozen=True)
class Case:
    """Conditional rule: first branch whose condition holds, else ``otherwise`` (may be None)."""

    branches: tuple[tuple[Expr, SimpleBody], ...]
    otherwise: SimpleBody | None


@dataclass(frozen=True)
class Choice:
    """Stochastic rule: ``(percent, body)`` alternatives; ``otherwise`` takes the rest. ``each`` draws per
    region instead of once per symbol per face."""

    alternatives: tuple[tuple[float, SimpleBody], ...]
    otherwise: SimpleBody | None
    each: bool = False


Body = Union[SimpleBody, Case, Choice]


@dataclass(frozen=True)
class Rule:
    symbol: str
    body: Body
    loc: SourceLocation | None = field(default=None, compare=False, repr=False)


@dataclass(frozen=True)
class Grammar:
    """A parsed grammar. ``start`` is the axiom; ``source`` the file it came from (not compared)."""

    rules: tuple[Rule, ...]
    start: str
    size: tuple[float, float] | None = None
    name: str | None = None
    source: str = field(default="<string>", compare=False)

    @cached_property
    def table(self) -> dict[str, Rule]:
        return {rule.symbol: rule for rule in self.rules}

    def rule(self, symbol: str) -> Rule:
        return self.table[symbol]

    @cached_property
    def translation_invariant(self) -> frozenset[str]:
        """Symbols whose derivation depends only on the region's size and floor (not on its position or on
        per-region draws): no ``floors`` and no ``each`` rule is reachable from them. The derivation derives their
        subtrees once per size (computed once per grammar, not per face)."""
        return self._closed({rule.symbol for rule in self.rules if _position_dependent(rule.body)})

    @cached_property
    def floor_invariant(self) -> frozenset[str]:
        """:attr:`translation_invariant` symbols from which no condition naming ``floor`` is reachable: their
        subtrees derive alike on every floor, so the derivation derives them once per size for the whole face."""
        return self._closed({rule.symbol for rule in self.rules if _reads(rule.body, "floor")}
                            | (self.table.keys() - self.translation_invariant))

    @cached_property
    def face_invariant(self) -> frozenset[str]:
        """:attr:`translation_invariant` symbols from which neither a ``choice`` (drawn once per face) nor a condition
        reading a face's variables (any but ``width``, ``height`` and ``floor``) is reachable: their subtrees derive
        alike on every face of a building (given the size and floor), so the subtrees' keys (module hints, see
        :class:`citygen.layout.Region`) are the same on every face."""
        return self._closed({rule.symbol for rule in self.rules if isinstance(rule.body, Choice) or (
            isinstance(rule.body, Case) and any(_variables(cond) - _REGION_VARIABLES for cond, _ in rule.body.branches))}
                            | (self.table.keys() - self.translation_invariant))

    def _closed(self, variant: set[str]) -> frozenset[str]:
        """The symbols from which no symbol of ``variant`` (nor an undefined one) is reachable."""
        graph = {rule.symbol: [s for s, _ in successors(rule.body)] for rule in self.rules}
        changed = True
        while changed:
            changed = False
            for symbol, succ in graph.items():
                if symbol not in variant and any(s in variant or s not in graph for s in succ):
                    variant.add(symbol)
                    changed = True
        return frozenset(graph) - variant


def successors(body: Body) -> list[tuple[str, SourceLocation | None]]:
    """Symbols a body refers to, with where they are written."""
    if isinstance(body, (Split, Repeat, SymSplit)):
        return [(i.symbol, i.loc) for i in body.items]
    if isinstance(body, RepeatABA):
        return [(body.a.symbol, body.a.loc), (body.b.symbol, body.b.loc)]
    if isinstance(body, Floors):
        return [(i.symbol, i.loc) for i in body.items]
    if isinstance(body, Grid):
        return [(s, None) for row in body.cells for s in row if s not in ("<", "v")]
    if isinstance(body, Rename):
        return [(body.symbol, body.loc)]
    if isinstance(body, Case):
        alts = [b for _, b in body.branches] + ([body.otherwise] if body.otherwise else [])
        return [s for b in alts for s in successors(b)]
    if isinstance(body, Choice):
        alts = [b for _, b in body.alternatives] + ([body.otherwise] if body.otherwise else [])
        return [s for b in alts for s in successors(b)]
    return []


def _position_dependent(body: Body) -> bool:
    if isinstance(body, Floors):
        return True
    if isinstance(body, Choice):
        return body.each or any(_position_dependent(b) for _, b in body.alternatives) or (
            body.otherwise is not None and _position_dependent(body.otherwise))
    if isinstance(body, Case):
        return any(_position_dependent(b) for _, b in body.branches) or (
            body.otherwise is not None and _position_dependent(body.otherwise))
    return False


#: The variables of a condition that are the region's own (the rest are the face's).
_REGION_VARIABLES = frozenset({"width", "height", "floor"})


def _reads(body: Body, name: str) -> bool:
    """Whether a condition of ``body`` (a ``case``) reads the variable ``name``."""
    return isinstance(body, Case) and any(name in _variables(cond) for cond, _ in body.branches)


def _variables(expr: Expr) -> set[str]:
    """The variables ``expr`` reads."""
    if isinstance(expr, Var):
        return {expr.name}
    if isinstance(expr, Unary):
        return _variables(expr.operand)
    if isinstance(expr, Binary):
        return _variables(expr.left) | _variables(expr.right)
    return set()
