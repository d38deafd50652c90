"""OSM JSON (the Overpass API's ``[out:json]``, Overpass Turbo's "raw OSM data" export) as OpenStreetMap elements.

The document is ``{"elements": [...]}``: nodes ``{"type": "node", "id", "lat", "lon"}``, ways ``{"type": "way",
"id", "nodes": [ids]}`` and relations ``{"type": "relation", "id", "members": [{"type", "ref", "role"}]}``, with
``"tags"``. ``out geom`` puts the coordinates on the ways (``"geometry"``, one point per node, null outside the
query's box) and on the relations' members (member ways without node ids, which get ids above the file's
largest). Elements are yielded as ``osm_sorted.sorted_copy`` takes them; a malformed one is left out with a
warning naming it, and an element of another type (``area``, ``count``) is ignored.
"""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

_KIND = {"node": "n", "way": "w", "relation": "r"}


def is_osm_json(doc: Any) -> bool:
    return isinstance(doc, Mapping) and "type" not in doc and isinstance(doc.get("elements"), list)


def osm_json_elements(doc: Mapping[str, Any], where: str) -> tuple[list[tuple], list[str]]:
    """The document's nodes, ways and relations (``sorted_copy``'s tuples), and a warning per element left out."""
    elements: list[tuple] = []
    problems: list[str] = []
    geometry: list[tuple[int, list]] = []  # (place in ``elements``, points) of ways and members with coordinates
    for k, e in enumerate(doc["elements"]):
        kind = _kind(e.get("type")) if isinstance(e, Mapping) else None
        if kind is None:
            if not isinstance(e, Mapping):
                problems.append(f"{where}: element {k} is not an object -- left out")
            continue
        i = e.get("id")
        tags = e.get("tags", {})
        if not _is_id(i) or not isinstance(tags, Mapping):
            problems.append(f"{where}: element {k} ({e.get('type')} {i!r}): no integer id, or tags that are not an "
                            "object -- left out")
            continue
        tags = {str(key): str(value) for key, value in tags.items()}
        if kind == "n":
            elements.append(("n", i, *_point(e)))
        elif kind == "w":
            refs = e.get("nodes")
            if not isinstance(refs, list) or not all(map(_is_id, refs)):
                problems.append(f"{where}: element {k} (way {i}): \"nodes\" is not a list of node ids -- left out")
                continue
            elements.append(("w", i, refs, tags))
            if isinstance(e.get("geometry"), list):
                geometry.append((len(elements) - 1, e["geometry"]))
        else:
            members = e.get("members")
            if not isinstance(members, list) or not all(
                    isinstance(m, Mapping) and _kind(m.get("type")) and _is_id(m.get("ref")) for m in members):
                problems.append(f"{where}: element {k} (relation {i}): \"members\" is not a list of {{type, ref, "
                                "role}} -- left out")
                continue
            elements.append(("r", i, [(_KIND[m["type"]], m["ref"], str(m.get("role", ""))) for m in members], tags))
            geometry += [(-1, m) for m in members if m["type"] == "way" and isinstance(m.get("geometry"), list)]
    return elements + _geometry_nodes(elements, geometry), problems


def _geometry_nodes(elements: list[tuple], geometry: list[tuple[int, Any]]) -> list[tuple]:
    """Nodes for the coordinates ``out geom`` puts on ways, and ways for the relation members it describes by
    coordinates alone (their nodes numbered above the largest node id)."""
    out: list[tuple] = []
    ways = {e[1] for e in elements if e[0] == "w"}
    next_id = max((e[1] for e in elements if e[0] == "n"), default=0)
    next_id = max([next_id, *(r for e in elements if e[0] == "w" for r in e[2])]) + 1
    for place, g in geometry:
        if place >= 0:  # a way: one point per node id
            refs = elements[place][2]
            out += [("n", r, *_point(p)) for r, p in zip(refs, g) if isinstance(p, Mapping)]
        elif g["ref"] not in ways:  # a member way known only by its coordinates
            points = [_point(p) for p in g["geometry"] if isinstance(p, Mapping)]
            refs = list(range(next_id, next_id + len(points)))
            next_id += len(points)
            out += [("n", r, *p) for r, p in zip(refs, points)]
            out.append(("w", g["ref"], refs, {}))
            ways.add(g["ref"])
    return out


def _point(e: Mapping[str, Any]) -> tuple[float | None, float | None]:
    """(lon, lat) of a node or geometry point; (None, None) when missing, not finite or out of range."""
    lon, lat = _coordinate(e.get("lon"), 180), _coordinate(e.get("lat"), 90)
    return (None, None) if lon is None or lat is None else (lon, lat)


def _coordinate(v: Any, limit: float) -> float | None:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return None
    return float(v) if -limit <= v <= limit else None  # (NaN fails the test; huge integers are compared exactly)


def _kind(v: Any) -> str | None:
    return _KIND.get(v) if isinstance(v, str) else None


def _is_id(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool) and -(1 << 62) < v < 1 << 62
