"""Every shipped ruleset at sizes nobody tuned it for: a facade is dressed plausibly or the generator says it cannot
(the scene's fallback chain takes over) -- never a broken facade reported as a success. A bounded slice of the
sweep (``tests/sweep.py``); ``benchmarks/facade_sweep.py`` runs the whole grid."""
from __future__ import annotations

import pytest

from citygen.registry import default_registry
from tests.sweep import SHIPPED, SMALL_HEIGHTS, SMALL_WIDTHS, run_case


@pytest.mark.parametrize("name", SHIPPED)
def test_no_shipped_ruleset_reports_a_broken_facade_as_dressed(name):
    registry = default_registry()
    cases = [run_case(registry, name, w, h, storey)
             for storey, heights in ((3.0, SMALL_HEIGHTS), (2.6, (7.0, 31.0)), (3.6, (13.5,)))
             for h in heights for w in SMALL_WIDTHS]
    bad = [f"{c.outcome} at {c.width:g} x {c.height:g} m / {c.storey:g} m storeys: {c.reasons[:2]}"
           for c in cases if c.bad]
    assert not bad, f"{len(bad)} of {len(cases)} broken facades reported as a success:\n" + "\n".join(bad[:5])
    # the shipped rulesets are meant for buildings: most mid-sized faces get a facade
    mid = [c for c in cases if 5 <= c.width <= 30 and c.height >= 7]
    assert sum(c.outcome == "dressed" for c in mid) >= 0.7 * len(mid), [c.outcome for c in mid]
