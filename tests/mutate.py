"""Mutations of user-written input files, for the fuzz harness (``benchmarks/fuzz_readers.py``) and the bounded
property tests of every reader: delete/duplicate/swap lines and tokens, numbers replaced by edge values, stray
brackets, unicode, truncation; JSON documents also mutated as trees (values of the wrong type, keys removed).

Every mutation is a pure function of the text and a ``random.Random``, so a case is reproduced from its seed.
"""
from __future__ import annotations

import json
import math
import random
import re
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]

_NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?![\w.])")
_TOKEN = re.compile(r"[\w.+-]+|[^\w\s]")

#: Edge values for a number, per dialect (each is valid syntax where the format has NaN/inf at all).
NUMBERS = {
    "dsl": ("0", "-1", "nan", "inf", "-inf", "1e308", "1e-308", "1e400", "99999999999999999999999999", "-0", ""),
    "toml": ("0", "-1", "nan", "inf", "-inf", "1e308", "1e-308", "99999999999999999999999999", "-0.0", '""',
             "[]", "{}", "true"),
    "json": ("0", "-1", "NaN", "Infinity", "-Infinity", "1e308", "1e-308", "1e400", "99999999999999999999999999",
             '""', "null", "[]", "{}", "true", '"x"'),
}
#: Tokens that break structure or types.
ODD = ("", "[", "]", "{", "}", "(", ")", "'", '"', "|", ":", "=", ",", "..", "*", "%", "^", "é", "\u200b",
       "\U0001f3e0", "\x00", "true", "null", "x" * 300, "-", "#", ";", "\t", "\\")

#: Values a JSON tree mutation puts in place of a node.
JSON_VALUES: tuple[Any, ...] = (0, -1, math.nan, math.inf, -math.inf, 1e308, 1e-308, 10 ** 30, 10 ** 400, "", "x",
                                None, [], {}, True, "\U0001f3e0", [[]], [0, 0], {"type": None})


def _lines(text: str) -> list[str]:
    return text.splitlines(keepends=True) or [""]


def delete_line(text: str, rng: random.Random) -> str:
    lines = _lines(text)
    del lines[rng.randrange(len(lines))]
    return "".join(lines)


def duplicate_line(text: str, rng: random.Random) -> str:
    lines = _lines(text)
    i = rng.randrange(len(lines))
    lines.insert(i, lines[i] if lines[i].endswith("\n") else lines[i] + "\n")
    return "".join(lines)


def swap_lines(text: str, rng: random.Random) -> str:
    lines = _lines(text)
    i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
    lines[i], lines[j] = lines[j], lines[i]
    return "".join(line if line.endswith("\n") else line + "\n" for line in lines)


def _spans(pattern: re.Pattern[str], text: str) -> list[tuple[int, int]]:
    return [m.span() for m in pattern.finditer(text)]


def _replace(text: str, span: tuple[int, int], new: str) -> str:
    return text[:span[0]] + new + text[span[1]:]


def delete_token(text: str, rng: random.Random) -> str:
    spans = _spans(_TOKEN, text)
    return _replace(text, rng.choice(spans), "") if spans else text


def duplicate_token(text: str, rng: random.Random) -> str:
    spans = _spans(_TOKEN, text)
    if not spans:
        return text
    a, b = rng.choice(spans)
    return text[:b] + " " + text[a:b] + text[b:]


def swap_tokens(text: str, rng: random.Random) -> str:
    spans = _spans(_TOKEN, text)
    if len(spans) < 2:
        return text
    first, second = sorted(rng.sample(spans, 2))
    return (text[:first[0]] + text[second[0]:second[1]] + text[first[1]:second[0]] + text[first[0]:first[1]]
            + text[second[1]:])


def odd_token(text: str, rng: random.Random) -> str:
    """Replace a token by a bracket, quote, operator, unicode or a very long word."""
    spans = _spans(_TOKEN, text)
    return _replace(text, rng.choice(spans), rng.choice(ODD)) if spans else text


def insert_odd(text: str, rng: random.Random) -> str:
    i = rng.randrange(len(text) + 1)
    return text[:i] + rng.choice(ODD) + text[i:]


def nest_token(text: str, rng: random.Random) -> str:
    """Wrap a token in 40, 400 or 3000 levels of brackets or prefix operators (was RecursionError in four
    readers, issue 23)."""
    spans = _spans(_TOKEN, text)
    if not spans:
        return text
    span = rng.choice(spans)
    depth = rng.choice((40, 400, 3000))
    opening, closing = rng.choice((("(", ")"), ("{", "}"), ("[", "]"), ("-", ""), ("not ", "")))
    return _replace(text, span, opening * depth + text[span[0]:span[1]] + closing * depth)


