"""GeoJSON footprints (RFC 7946 lon/lat, or projected with a ``crs`` member / the ``crs`` option)."""
from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from citygen.errors import FootprintError
from citygen.footprints import FootprintStream, ImportResult, Skipped
from pyproj import CRS

from citygen_footprints.assemble import Aside, RawFeature, assemble, assembled
from citygen_footprints.frame import parse_crs
from citygen_footprints.jsonload import stream_object
from citygen_footprints.options import ImportOptions
from citygen_footprints.repair import FeatureProblem, clean_rings

DEFAULT_CRS = "OGC:CRS84"
OSM_TYPES = ("node", "way", "relation")
_HSTORE = re.compile(r'"((?:[^"\\]|\\.)*)"\s*=>\s*"((?:[^"\\]|\\.)*)"')


def _file_crs(doc: Mapping[str, Any], where: str = "") -> str | None:
    """The name in a (pre-RFC 7946) ``"crs": {"type": "name", "properties": {"name": ...}}`` member, or a plain
    ``"crs": "EPSG:3067"`` string; any other crs member is an error (was: ignored, reading the file as lon/lat)."""
    member = doc.get("crs")
    if member is None:
        return None
    if isinstance(member, str) and member.strip():
        return member.strip()
    if isinstance(member, Mapping) and isinstance(member.get("properties"), Mapping):
        name = member["properties"].get("name")
        if isinstance(name, str) and name.strip():
            return name
    raise FootprintError(f"the file's crs member {str(member)[:80]!r} is not understood", where=where,
                         hint='use "crs": {"type": "name", "properties": {"name": "EPSG:nnnn"}}, or set crs = '
                              '"EPSG:nnnn" in the scene\'s [footprints] table')


def choose_crs(doc: Mapping[str, Any], options: ImportOptions, where: str) -> tuple[CRS, list[str]]:
    """The CRS to read ``doc`` in: the ``crs`` option, else the file's crs member, else lon/lat (RFC 7946)."""
    declared = _file_crs(doc, where)
    if options.crs is None:
        return parse_crs(declared or DEFAULT_CRS, where), []
    crs = parse_crs(options.crs, where)
    if declared and parse_crs(declared, where) != crs:
        return crs, [f"{where}: the scene's crs {options.crs} overrides the file's crs {declared}"]
    return crs, []


def attributes_of(properties: Mapping[str, Any]) -> dict[str, Any]:
    """Feature properties without nulls, with nested OSM tags (``tags`` dict, GDAL ``other_tags`` hstore) merged."""
    attributes = {k: v for k, v in properties.items() if v is not None and k not in ("tags", "other_tags")}
    tags = properties.get("tags")
    if isinstance(tags, Mapping):
        for key, value in tags.items():
            attributes.setdefault(key, value)
    other = properties.get("other_tags")
    if isinstance(other, str):
        for key, value in _HSTORE.findall(other):
            attributes.setdefault(key.replace('\\"', '"'), value.replace('\\"', '"'))
    return attributes


def feature_id(feature: Mapping[str, Any], properties: Mapping[str, Any], index: int,
               id_property: str | None) -> str:
    """A stable id: ``id_property``, else ``@id``, the Feature ``id``, ``id`` (``way/123`` with ``osm_type``)."""
    keys = [properties.get(id_property)] if id_property else []
    keys += [properties.get("@id"), feature.get("id"), properties.get("id")]
    value = next((k for k in keys if k is not None and k != ""), None)
    if value is None:
        return f"feature/{index}"
    osm_type = properties.get("osm_type", properties.get("@type"))
    if isinstance(value, int | float) and not isinstance(value, bool) and osm_type in OSM_TYPES \
            and (isinstance(value, int) or math.isfinite(value)):  # (an int beyond float range is still an id)
        return f"{osm_type}/{int(value)}"
    return str(value)


def _geometry_polygons(geometry: Any) -> list[Any]:
    if not isinstance(geometry, Mapping):
        raise FeatureProblem("no geometry (null) -- give the building a Polygon or MultiPolygon outline")
    kind = geometry.get("type")
    coords = geometry.get("coordinates")
    if kind not in ("Polygon", "MultiPolygon"):
        raise FeatureProblem(f"{kind} geometry is not a building outline "
                             "-- map the building as a Polygon or MultiPolygon")
    if not coords:
        raise FeatureProblem("empty geometry (no coordinates) -- draw the building outline or remove the feature")
    if not isinstance(coords, list):
        raise FeatureProblem(f"{kind} coordinates are not a list -- fix the geometry")
    return [coords] if kind == "Polygon" else coords


