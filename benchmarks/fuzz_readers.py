"""Fuzz every reader of user-written files: bad input must give a CitygenError, never a traceback.

    .venv/bin/python benchmarks/fuzz_readers.py [--cases 300] [--readers split layers ...] [--timeout 10] [--seed 0]

Takes every shipped ruleset (``rulesets/``), layout JSON, scene (``scenes/``) and small footprint files and loads
mutated copies (``tests/mutate.py``: lines and tokens deleted, duplicated, swapped; numbers replaced by 0, -1,
nan, inf, 1e308, 1e-308, huge integers; stray brackets, unicode; truncation at every position of the small files;
JSON also mutated as a tree) through the public entry points: the ruleset kinds' ``load`` from
``default_registry()`` -- and, when it loads, ``generate`` of a 12 x 9 m preview --, ``FacadeLayout.loads``,
``load_scene`` and the footprint importers. Each mutation is also applied once per number (every number of the
file replaced by every edge value) for files of at most ``--exhaustive-below`` characters.

Four more readers: ``osm`` -- the building ways and multipolygons near the first ``building:part`` of
``helsinki.osm.pbf`` written as .osm XML, .opl and .osm.pbf, mutated as objects (edge tag values of ``height``,
``building:levels``, ``min_height``, ``roof:*``, ``building:part``; ways cut to 0/1/2 nodes, unclosed, with missing
or swapped nodes; duplicate ids; multipolygon members missing; nodes at edge coordinates), then as text, or the PBF
as bytes (truncated, flipped bits, zeroed or repeated blocks); ``cityjsonseq`` -- three Delft buildings as
CityJSONSeq, lines dropped, duplicated, swapped, cut, mutated as JSON trees, the header's transform given edge
values; ``extreme`` -- a fixed list of huge-but-finite footprints (coordinates, z, heights, widths, tags; EXTREME)
among three good ones through ``generate_city`` and ``citygen validate``: a run must write a stage with zero
validation errors and finite points, keep the good buildings and skip the bad one with a reason (not an
internal error); ``osm-city`` -- the ``osm`` reader's mutated files (``--cases`` // OSM_CITY_SHARE of them per
format, at least one: each case is a city of up to 40 buildings) as the footprints of the Helsinki OSM demo scene
(``scenes/helsinki_osm.toml``: its rules, roofs and ground) through ``generate_city``: when the importer reads
the file (N footprints kept, any N, none required), the city run must not raise, must write a stage with zero
validation errors and finite points, and every footprint must be written or skipped with a reason that is not an
internal error. ``cmp``: the CMP annotations of ``tests/data/inverse`` (label maps and label table beside them)
through ``import_cmp``, then greedy extraction: an import must give an exact partition whose grammar re-derives it.

Prints per reader the cases run, how many loaded / were refused with a CitygenError, and every other exception
(type, message, the last frame) and every case over the timeout, with the input written to ``--out`` to
reproduce (an ``osm-city`` input is the footprint file: run it with the demo scene's ``[footprints] path`` set to
it). A generated layout or footprint with a non-finite number counts as a failure too, and so does a
RuntimeWarning (numpy or shapely overflow printed among the messages) from a footprint reader.
"""
from __future__ import annotations

import argparse
import json
import math
import random
import re
import shutil
import signal
import sys
import tempfile
import time
import traceback
import warnings
from collections import Counter, defaultdict
from collections.abc import Iterator
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from citygen.errors import CitygenError  # noqa: E402
from citygen.layout import FacadeLayout  # noqa: E402
from citygen.registry import default_registry  # noqa: E402
from citygen.request import FacadeRequest  # noqa: E402
from citygen.scene import load_scene  # noqa: E402
from tests.mutate import (NUMBERS, city_of_footprints, generate_and_check, mutate, mutate_bytes,  # noqa: E402
                          mutate_jsonl, mutate_osm, number_spans, osm_model, write_osm)

