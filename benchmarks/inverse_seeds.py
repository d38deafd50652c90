"""ADP over several seeds per CMP facade, reported as wu2014 Table 1 does: minimum and mean of the runs.

    python benchmarks/inverse_seeds.py [--runs K] [--iterations N] [--limit L]

wu2014 Table 1 gives, for ADP and importance sampling, the minimum (left) and the average (right) cost of ten runs
and one greedy cost; its "28 % below greedy" is the minimum column (110 vs 152.7; the average column, 121.8, is
20 % below). Per facade this prints greedy cost, ADP cost min / mean over seeds 0..K-1 and both gaps; then the
means over the facades. Skips cleanly when the shared data is absent.
"""
from __future__ import annotations

import argparse
import statistics
from pathlib import Path

from citygen_inverse.cmp import import_cmp
from citygen_inverse.extract import extract_grammar

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "cmp_facade" / "base"


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=10, help="seeds 0..K-1 per facade")
    parser.add_argument("--iterations", type=int, default=2000)
    parser.add_argument("--limit", type=int, default=0, help="first L facades (0 = all)")
    args = parser.parse_args()
    files = sorted(DATA.glob("cmp_*.xml"))[: args.limit or None]
    if not files:
        print(f"no CMP data at {DATA}; skipped")
        return 0
    greedy, best, mean = [], [], []
    for path in files:
        layout = import_cmp(path)
        g = extract_grammar(layout, "greedy").cost
        costs = [extract_grammar(layout, "adp", args.iterations, seed=s).cost for s in range(args.runs)]
        greedy.append(g), best.append(min(costs)), mean.append(statistics.mean(costs))
        print(f"{path.stem}: greedy {g:.1f} | ADP min {best[-1]:.1f} mean {mean[-1]:.1f} "
              f"(spread {max(costs) - min(costs):.1f}) | below greedy: min {100 * (1 - best[-1] / g):.1f} %, "
              f"mean {100 * (1 - mean[-1] / g):.1f} %", flush=True)
    gap = lambda a: 100 * statistics.mean(1 - x / g for x, g in zip(a, greedy))  # noqa: E731
    print(f"{len(files)} facades, ADP {args.iterations} x {args.runs} seeds: greedy mean cost "
          f"{statistics.mean(greedy):.1f}; ADP min {statistics.mean(best):.1f} ({gap(best):.1f} % below greedy), "
          f"ADP mean {statistics.mean(mean):.1f} ({gap(mean):.1f} % below greedy)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
