"""Party-wall roofs on generated outlines: how often the weighted skeleton gives up or cracks.

    python benchmarks/party_roofs.py [--cases 600] [--shape hipped]

The outlines of the roof tests (random star polygons, L/U shapes, rectangles with courtyards; a fixed,
derandomised Hypothesis draw) each get a random set of party walls (any edges but not all). Prints per kind of
outline how many roofs were built with their party walls, how many fell back to the free roof (with the builder's
note, grouped) and how many came out cracked (an open mesh edge that is not an eave on the outline)."""
from __future__ import annotations

import argparse
import re
import sys
from collections import Counter
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from citygen.registry import default_registry  # noqa: E402
from citygen.roof import RoofSpec, roof_notes  # noqa: E402
from tests.roofs.shapes import polygons  # noqa: E402
from tests.roofs.test_builders import _open_edges, _outline_edges, _same_edges  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", type=int, default=600)
    parser.add_argument("--shape", default="hipped")
    args = parser.parse_args()
    builder = default_registry().roof_builders[args.shape]
    counts: Counter = Counter()
    notes_seen: Counter = Counter()

    @settings(max_examples=args.cases, derandomize=True, deadline=None, database=None,
              suppress_health_check=list(HealthCheck))
    @given(polygons, st.data())
    def run(outline, data) -> None:
        n = sum(len(r.coords) - 1 for r in (outline.exterior, *outline.interiors))
        party = tuple(sorted(data.draw(st.sets(st.integers(0, n - 1), max_size=n - 1))))
        kind = "courtyard" if outline.interiors else "simple"
        with roof_notes() as notes:
            mesh = builder.build(outline, 12.0, RoofSpec(args.shape, 30.0, party=party))
        try:
            edges, _ = _open_edges(mesh)
            closed = _same_edges(edges, _outline_edges(outline))
        except AssertionError:
            closed = False
        outcome = "cracked" if not closed else "free roof (note)" if notes else "with party walls"
        counts[kind, outcome] += 1
        for note in notes:
            notes_seen[re.sub(r"\d+(\.\d+)?", "N", note)] += 1

    run()
    for kind in ("simple", "courtyard"):
        total = sum(v for (k, _), v in counts.items() if k == kind)
        parts = ", ".join(f"{counts[kind, o]} {o}" for o in ("with party walls", "free roof (note)", "cracked"))
        print(f"{kind}: {total} outlines: {parts}")
    for note, count in notes_seen.most_common():
        print(f"  {count}: {note}")


if __name__ == "__main__":
    main()
