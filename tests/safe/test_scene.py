"""The safe kind in the city pipeline: a tiny scene dressed with ``cmp_b0035.safe`` validates."""
from __future__ import annotations

from citygen.usd.validate import validate_stage

from ..mini_scene import generate_mini_scene
from .conftest import ROOT


def test_safe_ruleset_dresses_a_small_scene(tmp_path):
    buildings = [(1, (0, 0, 16, 10), 4), (2, (30, 0, 24, 9), 2), (3, (0, 30, 7, 12), 6)]
    report, out = generate_mini_scene(tmp_path, buildings, ROOT / "rulesets" / "cmp_b0035.safe", seed=5,
                                      defaults="corner_width = 0.5")
    assert report.written == 3 and not report.skipped
    assert not [w for w in report.warnings if "fell back" in w or "not a partition" in w], report.warnings
    assert [f for f in validate_stage(out) if f.severity == "error"] == []
