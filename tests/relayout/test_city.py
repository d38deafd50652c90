"""A relayout model on real buildings: the core pipeline dresses a tiny scene with ``townhouse.relayout``."""
from __future__ import annotations

import json
import math
from pathlib import Path

from citygen.pipeline import generate_city
from citygen.scene import load_scene
from citygen.usd.validate import validate_stage

REPO = Path(__file__).resolve().parents[2]
LON, LAT = 24.94, 60.17


def _rect(x: float, y: float, w: float, d: float) -> list[list[float]]:
    """A w x d metre rectangle at (x, y) metres from the origin, as a closed lon/lat ring."""
    mx = 1.0 / (111_320.0 * math.cos(math.radians(LAT)))
    my = 1.0 / 111_320.0
    pts = [(x, y), (x + w, y), (x + w, y + d), (x, y + d), (x, y)]
    return [[LON + px * mx, LAT + py * my] for px, py in pts]


def test_townhouse_model_dresses_a_small_scene(tmp_path):
    # ordinary buildings of 2..5 storeys and one kiosk too small for the model (its faces fall back)
    buildings = [(1, _rect(0, 0, 12, 10), 3), (2, _rect(30, 0, 21, 9), 4), (3, _rect(0, 30, 9, 14), 5),
                 (4, _rect(30, 30, 16, 12), 2), (5, _rect(60, 0, 1.6, 1.6), 1)]
    features = [{"type": "Feature", "properties": {"id": i, "osm_type": "way", "building:levels": str(levels)},
                 "geometry": {"type": "Polygon", "coordinates": [ring]}} for i, ring, levels in buildings]
    (tmp_path / "mini.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": features}))
    (tmp_path / "mini.toml").write_text(
        f'[scene]\nseed = 3\n[footprints]\npath = "mini.geojson"\n[[assign]]\n'
        f'ruleset = "{(REPO / "rulesets" / "townhouse.relayout").as_posix()}"\n[output]\npath = "mini.usda"\n')
    out = tmp_path / "mini.usda"
    report = generate_city(load_scene(tmp_path / "mini.toml"), out=out)
    assert report.written == 5 and not report.skipped
    fell_back = [w for w in report.warnings if "fell back" in w]
    assert fell_back and all(w.startswith("way/5") for w in fell_back), fell_back  # only the kiosk
    assert not [w for w in report.warnings if not w.startswith("way/5")], report.warnings
    assert [f for f in validate_stage(out) if f.severity == "error"] == []
