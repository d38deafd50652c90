"""From raw features in source coordinates to an ImportResult: ids, local frame, repair, heights.

Both importers reduce their format to :class:`RawFeature` records (rings in the source CRS, attributes,
optionally a height known from 3D geometry) and hand them to :func:`assemble`, so ids, projection, repair and
height rules are the same for every format.
"""
from __future__ import annotations

import pickle
import tempfile
from array import array
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from citygen.footprints import Footprint, FootprintStream, ImportResult, Skipped
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


class Heads:
    """What fixing the frame and the ids needs of every feature, ~0.1 kB each (the feature itself lies elsewhere):
    its index, id, first corner and bounds."""

    def __init__(self) -> None:
        self.index = array("q")
        self.ids: list[str] = []
        self.corners = array("d")  # (first x, first y, min x, min y, max x, max y) a feature

    def __len__(self) -> int:
        return len(self.ids)

    def add(self, feature: RawFeature) -> None:
        points = _points(feature)
        self.index.append(feature.index)
        self.ids.append(feature.id)
        self.corners.extend([*points[0].tolist(), *points.min(axis=0).tolist(), *points.max(axis=0).tolist()])

    def outside(self, k: int) -> bool:
        """Whether a corner of feature ``k`` is outside the lon/lat range (its bounds are)."""
        x0, y0, x1, y1 = self.bounds(k)
        return x0 < -180 or x1 > 180 or y0 < -90 or y1 > 90

    def first(self, k: int) -> tuple[float, float]:
        return self.corners[6 * k], self.corners[6 * k + 1]

    def bounds(self, k: int) -> tuple[float, float, float, float]:
        return tuple(self.corners[6 * k + 2:6 * k + 6])


class Pickles:
    """Objects pickled one after another to an anonymous temporary file (gone when closed or the process ends):
    what a streaming reader puts aside; :meth:`load` gives object ``k`` back."""

    def __init__(self) -> None:
        self.scratch = tempfile.TemporaryFile()  # noqa: SIM115 (closed by close(), or with the process)
        self.places = array("q")  # (offset, size) an object
        self.end = 0

    def put(self, value: Any) -> None:
        data = pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
        self.places.extend((self.end, len(data)))
        self.scratch.write(data)
        self.end += len(data)

    def load(self, k: int) -> Any:
        self.scratch.seek(self.places[2 * k])
        return pickle.loads(self.scratch.read(self.places[2 * k + 1]))

    def close(self) -> None:
        self.scratch.close()


class Aside(Pickles):
    """Features put aside as a streaming reader reads them, only their :class:`Heads` kept (``heads``): ``load(k)``
    gives feature ``k`` back once the ids and the frame are fixed."""

    def __init__(self) -> None:
        super().__init__()
        self.heads = Heads()

    def add(self, feature: RawFeature) -> None:
        self.put(feature)
        self.heads.add(feature)


def _points(feature: RawFeature) -> np.ndarray:
    """Every corner of the feature's rings, ``(n, 2)``, in ring order."""
    rings = [np.asarray(r, dtype=float).reshape(-1, 2) for p in feature.parts for r in p]
    return rings[0] if len(rings) == 1 else np.concatenate(rings)


def unique_ids(ids: list[str], where: Callable[[int], str]) -> list[str]:
    """Suffix repeated ids in file order (``way/1``, ``way/1#2``, ...) so every footprint id is unique (``ids``
    renamed in place; ``where(k)``: where feature ``k`` is); the warnings."""
    taken = set(ids)
    seen: set[str] = set()
    warnings = []
    for k, fid in enumerate(ids):
        if fid in seen:
            n = 2
            while f"{fid}#{n}" in taken:
                n += 1
            new = f"{fid}#{n}"
            taken.add(new)
            warnings.append(f"{fid} ({where(k)}): duplicate id, renamed to {new} -- make ids unique in the source "
                            "or set id_property to a unique property")
            ids[k] = fid = new
        seen.add(fid)
    return warnings


def _project(features: Sequence[RawFeature], frame) -> list[tuple[Part, ...]]:
    rings = [ring for f in features for part in f.parts for ring in part]
    if not rings:
        return []
    local = frame.to_local(np.concatenate(rings))
    bounds = np.cumsum([len(r) for r in rings])[:-1]
    pieces = iter(np.split(local, bounds))
    return [tuple([next(pieces) for _ in part] for part in f.parts) for f in features]


