"""Importer options: the scene's ``[footprints]`` table, validated once into a frozen object."""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from citygen.errors import SceneError

from citygen_footprints.heights import TYPE_LEVELS, HeightSettings

#: keys of the [footprints] table that belong to the scene reader, not to the importer
SCENE_KEYS = frozenset({"path", "format"})
BAD_HEIGHT_CHOICES = ("fallback", "skip")
CITYJSON_HEIGHT_CHOICES = ("geometry", "attribute")
OSM_PARTS_CHOICES = ("replace", "ignore")


@dataclass(frozen=True)
class ImportOptions:
    """Everything an importer can be told; see docs/footprints.md for each option."""

    default_height: float = 10.0
    floor_height: float = 3.0
    max_height: float = 1000.0
    crs: str | None = None
    crs_check: bool = True
    id_property: str | None = None
    origin: tuple[float, float] | None = None
    min_area: float = 1.0
    min_part_area: float | None = None
    repair_min_area_ratio: float = 0.9
    bad_height: str = "fallback"
    base_offsets: bool = True
    cityjson_height: str = "geometry"
    osm_parts: str = "replace"
    type_levels: tuple[tuple[str, float], ...] = TYPE_LEVELS
    slenderness: float = 3.0

    @property
    def heights(self) -> HeightSettings:
        return HeightSettings(self.default_height, self.floor_height, self.max_height, self.base_offsets,
                              self.type_levels, self.slenderness)

    @property
    def part_area(self) -> float:
        """Polygon parts (of a multipolygon or a repair) smaller than this are dropped."""
        return self.min_area if self.min_part_area is None else self.min_part_area


def _fail(key: str, value: Any, expected: str) -> SceneError:
    return SceneError(f"[footprints] {key} = {value!r} is invalid", where="[footprints]",
                      hint=f"{key} must be {expected}")


def _number(key: str, value: Any, low: float, high: float = math.inf, low_open: bool = True) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise _fail(key, value, "a number")
    if value < low or (low_open and value == low) or value > high:
        raise _fail(key, value, f"in {'(' if low_open else '['}{low:g}, {high:g}]")
    return float(value)


def _choice(key: str, value: Any, choices: tuple[str, ...]) -> str:
    if value not in choices:
        raise _fail(key, value, "one of " + ", ".join(repr(c) for c in choices))
    return value


def parse_options(table: Mapping[str, Any]) -> tuple[ImportOptions, tuple[str, ...]]:
    """Validated options from a ``[footprints]`` table, plus warnings (unknown keys). Raises SceneError."""
    fields = ImportOptions.__dataclass_fields__
    unknown = sorted(set(table) - set(fields) - SCENE_KEYS)
    warnings = tuple(f"[footprints] unknown option {k!r} ignored (known: {', '.join(fields)})" for k in unknown)
    values: dict[str, Any] = {}
    for key in ("default_height", "floor_height", "max_height"):
        if key in table:
            values[key] = _number(key, table[key], 0.0)
    for key in ("min_area", "min_part_area", "slenderness"):
        if key in table:
            values[key] = _number(key, table[key], 0.0, low_open=False)
    if "repair_min_area_ratio" in table:
        values["repair_min_area_ratio"] = _number("repair_min_area_ratio", table["repair_min_area_ratio"], 0.0, 1.0,
                                                  low_open=False)
    for key in ("crs", "id_property"):
        if key in table:
            if not isinstance(table[key], str) or not table[key]:
                raise _fail(key, table[key], "a non-empty string")
            values[key] = table[key]
    for key in ("crs_check", "base_offsets"):
        if key in table:
            if not isinstance(table[key], bool):
                raise _fail(key, table[key], "true or false")
            values[key] = table[key]
    if "origin" in table:
        origin = table["origin"]
        if not isinstance(origin, list | tuple) or len(origin) != 2:
            raise _fail("origin", origin, "[x, y] in the input CRS (lon, lat for geographic data)")
        values["origin"] = (_number("origin", origin[0], -math.inf), _number("origin", origin[1], -math.inf))
    if "type_levels" in table:
        levels = table["type_levels"]
        if not isinstance(levels, Mapping) or not all(isinstance(k, str) for k in levels):
            raise _fail("type_levels", levels, "a table of building type = levels, e.g. { kiosk = 1, garage = 1 }")
        values["type_levels"] = tuple(sorted({**dict(TYPE_LEVELS), **{
            k: _number(f"type_levels.{k}", v, 0.0) for k, v in levels.items()}}.items()))
    if "bad_height" in table:
        values["bad_height"] = _choice("bad_height", table["bad_height"], BAD_HEIGHT_CHOICES)
    if "cityjson_height" in table:
        values["cityjson_height"] = _choice("cityjson_height", table["cityjson_height"], CITYJSON_HEIGHT_CHOICES)
    if "osm_parts" in table:
        values["osm_parts"] = _choice("osm_parts", table["osm_parts"], OSM_PARTS_CHOICES)
    return ImportOptions(**values), warnings
