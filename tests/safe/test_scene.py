"""The safe kind in the city pipeline: a tiny scene dressed with ``cmp_b0035.safe`` validates."""
from __future__ import annotations

import json
import math

from citygen.pipeline import generate_city
from citygen.scene import load_scene
from citygen.usd.validate import validate_stage

from .conftest import ROOT

LON, LAT = 24.94, 60.17


def _rect(x: float, y: float, w: float, d: float) -> list[list[float]]:
    """A w x d metre rectangle at (x, y) metres from the origin, as a closed lon/lat ring."""
    mx = 1.0 / (111_320.0 * math.cos(math.radians(LAT)))
    my = 1.0 / 111_320.0
    pts = [(x, y), (x + w, y), (x + w, y + d), (x, y + d), (x, y)]
    return [[LON + px * mx, LAT + py * my] for px, py in pts]


def test_safe_ruleset_dresses_a_small_scene(tmp_path):
    buildings = [(1, _rect(0, 0, 16, 10), 4), (2, _rect(30, 0, 24, 9), 2), (3, _rect(0, 30, 7, 12), 6)]
    features = [{"type": "Feature", "properties": {"id": i, "osm_type": "way", "building:levels": str(levels)},
                 "geometry": {"type": "Polygon", "coordinates": [ring]}} for i, ring, levels in buildings]
    (tmp_path / "mini.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": features}))
    (tmp_path / "mini.toml").write_text(
        f'[scene]\nseed = 5\n[footprints]\npath = "mini.geojson"\n[defaults]\ncorner_width = 0.5\n[[assign]]\n'
        f'ruleset = "{(ROOT / "rulesets" / "cmp_b0035.safe").as_posix()}"\n[output]\npath = "mini.usda"\n')
    out = tmp_path / "mini.usda"
    report = generate_city(load_scene(tmp_path / "mini.toml"), out=out)
    assert report.written == 3 and not report.skipped
    assert not [w for w in report.warnings if "fell back" in w or "not a partition" in w], report.warnings
    assert [f for f in validate_stage(out) if f.severity == "error"] == []
