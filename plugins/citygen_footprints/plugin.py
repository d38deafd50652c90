"""Registers the GeoJSON, CityJSON and OpenStreetMap footprint importers with citygen."""
from __future__ import annotations

import functools
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from citygen.errors import FootprintError
from citygen.footprints import FootprintStream, ImportResult
from citygen.hookspecs import hookimpl
from citygen.registry import FootprintImporter

from citygen_footprints.cityjson import import_cityjson, import_cityjson_seq, stream_cityjson_seq
from citygen_footprints.geojson import import_geojson, read_feature, stream_geojson
from citygen_footprints.jsonload import load_json
from citygen_footprints.options import parse_options
from citygen_footprints.osm import SUFFIXES as OSM_SUFFIXES
from citygen_footprints.osm import import_osm_json, stream_osm
from citygen_footprints.osm_json import is_osm_json


def read_footprints(path: Path, options: Mapping[str, Any]) -> ImportResult:
    """Read a GeoJSON, CityJSON, CityJSONSeq (``.jsonl``) or OSM JSON file; JSON files dispatch on their
    top-level ``type`` (OSM JSON has none, but a list of ``elements``)."""
    path = Path(path)
    parsed, warnings = parse_options(options)
    if path.name.lower().endswith(".jsonl"):
        return import_cityjson_seq(path, parsed, warnings)
    doc, lines = load_json(path, each=functools.partial(read_feature, path=path, options=parsed))  # (GeoJSON's)
    if isinstance(doc, Mapping) and doc.get("type") == "CityJSON":
        return import_cityjson(doc, path, parsed, warnings)
    if isinstance(doc, Mapping) and doc.get("type") in ("FeatureCollection", "Feature", "Polygon", "MultiPolygon"):
        return import_geojson(doc, path, parsed, lines, warnings)
    if is_osm_json(doc):
        return import_osm_json(doc, path, parsed, warnings)
    kind = doc.get("type") if isinstance(doc, Mapping) else type(doc).__name__
    raise FootprintError(f"neither GeoJSON nor CityJSON (top-level type is {kind!r})", where=str(path),
                         hint="give a GeoJSON FeatureCollection of (Multi)Polygons, a CityJSON file or OSM JSON "
                              "(an Overpass [out:json] result)")


def stream_footprints(path: Path, options: Mapping[str, Any]) -> FootprintStream:
    """:func:`read_footprints` as a stream: a GeoJSON FeatureCollection is read twice and never held whole
    (:func:`~citygen_footprints.geojson.stream_geojson`), a CityJSONSeq file a line at a time
    (:func:`~citygen_footprints.cityjson.stream_cityjson_seq`); CityJSON and OSM JSON files are read whole
    (OpenStreetMap files stream through their own importer, :func:`~citygen_footprints.osm.stream_osm`)."""
    path = Path(path)
    parsed, warnings = parse_options(options)
    if path.name.lower().endswith(".jsonl"):
        return stream_cityjson_seq(path, parsed, warnings)
    stream = stream_geojson(path, parsed, warnings)
    return stream if stream is not None else FootprintStream.of(read_footprints(path, options))


class GeoJSONImporter(FootprintImporter):
    id = "geojson"
    suffixes = (".geojson", ".json")
    description = "GeoJSON Polygon/MultiPolygon buildings (lon/lat or projected), OSM height tags; OSM JSON"

    def read(self, path: Path, options: dict[str, Any]) -> ImportResult:
        return read_footprints(path, options)

    def stream(self, path: Path, options: dict[str, Any]) -> FootprintStream:
        return stream_footprints(path, options)


class CityJSONImporter(FootprintImporter):
    id = "cityjson"
    suffixes = (".city.json", ".cityjson", ".city.jsonl")
    description = "CityJSON (and CityJSONSeq .jsonl) buildings: ground of the solid, height from the geometry"

    def read(self, path: Path, options: dict[str, Any]) -> ImportResult:
        return read_footprints(path, options)

    def stream(self, path: Path, options: dict[str, Any]) -> FootprintStream:
        return stream_footprints(path, options)


class OSMImporter(FootprintImporter):
    id = "osm"
    suffixes = OSM_SUFFIXES
    description = "OpenStreetMap XML / PBF (needs pyosmium: citygen[osm]): building ways, multipolygons, S3DB parts"

    def read(self, path: Path, options: dict[str, Any]) -> ImportResult:
        return self.stream(path, options).collected()

    def stream(self, path: Path, options: dict[str, Any]) -> FootprintStream:
        parsed, warnings = parse_options(options)
        return stream_osm(Path(path), parsed, warnings)


@hookimpl
def citygen_footprint_importers() -> list[FootprintImporter]:
    # CityJSON first: the registry picks the first importer whose suffix matches, and .city.json ends in .json
    return [CityJSONImporter(), GeoJSONImporter(), OSMImporter()]
