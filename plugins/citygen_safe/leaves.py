"""Facade leaf shapes (dang2014 §3): the terminal rectangles an edit works on, with where each came from.

A :class:`Leaf` is a terminal region placed at ``x, y, w, h`` plus ``origin``, the index of the input terminal it
copies (topological jumps duplicate and stretch leaves; the origin tells which input shape a copy stands for).
Every structure is written for the width problem; :func:`transpose` swaps the axes so the same code solves the
height problem (the paper's "interchanging width and height and x and y-splits").
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from citygen.layout import FacadeLayout, Region

EPS = 1e-6


@dataclass(frozen=True)
class Leaf:
    """A facade leaf shape: a rectangle, the terminal region it shows and the input terminal it copies."""

    x: float
    y: float
    w: float
    h: float
    region: Region
    origin: int

    @classmethod
    def fast(cls, x: float, y: float, w: float, h: float, region: Region, origin: int) -> Leaf:
        """``Leaf(x, y, w, h, region, origin)`` without the frozen dataclass's per-field ``object.__setattr__``
        (equal in every respect; as :meth:`citygen.layout.Region.fast`), for the thousands of leaves an edit
        places and copies."""
        leaf = object.__new__(cls)
        fields_ = leaf.__dict__
        fields_["x"] = x
        fields_["y"] = y
        fields_["w"] = w
        fields_["h"] = h
        fields_["region"] = region
        fields_["origin"] = origin
        return leaf

    @property
    def right(self) -> float:
        return self.x + self.w

    @property
    def top(self) -> float:
        return self.y + self.h

    @property
    def label(self) -> str | None:
        return self.region.label


@dataclass(frozen=True)
class Facade:
    """An editable facade: ``width x height`` partitioned by ``leaves``; ``transposed`` when x and y are swapped."""

    width: float
    height: float
    leaves: tuple[Leaf, ...]
    transposed: bool = False


def facade_from_layout(layout: FacadeLayout) -> Facade:
    leaves = tuple(Leaf(r.x, r.y, r.w, r.h, r, i) for i, r in enumerate(layout.leaves))
    return Facade(layout.width, layout.height, leaves)


def transpose(facade: Facade) -> Facade:
    """The same facade with x and y swapped (an involution)."""
    leaves = tuple(Leaf.fast(f.y, f.x, f.h, f.w, f.region, f.origin) for f in facade.leaves)
    return Facade(facade.height, facade.width, leaves, not facade.transposed)


def upright(facade: Facade) -> Facade:
    return transpose(facade) if facade.transposed else facade


def leaf_region(leaf: Leaf) -> Region:
    """The terminal region of a (upright) leaf at its current place."""
    return replace(leaf.region, x=leaf.x, y=leaf.y, w=leaf.w, h=leaf.h, children=())
