"""The facade sweep and the scenes' face audit (issue: plausible facades on every face of a real city).

Sweep: every shipped ruleset (or ``--rulesets``) at widths 2-60 m x heights 3-60 m x storeys 2.6/3.0/3.6 m
(``tests/sweep.py``), each case classified as ``citygen facade`` classifies it. A *bad* case is a broken result
reported as a success (implausible, constraints broken); ``fell-back`` and ``error`` are clean failures that the
scene's fallback chain takes over. Scenes (``--scenes``): every face of each scene generated, with the report's
count of faces dressed, dressed by a fallback ruleset, left plain, and the plausibility findings.

    python benchmarks/facade_sweep.py [--rulesets a.grammar b.layers] [--small] [--scenes scenes/helsinki.toml]
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from citygen.pipeline import generate_city  # noqa: E402
from citygen.registry import default_registry  # noqa: E402
from citygen.scene import load_scene  # noqa: E402
from tests.sweep import (HEIGHTS, SHIPPED, SMALL_HEIGHTS, SMALL_WIDTHS, STOREYS, WIDTHS,  # noqa: E402
                         sweep)

OUTCOMES = ("dressed", "fell-back", "error", "implausible", "constraints-broken")


def run_sweep(names: list[str], small: bool, show: int) -> int:
    registry = default_registry()
    widths, heights = (SMALL_WIDTHS, SMALL_HEIGHTS) if small else (WIDTHS, HEIGHTS)
    print(f"sweep: {len(widths)} widths x {len(heights)} heights x {len(STOREYS)} storeys per ruleset")
    print(f"{'ruleset':<28}" + "".join(f"{o:>20}" for o in OUTCOMES) + f"{'ms/case':>10}")
    bad_total = 0
    for name in names:
        t0 = time.process_time()
        counts: Counter[str] = Counter()
        bad = []
        for case in sweep(registry, [name], widths, heights, STOREYS):
            counts[case.outcome] += 1
            if case.bad:
                bad.append(case)
        n = sum(counts.values())
        ms = 1000 * (time.process_time() - t0) / max(n, 1)
        print(f"{name:<28}" + "".join(f"{counts[o]:>20}" for o in OUTCOMES) + f"{ms:>10.1f}")
        for case in bad[:show]:
            print(f"    {case.outcome} at {case.width:g} x {case.height:g} m, storeys {case.storey:g}: "
                  f"{case.reasons[0] if case.reasons else ''}")
        bad_total += len(bad)
    print(f"bad cases (a broken facade reported as a success): {bad_total}")
    return bad_total


def run_scenes(paths: list[str]) -> None:
    for path in paths:
        scene = load_scene(path)
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            report = generate_city(scene, out=Path(tmp) / "audit.usdc", jobs=2)
            wall = time.perf_counter() - t0
        faces = report.faces
        total = faces["dressed"] + faces["fallback"] + faces["plain"] + faces["outside-range"]
        print(f"{path}: {report.written} buildings, {total} generated faces in {wall:.1f} s")
        print("   ", next(line for line in report.summary().splitlines() if line.startswith("facades:")))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rulesets", nargs="*", default=list(SHIPPED), help="shipped ruleset file names")
    parser.add_argument("--small", action="store_true", help="the test suite's bounded grid")
    parser.add_argument("--show", type=int, default=3, help="bad cases listed per ruleset")
    parser.add_argument("--scenes", nargs="*", default=[], help="scene files whose every face to audit")
    args = parser.parse_args()
    bad = run_sweep(args.rulesets, args.small, args.show) if args.rulesets else 0
    run_scenes(args.scenes)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
