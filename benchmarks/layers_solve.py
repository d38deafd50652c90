"""Median solve times of layer stacks (ilcik2015 §6: 8 layers 0.8 s, 26 layers about 1 s on a 2015 desktop).

Run: python benchmarks/layers_solve.py [--repeat N] [--prealign]

``--prealign`` turns on the prealignment of the control patterns (§5.2 heuristic, ``budget prealign=true``) for
every case.

Times are of cold solves (kept direction solutions are forgotten before every repeat); "reused ms" is the same
request again in the same process, when both directions are taken from the kept solutions (faces of a
building that share height and floor lines, or width).
"""
from __future__ import annotations

import argparse
import dataclasses
import statistics
import time
from pathlib import Path

from citygen.request import FacadeRequest
from citygen_layers.parser import load
from citygen_layers.facade import clear_solved, generate

ROOT = Path(__file__).resolve().parents[1]
CASES = [
    ("Fig. 5 house (3 layers)", ROOT / "rulesets" / "residential_house.layers", FacadeRequest(6.0, 3.0, (0.0, 1.6, 3.0), True)),
    ("terraced house (3 layers)", ROOT / "rulesets" / "terraced_house.layers", FacadeRequest.preview(14, 16, 3.0, 4.0)),
    ("tenement (8 layers, 28 symbols)", ROOT / "rulesets" / "tenement.layers", FacadeRequest.preview(16, 15, 3.0, 4.0)),
    ("26-layer stack", ROOT / "benchmarks" / "data" / "layers" / "tonhalle26.layers",
     FacadeRequest.preview(24, 19, 3.0, 4.5, entrance=False)),
    ("under-constrained (budget)", ROOT / "benchmarks" / "data" / "layers" / "underconstrained.layers",
     FacadeRequest(17.0, 13.0, (0.0, 13.0))),
]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--prealign", action="store_true", help="budget prealign=true for every case")
    args = parser.parse_args()
    print(f"{'case':34} {'median ms':>10} {'cpu ms':>8} {'expansions':>10} {'reused ms':>10}  status")
    for name, path, request in CASES:
        ruleset = load(path)
        if args.prealign:
            ruleset = dataclasses.replace(ruleset, options=dataclasses.replace(ruleset.options, prealign=True))
        generate(ruleset, request)   # warm-up (imports)
        wall, cpu, reused = [], [], []
        for _ in range(args.repeat):
            clear_solved()
            t0, c0 = time.perf_counter(), time.process_time()
            layout = generate(ruleset, request)
            wall.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
            t0 = time.perf_counter()
            generate(ruleset, request)
            reused.append(time.perf_counter() - t0)
        status = "/".join(layout.meta["status"].values())
        if layout.meta.get("fallback"):      # no plausible layout: the plain wall keeps the solve's status
            status += " -> fell back: " + "; ".join(layout.meta["findings"][:1])
        expansions = layout.meta.get("expansions", "-")
        print(f"{name:34} {1e3 * statistics.median(wall):10.1f} {1e3 * statistics.median(cpu):8.1f} "
              f"{expansions:>10} {1e3 * statistics.median(reused):10.1f}  {status}")


if __name__ == "__main__":
    main()