REGISTRY = default_registry()
RULESET_SUFFIXES = {"split": ".grammar", "layers": ".layers", "relayout": ".relayout", "safe": ".safe"}
SAFE_LAYOUT = "cmp_b0035.layout.json"
EXTREME_SLACK = 6  # an extreme or osm-city case generates and validates a city: its limit is this many --timeout
CITY_READERS = ("extreme", "osm-city")
OSM_CITY_SHARE = 5  # osm-city runs --cases // OSM_CITY_SHARE mutated files per format (a city each, ~1.5 s CPU)
OSM_CITY_SCENE = "helsinki_osm.toml"  # its rules and output settings, with a fuzzed file as its footprints
CMP = REPO / "tests/data/inverse"  # CMP annotations (with their label maps and label table)
#: readers whose runs must not print numpy / shapely RuntimeWarnings either
FOOTPRINT_READERS = ("footprints", "osm", "cityjsonseq", *CITY_READERS)


#: huge-but-finite values end to end: (case, spec); each spec is one bad building among three good ones (x, y:
#: metres from the first corner; w: width; z: base; h: wall height), ``tags`` its tags, ``options`` the scene's
#: [footprints] keys; ``cityjson`` writes a CityJSON file without CRS (coordinates taken as metres), else GeoJSON
#: in EPSG:3067
EXTREME: list[tuple[str, dict]] = [
    *[(f"x = {x:g}", {"x": x}) for x in (1e7, 1e15, 1e300, -1e300)],
    *[(f"cityjson x = {x:g}", {"x": x, "cityjson": True}) for x in (1e7, 1e15, 1e300, -1e300)],
    *[(f"cityjson z = {z:g}", {"z": z, "cityjson": True}) for z in (1e7, 1e15, 1e300, -1e300)],
    *[(f"cityjson h = {h:g}", {"h": h, "cityjson": True}) for h in (1e4, 1e15, 1e300)],
    ("width 1e-12", {"w": 1e-12, "cityjson": True}),
    ("width 1e-12, min_area 1e-30", {"w": 1e-12, "cityjson": True, "options": {"min_area": 1e-30}}),
    ("width 1e-6, min_area 1e-30", {"w": 1e-6, "cityjson": True, "options": {"min_area": 1e-30}}),
    ("width 1e7", {"w": 1e7, "cityjson": True}),
    *[(f"height={v}", {"tags": {"height": v}}) for v in ("1e15", "1e300", "-1e300", "10000")],
    ("height=10000, max_height 20000", {"tags": {"height": "10000"}, "options": {"max_height": 20000}}),
    ("building:levels=1e15", {"tags": {"building:levels": "1e15"}}),
    ("min_height=1e300", {"tags": {"height": "12", "min_height": "1e300"}}),
    ("min_height=999", {"tags": {"height": "1000", "min_height": "999.99"}}),
    *[(f"{k}={v}", {"tags": {"height": "12", "roof:shape": "gabled", k: v}})
      for k, v in (("roof:height", "1e300"), ("roof:height", "10000"), ("roof:levels", "1e15"),
                   ("roof:angle", "89.9999999"), ("roof:angle", "1e300"), ("roof:height", "1e-300"))],
]
EXTREME_RULESET = "house.grammar"


