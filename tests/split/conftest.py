"""Shared helpers for the split-grammar tests."""
from __future__ import annotations

from pathlib import Path

import pytest

from citygen.errors import ParseError
from citygen.request import FacadeRequest
from citygen_split import parse

REPO = Path(__file__).resolve().parents[2]
RULESETS = sorted((REPO / "rulesets").glob("*.grammar"))

TERMINALS = """
Wall --> terminal(wall)
Wall1 --> terminal(wall)
Wall2 --> terminal(wall, material: brick)
Window --> terminal(window, depth: -0.25)
Window1 --> terminal(window, depth: -0.25)
Window2 --> terminal(window, depth: -0.2)
Door --> terminal(door, depth: -0.3)
A --> terminal(a)
B --> terminal(b)
C --> terminal(c)
"""


def grammar(text: str):
    """Parse ``text`` followed by the common terminals."""
    return parse(text + TERMINALS, "test.grammar")


def request(width: float, height: float, lines: tuple[float, ...] | None = None, **kw) -> FacadeRequest:
    return FacadeRequest(width=width, height=height, floor_lines=lines or (0.0, height), **kw)


def parse_error(text: str) -> ParseError:
    with pytest.raises(ParseError) as info:
        parse(text, "bad.grammar")
    return info.value


def leaves(layout) -> list[tuple[str, float, float, float, float]]:
    """Terminals as (symbol, x, y, w, h) rounded to 1e-9."""
    return [(r.symbol, *(round(v, 9) for v in (r.x, r.y, r.w, r.h))) for r in layout.terminals()]
