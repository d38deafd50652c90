"""The facade sweep (tests/sweep.py) for the split grammars: every outcome counted per ruleset.

Run: ``python benchmarks/split_sweep.py [--rulesets a.grammar b.grammar] [--small] [--grammars DIR]``. Prints one
line per ruleset: cases dressed / fell-back / implausible / constraints-broken / error and the most common finding
codes of the bad cases; ``--grammars DIR`` sweeps every ``*.grammar`` in DIR instead (e.g. extracted ones) at the
grid scaled around each grammar's ``@size`` (0.5x-2x).
"""
from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from citygen.registry import default_registry  # noqa: E402
from tests.sweep import HEIGHTS, SMALL_HEIGHTS, SMALL_WIDTHS, STOREYS, WIDTHS, classify, sweep  # noqa: E402

OUTCOMES = ("dressed", "fell-back", "implausible", "constraints-broken", "error")
SCALES = (0.5, 0.65, 0.8, 1.0, 1.25, 1.5, 1.7, 2.0)


def report(name: str, cases: list) -> Counter:
    counts = Counter(c.outcome for c in cases)
    codes = Counter(r.split(":")[0] for c in cases if c.bad for r in c.reasons[:1])
    print(f"{name:<28} " + " ".join(f"{counts[o]:>5}" for o in OUTCOMES) + "   " +
          ", ".join(f"{k} {v}" for k, v in codes.most_common(4)), flush=True)
    return counts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rulesets", nargs="*", default=["apartment.grammar", "house.grammar", "office.grammar",
                                                          "historic.grammar", "cmp_b0002.grammar"])
    parser.add_argument("--small", action="store_true", help="the bounded grid of the test suite")
    parser.add_argument("--grammars", type=Path, help="sweep every *.grammar here at 0.5x-2x its @size")
    args = parser.parse_args()
    registry = default_registry()
    start = time.perf_counter()
    print(f"{'ruleset':<28} " + " ".join(f"{o[:5]:>5}" for o in OUTCOMES))
    total: Counter = Counter()
    if args.grammars:
        from citygen_split import load
        for path in sorted(args.grammars.glob("*.grammar")):
            size = load(path).size
            kind = registry.kind_for_path(path)
            grammar = kind.load(path)
            cases = [classify(kind, grammar, path.name, sx * size[0], sy * size[1], storey)
                     for sx in SCALES for sy in SCALES for storey in (3.0,)]
            total += report(path.name, cases)
    else:
        widths, heights = (SMALL_WIDTHS, SMALL_HEIGHTS) if args.small else (WIDTHS, HEIGHTS)
        for name in args.rulesets:
            total += report(name, list(sweep(registry, (name,), widths, heights, STOREYS)))
    print(f"{'total':<28} " + " ".join(f"{total[o]:>5}" for o in OUTCOMES))
    print(f"{time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
