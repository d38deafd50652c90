"""Fuzz: cities of awkward footprints and tags through every ruleset kind. Each building is written or skipped
with a reason (never an internal error), the stage validates, and the run ends (bug fixture: a sliver face of a
400 m tower held up the city in the structure-aware editing QP)."""
from __future__ import annotations

from pathlib import Path

import pytest

from citygen.pipeline import generate_city
from citygen.scene import load_scene
from citygen.usd.validate import validate_stage
from tests.e2e.awkward import write_awkward_city

REPO = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.slow


@pytest.mark.parametrize("seed, count, max_height", [(1, 30, 400.0), (2, 30, 60.0)])
def test_awkward_city_is_written_or_skipped_with_reasons(tmp_path, seed, count, max_height):
    write_awkward_city(tmp_path / "awkward.geojson", seed, count, max_height)
    scene = (REPO / "scenes" / "helsinki_all_kinds.toml").read_text()
    scene = scene.replace("data/helsinki_buildings.geojson", "awkward.geojson")
    scene = scene.replace("../rulesets/", (REPO / "rulesets").as_posix() + "/")
    (tmp_path / "awkward.toml").write_text(scene)
    out = tmp_path / "awkward.usdc"
    report = generate_city(load_scene(tmp_path / "awkward.toml"), out=out, jobs=2)
    assert report.written + len(report.skipped) == count and report.written >= 0.8 * count
    assert all(s.reason and "internal error" not in s.reason for s in report.skipped)
    assert not [w for w in report.warnings if "internal error" in w]
    assert [f for f in validate_stage(out) if f.severity == "error"] == []
