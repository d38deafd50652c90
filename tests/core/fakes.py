"""In-process test plugins: a minimal ruleset kind and a local-metric footprint importer.

They exercise the core pipeline without depending on any first-party plugin, which is also the proof that the core
knows no specific ruleset kind.
"""
from __future__ import annotations

import json
from pathlib import Path

from shapely.geometry import Polygon, shape
from shapely.geometry.polygon import orient

from citygen.footprints import Footprint, ImportResult, Skipped
from citygen.hookspecs import hookimpl
from citygen.layout import FacadeLayout, Region
from citygen.registry import FootprintImporter, RulesetKind
from citygen.request import FacadeRequest


class GridKind(RulesetKind):
    """Per floor: corner strips, then windows of ``window`` m in bays of ``bay`` m; a door on the entrance face;
    openings of the optional ``material``."""

    id = "testgrid"
    suffixes = (".testgrid",)

    def load(self, path: Path) -> dict:
        return json.loads(Path(path).read_text())

    def generate(self, ruleset: dict, request: FacadeRequest) -> FacadeLayout:
        left, right = request.corner_widths
        inner = request.width - left - right
        floors = []
        for k, (y0, y1) in enumerate(zip(request.floor_lines[:-1], request.floor_lines[1:])):
            h = y1 - y0
            bays = max(1, round(inner / ruleset["bay"]))
            bw = inner / bays
            cells = [Region(0, y0, left, h, "Corner", "wall"), Region(request.width - right, y0, right, h, "Corner", "wall")]
            for b in range(bays):
                x = left + b * bw
                label = "door" if (k == 0 and request.entrance and b == bays // 2) else "window"
                ww, wh = min(ruleset["window"], 0.8 * bw), min(2.0 if label == "door" else 1.6, 0.7 * h)
                wy = 0.0 if label == "door" else 0.25 * (h - wh)
                cells += [Region(x, y0, (bw - ww) / 2, h, "Wall", "wall"),
                          Region(x + (bw + ww) / 2, y0, (bw - ww) / 2, h, "Wall", "wall"),
                          Region(x + (bw - ww) / 2, y0, ww, wy, "Wall", "wall"),
                          Region(x + (bw - ww) / 2, y0 + wy, ww, wh, "Opening", label, depth=-0.2,
                                 material=ruleset.get("material")),
                          Region(x + (bw - ww) / 2, y0 + wy + wh, ww, h - wy - wh, "Wall", "wall")]
            floors.append(Region(0, y0, request.width, h, "Floor", children=tuple(c for c in cells if c.w > 0 and c.h > 0)))
        return FacadeLayout(request.width, request.height, Region(0, 0, request.width, request.height, "Facade",
                                                                   children=tuple(floors)))


class LocalJsonImporter(FootprintImporter):
    """``.local.json``: ``[{"id", "coordinates" (metres), "height"}]`` -- no projection, for tests."""

    id = "localjson"
    suffixes = (".local.json",)

    def read(self, path: Path, options: dict) -> ImportResult:
        good, skipped = [], []
        for k, item in enumerate(json.loads(Path(path).read_text())):
            poly = shape({"type": "Polygon", "coordinates": item["coordinates"]})
            if not poly.is_valid or item.get("height", 1) <= 0:
                skipped.append(Skipped(str(item["id"]), "invalid polygon or height", f"{path.name}[{k}]"))
                continue
            good.append(Footprint(id=str(item["id"]), polygon=orient(Polygon(poly), 1.0),
                                  height=float(item.get("height", options.get("default_height", 10.0))),
                                  height_source="height" if "height" in item else "default",
                                  levels=item.get("levels"), attributes=item.get("tags", {}), source=f"{path.name}[{k}]"))
        return ImportResult(tuple(good), tuple(skipped))


class FakePlugin:
    @hookimpl
    def citygen_ruleset_kinds(self):
        return [GridKind()]

    @hookimpl
    def citygen_footprint_importers(self):
        return [LocalJsonImporter()]
