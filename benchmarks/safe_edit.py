"""CPU time per structure-aware edit (dang2014) of the CMP layout cmp_b0035 (150 terminals).

    .venv/bin/python benchmarks/safe_edit.py [--repeats 3] [--sizes 60x30 80x36 110x36]

Prints, per target size, the median process time of ``edit`` (floors + width variations + QP) and of one
spatial optimisation (resizing without topology change), the work counted (leaves sized), the number of jumps
chosen, the resulting leaf count, the chosen variation's distortion E(x) (the width QP's objective; large values
mean stretched shapes), the widest window, and any budget note or fallback (the ruleset's budget is 2 nominal CPU
seconds of work). Each repeat edits a freshly loaded
ruleset, so the floor jumps that the faces of one building share are paid every time (the first face's cost).
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from citygen.request import FacadeRequest
from citygen_safe.edit import size
from citygen_safe.generate import edit, settings_for
from citygen_safe.ruleset import load_ruleset

RULESET = Path(__file__).resolve().parents[1] / "rulesets" / "cmp_b0035.safe"
SIZES = ((15.6125, 12.0), (10.0, 12.0), (20.0, 12.0), (15.6125, 6.0), (22.0, 15.0), (25.0, 18.0), (5.0, 30.0),
         (40.0, 30.0), (60.0, 30.0), (80.0, 36.0), (110.0, 36.0), (140.0, 36.0))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--sizes", nargs="*", metavar="WxH", help="target sizes in m (default: the table's)")
    args = parser.parse_args()
    sizes = [tuple(float(v) for v in s.split("x")) for s in args.sizes] if args.sizes else SIZES
    ruleset = load_ruleset(RULESET)
    print(f"{RULESET.name}: {len(ruleset.facade.leaves)} terminals, median of {args.repeats} (CPU s)")
    for width, height in sizes:
        request = FacadeRequest.preview(width, height, 3.0)
        times, result = [], None
        for _ in range(args.repeats):
            fresh = load_ruleset(RULESET)  # a new ruleset object: no floor jumps remembered from the last repeat
            t0 = time.process_time()
            result = edit(fresh, request)
            times.append(time.process_time() - t0)
        qp = []
        for _ in range(args.repeats):
            t0 = time.process_time()
            size(ruleset.facade, settings_for(ruleset, request), width)
            qp.append(time.process_time() - t0)
        print(f"{width:7.3f} x {height:5.1f}: edit {statistics.median(times):7.3f} s, one QP "
              f"{statistics.median(qp) * 1000:6.1f} ms, work {result.work:6d}, {len(result.layout.leaves):4d} leaves, "
              f"{len(result.variations)} variations, {len(result.layout.meta['jumps'])} jumps, "
              f"E {result.layout.meta.get('distortion', float('nan')):.3g}, widest window "
              f"{max((r.w for r in result.layout.leaves if r.label == 'window'), default=0.0):.2f} m"
              + (f"; fallback: {result.layout.meta['fallback']}" if "fallback" in result.layout.meta else "")
              + (f"; {'; '.join(result.diagnostics)}" if result.diagnostics else ""))


if __name__ == "__main__":
    main()
