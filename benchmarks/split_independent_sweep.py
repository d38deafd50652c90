"""Size-independent grammars of CMP facades at 0.5x-2x their size: how many faces are dressed, fall back, or are
broken but reported as dressed (issue 21).

    python benchmarks/split_independent_sweep.py [--limit K] [--step S] [--method greedy|adp] [--iterations N]

Per facade (every S-th CMP base facade, at most K): import, extract the ``--size-independent`` grammar, derive it
through the split kind (``generate``: alternatives tried, else plain wall) at width and height factors
0.5, 0.65, 0.8, 1, 1.25, 1.5, 1.7, 2 (3 m storeys, 4 m ground floor, entrance), each case classified as
``citygen facade`` does. Prints the outcome counts, the most common finding codes and labels, how many facades
have repeated bays, the grid rules in the grammars and, with ``--plain``, the counts of the plain derivation (no
alternatives: what the generator did before). Skips cleanly when the shared data is absent.
"""
from __future__ import annotations

import argparse
import re
import time
from collections import Counter
from pathlib import Path

import citygen_split
from citygen.cli import facade_outcome
from citygen.errors import CitygenError
from citygen.registry import default_registry
from citygen.request import FacadeRequest
from citygen_inverse.cmp import import_cmp
from citygen_inverse.independent import extract_size_independent

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "cmp_facade" / "base"
FACTORS = (0.5, 0.65, 0.8, 1.0, 1.25, 1.5, 1.7, 2.0)


def grid_items(text: str) -> list[int]:
    """Items (regions) of each ``grid`` rule in a grammar's text."""
    out = []
    for line in text.splitlines():
        m = re.search(r"--> grid \{.*?;.*?;(.*)\}", line)
        if m:
            out.append(sum(1 for tok in m.group(1).replace("/", " ").split() if tok not in ("<", "v")))
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--limit", type=int, default=40)
    parser.add_argument("--step", type=int, default=7, help="every S-th facade")
    parser.add_argument("--method", default="greedy")
    parser.add_argument("--iterations", type=int, default=200)
    parser.add_argument("--plain", action="store_true", help="also count the plain derivation (no alternatives)")
    args = parser.parse_args()
    files = sorted(DATA.glob("cmp_*.xml"))[:: args.step][: args.limit]
    if not files:
        print(f"no CMP data at {DATA}; nothing to sweep")
        return 0
    kind = default_registry().ruleset_kind("split")
    counts: dict[str, Counter] = {"generate": Counter(), "plain": Counter()}
    codes: dict[str, Counter] = {"generate": Counter(), "plain": Counter()}
    grids, with_bays, start = [], 0, time.perf_counter()
    for path in files:
        layout = import_cmp(path)
        result = extract_size_independent(layout, args.method, args.iterations)
        grids.append(grid_items(result.text))
        with_bays += " bays of " in result.text.split("@size")[0]
        grammar = citygen_split.parse(result.text, path.name)
        for fw in FACTORS:
            for fh in FACTORS:
                req = FacadeRequest.preview(fw * layout.width, fh * layout.height, floor_height=3.0,
                                            ground_height=4.0)
                for mode in ("generate", "plain") if args.plain else ("generate",):
                    try:
                        out = kind.generate(grammar, req) if mode == "generate" else citygen_split.derive(grammar, req)
                    except CitygenError:
                        counts[mode]["error"] += 1
                        continue
                    outcome, reasons = facade_outcome(out, req)
                    counts[mode][outcome] += 1
                    if outcome != "dressed":
                        codes[mode].update({" ".join(r.split()[:2]).rstrip(":") for r in reasons[1:] or reasons
                                            if ":" in r and not r.split(":")[1].startswith(" ...")})
    cases = len(files) * len(FACTORS) ** 2
    print(f"{len(files)} facades x {len(FACTORS) ** 2} sizes = {cases} cases, {time.perf_counter() - start:.0f} s")
    for mode in counts:
        if counts[mode]:
            print(f"{mode:>9}: " + ", ".join(f"{k} {v}" for k, v in counts[mode].most_common()) + "  | codes: "
                  + ", ".join(f"{k} {v}" for k, v in codes[mode].most_common(8)))
    print(f"repeated bays found in {with_bays} of {len(files)} facades")
    with_grid = [g for g in grids if g]
    print(f"grid rules: in {len(with_grid)} of {len(grids)} grammars; largest "
          f"{sorted((max(g) for g in with_grid), reverse=True)[:8]} items")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
