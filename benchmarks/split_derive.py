"""Median time to derive each shipped grammar on a 20 x 15 m and an 80 x 60 m face.

Run: ``python benchmarks/split_derive.py [--repeat N]``. Prints one line per grammar and size: median and best
milliseconds, and the number of terminal regions.
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from citygen.request import FacadeRequest
from citygen_split import derive, load

RULESETS = Path(__file__).resolve().parents[1] / "rulesets"
SIZES = ((20.0, 15.0), (80.0, 60.0))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=15)
    args = parser.parse_args()
    print(f"{'grammar':<12} {'face':>9} {'median ms':>10} {'best ms':>9} {'terminals':>10}")
    for path in sorted(RULESETS.glob("*.grammar")):
        grammar = load(path)
        for width, height in SIZES:
            request = FacadeRequest.preview(width, height, ground_height=4.0, entrance=True)
            request = FacadeRequest(width=width, height=height, floor_lines=request.floor_lines, entrance=True,
                                    corner_widths=(0.4, 0.4), context=request.context, seed=(1,))
            times = []
            for _ in range(args.repeat):
                start = time.perf_counter()
                layout = derive(grammar, request)
                times.append((time.perf_counter() - start) * 1e3)
            print(f"{path.stem:<12} {f'{width:g}x{height:g}':>9} {statistics.median(times):>10.2f} "
                  f"{min(times):>9.2f} {len(layout.terminals()):>10}")


if __name__ == "__main__":
    main()
