"""Roof time against courtyard count: one square footprint with ``h`` square courtyards on a grid (issue 23 #2).

    .venv/bin/python benchmarks/roof_courtyards.py [--shape hipped] [--holes 10 25 50 100 200] [--repeat 1]

Prints per count the outline's vertices, the roof's CPU time (process_time, best of ``--repeat``) and the time per
vertex, and the fitted exponent ``k`` of ``time ~ vertices^k`` between the first and last counts.
"""
from __future__ import annotations

import argparse
import math
import random
import time

from shapely.geometry import Polygon

from citygen.registry import default_registry
from citygen.roof import roof_spec


def courtyards(holes: int, cell: float = 10.0, hole: float = 4.0, seed: int = 0) -> Polygon:
    """A square of ``ceil(sqrt(holes))`` cells a side, ``holes`` of its cells with a courtyard near the middle
    (moved up to 1 m at random: a grid of equal courtyards is a storm of simultaneous events)."""
    rng = random.Random(seed)
    side = math.ceil(math.sqrt(holes))
    interiors = []
    for k in range(holes):
        x0 = (k % side) * cell + (cell - hole) / 2 + rng.uniform(-1, 1)
        y0 = (k // side) * cell + (cell - hole) / 2 + rng.uniform(-1, 1)
        interiors.append([(x0, y0), (x0, y0 + hole), (x0 + hole, y0 + hole), (x0 + hole, y0)])
    return Polygon([(0, 0), (side * cell, 0), (side * cell, side * cell), (0, side * cell)], interiors)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--shape", default="hipped")
    parser.add_argument("--holes", type=int, nargs="+", default=[10, 25, 50, 100, 200])
    parser.add_argument("--repeat", type=int, default=1)
    args = parser.parse_args()
    builder = default_registry().roof_builders[args.shape]
    rows = []
    for holes in args.holes:
        outline = courtyards(holes)
        spec = roof_spec({}, 10.0, shape=args.shape, pitch=30.0)
        best = math.inf
        for _ in range(args.repeat):
            t0 = time.process_time()
            builder.build(outline, 10.0, spec)
            best = min(best, time.process_time() - t0)
        vertices = 4 * (holes + 1)
        rows.append((vertices, best))
        print(f"{holes:5d} courtyards, {vertices:5d} vertices: {best:8.3f} s CPU, {1e3 * best / vertices:7.3f} ms "
              f"per vertex", flush=True)
    if len(rows) > 1 and rows[0][1] > 0:
        (n0, t0), (n1, t1) = rows[0], rows[-1]
        print(f"time ~ vertices^{math.log(t1 / t0) / math.log(n1 / n0):.2f} between {n0} and {n1} vertices")


if __name__ == "__main__":
    main()
