"""OpenStreetMap files (``.osm``, ``.osm.pbf``, ``.osm.bz2``, ...) read with pyosmium (libosmium).

Buildings are closed ways and multipolygon relations tagged ``building`` or ``building:part`` (not ``no``);
libosmium assembles the areas (rings from unordered member ways, holes). Simple 3D Buildings: an outline that has
``building:part`` areas inside it is drawn by its parts (``osm_parts = "replace"``, the default) -- each part
with its own height tags (``min_height``, ``building:min_level`` lift its base) and the outline's other tags
(``building``, address, ...) unless it has its own; ``osm_parts = "ignore"`` keeps the outlines and drops the parts.
What cannot become a building is reported by id: an open way, a relation whose members are missing from the
extract (clipped at its edge), a way with nodes missing.

A file not in the order libosmium needs (nodes, ways, relations, each sorted by id, once, no negative id: an
Overpass export, a file saved by an editor, concatenated extracts) is read from a sorted copy (``osm_sorted``).
"""
from __future__ import annotations

import tempfile
from array import array
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import shapely
from citygen.errors import FootprintError
from citygen.footprints import FootprintStream, ImportResult, Skipped
from shapely.geometry import Polygon

from citygen_footprints.assemble import Aside, Pickles, RawFeature, assembled
from citygen_footprints.frame import parse_crs
from citygen_footprints.options import ImportOptions
from citygen_footprints.osm_json import osm_json_elements
from citygen_footprints.osm_sorted import deleted_marks, plain, sorted_copy
from citygen_footprints.repair import FeatureProblem, clean_rings

INSTALL_HINT = "pip install 'citygen[osm]'"
SUFFIXES = (".osm", ".osm.pbf", ".pbf", ".osm.bz2", ".osm.gz", ".osc", ".opl")
#: tags a part does not take from its outline: its own shape and height
OWN_KEYS = ("height", "min_height", "building:levels", "building:min_level", "building:part", "roof:", "type")
#: a part belongs to the outline holding at least this share of its area
PART_SHARE = 0.5
_RANK = {"n": 0, "w": 1, "r": 2}  # the order of types libosmium needs


@dataclass(frozen=True)
class _Area:
    """One building area as read: OSM id, tags, rings (lon, lat) as GeoJSON polygon coordinates."""

    index: int
    id: str
    tags: Mapping[str, str]
    polygons: list[list[list[tuple[float, float]]]]

    @property
    def is_part(self) -> bool:
        return "building" not in self.tags or self.tags["building"] == "no"


class _Areas(Pickles):
    """Building areas put aside as libosmium hands them over, with what ordering them and matching parts to
    outlines needs: each one's place in the file, id, whether it is a part, and its bounds."""

    def __init__(self) -> None:
        super().__init__()
        self.index = array("q")
        self.ids: list[str] = []
        self.part = bytearray()
        self.bounds = array("d")  # (min lon, min lat, max lon, max lat) an area

    def add(self, area: _Area) -> None:
        self.put(area)
        self.index.append(area.index)
        self.ids.append(area.id)
        self.part.append(area.is_part)
        corners = [c for p in area.polygons for c in p[0]] or [(0.0, 0.0)]
        lon, lat = zip(*corners)
        self.bounds.extend((min(lon), min(lat), max(lon), max(lat)))

    def ordered(self, leave_out: set[str]) -> list[int]:
        """The areas in file order, those whose ids are in ``leave_out`` left out."""
        keep = [k for k, oid in enumerate(self.ids) if oid not in leave_out]
        return sorted(keep, key=self.index.__getitem__)


def _osmium():
    try:
        import osmium
    except ImportError as exc:
        raise FootprintError(f"reading OpenStreetMap files needs pyosmium, which is not installed ({exc})",
                             hint=f"{INSTALL_HINT}, or convert the file to GeoJSON") from exc
    return osmium


def _is_building(tags) -> bool:
    return tags.get("building", "no") != "no" or tags.get("building:part", "no") != "no"


def _rings(area) -> list[list[list[tuple[float, float]]]]:
    """The area's polygons: per outer ring, the outer then its inner rings, as (lon, lat) lists."""
    return [[[(n.lon, n.lat) for n in outer], *[[(n.lon, n.lat) for n in inner] for inner in area.inner_rings(outer)]]
            for outer in area.outer_rings()]