def _stray_lonlat(heads: Heads, load: Callable[[int], RawFeature]) -> tuple[list[int], list[tuple[int, Skipped]]]:
    """Features of a lon/lat file with coordinates outside the lon/lat range are skipped when they are fewer than
    half of the features (bad coordinates in a few buildings); when as many or more, all are kept and
    ``make_frame`` refuses the file (most likely projected metres without a declared CRS). Returns the kept
    features (positions in ``heads``) and the skipped ones."""
    kept = list(range(len(heads)))
    bad = [k for k in kept if heads.outside(k)]
    if not bad or 2 * len(bad) >= len(heads):
        return kept, []
    skipped = []
    for k in bad:
        x, y = _stray(load(k))
        skipped.append((heads.index[k], Skipped(heads.ids[k], f"coordinates such as ({x:.6g}, {y:.6g}) are outside "
                                                "the lon/lat range of the rest of the file -- fix them in the source "
                                                "data", load(k).where)))
    gone = set(bad)
    return [k for k in kept if k not in gone], skipped


def _stray(feature: RawFeature) -> tuple[float, float]:
    """The feature's first corner outside the lon/lat range."""
    points = _points(feature)
    return tuple(points[np.argmax(outside_lonlat(points))].tolist())


def _far_apart(heads: Heads, kept: list[int], lonlat: bool, load: Callable[[int], RawFeature]
               ) -> tuple[list[int], list[tuple[int, Skipped]]]:
    """Features with a coordinate far from the median of the features' first corners -- in a metric file (projected
    or unknown CRS) more than ``MAX_DISTANCE`` units in x or y, in a ``lonlat`` file more than
    ``MAX_SPREAD_LONLAT`` metres on the sphere -- are skipped when fewer than half of the features (bad coordinates
    in a few buildings would otherwise drag the frame's centre away from the rest); else all are kept. A metric
    file's reach comes from each feature's bounds (the same figure), a lon/lat file's from its corners."""
    if not kept:
        return [], []
    centre = np.median([heads.first(k) for k in kept], axis=0)
    limit = MAX_SPREAD_LONLAT if lonlat else MAX_DISTANCE
    reach, corners = [], []
    for k in kept:
        if lonlat:
            points = _points(load(k))
            distance = _sphere_distance(points, centre)
            far = int(np.argmax(distance))  # (the first NaN, if any)
            reach.append(float(distance[far]))
            corners.append(points[far])
        else:
            reach.append(float(np.abs(np.asarray(heads.bounds(k)).reshape(2, 2) - centre).max()))
    bad = [i for i, d in enumerate(reach) if not d <= limit]
    if not bad or 2 * len(bad) >= len(kept):
        return kept, []
    skipped = []
    for i in bad:
        k = kept[i]
        if lonlat:
            reason = (f"its corner at ({corners[i][0]:.7g}, {corners[i][1]:.7g}) lies {reach[i] / 1e3:,.0f} km from "
                      f"the other buildings (more than {limit / 1e3:,.0f} km) -- fix its coordinates in the source "
                      "data")
        else:
            reason = (f"its coordinates lie {reach[i]:.3g} units of the file's CRS from the other buildings (more "
                      f"than {limit:g}) -- fix them in the source data")
        skipped.append((heads.index[k], Skipped(heads.ids[k], reason, load(k).where)))
    gone = set(bad)
    return [k for i, k in enumerate(kept) if i not in gone], skipped


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


#: Features projected and repaired at a time (one batch through the projection, as many footprints held).
BATCH = 1024


def assemble(features: Sequence[RawFeature], skipped: Sequence[tuple[int, Skipped]], warnings: Sequence[str],
             crs: CRS | None, options: ImportOptions, path: Path) -> ImportResult:
    """Project, repair and measure ``features``; every problem becomes a Skipped or a warning, never an abort.

    ``skipped`` holds (feature index, Skipped) of features the reader already rejected; the result lists all
    skipped features in file order.
    """
    heads = Heads()
    for feature in features:
        heads.add(feature)
    return assembled(heads, features.__getitem__, skipped, warnings, crs, options, path).collected()


