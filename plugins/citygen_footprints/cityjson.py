"""CityJSON footprints: Building / BuildingPart objects, footprint from the ground of their solid.

The footprint is the 2D union of the solid's ground surfaces (near-horizontal, facing down); a solid without
them (3dfier LoD1 output leaves the bottom open) falls back to the union of all its faces projected to the
plane. Base = lowest z of the geometry; height = highest minus lowest z (``cityjson_height = "geometry"``), or
from the attributes (``measuredHeight``, ``storeysAboveGround``) with ``cityjson_height = "attribute"``.
"""
from __future__ import annotations

import reprlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import shapely
from citygen.errors import FootprintError
from citygen.footprints import FootprintStream, ImportResult, Skipped
from pyproj import CRS
from shapely.geometry import Polygon

from citygen_footprints.assemble import Aside, RawFeature, assemble, assembled
from citygen_footprints.frame import parse_crs
from citygen_footprints.heights import Height, resolve_height
from citygen_footprints.jsonload import iter_lines
from citygen_footprints.options import ImportOptions
from citygen_footprints.repair import FeatureProblem

BUILDING_TYPES = ("Building", "BuildingPart")
SOLIDS = ("Solid", "MultiSolid", "CompositeSolid")
SURFACES = ("MultiSurface", "CompositeSurface")
#: |normal z| above this makes a surface horizontal (about 8 degrees)
HORIZONTAL = 0.99