def extreme_files(directory: Path, spec: dict) -> Path:
    """The footprint file and scene of one EXTREME case in ``directory``; returns the scene path."""
    boxes = [(0.0, 0.0, 10.0, 0.0, 9.0, {}), (20.0, 0.0, 10.0, 0.0, 9.0, {}), (0.0, 20.0, 10.0, 0.0, 9.0, {}),
             (spec.get("x", 40.0), spec.get("y", 0.0), spec.get("w", 10.0), spec.get("z", 0.0), spec.get("h", 9.0),
              spec.get("tags", {}))]
    if spec.get("cityjson"):
        objects, vertices = {}, []
        for k, (x, y, w, z, h, tags) in enumerate(boxes):
            first = len(vertices)
            vertices += [[x + dx, y + dy, zz] for zz in (z, z + h) for dx, dy in ((0, 0), (w, 0), (w, 10), (0, 10))]
            faces = [[[0, 3, 2, 1]], [[4, 5, 6, 7]], [[0, 1, 5, 4]], [[1, 2, 6, 5]], [[2, 3, 7, 6]], [[3, 0, 4, 7]]]
            objects[f"b{k}"] = {"type": "Building", "attributes": tags, "geometry": [{
                "type": "Solid", "lod": "1", "boundaries": [[[[first + i for i in f[0]]] for f in faces]]}]}
        doc = {"type": "CityJSON", "version": "2.0", "CityObjects": objects, "vertices": vertices}
        footprints = directory / "extreme.city.json"
    else:
        features = []
        for k, (x, y, w, _, _, tags) in enumerate(boxes):
            x0, y0 = 385_000.0 + x, 6_672_000.0 + y
            ring = [[x0, y0], [x0 + w, y0], [x0 + w, y0 + 10], [x0, y0 + 10], [x0, y0]]
            features.append({"type": "Feature", "id": f"b{k}", "properties": {"building": "yes", **tags},
                              "geometry": {"type": "Polygon", "coordinates": [ring]}})
        doc = {"type": "FeatureCollection", "crs": {"type": "name", "properties": {"name": "EPSG:3067"}},
               "features": features}
        footprints = directory / "extreme.geojson"
    footprints.write_text(json.dumps(doc))
    options = "".join(f"{k} = {v!r}\n" for k, v in spec.get("options", {}).items())
    scene = directory / "extreme.toml"
    scene.write_text(f'[scene]\nseed = 1\n[footprints]\npath = "{footprints.name}"\n{options}'
                     f'[[assign]]\nruleset = "{(REPO / "rulesets" / EXTREME_RULESET).as_posix()}"\n'
                     '[output]\npath = "extreme.usda"\n')
    return scene


class Timeout(BaseException):
    """A case over the time limit (not an Exception: the pipeline's per-building guard must not catch it)."""


def _alarm(signum, frame):  # noqa: ARG001
    raise Timeout()


def write(path: Path, content: str | bytes) -> None:
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content, encoding="utf-8")


def small_cityjson(objects: int = 3) -> str:
    """The first ``objects`` buildings of the Delft CityJSON (with their parts), vertices renumbered."""
    doc = json.loads((REPO / "scenes/data/delft_buildings.city.json").read_text())
    keep: dict = {}
    for oid, obj in doc["CityObjects"].items():
        if obj.get("type") == "Building" and len([k for k in keep if doc["CityObjects"][k]["type"] == "Building"]) \
                < objects:
            keep[oid] = obj
            for child in obj.get("children", []):
                keep[child] = doc["CityObjects"][child]
    old = doc["vertices"]
    index: dict[int, int] = {}

    def remap(b):
        if isinstance(b, list):
            return [remap(x) for x in b]
        if b not in index:
            index[b] = len(index)
        return index[b]
    for obj in keep.values():
        for geometry in obj.get("geometry", []):
            geometry["boundaries"] = remap(geometry["boundaries"])
            geometry.pop("semantics", None)
    doc["CityObjects"] = keep
    doc["vertices"] = [old[i] for i in sorted(index, key=index.get)]
    return json.dumps(doc, indent=1)


