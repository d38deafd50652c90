"""CPU of a scene's builds (derivation, checks, roofs and geometry) in one process, and of their geometry part.

    python benchmarks/split_builds.py [SCENE] [--repeat N] [--limit N] [--profile [TOP]]

Builds every building of the scene ``--repeat`` times as ``citygen generate --jobs 1`` does (no stage is written)
and prints, per repeat, the CPU seconds of the builds (``Builder.build``, this thread) and of ``build_geometry``
inside them, then the least of each. The stage's bytes are checked by ``citygen generate`` itself (sha256 of the
written files); this only times.
``--profile`` builds once under cProfile instead and prints the function calls (which do not depend on the load)
and the ``TOP`` functions by own time.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from facade_phases import REPO, _work  # noqa: E402  (the scene's buildings, in the pipeline's order)
from profiling import profiled  # noqa: E402  (benchmarks/profiling.py)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(REPO / "scenes" / "helsinki.toml"))
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--limit", type=int, default=0, help="build only the first N buildings")
    parser.add_argument("--profile", type=int, nargs="?", const=40, default=0, metavar="TOP")
    args = parser.parse_args()
    import citygen.builder as builder_module
    from citygen.builder import Builder

    (scene, registry, rulesets), work = _work(Path(args.scene))
    if args.limit:
        work = work[: args.limit]
    geometry = [0.0]
    original = builder_module.build_geometry

    def timed(*a, **kw):
        start = time.thread_time()
        try:
            return original(*a, **kw)
        finally:
            geometry[0] += time.thread_time() - start

    if args.profile:
        builder = Builder(scene, scene.seed, registry, rulesets)
        profiled(lambda: [builder.build(*item) for item in work], args.profile)
        return
    builder_module.build_geometry = timed
    best = [float("inf"), float("inf")]
    for k in range(args.repeat):
        builder = Builder(scene, scene.seed, registry, rulesets)
        geometry[0] = 0.0
        start = time.thread_time()
        for item in work:
            builder.build(*item)
        total = time.thread_time() - start
        best = [min(best[0], total), min(best[1], geometry[0])]
        print(f"repeat {k + 1}: builds {total:.2f} s CPU (geometry {geometry[0]:.2f} s), "
              f"{1e3 * total / max(len(work), 1):.1f} ms per building", flush=True)
    print(f"{Path(args.scene).name}: {len(work)} buildings, least builds {best[0]:.2f} s CPU, "
          f"geometry {best[1]:.2f} s, derivation and checks {best[0] - best[1]:.2f} s (not from one repeat)")


if __name__ == "__main__":
    main()
