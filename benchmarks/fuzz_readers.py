"""Fuzz every reader of user-written files: bad input must give a CitygenError, never a traceback.

    .venv/bin/python benchmarks/fuzz_readers.py [--cases 300] [--readers split layers ...] [--timeout 10] [--seed 0]

Takes every shipped ruleset (``rulesets/``), layout JSON, scene (``scenes/``) and small footprint files and loads
mutated copies (``tests/mutate.py``: lines and tokens deleted, duplicated, swapped; numbers replaced by 0, -1,
nan, inf, 1e308, 1e-308, huge integers; stray brackets, unicode; truncation at every position of the small files;
JSON also mutated as a tree) through the public entry points: the ruleset kinds' ``load`` from
``default_registry()`` -- and, when it loads, ``generate`` of a 12 x 9 m preview --, ``FacadeLayout.loads``,
``load_scene`` and the footprint importers. Each mutation is also applied once per number (every number of the
file replaced by every edge value) for files of at most ``--exhaustive-below`` characters.

Prints per reader the cases run, how many loaded / were refused with a CitygenError, and every other exception
(type, message, the last frame) and every case over the timeout, with the input written to ``--out`` to
reproduce. A generated layout or footprint with a non-finite number counts as a failure too.
"""
from __future__ import annotations

import argparse
import json
import math
import random
import shutil
import signal
import sys
import tempfile
import time
import traceback
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
from tests.mutate import NUMBERS, mutate, number_spans  # noqa: E402

REGISTRY = default_registry()
RULESET_SUFFIXES = {"split": ".grammar", "layers": ".layers", "relayout": ".relayout", "safe": ".safe"}
SAFE_LAYOUT = "cmp_b0035.layout.json"


class Timeout(Exception):
    pass


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

    def _footprints(self, name: str, text: str | bytes) -> str:
        path = self.root / ("fuzz.city.json" if name.endswith(".city.json") else "fuzz.geojson")
        write(path, text)
        result = REGISTRY.importer_for(path).read(path, {})
        for fp in result.footprints:
            self._check_finite((fp.height, fp.base, fp.lift, *fp.polygon.bounds), f"footprint {fp.id}")
        return f"read ({len(result.footprints)} kept, {len(result.skipped)} skipped)"

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
        if reader == "footprints":
            return self._footprints(name, text)
        raise ValueError(reader)

    def case(self, reader: str, name: str, text: str | bytes) -> tuple[str, str | None, float]:
        """(outcome, failure description or None, CPU seconds)."""
        signal.setitimer(signal.ITIMER_REAL, self.timeout)
        t0 = time.process_time()
        try:
            outcome, failure = self.run(reader, name, text), None
        except CitygenError:
            outcome, failure = "refused", None
        except Timeout:
            outcome, failure = "timeout", f"over {self.timeout:g} s"
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=300, help="random mutations per shipped file")
    parser.add_argument("--readers", nargs="*", help="subset of: " + ", ".join(
        [*RULESET_SUFFIXES, "layout", "scene", "footprints"]))
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
                for what, mutated in cases(name, text, dialect, args.cases, rng, args.exhaustive_below):
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
        sample = args.out / f"{index:03d}-{reader}{suffix}"
        write(sample, shortest[2])
        print(f"[{reader}] {failure}\n    {len(hits)} case(s); e.g. {shortest[0]} {shortest[1]} -> {sample}")
    print(f"{len(failures)} distinct failures")


if __name__ == "__main__":
    main()
