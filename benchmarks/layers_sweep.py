"""The facade sweep for the shipped layer stacks (or any `.layers` files): outcomes per ruleset over the full grid.

    python benchmarks/layers_sweep.py [--rulesets terraced_house.layers ...] [--small] [--show N]

Prints, per ruleset, how many cases were dressed / fell back / implausible / constraints-broken / error, the solve
time, and the first ``--show`` bad cases with their reasons. Exit status 1 when any case is bad.
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


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rulesets", nargs="*", default=[n for n in sw.SHIPPED if n.endswith(".layers")])
    parser.add_argument("--small", action="store_true", help="the test suite's bounded grid")
    parser.add_argument("--show", type=int, default=5, help="bad / fell-back cases to print per ruleset")
    args = parser.parse_args()
    registry = default_registry()
    widths, heights = (sw.SMALL_WIDTHS, sw.SMALL_HEIGHTS) if args.small else (sw.WIDTHS, sw.HEIGHTS)
    any_bad = False
    for name in args.rulesets:
        start = time.process_time()
        cases = list(sw.sweep(registry, (name,), widths, heights))
        cpu = time.process_time() - start
        counts = Counter(c.outcome for c in cases)
        print(f"{name}: {len(cases)} cases, " + ", ".join(f"{v} {k}" for k, v in sorted(counts.items()))
              + f"; {cpu:.1f} s CPU ({1000 * cpu / len(cases):.0f} ms a case)")
        shown = 0
        for c in cases:
            if c.outcome != "dressed" and shown < args.show:
                shown += 1
                print(f"  {c.outcome} {c.width:g} x {c.height:g} storey {c.storey:g}: {'; '.join(c.reasons[:2])}")
        any_bad |= any(c.bad for c in cases)
    return 1 if any_bad else 0


if __name__ == "__main__":
    sys.exit(main())
