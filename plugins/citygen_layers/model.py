"""The layer-stack data model (§3, Fig. 2): symbols, counters, patterns, shapes, layers, ruleset."""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from citygen.errors import SourceLocation

#: Directions of the factorised layout (§3.2 "Factorization of Dimensions").
DIRECTIONS = ("x", "y")


@dataclass(frozen=True)
class Symbol:
    """An abstract 1D element. ``size is None`` makes it *unsized* (§3.3): the solver chooses its size. ``least``
    and ``most`` (``min=``, ``max=``, beyond the paper) bound the size of its visible letters."""

    name: str
    size: float | None = None
    least: float | None = None
    most: float | None = None
    label: str | None = None
    opaque: bool = False
    transparent: bool = False
    attached: bool = False
    unoccludable: bool = False
    depth: float | None = None
    material: str | None = None
    asset: str | None = None


@dataclass(frozen=True)
class Counter:
    """A global counting parameter ``k`` of ``X^k`` (§3.2); ``lo == hi`` when bound. ``hi is None``: unbounded."""

    name: str
    lo: int = 0
    hi: int | None = None

    @property
    def bound(self) -> bool:
        return self.hi is not None and self.lo == self.hi


# --- pattern syntax tree (§3.2) -----------------------------------------------------------------------------

@dataclass(frozen=True)
class Sym:
    name: str
    where: SourceLocation | None = field(default=None, compare=False)


@dataclass(frozen=True)
class Seq:
    items: tuple[Node, ...]


@dataclass(frozen=True)
class Alt:
    options: tuple[Node, ...]


@dataclass(frozen=True)
class Rep:
    """``body^k``: ``k`` a literal or a counter name; ``negate`` reflects the base (negative ``k``)."""

    body: Node
    count: int | str
    negate: bool = False
    where: SourceLocation | None = field(default=None, compare=False)


Node = Sym | Seq | Alt | Rep


@dataclass(frozen=True)
class Pattern:
    """A pattern; with ``substitutions`` it is a substituted pattern (§3.3): control pattern + content patterns."""

    name: str
    control: Node
    substitutions: Mapping[str, Node] = field(default_factory=dict)
    where: SourceLocation | None = field(default=None, compare=False)

    @property
    def substituted(self) -> bool:
        return bool(self.substitutions)


@dataclass(frozen=True)
class ShapeSpec:
    """Attributes of the shape of symbol pair ``(h, v)``, optionally only in one layer or pattern (§3.5)."""

    h: str
    v: str
    layer: str | None = None
    pattern: str | None = None
    label: str | None = None
    depth: float | None = None
    material: str | None = None
    asset: str | None = None
    visible: bool | None = None


@dataclass(frozen=True)
class Layer:
    """A rectilinear grid of shapes: the outer product of pattern ``x`` and pattern ``y`` (§3.1).

    ``mask`` lists the visible symbols (a shape is visible when either of its symbols is); ``None`` shows all.
    ``groups`` are the alignment groups per direction (§3.5).
    """

    name: str
    x: str
    y: str
    depth: float
    mask: frozenset[str] | None = None
    groups: tuple[str, str] = ("main", "main")


@dataclass(frozen=True)
class SolveOptions:
    """Tolerance and budget of the solver (§5, and the §6.3 limitation removed by a budget)."""

    tolerance: float | None = None     # initial mu in metres; None: 5 % of the canvas side
    growth: float = 2.0                # mu is multiplied by this until a solution is found
    rounds: int = 8                    # mu rounds before the best-effort result is taken
    expansions: int = 3000             # ADN node expansions over the whole solve (deterministic)
    time: float = 20.0                 # seconds of CPU time, a safety net only (far above the expansion budget)
    candidates: int = 48               # candidates tried per mu round
    samples: int = 3                   # sizes sampled per unsized symbol (§5.1)
    prealign: bool = False             # restrict alignment to prealigned control columns (§5.2 heuristic)


@dataclass(frozen=True)
class Ruleset:
    """A parsed ``.layers`` file: an immutable stack (``layers[0]`` is the bottom layer)."""

    name: str
    canvas: tuple[float, float]
    symbols: Mapping[str, Symbol]
    counters: Mapping[str, Counter]
    patterns: Mapping[str, Pattern]
    layers: tuple[Layer, ...]
    shapes: tuple[ShapeSpec, ...] = ()
    floors: str | None = None
    storeys: frozenset[str] = frozenset()   # empty: every letter of the floor word is a storey
    options: SolveOptions = SolveOptions()
    source: str = "<string>"
    cut: bool = False       # occlusion cut: a shape partly covered by upper layers is cut to its uncovered pieces
    mirror: bool = False    # mirror building: each building takes the layout or its mirror image (its style seed)

    def layer(self, name: str) -> Layer:
        return next(layer for layer in self.layers if layer.name == name)