def truncate(text: str, rng: random.Random) -> str:
    return text[:rng.randrange(len(text) + 1)]


def number_mutation(dialect: str) -> Callable[[str, random.Random], str]:
    def edge_number(text: str, rng: random.Random) -> str:
        spans = _spans(_NUMBER, text)
        return _replace(text, rng.choice(spans), rng.choice(NUMBERS[dialect])) if spans else text
    edge_number.__name__ = f"edge_number_{dialect}"
    return edge_number


def text_mutations(dialect: str) -> tuple[Callable[[str, random.Random], str], ...]:
    return (delete_line, duplicate_line, swap_lines, delete_token, duplicate_token, swap_tokens, odd_token,
            insert_odd, nest_token, truncate, number_mutation(dialect), number_mutation(dialect), number_mutation(dialect))


def number_spans(text: str) -> list[tuple[int, int]]:
    """Where the numbers are (for exhaustive edge-value replacement)."""
    return _spans(_NUMBER, text)


def _nodes(doc: Any, path: tuple = ()) -> list[tuple]:
    found = [path]
    if isinstance(doc, dict):
        for key, value in doc.items():
            found += _nodes(value, path + (key,))
    elif isinstance(doc, list):
        for index, value in enumerate(doc):
            found += _nodes(value, path + (index,))
    return found


def mutate_tree(doc: Any, rng: random.Random) -> Any:
    """A deep copy of ``doc`` with one node replaced, removed or duplicated."""
    doc = json.loads(json.dumps(doc))
    path = rng.choice(_nodes(doc))
    if not path:
        return rng.choice(JSON_VALUES)
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    key = path[-1]
    action = rng.randrange(4)
    if action == 0 and isinstance(parent, dict):
        del parent[key]
    elif action == 0 and isinstance(parent, list):
        del parent[key]
    elif action == 1 and isinstance(parent, list):
        parent.insert(key, json.loads(json.dumps(parent[key])))
    elif action == 2 and isinstance(parent, list) and len(parent) > 1:
        other = rng.randrange(len(parent))
        parent[key], parent[other] = parent[other], parent[key]
    else:
        parent[key] = rng.choice(JSON_VALUES)
    return doc


def mutate_json(text: str, rng: random.Random, rounds: int = 1) -> str:
    doc = json.loads(text)
    for _ in range(rounds):
        doc = mutate_tree(doc, rng)
    return json.dumps(doc, indent=1)


def mutate(text: str, dialect: str, rng: random.Random) -> str:
    """One random mutation (JSON: a tree mutation half of the time); occasionally two stacked."""
    rounds = 2 if rng.random() < 0.25 else 1
    for _ in range(rounds):
        if dialect == "json" and rng.random() < 0.5:
            try:
                text = mutate_json(text, rng)
                continue
            except ValueError:
                pass
        text = rng.choice(text_mutations(dialect))(text, rng)
    return text


def scratch_rulesets(directory: Path) -> Path:
    """A copy of the shipped ``rulesets/`` in ``directory`` (so mutated rulesets find the files they name)."""
    target = directory / "rulesets"
    if not target.exists():
        shutil.copytree(REPO / "rulesets", target)
    return target


def load_and_generate(path: Path) -> None:
    """Load a ruleset through its kind in the default registry and generate a 12 x 9 m preview; a CitygenError
    is a fine answer to bad input, anything else propagates (and so does a layout with a non-finite number)."""
    from citygen.errors import CitygenError
    from citygen.registry import default_registry
    from citygen.request import FacadeRequest
    kind = default_registry().kind_for_path(path)
    try:
        layout = kind.generate(kind.load(path), FacadeRequest.preview(12, 9))
    except CitygenError:
        return
    for r in layout.root.terminals():
        assert all(math.isfinite(v) for v in (r.x, r.y, r.w, r.h, r.depth)), r


def fuzz_ruleset(scratch: Path, original: Path, seed: int) -> None:
    """Mutate ``original`` (seeded), write it into ``scratch`` next to the shipped rulesets, load and generate."""
    text = mutate(original.read_text(encoding="utf-8"), "dsl", random.Random(seed))
    path = scratch / f"fuzz{original.suffix}"
    path.write_text(text, encoding="utf-8")
    load_and_generate(path)


# --- OpenStreetMap: a small model (nodes, ways, relations) mutated as objects, written with pyosmium ----------------

#: tags that carry a building's shape and height, and values they should never break the reader with
OSM_KEYS = ("height", "building:levels", "min_height", "building:min_level", "roof:shape", "roof:height",
            "roof:levels", "building:part", "building", "type")
