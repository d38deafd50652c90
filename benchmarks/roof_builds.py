"""CPU and output digest of the roofs a scene's builds make, replayed alone.

    python benchmarks/roof_builds.py capture SCENE [SCENE ...] -o calls.pkl
    python benchmarks/roof_builds.py replay calls.pkl [--repeat N] [--profile]

``capture`` builds every building of the scenes as ``citygen generate --jobs 1`` does and records each call of a
roof builder (its id, outline, wall top and spec). ``replay`` makes those roofs again, ``--repeat`` times, and
prints the CPU seconds of each repeat and a sha256 of every mesh's bytes (points, counts, indices) and every
failure's message, in order: two versions of the roof code that print the same digest made the same roofs.
``--profile`` prints the function-call counts and the top functions of one repeat (cProfile).
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


def capture(scenes: list[str], out: Path) -> None:
    from facade_phases import _work  # (the scene's buildings, in the pipeline's order)

    from citygen.builder import Builder

    calls: list[tuple] = []
    for path in scenes:
        (scene, registry, rulesets), work = _work(Path(path))
        for builder in registry.roof_builders.values():
            original = builder.build

            def recorded(outline, top, spec=None, _id=builder.id, _build=original):
                calls.append((_id, outline, top, spec))
                return _build(outline, top, spec)

            builder.build = recorded
        build = Builder(scene, scene.seed, registry, rulesets)
        for item in work:
            build.build(*item)
        print(f"{Path(path).name}: {len(work)} buildings, {len(calls)} roof calls so far", flush=True)
    out.write_bytes(pickle.dumps(calls))


def replay(calls_path: Path, repeat: int, profile: bool) -> None:
    from citygen.registry import default_registry
    from citygen.roof import ROOF_BUDGET, roof_budget, roof_notes

    calls = pickle.loads(calls_path.read_bytes())
    roofs = default_registry().roof_builders

    def run() -> str:
        digest = hashlib.sha256()
        for shape, outline, top, spec in calls:
            try:
                with roof_notes() as notes, roof_budget(ROOF_BUDGET):
                    mesh = roofs[shape].build(outline, top, spec)
                for a in (mesh.points, mesh.counts, mesh.indices):
                    digest.update(a.tobytes())
                digest.update(repr(list(notes)).encode())
            except Exception as exc:  # noqa: BLE001 (a failure is an output too: the pipeline builds a flat roof)
                digest.update(f"{type(exc).__name__}: {exc}".encode())
        return digest.hexdigest()

    if profile:
        profiled(run, 25)
        return
    for k in range(repeat):
        start = time.process_time()
        digest = run()
        print(f"repeat {k + 1}: {len(calls)} roofs, {time.process_time() - start:.3f} s CPU, digest {digest}",
              flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    cap = sub.add_parser("capture")
    cap.add_argument("scenes", nargs="+")
    cap.add_argument("-o", "--out", type=Path, required=True)
    rep = sub.add_parser("replay")
    rep.add_argument("calls", type=Path)
    rep.add_argument("--repeat", type=int, default=3)
    rep.add_argument("--profile", action="store_true")
    args = parser.parse_args()
    if args.command == "capture":
        capture(args.scenes, args.out)
    else:
        replay(args.calls, args.repeat, args.profile)


if __name__ == "__main__":
    main()
