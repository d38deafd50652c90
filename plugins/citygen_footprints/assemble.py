"""From raw features in source coordinates to an ImportResult: ids, local frame, repair, heights.

Both importers reduce their format to :class:`RawFeature` records (rings in the source CRS, attributes,
optionally a height known from 3D geometry) and hand them to :func:`assemble`, so ids, projection, repair and
height rules are the same for every format.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from citygen.footprints import Footprint, ImportResult, Skipped
from pyproj import CRS

from citygen_footprints.frame import is_geographic, make_frame, outside_lonlat
from citygen_footprints.heights import Height, infer_height, resolve_height
from citygen_footprints.options import ImportOptions
from citygen_footprints.repair import FeatureProblem, Part, build_polygon


#: no building may lie further than this from the scene origin, nor its base or top further from z = 0 (metres):
#: 10,000 km is beyond any city, and the stage's float32 points still resolve a metre there
MAX_DISTANCE = 1e7
#: in a lon/lat file no building may lie further than this (metres on the sphere) from the others: the local
#: frame is one transverse Mercator around the data's centre, so one far corner would drag every building away from
#: the origin (a node at lon -180 put central Helsinki 3,400 km off, where its roofs fell back to flat) and be drawn
#: as a building thousands of kilometres long; 1,000 km is beyond any city
MAX_SPREAD_LONLAT = 1e6
EARTH_RADIUS = 6_371_008.8  # metres, the mean radius (IUGG)


@dataclass(frozen=True)
class RawFeature:
    """One feature as read from the file (``index`` = its position there), before projection and repair."""

    index: int
    id: str
    where: str
    source: str
    attributes: Mapping[str, Any]
    parts: tuple[Part, ...]
    warnings: tuple[str, ...] = ()
    height: Height | None = None
    base: float = 0.0


def unique_ids(features: Sequence[RawFeature]) -> tuple[list[RawFeature], list[str]]:
    """Suffix repeated ids in file order (``way/1``, ``way/1#2``, ...) so every footprint id is unique."""
    taken = {f.id for f in features}
    seen: set[str] = set()
    out, warnings = [], []
    for f in features:
        if f.id in seen:
            n = 2
            while f"{f.id}#{n}" in taken:
                n += 1
            new = f"{f.id}#{n}"
            taken.add(new)
            warnings.append(f"{f.id} ({f.where}): duplicate id, renamed to {new} -- make ids unique in the source "
                            "or set id_property to a unique property")
            f = replace(f, id=new)
        seen.add(f.id)
        out.append(f)
    return out, warnings


def _project(features: Sequence[RawFeature], frame) -> list[tuple[Part, ...]]:
    rings = [ring for f in features for part in f.parts for ring in part]
    if not rings:
        return []
    local = frame.to_local(np.concatenate(rings))
    bounds = np.cumsum([len(r) for r in rings])[:-1]
    pieces = iter(np.split(local, bounds))
    return [tuple([next(pieces) for _ in part] for part in f.parts) for f in features]


def _stray_lonlat(features: Sequence[RawFeature]) -> tuple[list[RawFeature], list[tuple[int, Skipped]]]:
    """Features of a lon/lat file with coordinates outside the lon/lat range are skipped when they are fewer than
    half of the features (bad coordinates in a few buildings); when as many or more, all are kept and
    ``make_frame`` refuses the file (most likely projected metres without a declared CRS)."""
    bad = [f for f in features if any(outside_lonlat(np.asarray(r, dtype=float).reshape(-1, 2)).any()
                                      for p in f.parts for r in p)]
    if not bad or 2 * len(bad) >= len(features):
        return list(features), []
    skipped = []
    for f in bad:
        points = np.concatenate([np.asarray(r, dtype=float).reshape(-1, 2) for p in f.parts for r in p])
        x, y = points[np.argmax(outside_lonlat(points))]
        skipped.append((f.index, Skipped(f.id, f"coordinates such as ({x:.6g}, {y:.6g}) are outside the lon/lat "
                                               "range of the rest of the file -- fix them in the source data",
                                         f.where)))
    gone = {id(f) for f in bad}
    return [f for f in features if id(f) not in gone], skipped


def _far_apart(features: Sequence[RawFeature], lonlat: bool
               ) -> tuple[list[RawFeature], list[tuple[int, Skipped]]]:
    """Features with a coordinate far from the median of the features' first corners -- in a metric file (projected
    or unknown CRS) more than ``MAX_DISTANCE`` units in x or y, in a ``lonlat`` file more than
    ``MAX_SPREAD_LONLAT`` metres on the sphere -- are skipped when fewer than half of the features (bad coordinates
    in a few buildings would otherwise drag the frame's centre away from the rest); else all are kept."""
    if not features:
        return [], []
    rings = [[np.asarray(r, dtype=float).reshape(-1, 2) for p in f.parts for r in p] for f in features]
    centre = np.median([r[0][0] for r in rings], axis=0)
    limit = MAX_SPREAD_LONLAT if lonlat else MAX_DISTANCE
    reach, corners = [], []
    for f in rings:
        points = np.concatenate(f)
        distance = _sphere_distance(points, centre) if lonlat else np.abs(points - centre).max(axis=1)
        far = int(np.argmax(distance))  # (the first NaN, if any)
        reach.append(float(distance[far]))
        corners.append(points[far])
    bad = [k for k, d in enumerate(reach) if not d <= limit]
    if not bad or 2 * len(bad) >= len(features):
        return list(features), []
    skipped = []
    for k in bad:
        if lonlat:
            reason = (f"its corner at ({corners[k][0]:.7g}, {corners[k][1]:.7g}) lies {reach[k] / 1e3:,.0f} km from "
                      f"the other buildings (more than {limit / 1e3:,.0f} km) -- fix its coordinates in the source "
                      "data")
        else:
            reason = (f"its coordinates lie {reach[k]:.3g} units of the file's CRS from the other buildings (more "
                      f"than {limit:g}) -- fix them in the source data")
        skipped.append((features[k].index, Skipped(features[k].id, reason, features[k].where)))
    gone = set(bad)
    return [f for k, f in enumerate(features) if k not in gone], skipped


def _sphere_distance(points: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """Great-circle distances (metres) of lon/lat ``points`` ``(n, 2)`` from ``centre`` (haversine)."""
    lon, lat = np.radians(points[:, 0]), np.radians(points[:, 1])
    lon0, lat0 = np.radians(centre)
    h = np.sin((lat - lat0) / 2) ** 2 + np.cos(lat) * np.cos(lat0) * np.sin((lon - lon0) / 2) ** 2
    return 2 * EARTH_RADIUS * np.arcsin(np.sqrt(np.clip(h, 0.0, 1.0)))


def _out_of_reach(parts: Sequence[Part], base: float, top: float) -> str | None:
    """Why a footprint in the local frame cannot be written (too far from the origin or z = 0), or None."""
    reach = max(float(np.abs(r).max()) for p in parts for r in p)
    if not reach <= MAX_DISTANCE:
        return (f"it lies {reach:.3g} m from the scene origin, more than {MAX_DISTANCE:g} m -- fix its coordinates "
                "or the file's CRS")
    if not (abs(base) <= MAX_DISTANCE and abs(top) <= MAX_DISTANCE):
        return (f"its base z = {base:.3g} m / top {top:.3g} m lie beyond ±{MAX_DISTANCE:g} m -- fix the z "
                "coordinates (or min_height) in the source data")
    return None


def assemble(features: Sequence[RawFeature], skipped: Sequence[tuple[int, Skipped]], warnings: Sequence[str],
             crs: CRS | None, options: ImportOptions, path: Path) -> ImportResult:
    """Project, repair and measure ``features``; every problem becomes a Skipped or a warning, never an abort.

    ``skipped`` holds (feature index, Skipped) of features the reader already rejected; the result lists all
    skipped features in file order.
    """
    features, id_warnings = unique_ids(features)
    out_warnings = list(warnings) + id_warnings
    out_skipped = list(skipped)
    lonlat = crs is not None and is_geographic(crs)
    if lonlat and options.crs_check:
        features, stray = _stray_lonlat(features)
        out_skipped += stray
    features, far = _far_apart(features, lonlat)
    out_skipped += far
    points = np.concatenate([r for f in features for p in f.parts for r in p]) if features else np.zeros((0, 2))
    frame = make_frame(crs, points, options.origin, str(path), options.crs_check)
    footprints = []
    for feature, parts in zip(features, _project(features, frame), strict=True):
        label = f"{feature.id} ({feature.where})"
        out_warnings.extend(f"{label}: {w}" for w in feature.warnings)
        try:
            polygon, notes = build_polygon(parts, options.min_area, options.part_area, options.repair_min_area_ratio)
        except FeatureProblem as problem:
            out_skipped.append((feature.index, Skipped(feature.id, str(problem), feature.where)))
            continue
        out_warnings.extend(f"{label}: {w}" for w in notes)
        height = feature.height or infer_height(resolve_height(feature.attributes, label, options.heights),
                                                feature.attributes, _least_width(polygon), options.heights)
        out_warnings.extend(height.warnings)
        base = feature.base + height.base_offset
        if problem := _out_of_reach(parts, base, base + height.height):
            out_skipped.append((feature.index, Skipped(feature.id, problem, feature.where)))
            continue
        if height.rejected and options.bad_height == "skip":
            reason = (f"unusable height data ({', '.join(height.rejected)}) -- fix the tags, or set "
                      "bad_height = \"fallback\" to use the next height source")
            out_skipped.append((feature.index, Skipped(feature.id, reason, feature.where)))
            continue
        footprints.append(Footprint(id=feature.id, polygon=polygon, height=height.height,
                                    height_source=height.source, levels=height.levels,
                                    base=base, attributes=dict(feature.attributes),
                                    source=feature.source, lift=height.base_offset, height_is_total=height.total))
    ordered = tuple(s for _, s in sorted(out_skipped, key=lambda item: item[0]))
    return ImportResult(tuple(footprints), ordered, tuple(out_warnings), frame.georef)


def _least_width(polygon) -> float:
    """The short side of the footprint's minimum rotated rectangle (metres)."""
    corners = np.asarray(polygon.minimum_rotated_rectangle.exterior.coords)[:3]
    return float(min(np.hypot(*(corners[1] - corners[0])), np.hypot(*(corners[2] - corners[1]))))