def _read_error(exc: Exception, path: Path) -> FootprintError:
    """libosmium's reason the file cannot be read, with what to do about it."""
    message = str(exc)
    words = ("xml", "opl", "pbf", "uncompress", "illegal", "coordinate", "eof", "element")
    if any(word in message.lower() for word in words):
        hint = "the file is corrupt or truncated: re-download or re-export it (`osmium fileinfo -e FILE` checks it)"
    else:
        hint = "give an .osm (XML), .osm.pbf or .opl file"
    return FootprintError(f"cannot read the OpenStreetMap file: {message}", where=str(path), hint=hint)


def _objects(osmium, path: Path, areas: bool = True, source: Path | None = None):
    """The file's objects, nodes located and building areas assembled (``areas``, else only the OSM objects);
    FootprintError naming ``source`` (default: the file) when libosmium cannot read it (it raises RuntimeError
    for unreadable, truncated or unsorted files, ValueError or InvalidLocationError for malformed ids, versions
    and coordinates)."""
    try:
        if areas:
            areas_of = osmium.filter.KeyFilter("building", "building:part")  # only building relations are assembled
            yield from osmium.FileProcessor(str(path)).with_locations().with_areas(areas_of)
        else:
            yield from osmium.FileProcessor(str(path), osmium.osm.NODE | osmium.osm.WAY | osmium.osm.RELATION)
    except (RuntimeError, ValueError, OverflowError, osmium.InvalidLocationError) as exc:
        raise _read_error(exc, source or path) from exc


def read_areas(path: Path) -> tuple[_Areas, list[int], list[tuple[int, Skipped]], list[str]]:
    """Building areas put aside and their order in the file, the buildings that could not be assembled (with
    why), and a note when the file was read from a sorted copy."""
    osmium = _osmium()
    deleted = deleted_marks(path)
    if deleted:
        why = f"{len(deleted)} objects marked deleted by an editor (left out)"
    else:
        try:
            areas, order, skipped, why = _scan(osmium, path, path)
            if why is None:
                return areas, order, skipped, []
        except FootprintError as err:
            if not _order_error(err):
                raise
            why = "objects out of order or repeated (the last of each kept)"
    areas, order, skipped = _via_copy(osmium, plain(_objects(osmium, path, areas=False), deleted), path)
    return areas, order, skipped, [f"{path.name}: {why} -- read from a copy sorted as libosmium needs (nodes, "
                                   "ways, relations, each by id; `osmium sort` makes one ahead)"]


def _via_copy(osmium, elements, source: Path) -> tuple[_Areas, list[int], list[tuple[int, Skipped]]]:
    """``read_areas`` of ``source`` from a sorted copy of its ``elements`` (see ``osm_sorted.sorted_copy``)."""
    with tempfile.TemporaryDirectory(prefix="citygen-osm-") as tmp:
        copy = Path(tmp) / "sorted.osm.pbf"
        try:
            names = sorted_copy(osmium, elements, copy)
        except OverflowError as exc:
            raise FootprintError(f"cannot read the OpenStreetMap file: {exc}", where=str(source),
                                 hint="renumber the file's objects (`osmium renumber`)") from exc
        areas, order, skipped, _ = _scan(osmium, copy, source, names)
    return areas, order, skipped


def _order_error(err: FootprintError) -> bool:
    """Whether libosmium stopped at an object out of order or repeated (which a sorted copy mends)."""
    return isinstance(err.__cause__, RuntimeError) and any(
        words in str(err.__cause__) for words in ("out of order", "twice in input"))


