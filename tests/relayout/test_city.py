"""A relayout model on real buildings: the core pipeline dresses a tiny scene with ``townhouse.relayout``."""
from __future__ import annotations

from pathlib import Path

from citygen.usd.validate import validate_stage

from ..mini_scene import generate_mini_scene

REPO = Path(__file__).resolve().parents[2]


def test_townhouse_model_dresses_a_small_scene(tmp_path):
    # ordinary buildings of 2..5 storeys and one kiosk too small for the model (its faces fall back)
    buildings = [(1, (0, 0, 12, 10), 3), (2, (30, 0, 21, 9), 4), (3, (0, 30, 9, 14), 5), (4, (30, 30, 16, 12), 2),
                 (5, (60, 0, 1.6, 1.6), 1)]
    report, out = generate_mini_scene(tmp_path, buildings, REPO / "rulesets" / "townhouse.relayout", seed=3)
    assert report.written == 5 and not report.skipped
    # only the kiosk, in one warning for its four faces (it was one per face)
    assert report.warnings == [w for w in report.warnings if w.startswith("way/5")]
    assert len(report.warnings) == 1 and "4 face(s) outside the ruleset's size range" in report.warnings[0]
    assert "faces 0, 1, 2, 3: 1.60 x" in report.warnings[0] and "must lie in" in report.warnings[0]
    assert [f for f in validate_stage(out) if f.severity == "error"] == []
