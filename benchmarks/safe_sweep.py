"""The facade sweep (tests/sweep.py) for the shipped ``.safe`` rulesets: outcomes, bad cases and CPU per case.

    .venv/bin/python benchmarks/safe_sweep.py [--small] [--rulesets cmp_b0035.safe] [--show 10]

Runs every ruleset over the full grid (widths 2-60 m x heights 3-60 m x storeys 2.6/3.0/3.6 m; ``--small``: the
test suite's bounded grid) and prints the count of each outcome, the CPU seconds per case (median, max) and the
first ``--show`` bad cases (a broken layout reported as a success) and fallbacks with their reasons.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from sweep import (HEIGHTS, SHIPPED, SMALL_HEIGHTS, SMALL_WIDTHS, STOREYS, WIDTHS,  # noqa: E402
                   run_case)

from citygen.registry import load_registry  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rulesets", nargs="*", default=[n for n in SHIPPED if n.endswith(".safe")])
    parser.add_argument("--small", action="store_true", help="the test suite's bounded grid")
    parser.add_argument("--show", type=int, default=10, help="bad cases and fallbacks listed per ruleset")
    args = parser.parse_args()
    widths, heights = (SMALL_WIDTHS, SMALL_HEIGHTS) if args.small else (WIDTHS, HEIGHTS)
    registry = load_registry()
    for name in args.rulesets:
        outcomes: Counter[str] = Counter()
        times, bad, fell = [], [], []
        for storey in STOREYS:
            for height in heights:
                for width in widths:
                    t0 = time.process_time()
                    case = run_case(registry, name, width, height, storey)
                    times.append(time.process_time() - t0)
                    outcomes[case.outcome] += 1
                    (bad if case.bad else fell if case.outcome != "dressed" else []).append(case)
        print(f"{name}: {len(times)} cases, " + ", ".join(f"{v} {k}" for k, v in sorted(outcomes.items()))
              + f"; CPU per case median {statistics.median(times):.3f} s, max {max(times):.2f} s, "
              f"total {sum(times):.1f} s")
        for case in bad[:args.show] + fell[:args.show]:
            print(f"  {case.outcome} {case.width:g} x {case.height:g} m, storey {case.storey:g}: "
                  + "; ".join(case.reasons[:3]))


if __name__ == "__main__":
    main()
