from __future__ import annotations

from pathlib import Path

import pytest

from citygen.layout import FacadeLayout, Region
from citygen_safe.leaves import facade_from_layout

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def cmp_facade():
    return facade_from_layout(FacadeLayout.loads((ROOT / "rulesets" / "cmp_b0035.layout.json").read_text()))


def layout_of(width: float, height: float, rects: list[tuple[float, float, float, float, str]]) -> FacadeLayout:
    """A flat layout from ``(x, y, w, h, label)`` rectangles (symbol = label)."""
    leaves = tuple(Region(x, y, w, h, label, label) for x, y, w, h, label in rects)
    return FacadeLayout(width, height, Region(0, 0, width, height, "F", children=leaves))


def regular(cols: int, rows: int, bay: float = 3.0, floor: float = 3.0, win: float = 1.2) -> FacadeLayout:
    """``rows`` floors of ``cols`` bays, each bay wall | window | wall with wall above and below the window."""
    rects = []
    side = (bay - win) / 2
    for r in range(rows):
        y = r * floor
        for c in range(cols):
            x = c * bay
            rects += [(x, y, side, floor, "wall"), (x + bay - side, y, side, floor, "wall"),
                      (x + side, y, win, 0.9, "wall"), (x + side, y + 0.9, win, 1.5, "window"),
                      (x + side, y + 2.4, win, floor - 2.4, "wall")]
    return layout_of(cols * bay, rows * floor, rects)
