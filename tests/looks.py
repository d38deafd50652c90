"""Helpers of the visual audit's tests (docs/performance.md, "Visual audit"): a shipped ruleset generated as a
user previews it, and what an art director looks at -- the openings of each storey."""
from __future__ import annotations

from pathlib import Path

from citygen.layout import FacadeLayout, Region
from citygen.registry import default_registry
from citygen.request import FacadeRequest

RULESETS = Path(__file__).resolve().parents[1] / "rulesets"


def generated(name: str, width: float, height: float, storey: float, ground: float | None = None,
              entrance: bool = True, seed: int = 0) -> tuple[FacadeLayout, FacadeRequest]:
    """``citygen facade rulesets/NAME --size W H --floor-height S [--ground-height G] --seed N``."""
    registry = default_registry()
    kind = registry.kind_for_path(RULESETS / name)
    request = FacadeRequest.preview(width, height, floor_height=storey, ground_height=ground, entrance=entrance,
                                    seed=seed)
    return kind.generate(kind.load(RULESETS / name), request), request


def storeys(layout: FacadeLayout, request: FacadeRequest, label: str = "window") -> list[list[Region]]:
    """The terminals of ``label`` standing in each storey (by their foot), bottom up."""
    lines = request.floor_lines
    rows: list[list[Region]] = [[] for _ in lines[:-1]]
    for r in layout.terminals():
        if r.label == label:
            k = max(i for i, y in enumerate(lines[:-1]) if r.y >= y - 1e-6)
            rows[k].append(r)
    return rows
