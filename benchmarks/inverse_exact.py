"""How far ADP is from the cheapest grammar: method exact over the CMP facades.

    python benchmarks/inverse_exact.py [--limit N] [--every K] [--iterations 2000] [--time-limit 20]

Per facade (every K-th of the first N base facades, imported with default options): greedy, ADP(N) and exact
(the same ADP run, then the integer program over the same candidate rules, ``exact.py``, stopped after
``--time-limit`` seconds) cost, the program's lower bound and whether it proved its grammar optimal. The summary
gives the mean cost below greedy of ADP and of exact, and the most any grammar over the candidate rules can be
below greedy on average (the lower bounds: for a facade whose program was stopped the bound, not a grammar). Skips
cleanly when the shared data is absent.
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from citygen_inverse.cmp import import_cmp
from citygen_inverse.extract import extract_grammar

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "cmp_facade" / "base"


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--limit", type=int, default=300)
    parser.add_argument("--every", type=int, default=1)
    parser.add_argument("--iterations", type=int, default=2000)
    parser.add_argument("--time-limit", type=float, default=20.0, help="seconds of the integer program")
    args = parser.parse_args()
    files = sorted(DATA.glob("*.xml"))[: args.limit: args.every]
    if not files:
        print(f"no CMP data under {DATA}; skipped")
        return 0
    rows = []
    for f in files:
        layout = import_cmp(f)
        greedy = extract_grammar(layout, "greedy")
        adp = extract_grammar(layout, "adp", args.iterations, seed=0)
        t = time.process_time()
        exact = extract_grammar(layout, "exact", args.iterations, seed=0, time_limit=args.time_limit + adp.seconds)
        cpu = time.process_time() - t - adp.cpu_seconds  # (about: the program's share of the run)
        rows.append((f.stem, greedy.terminals, greedy.cost, adp.cost, exact.cost, exact.bound, exact.optimal, cpu))
        print(f"{f.stem}: {greedy.terminals} T | greedy {greedy.cost:.1f} | ADP {adp.cost:.1f} | exact "
              f"{exact.cost:.1f} | bound {exact.bound:.1f} | {'optimal' if exact.optimal else 'stopped'} | "
              f"program {cpu:.2f} s cpu", flush=True)
    below = lambda cost, greedy: 100 * (1 - cost / greedy)  # noqa: E731
    proven = [r for r in rows if r[6]]
    print(f"{len(rows)} facades, mean {statistics.mean(r[1] for r in rows):.0f} terminals; proven optimal: "
          f"{len(proven)} (program median {statistics.median(r[7] for r in proven) if proven else 0:.2f} s cpu)")
    mean = lambda k: statistics.mean(below(r[k], r[2]) for r in rows)  # noqa: E731
    print(f"below greedy on average: ADP {mean(3):.2f} %, exact {mean(4):.2f} %, at most {mean(5):.2f} % (by the "
          "lower bounds)")
    print(f"exact cheaper than ADP on {sum(r[4] < r[3] - 1e-9 for r in rows)}; ADP already optimal on "
          f"{sum(abs(r[3] - r[4]) < 1e-9 for r in proven)} of the {len(proven)} proven; on those ADP is "
          f"{statistics.mean(r[3] - r[4] for r in proven) if proven else 0:.2f} above the optimum on average")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
