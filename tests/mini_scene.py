"""A tiny scene of rectangular OSM-like buildings near Helsinki, generated with one ruleset (pipeline tests)."""
from __future__ import annotations

import json
import math
from pathlib import Path

from citygen.pipeline import Report, generate_city
from citygen.scene import load_scene

LON, LAT = 24.94, 60.17


def rect(x: float, y: float, w: float, d: float) -> list[list[float]]:
    """A w x d metre rectangle at (x, y) metres from the origin, as a closed lon/lat ring."""
    mx = 1.0 / (111_320.0 * math.cos(math.radians(LAT)))
    my = 1.0 / 111_320.0
    pts = [(x, y), (x + w, y), (x + w, y + d), (x, y + d), (x, y)]
    return [[LON + px * mx, LAT + py * my] for px, py in pts]


def generate_mini_scene(tmp_path: Path, buildings: list[tuple[int, tuple[float, float, float, float], int]],
                        ruleset: Path, seed: int, defaults: str = "") -> tuple[Report, Path]:
    """Generate ``buildings`` ((id, (x, y, w, d) metres, levels) each) dressed with ``ruleset`` to a .usda."""
    features = [{"type": "Feature", "properties": {"id": i, "osm_type": "way", "building:levels": str(levels)},
                 "geometry": {"type": "Polygon", "coordinates": [rect(*box)]}} for i, box, levels in buildings]
    (tmp_path / "mini.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": features}))
    (tmp_path / "mini.toml").write_text(
        f'[scene]\nseed = {seed}\n[footprints]\npath = "mini.geojson"\n'
        + (f'[defaults]\n{defaults}\n' if defaults else "")
        + f'[[assign]]\nruleset = "{ruleset.as_posix()}"\n[output]\npath = "mini.usda"\n')
    out = tmp_path / "mini.usda"
    return generate_city(load_scene(tmp_path / "mini.toml"), out=out), out