def features_of(doc: Any, path: Path) -> list[Any]:
    """The features of a FeatureCollection, Feature or bare (Multi)Polygon; FootprintError for anything else."""
    kind = doc.get("type") if isinstance(doc, Mapping) else type(doc).__name__
    if kind == "FeatureCollection" and isinstance(doc.get("features"), list):
        return doc["features"]
    if kind == "Feature":
        return [doc]
    if kind in ("Polygon", "MultiPolygon"):
        return [{"type": "Feature", "geometry": doc, "properties": {}}]
    raise FootprintError(f"not a GeoJSON FeatureCollection (top-level type is {kind!r})", where=str(path),
                         hint="give a FeatureCollection of Polygon/MultiPolygon features, or a CityJSON file")


@dataclass(frozen=True)
class SkippedFeature:
    """An element of a GeoJSON ``features`` array that cannot become a building: its position and why."""

    index: int
    skipped: Skipped


def read_feature(index: int, feature: Any, line: int | None, path: Path, options: ImportOptions
                 ) -> RawFeature | SkippedFeature:
    """Element ``index`` of a GeoJSON ``features`` array (starting at 1-based ``line`` of ``path``, if known) as the
    importer keeps it: what :func:`load_json` stores in place of each element as it decodes them
    (``each``), so a big file's features are never all held as JSON objects (~2 kB a feature) at once."""
    where = f"{path.name}{'' if line is None else f':{line}'}, feature {index}"
    if not isinstance(feature, Mapping) or feature.get("type") != "Feature":
        return SkippedFeature(index, Skipped(f"feature/{index}", "not a GeoJSON Feature object -- each element of "
                                             "features must be {\"type\": \"Feature\", \"geometry\": ...}", where))
    properties = feature.get("properties") if isinstance(feature.get("properties"), Mapping) else {}
    fid = feature_id(feature, properties, index, options.id_property)
    try:
        cleaned = clean_rings(_geometry_polygons(feature.get("geometry")))
    except FeatureProblem as problem:
        return SkippedFeature(index, Skipped(fid, str(problem), where))
    return RawFeature(index, fid, where, f"{path.name}#{index}", attributes_of(properties), cleaned.parts,
                      cleaned.warnings)


def import_geojson(doc: Any, path: Path, options: ImportOptions, lines: list[int] | None = None,
                   warnings: tuple[str, ...] = ()) -> ImportResult:
    """Footprints from a decoded GeoJSON document; ``lines`` are the 1-based start lines of its features, which
    may already be read (:func:`read_feature`)."""
    features = features_of(doc, path)
    crs, crs_warnings = choose_crs(doc, options, str(path))
    raws: list[RawFeature] = []
    skipped: list[tuple[int, Skipped]] = []
    for index, feature in enumerate(features):
        if not isinstance(feature, RawFeature | SkippedFeature):
            feature = read_feature(index, feature, lines[index] if lines and index < len(lines) else None, path,
                                   options)
        if isinstance(feature, SkippedFeature):
            skipped.append((feature.index, feature.skipped))
        else:
            raws.append(feature)
    return assemble(raws, skipped, [*warnings, *crs_warnings], crs, options, path)


def stream_geojson(path: Path, options: ImportOptions, warnings: tuple[str, ...] = ()) -> FootprintStream | None:
    """A GeoJSON FeatureCollection's footprints as a stream, the file read twice: first feature by feature
    (:func:`~citygen_footprints.jsonload.stream_object`), each :func:`read_feature` put
    :class:`~citygen_footprints.assemble.Aside`; then, once the ids and the frame are fixed, the features
    taken back from the file as the footprints are used. ``None`` when the file is not a FeatureCollection (or does
    not decode): :func:`import_geojson` and the other readers take it whole."""
    aside, skipped = Aside(), []

    def keep(index: int, element: Any, line: int) -> None:
        feature = read_feature(index, element, line, path, options)
        if isinstance(feature, SkippedFeature):
            skipped.append((feature.index, feature.skipped))
        else:
            aside.add(feature)

    doc = stream_object(path, "features", keep, "FeatureCollection")
    if doc is None:
        aside.close()
        return None
    crs, crs_warnings = choose_crs(doc, options, str(path))
    return assembled(aside.heads, aside.load, skipped, [*warnings, *crs_warnings], crs, options, path)