def small_osm(buildings: int = 40) -> dict:
    """The building ways and multipolygon relations of ``helsinki.osm.pbf`` (outlines and ``building:part``s)
    within about 110 m of its first ``building:part``, at most ``buildings`` of them, with their nodes, as a
    ``tests.mutate.osm_model``."""
    import osmium
    pbf = REPO / "scenes/data/helsinki.osm.pbf"
    located = osmium.FileProcessor(pbf, osmium.osm.NODE | osmium.osm.WAY).with_locations()
    lon, lat = next((o.nodes[0].lon, o.nodes[0].lat) for o in located if o.is_way() and "building:part" in o.tags)
    ways, relations, members = [], [], set()
    for o in osmium.FileProcessor(pbf, osmium.osm.ALL).with_locations():
        if o.is_relation() and o.tags.get("type") == "multipolygon" and "building" in o.tags and len(relations) < 2:
            refs = [(m.type, m.ref, m.role) for m in o.members]
            if len(refs) <= 6:
                relations.append((o.id, refs, dict(o.tags)))
                members |= {ref for kind, ref, _ in refs if kind == "w"}
        elif o.is_way() and ("building" in o.tags or "building:part" in o.tags) and len(ways) < buildings and \
                o.nodes[0].location.valid() and abs(o.nodes[0].lon - lon) < 2e-3 and abs(o.nodes[0].lat - lat) < 1e-3:
            ways.append((o.id, [n.ref for n in o.nodes], dict(o.tags)))
    taken = {w[0] for w in ways}
    for o in osmium.FileProcessor(pbf, osmium.osm.WAY):
        if o.id in members and o.id not in taken:
            ways.append((o.id, [n.ref for n in o.nodes], dict(o.tags)))
    wanted = {ref for _, refs, _ in ways for ref in refs}
    nodes = {o.id: (o.lon, o.lat) for o in osmium.FileProcessor(pbf, osmium.osm.NODE) if o.id in wanted}
    return osm_model(nodes, ways, relations)


def small_cityjsonseq(objects: int = 3) -> str:
    """``small_cityjson`` as CityJSON Text Sequences: a header line, then one CityJSONFeature per building."""
    doc = json.loads(small_cityjson(objects))
    header = {k: v for k, v in doc.items() if k not in ("CityObjects", "vertices")}
    header.update(CityObjects={}, vertices=[])
    lines = [json.dumps(header)]
    for oid, obj in doc["CityObjects"].items():
        if obj["type"] != "Building":
            continue
        objects_ = {oid: obj, **{c: doc["CityObjects"][c] for c in obj.get("children", [])}}
        index: dict[int, int] = {}

        def remap(b):
            if isinstance(b, list):
                return [remap(x) for x in b]
            return index.setdefault(b, len(index))
        for o in objects_.values():
            for geometry in o.get("geometry", []):
                geometry["boundaries"] = remap(geometry["boundaries"])
        vertices = [doc["vertices"][i] for i in sorted(index, key=index.get)]
        lines.append(json.dumps({"type": "CityJSONFeature", "id": oid, "CityObjects": objects_,
                                 "vertices": vertices}))
    return "\n".join(lines) + "\n"


def seeds() -> dict[str, list[tuple[str, str, str]]]:
    """reader -> [(name, text, dialect)] of the shipped inputs."""
    out: dict[str, list[tuple[str, str, str]]] = defaultdict(list)
    for reader, suffix in RULESET_SUFFIXES.items():
        for path in sorted((REPO / "rulesets").glob(f"*{suffix}")):
            out[reader].append((path.name, path.read_text(), "dsl"))
    out["safe"].append((SAFE_LAYOUT, (REPO / "rulesets" / SAFE_LAYOUT).read_text(), "json"))
    for path in sorted((REPO / "rulesets").glob("*.layout.json")):
        out["layout"].append((path.name, path.read_text(), "json"))
    for path in sorted((REPO / "scenes").glob("*.toml")):
        out["scene"].append((path.name, path.read_text(), "toml"))
    for path in (REPO / "scenes/data/roofs_demo.geojson", REPO / "tests/data/footprints/bad_footprints.geojson"):
        out["footprints"].append((path.name, path.read_text(), "json"))
    out["footprints"].append(("delft3.city.json", small_cityjson(), "json"))
    model = small_osm()
    out["osm"] += [("helsinki.osm", model, "osm"), ("helsinki.opl", model, "osm"), ("helsinki.osm.pbf", model, "pbf"),
                   ("helsinki_overpass.osm", model, "osm"), ("helsinki_overpass.json", model, "osmjson")]
    out["osm-city"] = list(out["osm"])
    out["cityjsonseq"].append(("delft3.city.jsonl", small_cityjsonseq(), "jsonl"))
    out["extreme"] += [(what, spec, "extreme") for what, spec in EXTREME]
    for path in sorted(CMP.glob("*.xml")):
        out["cmp"].append((path.name, path.read_text(), "dsl"))
    return out


