"""The layout model of bao2013 §4-§5: a hierarchical segmentation plus the user's constraints.

Symbols live in one namespace (as in the paper's Fig. 7): a symbol names one region of the input segmentation,
and regions marked identical share it (same size, same decomposition). A composite symbol is split along ``x``
(children left to right) or ``y`` (children bottom to top) into its input arrangement of child symbols.

Sequence items are sets of child symbols; the tokens :data:`BEGIN` (⊢) and :data:`END` (⊣) stand for the
region's beginning and end.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

BEGIN = "^"
END = "$"
ANCHORS = {"min": 0.0, "center": 0.5, "max": 1.0}

Item = frozenset  # a set of symbols (or the singleton {BEGIN} / {END})


@dataclass(frozen=True)
class Symbol:
    """One region of the input segmentation: terminal (``split is None``) or composite."""

    name: str
    extent: tuple[float, float]  # input width, height
    label: str | None = None
    depth: float = 0.0
    material: str | None = None
    asset: str | None = None
    split: str | None = None  # "x" or "y"
    children: tuple[str, ...] = ()

    @property
    def is_terminal(self) -> bool:
        return self.split is None


@dataclass(frozen=True)
class SizeRange:
    """Region-size constraint along one axis, with a truncated-Gaussian initial-size distribution."""

    lo: float
    hi: float
    mean: float
    sigma: float


@dataclass(frozen=True)
class Frequency:
    """``lo <= count(members) <= hi`` within one composite; ``relative`` scales bounds by size / input size."""

    members: frozenset[str]
    lo: float
    hi: float
    relative: bool = False
    text: str = ""
    line: int = 0


@dataclass(frozen=True)
class InstancePolicy:
    """Instances of a symbol within one parent: replicas (default) or independent, ``lo..hi`` distinct ones."""

    lo: float = 1
    hi: float = 1
    relative: bool = False


@dataclass(frozen=True)
class Pattern:
    """A contextual occurrence pattern: ``before`` + ``body`` + ``after`` must match consecutive elements."""

    body: tuple[Item, ...]
    before: tuple[Item, ...] = ()
    after: tuple[Item, ...] = ()

    @property
    def items(self) -> tuple[Item, ...]:
        return self.before + self.body + self.after


@dataclass(frozen=True)
class Alignment:
    """Regions matching ``a`` and ``b`` that overlap along the axis align at their anchors (0 min .. 1 max)."""

    a: Pattern
    a_anchor: float
    b: Pattern
    b_anchor: float
    within: str | None = None
    text: str = ""
    line: int = 0


@dataclass(frozen=True)
class SameSize:
    """All occurrences of sequences ``a`` and ``b`` have the same extent along their arrangement axis."""

    a: Pattern
    b: Pattern
    within: str | None = None
    across: bool = False  # across the faces of a building (§9.1)
    text: str = ""
    line: int = 0


@dataclass(frozen=True)
class CompositeRules:
    """Constraints of one composite symbol's arrangement."""

    sequences: tuple[tuple[Item, ...], ...]
    frequencies: tuple[Frequency, ...] = ()
    instances: Mapping[str, InstancePolicy] = field(default_factory=dict)
    symmetric: bool = False


@dataclass(frozen=True)
class Model:
    """A relayout model: segmentation, per-axis size ranges, per-composite rules and global constraints."""

    name: str
    root: str
    symbols: Mapping[str, Symbol]
    sizes: Mapping[tuple[str, str], SizeRange]
    rules: Mapping[str, CompositeRules]
    alignments: tuple[Alignment, ...] = ()
    samesizes: tuple[SameSize, ...] = ()
    mirror: Mapping[str, str] = field(default_factory=dict)
    source: str = "<model>"
    #: least extent of a terminal along an axis, whichever axis its parent splits (``(symbol, axis)``; e.g. the
    #: plausible minimum of an opening of a model built from a layout); terminals not listed have none
    terminal_min: Mapping[tuple[str, str], float] = field(default_factory=dict)

    @property
    def width(self) -> float:
        return self.symbols[self.root].extent[0]

    @property
    def height(self) -> float:
        return self.symbols[self.root].extent[1]

    def terminal_count(self) -> int:
        """Terminal regions of the input segmentation."""
        memo: dict[str, int] = {}

        def count(name: str) -> int:
            if name not in memo:
                sym = self.symbols[name]
                memo[name] = 1 if sym.is_terminal else sum(count(c) for c in sym.children)
            return memo[name]
        return count(self.root)

    def mirrored(self, name: str) -> str:
        return self.mirror.get(name, name)
