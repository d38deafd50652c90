"""A copy of an OpenStreetMap file in the order libosmium needs, for files written by other tools than osmium.

libosmium reads a file in one pass with a node location index: nodes, then ways, then relations, each sorted by
id, every object once, no negative id. Common files break this, and without the copy they lose their buildings:

* Overpass API exports (Overpass Turbo's ``out body; >; out skel qt;``) list the buildings' ways first and their
  nodes after them, in quad-tile order: every way lost all its nodes;
* files saved by an editor (JOSM) give new objects negative ids, which the location index cannot hold, and keep
  deleted objects marked ``action="delete"``, which libosmium reads as any other;
* extracts concatenated instead of merged repeat objects (libosmium stops at the second).

``sorted_copy`` writes the file's objects sorted by type and id, the last of repeated ones, negative ids moved
above the largest id of their type (``plain`` reads them with pyosmium, leaving the deleted ones out). Nodes are
held as arrays (24 bytes each), ways and relations as tuples; nodes' tags are dropped (no building is a node).
"""
from __future__ import annotations

import bz2
import gzip
import re
from array import array
from pathlib import Path

import numpy as np

_XML = ((".osm", open), (".osm.gz", gzip.open), (".osm.bz2", bz2.open))  # (what an editor saves)
_DELETE = re.compile(rb"""action\s*=\s*["']delete["']""")
_ELEMENT = re.compile(rb"""<\s*(node|way|relation)\b[^>]*?\bid\s*=\s*["'](-?\d+)["']""")
_NAME = {"w": "way", "r": "relation"}


def deleted_marks(path: Path, chunk: int = 1 << 24) -> set[tuple[str, int]]:
    """(type letter, id) of the objects an editor marked ``action="delete"`` in an XML file; the file is
    streamed, only the elements holding the mark are parsed."""
    opener = next((o for suffix, o in _XML if path.name.lower().endswith(suffix)), None)
    if opener is None:
        return set()
    found: set[tuple[str, int]] = set()
    tail = b""
    try:
        with opener(path, "rb") as f:
            while block := f.read(chunk):
                data = tail + block
                for mark in _DELETE.finditer(data):
                    start = data.rfind(b"<", 0, mark.start())
                    element = _ELEMENT.match(data, start) if start >= 0 else None
                    if element and data.find(b">", start, mark.start()) < 0:
                        found.add((element.group(1)[:1].decode(), int(element.group(2))))
                tail = data[-4096:]  # (an element cut at the block's end is seen again whole)
    except (OSError, EOFError, ValueError):
        return set()  # (libosmium then reports what is wrong with the file)
    return found


def plain(objects, deleted: set[tuple[str, int]] = frozenset()):
    """pyosmium's nodes, ways and relations as ``sorted_copy`` takes them, without the ``deleted`` ones; an object
    libosmium reads as deleted (``visible="false"``, an osmChange ``<delete>``) as a deleted one."""
    for obj in objects:
        kind = obj.type_str()
        if (kind, obj.id) in deleted:
            continue
        if not obj.visible:
            yield kind, obj.id, None, None
        elif kind == "n":
            where = obj.location
            yield ("n", obj.id, where.lon, where.lat) if where.valid() else ("n", obj.id, None, None)
        elif kind == "w":
            yield "w", obj.id, [n.ref for n in obj.nodes], dict(obj.tags)
        else:
            yield "r", obj.id, [(m.type, m.ref, m.role) for m in obj.members], dict(obj.tags)


def sorted_copy(osmium, elements, out: Path) -> dict[str, tuple[str, int]]:
    """Write ``elements`` -- ("n", id, lon, lat) (lon, lat None: no location), ("w", id, node ids, tags),
    ("r", id, [(type letter, ref, role)], tags), a way or relation with None for both deleted (a later version
    of an object replaces an earlier one) -- to ``out`` as libosmium needs them (module docstring).
    Returns per way and relation of the copy its name and place among the ways and relations read
    (``"way/-5"``, first appearance)."""
    ids, lons, lats = array("q"), array("d"), array("d")
    ways: dict[int, tuple] = {}
    relations: dict[int, tuple] = {}
    first: dict[tuple[str, int], int] = {}
    for kind, i, a, b in elements:
        if kind == "n":
            ids.append(i)
            lons.append(np.nan if a is None else a)
            lats.append(np.nan if b is None else b)
            continue
        first.setdefault((kind, i), len(first))
        (ways if kind == "w" else relations)[i] = (a, b)
    node_ids = np.frombuffer(ids, dtype=np.int64)
    top = {"n": int(node_ids.max(initial=0)), "w": max([0, *ways]), "r": max([0, *relations])}
    for kind, low in (("n", int(node_ids.min(initial=0))), ("w", min([0, *ways])), ("r", min([0, *relations]))):
        if top[kind] - low >= 1 << 63:
            raise OverflowError(f"{_NAME.get(kind, 'node')} ids {low} and {top[kind]} are too far apart to renumber "
                                "the negative ones")

    def new(kind: str, i: int) -> int:
        return top[kind] - i if i < 0 else i

    mutable, location = osmium.osm.mutable, osmium.osm.Location
    writer = osmium.SimpleWriter(str(out))
    try:
        renumbered = np.where(node_ids < 0, top["n"] - node_ids, node_ids)
        order = np.argsort(renumbered, kind="stable")
        last = np.ones(order.size, dtype=bool)  # the last of equal ids
        last[:-1] = renumbered[order[1:]] != renumbered[order[:-1]]
        keep = order[last]
        lon, lat = np.frombuffer(lons), np.frombuffer(lats)
        for i, x, y in zip(renumbered[keep].tolist(), lon[keep].tolist(), lat[keep].tolist()):
            writer.add_node(mutable.Node(id=i, location=location() if x != x else location(x, y)))
        for i in sorted(ways, key=lambda i: new("w", i)):
            refs, tags = ways[i]
            if tags is None:
                continue
            writer.add_way(mutable.Way(id=new("w", i), tags=tags, nodes=[new("n", r) for r in refs]))
        for i in sorted(relations, key=lambda i: new("r", i)):
            members, tags = relations[i]
            if tags is None:
                continue
            writer.add_relation(mutable.Relation(id=new("r", i), tags=tags, members=[
                (t, new(t, r), role) for t, r, role in members]))
    finally:
        writer.close()
    return {f"{_NAME[kind]}/{new(kind, i)}": (f"{_NAME[kind]}/{i}", place) for (kind, i), place in first.items()}