def _scan(osmium, path: Path, source: Path, names: Mapping[str, tuple[str, int]] | None = None
          ) -> tuple[_Areas, list[int], list[tuple[int, Skipped]], str | None]:
    """``read_areas`` of the file ``source`` read from ``path``, and why its objects are not in the order
    libosmium needs (None when they are: nodes before ways before relations, no negative id; libosmium itself
    stops at ids out of order). ``names``: for a file read from its sorted copy, each way's and relation's name
    and place in ``source``, by its name in the copy."""
    where = source.name
    areas = _Areas()
    skipped: dict[str, Skipped] = {}
    order: dict[str, int] = {}  # building ways and multipolygon relations, and their areas, by place in the file
    made: set[str] = set()
    invisible: set[str] = set()
    last = 0

    def named(oid: str) -> str:
        oid, place = names[oid] if names else (oid, len(order))
        order.setdefault(oid, place)
        return oid
    for obj in _objects(osmium, path, source=source):
        if obj.is_area():
            if _is_building(obj.tags):
                oid = named(f"{'way' if obj.from_way() else 'relation'}/{obj.orig_id()}")
                made.add(oid)
                areas.add(_Area(order[oid], oid, dict(obj.tags), _rings(obj)))
            continue
        rank = _RANK[obj.type_str()]
        if rank < last or obj.id < 0:  # (the file is read again from a sorted copy: stop here)
            return areas, [], [], "negative ids (an editor's new objects)" if obj.id < 0 else \
                "nodes or ways after the ways or relations that use them (as in Overpass exports)"
        last = rank
        if not obj.visible:  # (deleted: an osmChange <delete>, visible="false")
            if rank:
                invisible.add(f"{'way' if rank == 1 else 'relation'}/{obj.id}")
            continue
        if not _is_building(obj.tags):
            continue
        if obj.is_way():
            oid = named(f"way/{obj.id}")
            missing = sum(not n.location.valid() for n in obj.nodes)
            if missing:
                skipped[oid] = Skipped(oid, f"{missing} of its {len(obj.nodes)} nodes are missing from the file "
                                            "(the extract cut the building) -- use an extract that keeps whole "
                                            "ways (osmium extract --strategy complete_ways; an Overpass query: "
                                            "`>;` then `out skel qt;`, or `out geom;` without a box)",
                                       f"{where}, {oid}")
            elif not obj.is_closed():
                skipped[oid] = Skipped(oid, "the building way is not closed -- close its outline or map it as a "
                                            "multipolygon relation", f"{where}, {oid}")
        elif obj.is_relation() and obj.tags.get("type") == "multipolygon":
            named(f"relation/{obj.id}")
    for oid in order.keys() - made - skipped.keys():
        what = "member ways or nodes missing from the extract, or rings that do not close" \
            if oid.startswith("relation/") else "fewer than three distinct nodes, or a self-crossing libosmium rejects"
        skipped[oid] = Skipped(oid, f"its outline could not be assembled into an area ({what}) -- use a complete "
                                    "extract or fix the outline in OSM", f"{where}, {oid}")
    return (areas, areas.ordered(invisible), sorted(((order[oid], s) for oid, s in skipped.items()),
                                                  key=lambda item: item[0]), None)


def _hosts(areas: _Areas, order: list[int]) -> dict[int, int]:
    """Simple 3D Buildings: per part (its position in ``areas``), the outline holding the largest share of its area,
    at least ``PART_SHARE``; of outlines holding as much (nested or overlapping outlines: a church and its tower,
    both tagged ``building``), one not tagged ``building:part`` itself, then the smallest, then the one later in the
    file. Outlines are found by their bounds and loaded only as candidates, each once: only the shapes of outlines
    near parts are held, never the city's."""
    outlines = [k for k in order if not areas.part[k]]
    parts = [k for k in order if areas.part[k]]
    if not outlines or not parts:
        return {}
    bounds = np.frombuffer(areas.bounds, dtype=float).reshape(-1, 4)
    tree = shapely.STRtree(shapely.box(*bounds[outlines].T))
    candidates: dict[int, tuple[shapely.Geometry, bool]] = {}  # (outlines near a part: its shape, is no part)

    def candidate(k: int) -> tuple[shapely.Geometry, bool]:
        if k not in candidates:
            outline = areas.load(k)
            candidates[k] = (_shape(outline), outline.tags.get("building:part", "no") == "no")
        return candidates[k]

    hosts: dict[int, int] = {}
    for part in parts:
        shape = _shape(areas.load(part))
        if shape.is_empty or shape.area == 0:
            continue
        best, best_key = None, (PART_SHARE, False, -np.inf, -1)
        for k in (outlines[i] for i in tree.query(shapely.box(*bounds[part]))):
            found, pure = candidate(k)
            if not found.intersects(shape):
                continue
            key = (round(found.intersection(shape).area / shape.area, 9), pure, -found.area, areas.index[k])
            if key >= best_key:
                best, best_key = k, key
        if best is not None:
            hosts[part] = best
    return hosts


