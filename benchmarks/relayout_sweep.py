"""The facade sweep for relayout models: every shipped ``.relayout`` ruleset over the sweep grid, outcomes counted.

    python benchmarks/relayout_sweep.py [--small] [--rulesets townhouse.relayout ...] [--show bad|fell-back|all]

Prints, per ruleset, the cases dressed / fell-back / implausible / constraints-broken / error, the CPU seconds per
case (median, max), and the first reasons of the cases asked for with ``--show``.
"""
from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from citygen.registry import default_registry  # noqa: E402
from tests import sweep as sw  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rulesets", nargs="*", default=[n for n in sw.SHIPPED if n.endswith(".relayout")])
    parser.add_argument("--small", action="store_true", help="the test suite's bounded grid")
    parser.add_argument("--show", choices=("bad", "fell-back", "all"), default=None)
    args = parser.parse_args(argv)
    registry = default_registry()
    widths, heights = (sw.SMALL_WIDTHS, sw.SMALL_HEIGHTS) if args.small else (sw.WIDTHS, sw.HEIGHTS)
    bad = 0
    for name in args.rulesets:
        counts: Counter = Counter()
        times = []
        for storey in sw.STOREYS:
            for height in heights:
                for width in widths:
                    t0 = time.process_time()
                    case = sw.run_case(registry, name, width, height, storey)
                    times.append(time.process_time() - t0)
                    counts[case.outcome] += 1
                    bad += case.bad
                    if args.show and (args.show == "all" or case.outcome == args.show
                                      or (args.show == "bad" and case.bad)):
                        print(f"  {name} {width:g} x {height:g} / {storey:g}: {case.outcome}: "
                              f"{'; '.join(case.reasons[:2])[:200]}")
        times.sort()
        print(f"{name}: {sum(counts.values())} cases: " + ", ".join(f"{v} {k}" for k, v in sorted(counts.items()))
              + f"; CPU s per case median {times[len(times) // 2]:.3f}, max {times[-1]:.2f}, total {sum(times):.1f}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