def assembled(heads: Heads, load: Callable[[int], RawFeature], skipped: Sequence[tuple[int, Skipped]],
              warnings: Sequence[str], crs: CRS | None, options: ImportOptions, path: Path) -> FootprintStream:
    """:func:`assemble` as a stream, from the features' ``heads`` (what fixes the ids and the frame) and ``load(k)``,
    which gives feature ``k`` again (from wherever it was put: only a :data:`BATCH` of them is held at a time)."""
    ids = list(heads.ids)
    out_warnings = [*warnings, *unique_ids(ids, lambda k: load(k).where)]
    heads.ids = ids
    out_skipped = list(skipped)
    lonlat = crs is not None and is_geographic(crs)
    kept = list(range(len(heads)))
    if lonlat and options.crs_check:
        kept, stray = _stray_lonlat(heads, load)
        out_skipped += stray
    kept, far = _far_apart(heads, kept, lonlat, load)
    out_skipped += far
    frame = make_frame(crs, _frame_points(heads, kept, load), options.origin, str(path), options.crs_check)
    ordered: list[Skipped] = []

    def footprints() -> Iterator[Footprint]:
        for start in range(0, len(kept), BATCH):
            batch = [load(k) for k in kept[start:start + BATCH]]
            batch = [f if f.id == ids[k] else replace(f, id=ids[k]) for f, k in zip(batch, kept[start:start + BATCH])]
            for feature, parts in zip(batch, _project(batch, frame), strict=True):
                footprint = _footprint(feature, parts, options, out_warnings, out_skipped)
                if footprint is not None:
                    yield footprint
        ordered[:] = [s for _, s in sorted(out_skipped, key=lambda item: item[0])]

    return FootprintStream(footprints(), ordered, out_warnings, frame.georef)


def _frame_points(heads: Heads, kept: Sequence[int], load: Callable[[int], RawFeature]) -> np.ndarray:
    """Points standing for the ``kept`` features' corners in :func:`make_frame`: the first corner outside the
    lon/lat range (if any) and each feature's bounds' two corners -- the same bounds, and the same first corner
    outside the range, as all of their corners."""
    first = next((k for k in kept if heads.outside(k)), None)
    corners = np.frombuffer(heads.corners, dtype=float).reshape(-1, 6)[np.asarray(kept, dtype=np.intp), 2:]
    return np.concatenate([np.zeros((0, 2)) if first is None else [_stray(load(first))], corners.reshape(-1, 2)])


def _footprint(feature: RawFeature, parts: tuple[Part, ...], options: ImportOptions, out_warnings: list[str],
               out_skipped: list[tuple[int, Skipped]]) -> Footprint | None:
    """One feature's footprint in the local frame (``parts`` projected), its warnings and skip put in the lists."""
    label = f"{feature.id} ({feature.where})"
    out_warnings.extend(f"{label}: {w}" for w in feature.warnings)
    try:
        polygon, notes = build_polygon(parts, options.min_area, options.part_area, options.repair_min_area_ratio)
    except FeatureProblem as problem:
        out_skipped.append((feature.index, Skipped(feature.id, str(problem), feature.where)))
        return None
    out_warnings.extend(f"{label}: {w}" for w in notes)
    height = feature.height or infer_height(resolve_height(feature.attributes, label, options.heights),
                                            feature.attributes, _least_width(polygon), options.heights)
    out_warnings.extend(height.warnings)
    base = feature.base + height.base_offset
    if problem := _out_of_reach(parts, base, base + height.height):
        out_skipped.append((feature.index, Skipped(feature.id, problem, feature.where)))
        return None
    if height.rejected and options.bad_height == "skip":
        reason = (f"unusable height data ({', '.join(height.rejected)}) -- fix the tags, or set "
                  "bad_height = \"fallback\" to use the next height source")
        out_skipped.append((feature.index, Skipped(feature.id, reason, feature.where)))
        return None
    return Footprint(id=feature.id, polygon=polygon, height=height.height, height_source=height.source,
                     levels=height.levels, base=base, attributes=dict(feature.attributes), source=feature.source,
                     lift=height.base_offset, height_is_total=height.total)


def _least_width(polygon) -> float:
    """The short side of the footprint's minimum rotated rectangle (metres)."""
    corners = np.asarray(polygon.minimum_rotated_rectangle.exterior.coords)[:3]
    return float(min(np.hypot(*(corners[1] - corners[0])), np.hypot(*(corners[2] - corners[1]))))
