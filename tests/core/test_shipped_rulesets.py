"""Every ruleset shipped in rulesets/, whatever its kind, meets the FacadeRequest contract on any face."""
from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from citygen.coordinator import plan_floor_lines
from citygen.layout import check_partition
from citygen.registry import default_registry
from citygen.request import FaceContext, FacadeRequest, check_request
from citygen.scene import Defaults

REPO = Path(__file__).resolve().parents[2]
REGISTRY = default_registry()
SUFFIXES = {s for kind in REGISTRY.ruleset_kinds.values() for s in kind.suffixes}
RULESETS = sorted(p for p in (REPO / "rulesets").iterdir() if p.suffix in SUFFIXES)


def test_every_shipped_ruleset_has_a_kind():
    assert len(RULESETS) >= 4
    assert {p.suffix for p in RULESETS} >= {".grammar", ".relayout"}


@pytest.mark.parametrize("path", RULESETS, ids=lambda p: p.name)
@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(width=st.floats(2.5, 40.0), height=st.floats(3.0, 30.0), levels=st.one_of(st.none(), st.integers(1, 9)),
       entrance=st.booleans(), corner=st.floats(0.0, 0.6), seed=st.integers(0, 999))
def test_ruleset_meets_the_request(path, width, height, levels, entrance, corner, seed):
    kind = REGISTRY.kind_for_path(path)
    ruleset = kind.load(path)
    lines = plan_floor_lines(height, levels, Defaults())
    corners = (min(corner, 0.15 * width),) * 2
    request = FacadeRequest(width=width, height=height, floor_lines=lines, entrance=entrance, corner_widths=corners,
                            context=FaceContext("b", 0, len(lines) - 1, street_facing=True), seed=(seed, "b", 0))
    layout = kind.generate(ruleset, request)
    assert check_partition(layout) == []
    assert check_request(layout, request) == []  # also when a model falls back to plain walls
    assert kind.generate(ruleset, request) == layout  # deterministic