def _vertices(doc: Mapping[str, Any], path: Path) -> np.ndarray:
    raw = doc.get("vertices", [])
    try:
        try:
            vertices = np.asarray(raw, dtype=float)
        except OverflowError:  # an integer beyond float range: inf, so only the buildings using it are skipped
            vertices = np.asarray([[_finite_or_inf(v) for v in p] for p in raw], dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise FootprintError("CityJSON vertices are not all [x, y, z] numbers", where=str(path)) from None
    if vertices.size and (vertices.ndim != 2 or vertices.shape[1] != 3):
        raise FootprintError(f"CityJSON vertices have shape {vertices.shape}, expected (n, 3)", where=str(path))
    vertices = vertices.reshape(-1, 3)  # also no vertices at all: (0, 3)
    transform = doc.get("transform")
    if isinstance(transform, Mapping):
        try:
            scale = np.asarray(transform.get("scale", [1, 1, 1]), dtype=float)
            translate = np.asarray(transform.get("translate", [0, 0, 0]), dtype=float)
        except (TypeError, ValueError, OverflowError):
            scale = translate = np.zeros(0)
        if scale.shape != (3,) or translate.shape != (3,) or not np.isfinite([*scale, *translate]).all():
            raise FootprintError("CityJSON transform needs scale and translate of 3 finite numbers each",
                                 where=str(path), hint='e.g. "transform": {"scale": [0.001, 0.001, 0.001], '
                                                       '"translate": [0, 0, 0]}')
        with np.errstate(over="ignore"):  # a vertex beyond float range becomes inf: its buildings are skipped
            vertices = vertices * scale + translate
    return vertices


def _finite_or_inf(value: Any) -> Any:
    return np.inf if isinstance(value, int) and abs(value) > 2 ** 1023 else value


def _rank(geometry: Mapping[str, Any]) -> tuple[int, float]:
    """Sort key: solids before surfaces, LoD 1 first, then ascending LoD, LoD 0 last."""
    try:
        lod = float(geometry.get("lod", 9))
    except (TypeError, ValueError):
        lod = 9.0
    return (0 if geometry.get("type") in SOLIDS else 1, lod if lod >= 1 else 99.0)


def _surfaces(geometry: Mapping[str, Any]) -> list[list[list[int]]]:
    """Every surface (a list of rings of vertex indices) of the exterior shells of a geometry."""
    kind, boundaries = geometry.get("type"), geometry.get("boundaries") or []
    if kind == "Solid":
        return list(boundaries[0]) if boundaries else []
    if kind in ("MultiSolid", "CompositeSolid"):
        return [surface for solid in boundaries if solid for surface in solid[0]]
    return list(boundaries)


def _newell(rings: list[np.ndarray]) -> np.ndarray:
    """Newell normals ``(n, 3)`` of 3D rings (not closed): length = twice the area, z = twice the xy area."""
    points = np.concatenate(rings)
    sizes = np.array([len(r) for r in rings])
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    nxt = np.arange(len(points)) + 1
    nxt[starts + sizes - 1] = starts
    a, b = points, points[nxt]
    terms = np.column_stack([(a[:, 1] - b[:, 1]) * (a[:, 2] + b[:, 2]),
                             (a[:, 2] - b[:, 2]) * (a[:, 0] + b[:, 0]),
                             (a[:, 0] - b[:, 0]) * (a[:, 1] + b[:, 1])])
    return np.add.reduceat(terms, starts, axis=0)


def footprint_of(geometry: Mapping[str, Any], vertices: np.ndarray) -> tuple[shapely.Geometry, float, float, bool]:
    """(2D footprint, min z, max z, had ground surfaces) of one CityJSON geometry; FeatureProblem if none."""
    try:
        surfaces = [[vertices[np.asarray(ring, dtype=np.intp)] for ring in surface if len(ring) >= 3]
                    for surface in _surfaces(geometry)]
    except (IndexError, ValueError, TypeError, OverflowError):
        raise FeatureProblem("a surface refers to a vertex index that does not exist "
                             "-- the CityJSON file is corrupt; re-export it") from None
    surfaces = [s for s in surfaces if s]
    if not surfaces:
        raise FeatureProblem("the geometry has no surfaces -- check its boundaries")
    if not all(np.isfinite(r).all() for s in surfaces for r in s):
        raise FeatureProblem("a vertex is NaN or infinite (or beyond float range after the transform) "
                             "-- fix the vertices or the transform in the source data")
    with np.errstate(over="ignore", invalid="ignore"):  # huge coordinates: no finite normal, so no flat surface
        normals = _newell([s[0] for s in surfaces])
        length = np.linalg.norm(normals, axis=1)
        nz = np.divide(normals[:, 2], length, out=np.zeros(len(length)), where=length > 0)
    flat = np.abs(normals[:, 2]) > 2e-9  # projected area above 1e-9 m²
    if not flat.any():
        raise FeatureProblem("the geometry has no surface with a footprint area -- check its boundaries")
    is_down = (nz < -HORIZONTAL) if geometry.get("type") in SOLIDS else (np.abs(nz) > HORIZONTAL)
    polygons = np.array([Polygon(s[0][:, :2], [r[:, :2] for r in s[1:]]) if flat[i] else None
                         for i, s in enumerate(surfaces)], dtype=object)
    invalid = flat & ~shapely.is_valid(polygons)
    polygons[invalid] = shapely.make_valid(polygons[invalid])
    ground = flat & is_down
    z = np.concatenate([r[:, 2] for s in surfaces for r in s])
    chosen = polygons[ground] if ground.any() else polygons[flat]
    with np.errstate(over="ignore", invalid="ignore"):  # huge coordinates: GEOS overflows, the area check skips it
        footprint = shapely.union_all(chosen)
    return footprint, float(z.min()), float(z.max()), bool(ground.any())


def _parts(geometry: shapely.Geometry) -> tuple[list[np.ndarray], ...]:
    polygons = [g for g in getattr(geometry, "geoms", [geometry]) if isinstance(g, Polygon) and not g.is_empty]
    return tuple([np.asarray(p.exterior.coords)] + [np.asarray(h.coords) for h in p.interiors] for p in polygons)


def _height(attributes: Mapping[str, Any], label: str, zmin: float, zmax: float, options: ImportOptions) -> Height:
    from_attributes = resolve_height(attributes, label, options.heights)
    extent = zmax - zmin
    if options.cityjson_height == "geometry" and 0 < extent <= options.max_height:
        return Height(extent, "geometry", from_attributes.levels)
    if from_attributes.source == "default" and 0 < extent <= options.max_height:
        return Height(extent, "geometry", None, 0.0, from_attributes.warnings, from_attributes.rejected)
    return from_attributes


def _geometries(obj: Any) -> list[Mapping[str, Any]]:
    """The object's usable geometries, best first (see :func:`_rank`)."""
    if not isinstance(obj, Mapping) or not isinstance(obj.get("geometry"), list):
        return []
    return sorted((g for g in obj["geometry"] if isinstance(g, Mapping)
                   and g.get("type") in SOLIDS + SURFACES), key=_rank)


def _attributes(obj: Mapping[str, Any], objects: Mapping[str, Any]) -> dict[str, Any]:
    """The object's attributes, its type and parent, and (for parts) the attributes of its parent."""
    attributes, parents = obj.get("attributes") or {}, obj.get("parents") or []
    if not isinstance(attributes, Mapping) or not isinstance(parents, list):
        raise FeatureProblem("attributes must be a JSON object and parents a list of ids -- fix the CityObject")
    attributes = dict(attributes)
    attributes["cityjson:type"] = obj["type"]
    for parent_id in parents:
        attributes.setdefault("cityjson:parent", parent_id)
        parent = objects.get(parent_id) if isinstance(parent_id, str) else None
        if isinstance(parent, Mapping):
            for key, value in (parent.get("attributes") or {}).items():
                attributes.setdefault(key, value)
    return attributes


def _crs(doc: Mapping[str, Any], path: Path, options: ImportOptions, notes: list[str]) -> CRS | None:
    metadata = doc.get("metadata") or {}
    declared = metadata.get("referenceSystem") if isinstance(metadata, Mapping) else None
    if not isinstance(metadata, Mapping) or not isinstance(declared, str | None):
        raise FootprintError(f"CityJSON metadata must be an object whose referenceSystem is a CRS name, got "
                             f"{reprlib.repr(metadata)}", where=str(path),
                             hint='e.g. "metadata": {"referenceSystem": "https://www.opengis.net/def/crs/EPSG/0/7415"}'
                                  ", or set crs in the scene's [footprints] table")
    crs_text = options.crs or declared
    if not crs_text:
        notes.append(f"{path}: no referenceSystem in metadata; coordinates kept as unknown metric units "
                     "-- set crs in the scene to geo-reference them")
        return None
    return parse_crs(crs_text, str(path))


Collected = tuple[list[RawFeature], list[tuple[int, Skipped]], int]


def collect_buildings(objects: Mapping[str, Any], vertices: np.ndarray, path: Path, options: ImportOptions,
                      start: int = 0, line: int | None = None) -> Collected:
    """RawFeatures and skips of the buildings among ``objects``, and how many solids had no ground surface."""
    raws, skipped, open_bottom = [], [], 0
    at = f"{path.name}:{line}" if line else path.name
    for offset, (oid, obj) in enumerate(objects.items()):
        if not isinstance(obj, Mapping) or obj.get("type") not in BUILDING_TYPES:
            continue
        index, where = start + offset, f"{at} CityObjects[{oid!r}]"
        children = obj.get("children") if isinstance(obj.get("children"), list) else []
        if any(_geometries(objects.get(child)) for child in children if isinstance(child, str)):
            continue  # represented by its parts, which inherit its attributes
        geometries = _geometries(obj)
        if not geometries:
            reason = "no Solid or MultiSurface geometry -- give it a LoD1 solid or a LoD0 footprint surface"
            skipped.append((index, Skipped(oid, reason, where)))
            continue
        try:
            footprint, zmin, zmax, had_ground = footprint_of(geometries[0], vertices)
            attributes = _attributes(obj, objects)
        except FeatureProblem as problem:
            skipped.append((index, Skipped(oid, str(problem), where)))
            continue
        parts = _parts(footprint)
        if not parts:  # the ground surfaces cancel out or collapse (e.g. coordinates too large to resolve them)
            skipped.append((index, Skipped(oid, "its footprint has no area (degenerate ground surfaces, or coordinates "
                                                "too large to tell its corners apart) -- check its boundaries and "
                                                "the file's transform", where)))
            continue
        open_bottom += not had_ground
        label = f"{oid} ({where})"
        raws.append(RawFeature(index, oid, where, f"{path.name}#{index}", attributes, parts,
                               height=_height(attributes, label, zmin, zmax, options), base=zmin))
    return raws, skipped, open_bottom


def _open_bottom_note(path: Path, count: int) -> list[str]:
    return [f"{path.name}: {count} solid(s) have no ground surface; their footprint is the union of their faces "
            "projected to the ground plane"] if count else []


def import_cityjson(doc: Mapping[str, Any], path: Path, options: ImportOptions,
                    warnings: tuple[str, ...] = ()) -> ImportResult:
    """Footprints of the Building and BuildingPart objects of a decoded CityJSON document."""
    objects = doc.get("CityObjects")
    if not isinstance(objects, Mapping):
        raise FootprintError("CityJSON file without a CityObjects object", where=str(path),
                             hint="is this a CityJSON file? (type must be CityJSON with CityObjects)")
    notes = list(warnings)
    crs = _crs(doc, path, options, notes)
    raws, skipped, open_bottom = collect_buildings(objects, _vertices(doc, path), path, options)
    return assemble(raws, skipped, notes + _open_bottom_note(path, open_bottom), crs, options, path)


def import_cityjson_seq(path: Path, options: ImportOptions, warnings: tuple[str, ...] = ()) -> ImportResult:
    """Footprints from CityJSON Text Sequences (``.city.jsonl``): a CityJSON header line, then one
    CityJSONFeature per line with its own vertices (quantised with the header's transform)."""
    return stream_cityjson_seq(path, options, warnings).collected()


def stream_cityjson_seq(path: Path, options: ImportOptions, warnings: tuple[str, ...] = ()) -> FootprintStream:
    """:func:`import_cityjson_seq` as a stream: the file read a line at a time, each line's buildings put
    :class:`~citygen_footprints.assemble.Aside`, then handed over as footprints once the ids and the frame are fixed
    (a 3D BAG tile set of any size is never in memory at once)."""
    lines = iter_lines(path)
    first = next(lines, None)
    if first is None or not isinstance(first[1], Mapping) or first[1].get("type") != "CityJSON":
        raise FootprintError("a CityJSONSeq file must start with a CityJSON header line", where=f"{path}:1",
                             hint="the first line holds type, version, transform and metadata")
    header = first[1]
    notes = list(warnings)
    crs = _crs(header, path, options, notes)
    aside, skipped, open_bottom, start = Aside(), [], 0, 0
    for number, feature in lines:
        if not isinstance(feature, Mapping) or not isinstance(feature.get("CityObjects"), Mapping):
            notes.append(f"{path.name}:{number}: not a CityJSONFeature (no CityObjects); line ignored")
            continue
        vertices = _vertices({"vertices": feature.get("vertices", []), "transform": header.get("transform")},
                             path)
        raws, rejected, opened = collect_buildings(feature["CityObjects"], vertices, path, options, start, number)
        for raw in raws:
            aside.add(raw)
        skipped += rejected
        open_bottom += opened
        start += len(feature["CityObjects"])
    return assembled(aside.heads, aside.load, skipped, notes + _open_bottom_note(path, open_bottom), crs, options,
                     path)