class Runner:
    """Loads one mutated input in a scratch copy of ``rulesets/`` and ``scenes/``."""

    def __init__(self, root: Path, timeout: float) -> None:
        self.root, self.timeout = root, timeout
        shutil.copytree(REPO / "rulesets", root / "rulesets")
        (root / "scenes").mkdir()
        self.request = FacadeRequest.preview(12, 9)

    def _check_finite(self, values: Iterator[float], what: str) -> None:
        for value in values:
            if not math.isfinite(value):
                raise ValueError(f"{what} has a non-finite number: {value!r}")

    def _ruleset(self, reader: str, name: str, text: str | bytes) -> str:
        rulesets = self.root / "rulesets"
        if name == SAFE_LAYOUT:  # the layout a .safe ruleset edits
            write(rulesets / SAFE_LAYOUT, text)
            target = rulesets / "cmp_b0035.safe"
        else:
            target = rulesets / f"fuzz{RULESET_SUFFIXES[reader]}"
            write(target, text)
        try:
            kind = REGISTRY.kind_for_path(target)
            ruleset = kind.load(target)
            layout = kind.generate(ruleset, self.request)
            self._check_finite((v for r in layout.root.terminals() for v in (r.x, r.y, r.w, r.h, r.depth)), "layout")
            return "generated"
        finally:
            if name == SAFE_LAYOUT:
                shutil.copy(REPO / "rulesets" / SAFE_LAYOUT, rulesets / SAFE_LAYOUT)

    def _footprints(self, name: str, data: str | bytes) -> str:
        path = self.root / f"fuzz{''.join(Path(name).suffixes)}"  # (the suffixes choose the importer)
        write(path, data)
        result = REGISTRY.importer_for(path).read(path, {})
        for fp in result.footprints:
            self._check_finite((fp.height, fp.base, fp.lift, *fp.polygon.bounds), f"footprint {fp.id}")
        return f"read ({len(result.footprints)} kept, {len(result.skipped)} skipped)"

    def _extreme(self, spec: dict) -> str:
        directory = self.root / "extreme"
        shutil.rmtree(directory, ignore_errors=True)
        directory.mkdir()
        scene = extreme_files(directory, spec)
        report = generate_and_check(load_scene(scene), directory / "extreme.usda", REGISTRY)
        if report.written < 3:
            raise ValueError(f"a good building was lost: written {report.written}, skipped "
                             f"{[(s.id, s.reason) for s in report.skipped]}")
        return f"generated ({report.written} written, {len(report.skipped)} skipped)"

    def _osm_city(self, name: str, data: str | bytes) -> str:
        """The fuzzed file as the footprints of the OSM demo scene, written beside the copied ``rulesets/``."""
        directory = self.root / "scenes"
        footprints = directory / f"fuzz-city{''.join(Path(name).suffixes)}"
        write(footprints, data)
        demo = (REPO / "scenes" / OSM_CITY_SCENE).read_text(encoding="utf-8")
        scene_path = directory / "fuzz-city.toml"
        write(scene_path, re.sub(r'(?m)^path = "data/[^"]*"', f'path = "{footprints.name}"', demo, count=1))
        scene = load_scene(scene_path)
        if scene.footprints.resolve() != footprints.resolve():
            raise RuntimeError(f"{OSM_CITY_SCENE} no longer names its footprints as path = \"data/...\"")
        out = self.root / "osm-city" / "city.usda"
        shutil.rmtree(out.parent, ignore_errors=True)
        out.parent.mkdir()
        kept, report = city_of_footprints(scene, out, REGISTRY)
        return f"generated ({kept} read, {report.written} written, {kept - report.written} skipped)"

    def _cmp(self, name: str, text: str | bytes) -> str:
        from citygen.layout import check_partition
        from citygen_inverse.cmp import import_cmp
        from citygen_inverse.extract import extract_grammar
        from citygen_inverse.verify import mismatches
        directory = self.root / "cmp"
        if not directory.exists():  # the label table and label maps beside the annotations, as in the CMP set
            shutil.copytree(CMP, directory, ignore=shutil.ignore_patterns("*.xml"))
        write(directory / name, text)
        layout = import_cmp(directory / name)
        problems = check_partition(layout) or mismatches(extract_grammar(layout, "greedy").text, layout)
        if problems:
            raise ValueError(f"imported layout: {problems[0]}")
        return "imported"

    def run(self, reader: str, name: str, text: str | bytes) -> str:
        if reader in RULESET_SUFFIXES:
            return self._ruleset(reader, name, text)
        if reader == "layout":
            FacadeLayout.loads(text.decode("latin-1") if isinstance(text, bytes) else text, name)
            return "loaded"
        if reader == "scene":
            path = self.root / "scenes" / "fuzz.toml"
            write(path, text)
            load_scene(path)
            return "loaded"
        if reader in ("footprints", "osm", "cityjsonseq"):
            return self._footprints(name, text)
        if reader == "extreme":
            return self._extreme(text)
        if reader == "osm-city":
            return self._osm_city(name, text)
        if reader == "cmp":
            return self._cmp(name, text)
        raise ValueError(reader)

    def case(self, reader: str, name: str, text: str | bytes) -> tuple[str, str | None, float]:
        """(outcome, failure description or None, CPU seconds)."""
        limit = self.timeout * (EXTREME_SLACK if reader in CITY_READERS else 1)  # (a whole city run per case)
        signal.setitimer(signal.ITIMER_REAL, limit)
        t0 = time.process_time()
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", RuntimeWarning)
                outcome, failure = self.run(reader, name, text), None
            noisy = [w for w in caught if issubclass(w.category, RuntimeWarning)]
            if noisy and reader in FOOTPRINT_READERS:  # numpy / shapely noise on stderr among the skip reasons
                where = f"{Path(noisy[0].filename).name}:{noisy[0].lineno}"
                outcome, failure = "crash", f"RuntimeWarning @ {where}: {str(noisy[0].message)[:160]}"
        except CitygenError:
            outcome, failure = "refused", None
        except Timeout:
            outcome, failure = "timeout", f"over {limit:g} s"
        except RecursionError as exc:
            outcome, failure = "crash", f"RecursionError: {str(exc)[:100]}"
        except Exception as exc:  # noqa: BLE001 -- the point: anything that is not a CitygenError
            frame = traceback.extract_tb(exc.__traceback__)[-1]
            where = f"{Path(frame.filename).name}:{frame.lineno} in {frame.name}"
            outcome, failure = "crash", f"{type(exc).__name__} @ {where}: {str(exc)[:160]}"
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
        return outcome, failure, time.process_time() - t0


