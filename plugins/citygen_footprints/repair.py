"""Per-feature geometry checks and repairs: raw rings -> one valid, oriented (Multi)Polygon, or a reason.

Two stages: :func:`clean_rings` works on source coordinates (malformed or non-finite values, unclosed rings,
repeated vertices, degenerate rings) before projection; :func:`build_polygon` works in the local metric frame
(self-intersections, overlapping parts, slivers, orientation). Problems are plain messages ending in what to
do; the importer adds the feature id and location.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
import shapely.ops
from shapely.geometry import LineString, MultiPolygon, Polygon
from shapely.geometry.polygon import orient
from shapely.validation import explain_validity

Ring = np.ndarray  #: (n, 2) float array, closed (first == last), no consecutive repeats
Part = list[Ring]  #: exterior ring then holes


#: Metres: the grid a union of parts is snapped to when floating point leaves it invalid (:func:`_union`).
GRID = 1e-6


class FeatureProblem(Exception):
    """This feature cannot become a footprint; the message says why and what to do."""


@dataclass(frozen=True)
class CleanResult:
    """Rings that survived :func:`clean_rings`, grouped in parts, and the warnings met."""

    parts: tuple[Part, ...]
    warnings: tuple[str, ...]


def _ring_array(ring: object, label: str) -> np.ndarray:
    if not isinstance(ring, list) or not ring:
        raise FeatureProblem(f"{label} is empty or not a list of positions -- give it as [[x, y], ...]")
    try:
        if any(isinstance(v, bool) for p in ring for v in p[:2]):
            raise TypeError
        points = np.array([p[:2] for p in ring], dtype=float)
    except (TypeError, ValueError, IndexError, OverflowError):
        raise FeatureProblem(f"{label} has a malformed position (each must be [x, y] numbers) "
                             "-- fix the coordinates in the source data") from None
    if points.ndim != 2 or points.shape[1] != 2:
        raise FeatureProblem(f"{label} has a position with fewer than 2 numbers -- fix the coordinates")
    bad = ~np.isfinite(points).all(axis=1)
    if bad.any():
        raise FeatureProblem(f"{label} vertex {int(np.argmax(bad))} is NaN or infinite "
                             "-- fix the coordinates in the source data")
    return points


def _distinct(points: np.ndarray) -> np.ndarray:
    """Drop consecutive repeated vertices (including the closing one)."""
    keep = np.ones(len(points), dtype=bool)
    keep[1:] = (np.diff(points, axis=0) != 0).any(axis=1)
    points = points[keep]
    if len(points) > 1 and (points[0] == points[-1]).all():
        points = points[:-1]
    return points


def clean_rings(polygons: Sequence[object]) -> CleanResult:
    """Check GeoJSON-style polygon coordinates (a list of polygons, each a list of rings).

    Unclosed rings are closed, repeated vertices dropped, degenerate holes dropped (warnings); a degenerate
    exterior drops its part if other parts remain. Raises FeatureProblem when nothing usable is left or a
    coordinate is malformed or non-finite.
    """
    parts: list[Part] = []
    warnings: list[str] = []
    first_problem = None
    multi = len(polygons) > 1
    for p, rings in enumerate(polygons):
        where = f"part {p} " if multi else ""
        if not isinstance(rings, list) or not rings:
            raise FeatureProblem(f"{where}polygon has no rings -- give at least the exterior ring")
        part: Part = []
        for r, ring in enumerate(rings):
            label = f"{where}{'exterior ring' if r == 0 else f'hole {r}'}"
            points = _ring_array(ring, label)
            if len(points) > 1 and not (points[0] == points[-1]).all():
                warnings.append(f"{label} was not closed (first != last position); closed it")
            distinct = _distinct(points)
            if len(distinct) < 3:
                problem = (f"{label} has only {len(distinct)} distinct point(s), not an area "
                           "-- draw the outline as a closed ring of at least 3 corners")
                if r == 0:
                    first_problem = first_problem or problem
                    if multi:
                        warnings.append(problem.split(" -- ")[0] + "; dropped the part")
                    break
                warnings.append(problem.split(" -- ")[0] + "; dropped the hole")
                continue
            part.append(np.vstack([distinct, distinct[:1]]))
        else:
            parts.append(part)
    if not parts:
        raise FeatureProblem(first_problem or "empty geometry -- draw the building outline")
    return CleanResult(tuple(parts), tuple(warnings))


def _polygonal(geom: shapely.Geometry) -> list[Polygon]:
    if isinstance(geom, Polygon):
        return [] if geom.is_empty else [geom]
    return [g for sub in getattr(geom, "geoms", []) for g in _polygonal(sub)]


def _union(polygons: list[Polygon]) -> shapely.Geometry:
    """The union of ``polygons``; where floating point leaves it invalid (a sliver of one part ending a
    1e-16 m off another's edge: "nested shells"), the union on a micrometre grid."""
    union = shapely.union_all(polygons)
    return union if union.is_valid else shapely.union_all(polygons, grid_size=GRID)


def _enclosed_area(ring: Ring) -> float:
    """Area of all faces the ring's linework encloses (what the author drew, however it crosses itself)."""
    return sum(face.area for face in shapely.ops.polygonize(shapely.union_all([LineString(ring)])))


def _repair(part: Part, ratio: float) -> tuple[list[Polygon], str | None]:
    polygon = Polygon(part[0], part[1:])
    if polygon.is_valid:
        return [polygon], None
    reason = explain_validity(polygon)
    repaired = _polygonal(shapely.make_valid(polygon))
    drawn = max(_enclosed_area(part[0]) - sum(_enclosed_area(h) for h in part[1:]), 0.0)
    kept = sum(p.area for p in repaired)
    if drawn <= 0 or kept < ratio * drawn:
        share = 0 if drawn <= 0 else kept / drawn
        raise FeatureProblem(f"invalid outline ({reason}); a repair keeps only {share:.0%} of its area "
                             "-- fix the ring in the source data")
    return repaired, f"invalid outline ({reason}) repaired into {len(repaired)} polygon(s) keeping " \
                     f"{kept / drawn:.0%} of the drawn area; check the outline"


def build_polygon(parts: Sequence[Part], min_area: float, min_part_area: float,
                  repair_ratio: float) -> tuple[Polygon | MultiPolygon, tuple[str, ...]]:
    """One valid, oriented (exterior CCW, holes CW) polygon from cleaned parts in metres, plus warnings.

    Invalid parts are repaired with ``shapely.make_valid`` when that keeps at least ``repair_ratio`` of the area
    the rings enclose; overlapping parts are merged; parts under ``min_part_area`` are dropped. Raises
    FeatureProblem when the repair would lose too much or the total area, or the area kept, is under ``min_area``.
    """
    warnings: list[str] = []
    polygons: list[Polygon] = []
    for part in parts:
        repaired, note = _repair(part, repair_ratio)
        polygons.extend(repaired)
        if note:
            warnings.append(note)
    merged = _polygonal(_union(polygons)) if len(polygons) > 1 else polygons
    area = sum(p.area for p in merged)
    if not math.isfinite(area):
        raise FeatureProblem(f"its area is {area} m² (coordinates too large to measure it) "
                             "-- fix the coordinates in the source data")
    if area < min_area or area == 0:
        raise FeatureProblem(f"area {area:.3g} m² is below min_area = {min_area:g} m² (a sliver) "
                             "-- lower min_area in the scene to keep it")
    kept = [p for p in merged if p.area >= min_part_area] or [max(merged, key=lambda p: p.area)]
    if len(kept) < len(merged) and sum(p.area for p in kept) < min_area:
        raise FeatureProblem(f"area {sum(p.area for p in kept):.3g} m² is below min_area = {min_area:g} m² once its "
                             f"parts smaller than {min_part_area:g} m² are dropped (slivers) -- lower min_area or "
                             "part_area in the scene to keep it")
    if len(kept) < len(merged):
        warnings.append(f"dropped {len(merged) - len(kept)} part(s) smaller than {min_part_area:g} m²")
    oriented = [orient(p, sign=1.0) for p in kept]
    return (oriented[0] if len(oriented) == 1 else MultiPolygon(oriented)), tuple(warnings)
