"""Exactness sweep of grammar extraction over every CMP facade (wu2014: grammars that describe the input exactly).

    python benchmarks/inverse_sweep.py [--iterations N] [--limit K]

Per facade: import with default options, extract greedy and ADP(N) (default 200), re-derive both at the input size
(every terminal rectangle and label, `citygen_inverse.verify.mismatches`), extract the size-independent grammar
from the greedy search and derive it at three other face sizes (each a partition). Prints failures, ADP below
greedy, and the greedy CPU distribution. Skips cleanly when the shared data is absent.
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import citygen_split
from citygen.errors import CitygenError
from citygen.layout import check_partition
from citygen.request import FacadeRequest
from citygen_inverse.cmp import import_cmp
from citygen_inverse.extract import extract_grammar
from citygen_inverse.independent import extract_size_independent
from citygen_inverse.verify import mismatches

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "cmp_facade" / "base"
SIZES = ((0.6, 0.8), (1.7, 1.0), (2.9, 1.4))  # (width, height) factors of the input size


def sweep(path: Path, iterations: int) -> tuple[list[str], float, float, float]:
    """Problems found on one facade, greedy cost, ADP cost and greedy CPU seconds."""
    layout = import_cmp(path)
    greedy = extract_grammar(layout, "greedy")
    adp = extract_grammar(layout, "adp", iterations)
    problems = [f"{name}: {p}" for name, e in (("greedy", greedy), ("adp", adp)) for p in mismatches(e.text, layout)]
    if adp.cost > greedy.cost + 1e-9:
        problems.append(f"ADP cost {adp.cost:.1f} above greedy {greedy.cost:.1f}")
    grammar = citygen_split.parse(extract_size_independent(layout, "greedy").text, path.name)
    for fw, fh in SIZES:
        derived = citygen_split.derive(grammar, FacadeRequest.preview(layout.width * fw, layout.height * fh))
        problems += [f"size-independent at {fw} x {fh}: {p}" for p in check_partition(derived)[:2]]
    return problems, greedy.cost, adp.cost, greedy.cpu_seconds


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--iterations", type=int, default=200)
    parser.add_argument("--limit", type=int, default=0, help="first K facades (0 = all)")
    args = parser.parse_args()
    files = sorted(DATA.glob("cmp_*.xml"))[: args.limit or None]
    if not files:
        print(f"no CMP data at {DATA}; nothing to sweep")
        return 0
    failed, below, cpu, start = 0, [], [], time.process_time()
    for path in files:
        try:
            problems, g, a, t = sweep(path, args.iterations)
        except CitygenError as exc:
            problems, g, a, t = [f"error: {exc}"], 0.0, 0.0, 0.0
        if problems:
            failed += 1
            print(f"{path.name}: " + "; ".join(problems[:3]))
        if g > 0:
            below.append(100 * (g - a) / g)
            cpu.append(1e3 * t)
    cpu.sort()
    print(f"{len(files)} facades, {failed} with problems, {time.process_time() - start:.0f} s cpu")
    print(f"ADP {args.iterations} below greedy: mean {statistics.fmean(below):.1f} %, "
          f"min {min(below):.1f} %, max {max(below):.1f} %")
    print(f"greedy cpu ms: median {cpu[len(cpu) // 2]:.0f}, p90 {cpu[int(0.9 * len(cpu))]:.0f}, max {cpu[-1]:.0f}")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