OSM_VALUES = ("", "nan", "NaN", "inf", "-inf", "-5", "0", "1e308", "1e-308", "12 m", "3;4", "3-", ";", "-", "IV",
              "\u00e9t\u00e9", "\U0001f3e0", "\u200b", "9" * 40, "1" + "0" * 400, "12,5", "40 ft", "5'", "no",
              "yes", "multipolygon", "x" * 300)
MISSING_ID = 987_654_321_987


def osm_model(nodes: dict, ways: list, relations: list) -> dict:
    """{"nodes": {id: (lon, lat)}, "ways": [(id, [node ids], {tags})], "relations": [(id, [(t, ref, role)],
    {tags})]} -- plain data, so a mutation is a deep copy and an edit."""
    return {"nodes": dict(nodes), "ways": [(i, list(r), dict(t)) for i, r, t in ways],
            "relations": [(i, list(m), dict(t)) for i, m, t in relations]}


def mutate_osm(model: dict, rng: random.Random) -> dict:
    """One structural or tag mutation: an edge tag value, a way cut to 0/1/2 nodes, unclosed, with a missing or
    repeated node, a self-crossing (two nodes swapped), a duplicate id, a relation member missing or its role
    changed, a node moved to an edge coordinate."""
    model = osm_model(model["nodes"], model["ways"], model["relations"])
    ways, relations, nodes = model["ways"], model["relations"], model["nodes"]
    wi = rng.randrange(len(ways))
    wid, refs, tags = ways[wi]
    action = rng.randrange(11)
    if action in (0, 1, 2):  # tags: the most frequent mutation
        target = rng.choice([t for _, _, t in ways + relations] if action else [tags])
        target[rng.choice(OSM_KEYS)] = rng.choice(OSM_VALUES)
    elif action == 3:
        del refs[rng.choice((0, 1, 2)):]
    elif action == 4 and refs:
        refs.pop()
    elif action == 5 and refs:
        refs[rng.randrange(len(refs))] = rng.choice((MISSING_ID, -1, 0, refs[0]))
    elif action == 6 and len(refs) > 3:
        i, j = rng.sample(range(len(refs) - 1), 2)
        refs[i], refs[j] = refs[j], refs[i]
    elif action == 7:
        other = rng.choice(ways)
        if rng.random() < 0.5:  # two ways share an id
            ways[wi] = (other[0], refs, tags)
        else:  # a way repeated
            ways.append((other[0], list(other[1]), dict(other[2])))
    elif action == 8 and relations:
        rid, members, rtags = rng.choice(relations)
        if members:
            k = rng.randrange(len(members))
            kind, ref, role = members[k]
            choice = rng.randrange(3)
            if choice == 0:
                del members[k]
            elif choice == 1:
                members[k] = (kind, MISSING_ID, role)
            else:
                members[k] = (kind, ref, rng.choice(("", "inner", "outer", "x")))
    elif action == 9:
        nid = rng.choice(list(nodes))
        lon, lat = nodes[nid]
        edge = rng.choice((180.0, -180.0, 90.0, -90.0, 0.0, 179.9999999, 1e-7, lon + 1e-9))
        nodes[nid] = (edge, lat) if rng.random() < 0.5 else (lon, max(-90.0, min(90.0, edge)))
    else:
        del nodes[rng.choice(list(nodes))]
    return model


def write_osm(model: dict, path: Path) -> None:
    """Write the model as ``path``'s format (.osm XML, .opl, .osm.pbf) with pyosmium, sorted by type and id; a name
    with ``overpass`` in the order the Overpass API writes (ways and relations by id, then the nodes), and a
    ``.json`` name as OSM JSON in that order."""
    import osmium
    from osmium.osm.mutable import Node, Relation, Way
    nodes = sorted(model["nodes"].items())
    ways, relations = sorted(model["ways"], key=lambda w: w[0]), sorted(model["relations"], key=lambda r: r[0])
    path.unlink(missing_ok=True)
    if path.suffix == ".json":
        names = {"n": "node", "w": "way", "r": "relation"}
        elements = [{"type": "way", "id": i, "nodes": refs, "tags": tags} for i, refs, tags in ways]
        elements += [{"type": "relation", "id": i, "tags": tags, "members": [
            {"type": names.get(t, t), "ref": ref, "role": role} for t, ref, role in members]}
            for i, members, tags in relations]
        elements += [{"type": "node", "id": i, "lat": lat, "lon": lon} for i, (lon, lat) in nodes]
        path.write_text(json.dumps({"version": 0.6, "generator": "Overpass API", "elements": elements}))
        return
    writer = osmium.SimpleWriter(str(path))
    overpass = "overpass" in path.name

    def add_nodes() -> None:
        for nid, (lon, lat) in nodes:
            writer.add_node(Node(id=nid, location=(lon, lat), version=1))
    try:
        if not overpass:
            add_nodes()
        for wid, refs, tags in ways:  # libosmium wants files sorted by id
            writer.add_way(Way(id=wid, nodes=refs, tags=tags, version=1))
        for rid, members, tags in relations:
            writer.add_relation(Relation(id=rid, members=members, tags=tags, version=1))
        if overpass:
            add_nodes()
    finally:
        writer.close()


