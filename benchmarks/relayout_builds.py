"""CPU and output digest of the relayout faces of a scene's builds (or of a grid of buildings), replayed alone.

    python benchmarks/relayout_builds.py capture SCENE [SCENE ...] -o calls.pkl
    python benchmarks/relayout_builds.py replay calls.pkl [--repeat N] [--profile]
    python benchmarks/relayout_builds.py grid [--repeat N] [--profile] [--models townhouse ...]

``capture`` builds every building of the scenes as ``citygen generate --jobs 1`` does and records each call of
the relayout kind's ``generate_building`` (the model and the building's face requests). ``replay`` dresses those
buildings again; ``grid`` dresses 4-face buildings of the shipped models on a grid of sizes, floor heights,
entrance faces and seeds (the faces of ``tests/relayout/test_building.py``). Both print the CPU seconds of the
dressing in each repeat and a sha256 of every layout (its JSON, exact floats, and which regions share a module
key), in order: two versions of the relayout code that print the same digest made the same layouts. ``--profile``
prints the function-call counts and the top functions of one repeat (cProfile).
"""
from __future__ import annotations

import argparse
import hashlib
import pickle
import sys
import time
from pathlib import Path

from profiling import profiled  # (benchmarks/profiling.py)

sys.path.insert(0, str(Path(__file__).resolve().parent))
REPO = Path(__file__).resolve().parents[1]
GRID_MODELS = ("townhouse", "fig7_walkthrough", "cmp_b0035")


def capture(scenes: list[str], out: Path) -> None:
    from facade_phases import _work  # (the scene's buildings, in the pipeline's order)

    from citygen.builder import Builder

    calls: list[tuple] = []
    for path in scenes:
        (scene, registry, rulesets), work = _work(Path(path))
        kind = registry.ruleset_kind("relayout")
        original = kind.generate_building

        def recorded(model, requests, _build=original):
            calls.append((model, list(requests)))
            return _build(model, requests)

        kind.generate_building = recorded
        build = Builder(scene, scene.seed, registry, rulesets)
        for item in work:
            build.build(*item)
        kind.generate_building = original
        print(f"{Path(path).name}: {len(work)} buildings, {len(calls)} relayout buildings so far", flush=True)
    out.write_bytes(pickle.dumps(calls))


def grid_calls(models: list[str]) -> list[tuple]:
    """4-face buildings (faces 1.0, 1.2, 1.4, 1.6 x the width; corner strips 0.3 / 0.4 m) of each model."""
    from citygen.request import FacadeRequest, FaceContext, split_floors
    from citygen_relayout import load_model

    sizes = {"townhouse": ((5.5, 9.0, 14.0, 21.0), (7.0, 11.25, 16.0)),
             "fig7_walkthrough": ((9.5, 12.0, 15.0), (10.0, 14.0, 19.0)),
             "cmp_b0035": ((9.5, 15.6, 24.0), (10.5, 14.0, 20.0))}
    calls = []
    for name in models:
        model = load_model(REPO / "rulesets" / f"{name}.relayout")
        widths, heights = sizes[name]
        for floors in ((3.0, 3.6), (3.2, 4.0)):
            for height in heights:
                for width in widths:
                    for seed in (0, 1):
                        lines = split_floors(height, *floors)
                        entrance = (seed + int(width)) % 4
                        calls.append((model, [
                            FacadeRequest(width * (1 + 0.2 * i), height, lines, entrance=i == entrance,
                                          corner_widths=(0.3, 0.4), context=FaceContext("b", i, len(lines) - 1),
                                          seed=(seed, i)) for i in range(4)]))
    return calls


def digest_of(layouts, digest) -> None:
    """Feed each layout's JSON and its module-key classes (first-seen order; the keys' values are per process)."""
    for layout in layouts:
        digest.update(layout.dumps().encode())
        classes: dict[int, int] = {}
        stack = [layout.root]
        while stack:
            region = stack.pop()
            if region.key is not None:
                digest.update(b"k%d" % classes.setdefault(region.key, len(classes)))
            else:
                digest.update(b"-")
            stack.extend(reversed(region.children))


def replay(calls: list[tuple], repeat: int, profile: bool) -> None:
    from citygen_relayout.building import generate_building

    def run() -> list:
        return [generate_building(model, requests) for model, requests in calls]

    def summary(built: list) -> tuple[str, int]:
        digest = hashlib.sha256()
        for layouts in built:
            digest_of(layouts, digest)
        return digest.hexdigest(), sum(1 for layouts in built for lay in layouts if lay.meta.get("fallback"))

    faces = sum(len(r) for _, r in calls)
    if profile:
        print(f"digest {summary(profiled(run, 30))[0]}")
        return
    for k in range(repeat):
        start = time.process_time()
        built = run()
        cpu = time.process_time() - start
        digest, fallbacks = summary(built)
        print(f"repeat {k + 1}: {len(calls)} buildings, {faces} faces ({fallbacks} fell back), "
              f"{cpu:.3f} s CPU, digest {digest}", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    cap = sub.add_parser("capture")
    cap.add_argument("scenes", nargs="+")
    cap.add_argument("-o", "--out", type=Path, required=True)
    for name in ("replay", "grid"):
        rep = sub.add_parser(name)
        if name == "replay":
            rep.add_argument("calls", type=Path)
        else:
            rep.add_argument("--models", nargs="+", default=list(GRID_MODELS), choices=GRID_MODELS)
        rep.add_argument("--repeat", type=int, default=3)
        rep.add_argument("--profile", action="store_true")
    args = parser.parse_args()
    if args.command == "capture":
        capture(args.scenes, args.out)
    elif args.command == "replay":
        replay(pickle.loads(args.calls.read_bytes()), args.repeat, args.profile)
    else:
        replay(grid_calls(args.models), args.repeat, args.profile)


if __name__ == "__main__":
    main()