def _with_parts(areas: _Areas, order: list[int]) -> tuple[list[int], dict[int, int], list[str]]:
    """Simple 3D Buildings: outlines that hold parts are replaced by them (the areas drawn, in file order, and
    each hosted part's outline); parts take the outline's other tags (:func:`_area`)."""
    hosts = _hosts(areas, order)
    drawn = set(hosts.values())
    note = [f"{len(drawn)} building outlines are drawn by their {len(hosts)} building:part areas (Simple 3D "
            "Buildings); set osm_parts = \"ignore\" to keep the outlines instead"] if drawn else []
    return [k for k in order if k not in drawn], hosts, note


def _area(areas: _Areas, k: int, host: int | None) -> _Area:
    """Area ``k``, a part with the tags of its ``host`` outline that are not its own shape's and height's."""
    area = areas.load(k)
    if host is None:
        return area
    outline = areas.load(host)
    inherited = {key: v for key, v in outline.tags.items() if not key.startswith(OWN_KEYS)}
    return replace(area, tags={**inherited, **area.tags, "building:outline": outline.id})


def _shape(area: _Area) -> shapely.Geometry:
    polys = [Polygon(p[0], p[1:]) for p in area.polygons if len(p[0]) >= 4]
    return shapely.make_valid(shapely.MultiPolygon(polys)) if polys else Polygon()


def stream_osm(path: Path, options: ImportOptions, warnings: tuple[str, ...] = ()) -> FootprintStream:
    """Footprints from an OpenStreetMap file (always lon/lat, EPSG:4326), as a stream: the areas libosmium
    assembles are put aside as they come, and handed over as footprints once the ids and the frame are fixed."""
    return _footprints(*read_areas(path), path, options, warnings)


def import_osm_json(doc: Mapping[str, Any], path: Path, options: ImportOptions, warnings: tuple[str, ...] = ()
                    ) -> ImportResult:
    """Footprints from an OSM JSON document (``osm_json``), read from a sorted copy as an OpenStreetMap file."""
    osmium = _osmium()
    elements, problems = osm_json_elements(doc, path.name)
    areas, order, skipped = _via_copy(osmium, elements, path)
    return _footprints(areas, order, skipped, problems, path, options, warnings).collected()


def _footprints(areas: _Areas, order: list[int], skipped: list[tuple[int, Skipped]], notes: list[str], path: Path,
                options: ImportOptions, warnings: tuple[str, ...]) -> FootprintStream:
    """The footprints of the building ``areas`` (in ``order``) read from ``path`` (Simple 3D Buildings parts
    applied), each put :class:`~citygen_footprints.assemble.Aside` as a feature."""
    if options.osm_parts == "replace":
        order, hosts, parts = _with_parts(areas, order)
        notes = [*notes, *parts]
    else:
        order, hosts = [k for k in order if not areas.part[k]], {}
    crs_warnings = [] if options.crs is None else [
        f"{path.name}: OpenStreetMap data is always lon/lat; the scene's crs {options.crs} is ignored"]
    aside = Aside()
    for k in order:
        area = _area(areas, k, hosts.get(k))
        where = f"{path.name}, {area.id}"
        attributes: dict[str, Any] = {**area.tags, "osm_type": area.id.split("/")[0],
                                      "osm_id": int(area.id.split("/")[1])}
        try:
            cleaned = clean_rings(area.polygons)
        except FeatureProblem as problem:
            skipped.append((area.index, Skipped(area.id, str(problem), where)))
            continue
        aside.add(RawFeature(area.index, area.id, where, f"{path.name}#{area.id}", attributes, cleaned.parts,
                             cleaned.warnings))
    areas.close()
    return assembled(aside.heads, aside.load, skipped, [*warnings, *crs_warnings, *notes],
                     parse_crs("EPSG:4326", str(path)), options, path)
