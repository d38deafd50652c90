"""Restart schedules of the relayout search on building faces (docs/relayout.md, "Restarts").

    python benchmarks/relayout_restarts.py [--models cmp_b0035 fig7_walkthrough] [--seeds 2]

Per model and schedule (Luby cutoffs 100 x (1, 1, 2, 1, ...) or the paper's fixed 1000): entrance faces over
widths x heights x (floor, ground floor) heights, a 6000-backtrack budget; prints CPU seconds (total, median,
p90, max), fallbacks and mean backtracks.
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from citygen.request import FaceContext, FacadeRequest, split_floors
from citygen_relayout import load_model
from citygen_relayout.api import relayout
from citygen_relayout.search import RESTARTS, Constraints

ROOT = Path(__file__).resolve().parents[1]
WIDTHS, HEIGHTS = (9, 12, 16, 22, 30), (10, 13, 16, 19, 22)
FLOORS = ((2.8, 3.2), (3.0, 3.6), (3.3, 4.4))


def run(model, restarts: str, seeds: int) -> str:
    times, fails, backtracks = [], 0, []
    for seed in range(1, seeds + 1):
        for floors in FLOORS:
            for w in WIDTHS:
                for h in HEIGHTS:
                    lines = split_floors(h, *floors)
                    req = FacadeRequest(w, h, lines, entrance=True, corner_widths=(0.3, 0.4),
                                        context=FaceContext("b", 0, len(lines) - 1), seed=(seed, 0))
                    c = Constraints(floor_lines=tuple(lines), corners=(0.3, 0.4), doors=1, shared={},
                                    key_salt=(seed, 0))
                    t = time.process_time()
                    r = relayout(model, w, h, rng=req.rng("relayout", model.name), constraints=c,
                                 backtrack_budget=6000, restarts=restarts)
                    times.append(time.process_time() - t)
                    fails += not r.success
                    backtracks.append(r.backtracks)
    times.sort()
    return (f"{model.name:18s} {restarts:5s} faces {len(times)}  cpu s total {sum(times):6.1f}  median "
            f"{statistics.median(times):.3f}  p90 {times[int(0.9 * len(times))]:.2f}  max {times[-1]:.2f}  "
            f"fallbacks {fails}  mean backtracks {statistics.mean(backtracks):.0f}")


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--models", nargs="*", default=["cmp_b0035", "fig7_walkthrough", "townhouse"])
    parser.add_argument("--seeds", type=int, default=2)
    args = parser.parse_args()
    for name in args.models:
        model = load_model(ROOT / "rulesets" / f"{name}.relayout")
        for restarts in RESTARTS:
            print(run(model, restarts, args.seeds), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
