"""Size resolution: absolute, relative and floating sizes of a split turned into exact extents.

The rules are normative in docs/grammar.md ("Sizes"). Extents are placed so that every item starts where the
previous ends and the last ends exactly at the parent's edge; zero-size items are dropped by the caller.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # (the AST works out its rules' size sums with :func:`totals`)
    from citygen_split.ast import Size


def totals(sizes: Sequence[Size]) -> tuple[float, float, float]:
    """The ``(absolute, floating, relative)`` sums of ``sizes`` that :func:`resolve` splits ``length`` by (a rule
    whose sizes never change computes them once: see :attr:`citygen_split.ast.Split.totals`)."""
    return (sum(s.value for s in sizes if s.kind == "abs"), sum(s.value for s in sizes if s.kind == "float"),
            sum(s.value for s in sizes if s.kind == "rel"))


def resolve(sizes: Sequence[Size], length: float, sums: tuple[float, float, float] | None = None) -> list[float]:
    """Extents of ``sizes`` filling ``length`` (never negative); ``sums``: ``totals(sizes)`` when known."""
    fixed_abs, floating, relative = sums or totals(sizes)
    if relative > 0:
        fixed = fixed_abs + floating
        if fixed <= length:
            share = (length - fixed) / relative
            return [s.value * share if s.kind == "rel" else s.value for s in sizes]
        scale = length / fixed
        return [0.0 if s.kind == "rel" else s.value * scale for s in sizes]
    if floating > 0 and fixed_abs <= length:
        share = (length - fixed_abs) / floating
        return [s.value * share if s.kind == "float" else s.value for s in sizes]
    scale = length / fixed_abs if fixed_abs > 0 else 0.0
    return [s.value * scale if s.kind == "abs" else 0.0 for s in sizes]


def place(extents: Sequence[float], start: float, length: float) -> list[tuple[float, float]]:
    """``(offset, extent)`` per item, one after the other from ``start``; the last item ends exactly at
    ``start + length``. Other items keep their extent bit for bit (so equal tiles stay equal) unless they would
    pass the end, where they are clipped."""
    end = start + length
    placed = []
    pos = start
    last = len(extents) - 1
    for i, extent in enumerate(extents):
        extent = max(extent, 0.0)
        if i == last or pos + extent > end:
            extent = max(end - pos, 0.0)
        placed.append((pos, extent))
        pos = pos + extent
    return placed


def preferred_length(sizes: Sequence[Size]) -> float:
    """The length a tile of ``sizes`` would like: every size in metres (relative weights count as metres)."""
    return sum(s.value for s in sizes)


def repeat_count(tile: float, length: float) -> int:
    """``n = max(1, round(L / T))`` tiles for a repeat."""
    return max(1, round(length / tile))


def aba_count(a: float, b: float, length: float) -> int:
    """Number of B items of ``repeatABA``: ``max(0, round((L - a) / (a + b)))``."""
    return max(0, round((length - a) / (a + b)))