def mutate_bytes(data: bytes, rng: random.Random) -> bytes:
    """A binary file truncated, with bytes flipped or a block zeroed or repeated."""
    action = rng.randrange(4)
    if action == 0:
        return data[:rng.randrange(len(data) + 1)]
    out = bytearray(data)
    if action == 1:
        for _ in range(rng.choice((1, 1, 2, 8))):
            out[rng.randrange(len(out))] ^= 1 << rng.randrange(8)
        return bytes(out)
    at, size = rng.randrange(len(out)), rng.choice((4, 16, 256, 4096))
    if action == 2:
        out[at:at + size] = bytes(len(out[at:at + size]))
        return bytes(out)
    return bytes(out[:at + size] + out[at:])


# --- CityJSONSeq: one JSON value per line ---------------------------------------------------------------------------

TRANSFORM_VALUES: tuple[Any, ...] = (0, -1, math.nan, math.inf, -math.inf, 1e308, 1e-308, 10 ** 30, 10 ** 400, "1",
                                     None, [], 1e-300)


def mutate_jsonl(text: str, rng: random.Random) -> str:
    """A line dropped, duplicated, swapped or cut (``text_mutations``), one line mutated as a JSON tree, or the
    header's transform scale/translate given an edge value."""
    lines = text.splitlines()
    action = rng.randrange(4)
    if action == 0 or not lines:
        return rng.choice(text_mutations("json"))(text, rng)
    if action == 1:
        try:
            header = json.loads(lines[0])
            member = rng.choice(("scale", "translate"))
            header["transform"][member][rng.randrange(3)] = rng.choice(TRANSFORM_VALUES)
            lines[0] = json.dumps(header)
            return "\n".join(lines) + "\n"
        except (ValueError, KeyError, TypeError, IndexError):
            return text
    i = rng.randrange(len(lines))
    try:
        lines[i] = json.dumps(mutate_tree(json.loads(lines[i]), rng))
    except ValueError:
        lines[i] = rng.choice(text_mutations("json"))(lines[i], rng)
    return "\n".join(lines) + "\n"


# --- whole cities: a scene generated from (fuzzed) footprints, and what every run must give -------------------------

def generate_and_check(scene: Any, out: Path, registry: Any = None) -> Any:
    """``generate_city`` of ``scene`` with one job into ``out``, then what every city run must give whatever its
    footprints: zero ``citygen validate`` errors, finite points, no building skipped with an internal error (an
    AssertionError names the first problem). Returns the run's report."""
    import numpy as np
    from pxr import Usd, UsdGeom

    from citygen.pipeline import generate_city
    from citygen.usd.validate import validate_stage
    report = generate_city(scene, out=out, jobs=1, registry=registry)
    errors = [f for f in validate_stage(out) if f.severity == "error"]
    assert not errors, f"citygen validate: {len(errors)} errors, e.g. {errors[0].where}: {errors[0].message}"
    stage = Usd.Stage.Open(str(out))
    for prim in stage.Traverse(Usd.PrimAllPrimsPredicate):
        if prim.IsA(UsdGeom.PointBased):
            points = UsdGeom.PointBased(prim).GetPointsAttr().Get()
            assert points is None or np.isfinite(np.asarray(points)).all(), f"{prim.GetPath()} has non-finite points"
    internal = [s for s in report.skipped if s.reason.startswith("internal error")]
    assert not internal, f"skipped with an internal error: {internal[0].id}: {internal[0].reason}"
    return report


def city_of_footprints(scene: Any, out: Path, registry: Any = None) -> tuple[int, Any]:
    """The scene's footprint file read as ``generate_city`` reads it (a CitygenError propagates: the file is
    refused), then its city through :func:`generate_and_check`. Once the file is read -- with N footprints kept,
    any N -- the run must not raise at all, and every footprint must be written or skipped with a reason.
    Returns N and the report."""
    from citygen.errors import CitygenError
    from citygen.pipeline import import_footprints
    imported = import_footprints(scene, registry)
    kept = len(imported.footprints)
    try:
        report = generate_and_check(scene, out, registry)
    except CitygenError as exc:
        raise AssertionError(f"the city of a file read with {kept} footprints failed: {type(exc).__name__}: "
                             f"{exc}") from exc
    skipped = len(report.skipped) - len(imported.skipped)  # (the report lists the import's skips first)
    assert report.written + skipped == kept, f"{kept} footprints read, {report.written} written, {skipped} skipped"
    return kept, report