def cases(name: str, text: str, dialect: str, count: int, rng: random.Random, exhaustive_below: int
          ) -> Iterator[tuple[str, str | bytes]]:
    """(description, mutated text): ``count`` random mutations, then for small files every truncation and every
    number replaced by every edge value."""
    for i in range(count):
        yield f"random #{i}", mutate(text, dialect, rng)
    for _ in range(3):  # not UTF-8
        data = text.encode()
        at = rng.randrange(len(data) + 1)
        yield f"byte 0xff at {at}", data[:at] + b"\xff" + data[at:]
    if len(text) <= exhaustive_below:
        for i in range(len(text)):
            yield f"truncated at {i}", text[:i]
        for a, b in number_spans(text):
            for value in NUMBERS[dialect]:
                yield f"number {text[a:b]!r} at {a} -> {value!r}", text[:a] + value + text[b:]


def osm_cases(name: str, model: dict, dialect: str, count: int, rng: random.Random, scratch: Path
              ) -> Iterator[tuple[str, str | bytes]]:
    """``count`` OSM files: the model mutated (``mutate_osm``, one to three times) and written in ``name``'s format
    (``write_osm``: also as Overpass writes XML and OSM JSON); text formats also get a text mutation a third of
    the time, PBF a byte mutation (truncation, flipped bytes, zeroed or repeated blocks) half of the time."""
    path = scratch / f"render-{name}"  # (the name chooses the format and order: see ``write_osm``)
    write_osm(model, path)
    seed = path.read_bytes()
    for i in range(count):
        if dialect == "pbf" and rng.random() < 0.5:
            yield f"random bytes #{i}", mutate_bytes(seed, rng)
            continue
        mutated = model
        for _ in range(rng.choice((1, 1, 2, 3))):
            mutated = mutate_osm(mutated, rng)
        try:
            write_osm(mutated, path)
        except Exception:  # noqa: BLE001 -- pyosmium cannot write it: not a case
            continue
        data = path.read_bytes()
        if dialect == "pbf":
            yield f"random model #{i}", mutate_bytes(data, rng) if rng.random() < 0.25 else data
        elif rng.random() < 1 / 3:
            yield f"random model+text #{i}", mutate(data.decode(), "json" if dialect == "osmjson" else "dsl", rng)
        else:
            yield f"random model #{i}", data.decode()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=300, help="random mutations per shipped file (osm-city: a "
                        f"city per case, --cases // {OSM_CITY_SHARE} per file)")
    parser.add_argument("--readers", nargs="*", help="subset of: " + ", ".join(
        [*RULESET_SUFFIXES, "layout", "scene", "footprints", "osm", "osm-city", "cityjsonseq", "extreme", "cmp"]))
    parser.add_argument("--timeout", type=float, default=10.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--exhaustive-below", type=int, default=1600, help="file size for exhaustive mutations")
    parser.add_argument("--out", type=Path, default=Path("fuzz-failures"), help="where failing inputs go")
    args = parser.parse_args()
    signal.signal(signal.SIGALRM, _alarm)
    failures: dict[tuple[str, str], list[tuple[str, str, str, str]]] = defaultdict(list)
    with tempfile.TemporaryDirectory() as tmp:
        runner = Runner(Path(tmp), args.timeout)
        for reader, files in seeds().items():
            if args.readers and reader not in args.readers:
                continue
            counts: Counter[str] = Counter()
            slowest = (0.0, "")
            t_reader = time.process_time()
            for name, text, dialect in files:
                rng = random.Random(f"{args.seed}:{reader}:{name}")
                if dialect in ("osm", "pbf", "osmjson"):
                    count = max(1, args.cases // OSM_CITY_SHARE) if reader == "osm-city" else args.cases
                    generated = osm_cases(name, text, dialect, count, rng, Path(tmp))
                elif dialect == "jsonl":
                    generated = ((f"random #{i}", mutate_jsonl(text, rng)) for i in range(args.cases))
                elif dialect == "extreme":
                    generated = iter([(name, text)])
                else:
                    generated = cases(name, text, dialect, args.cases, rng, args.exhaustive_below)
                for what, mutated in generated:
                    outcome, failure, seconds = runner.case(reader, name, mutated)
                    counts[outcome.split(" (")[0]] += 1
                    slowest = max(slowest, (seconds, f"{name} {what}"))
                    if failure:
                        failures[(reader, failure.split(": ")[0])].append((name, what, mutated, failure))
            total = sum(counts.values())
            print(f"{reader:10s} {total:6d} cases, {dict(sorted(counts.items()))}, "
                  f"{time.process_time() - t_reader:.1f} CPU s, slowest {slowest[0]:.2f} s ({slowest[1]})",
                  flush=True)
    if failures:
        args.out.mkdir(parents=True, exist_ok=True)
    for index, ((reader, _), hits) in enumerate(sorted(failures.items())):
        shortest = min(hits, key=lambda h: len(h[2]))
        failure = shortest[3]
        suffix = Path(shortest[0]).suffix
        sample = args.out / f"{index:03d}-{reader}{'.json' if reader == 'extreme' else suffix}"
        write(sample, json.dumps(shortest[2]) if isinstance(shortest[2], dict) else shortest[2])
        print(f"[{reader}] {failure}\n    {len(hits)} case(s); e.g. {shortest[0]} {shortest[1]} -> {sample}")
    print(f"{len(failures)} distinct failures")


if __name__ == "__main__":
    main()
