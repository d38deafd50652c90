"""Method exact: the cheapest grammar over the candidate rules as an integer program (``exact.py``)."""
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, example, given, settings, strategies as st

import citygen_split
from citygen_inverse.cmp import import_cmp
from citygen_inverse.exact import solve_exact
from citygen_inverse.extract import extract_grammar
from citygen_inverse.regions import LayoutIndex
from citygen_inverse.search import GrammarSearch

from .helpers import assert_reproduces, random_layout

DATA = Path(__file__).resolve().parents[1] / "data" / "inverse"


def cheapest_by_enumeration(search: GrammarSearch) -> float:
    """The least cost of a grammar over ``search``'s candidate rules, by enumerating every choice of one rule per
    signature reachable from the roots (each chosen rule counted once), with cost pruning: tiny layouts only."""
    best = math.inf

    def visit(cost: float, ruled: frozenset, pending: frozenset) -> None:
        nonlocal best
        if cost >= best:
            return
        if not pending:
            best = cost
            return
        sig = min(pending)
        acts = search.actions(sig)
        for k in range(len(acts)):
            now = ruled | {sig}
            visit(cost + acts.cost[k], now, (pending | frozenset(acts.kids(k))) - now)

    visit(0.0, frozenset(), frozenset(s for s in search.roots if search.index.sigs[s].n > 1))
    return best


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 100_000))
@example(8).via("the program's grammar is cheaper than ADP 10's: 18.1 vs 18.8")
@example(14).via("35.7 vs 36.6, 213 candidate rules")
def test_the_integer_program_finds_the_cheapest_grammar_over_the_candidates(seed):
    layout = random_layout(np.random.default_rng(seed), width=8.0, height=6.0, depth=5, pinwheel=0.2)
    search = GrammarSearch(LayoutIndex([layout], True, periodic=True))
    adp = search.run("adp", 10, 0)  # (short: on about one layout in eight the program finds a cheaper grammar)
    program = solve_exact(search, None)
    assume(sum(map(len, search._actions.values())) <= 250)  # (the enumeration is exponential)
    assert program.optimal and not program.stopped and program.cost <= adp.cost + 1e-9
    assert program.cost == pytest.approx(cheapest_by_enumeration(search), abs=1e-9)
    assert program.bound <= program.cost + 1e-6


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 100_000))
def test_exact_is_never_worse_than_adp_and_reproduces_the_layout(seed):
    layout = random_layout(np.random.default_rng(seed), depth=5, pinwheel=0.1)
    adp = extract_grammar(layout, "adp", 60, seed=1)
    exact = extract_grammar(layout, "exact", 60, seed=1)
    assert exact.cost <= adp.cost + 1e-9
    assert exact.bound <= exact.cost + 1e-6 and exact.optimal
    assert_reproduces(exact.text, layout)
    assert citygen_split.grammar_cost(citygen_split.parse(exact.text, "t")) == pytest.approx(exact.cost)
    assert extract_grammar(layout, "exact", 60, seed=1).text == exact.text  # an ended solve is deterministic


def test_exact_beats_adp_on_a_cmp_facade_and_proves_it_optimal():
    """cmp_b0002: ADP 2K's grammar costs 160.3, the cheapest over the same candidate rules 160.2."""
    layout = import_cmp(DATA / "cmp_b0002.xml")
    adp = extract_grammar(layout, "adp", 2000, seed=0)
    exact = extract_grammar(layout, "exact", 2000, seed=0)
    assert adp.cost == pytest.approx(160.3) and exact.cost == pytest.approx(160.2)
    assert exact.optimal and exact.bound == pytest.approx(160.2, abs=1e-4)
    assert "# integer program: optimal over the candidate rules" in exact.text
    assert_reproduces(exact.text, layout)


def test_a_stopped_program_keeps_adps_grammar_when_it_is_cheaper(monkeypatch):
    """The solver stopped before it found a grammar: the result is ADP's, with no optimality claimed."""
    import citygen_inverse.search as search_module
    from citygen_inverse.exact import ExactResult
    layout = random_layout(np.random.default_rng(7))
    adp = extract_grammar(layout, "adp", 40, seed=2)
    monkeypatch.setattr(search_module, "solve_exact", lambda search, limit: ExactResult(None, math.inf, 1.0, False,
                                                                                         True))
    exact = extract_grammar(layout, "exact", 40, seed=2)
    assert exact.cost == adp.cost and not exact.optimal and exact.stopped
    assert "stopped at the time limit" in exact.verdict()
    assert_reproduces(exact.text, layout)


def test_joint_extraction_with_exact_bounds_the_written_cost():
    """Several facades: the bound is moved by the written axiom's cost as the cost is."""
    from .test_extract import regular_facade
    facades = [regular_facade(5, 6), regular_facade(3, 4)]
    joint = extract_grammar(facades, "exact", 50, seed=0)
    assert joint.cost <= extract_grammar(facades, "adp", 50, seed=0).cost + 1e-9
    assert joint.optimal and joint.bound == pytest.approx(joint.cost)


def test_a_program_stopped_before_any_bound_keeps_adps_grammar():
    """Regression: HiGHS stopped by the time limit before its first bound returned no dual bound, and
    ``float(None)`` raised a TypeError (cmp_b0001 with --time-limit 0.3)."""
    layout = import_cmp(DATA / "cmp_b0045.xml")
    exact = extract_grammar(layout, "exact", 3, seed=0, time_limit=1e-4)
    assert exact.stopped and not exact.optimal and exact.bound == 0.0
    assert exact.verdict().startswith("no lower bound: stopped at the time limit")
    assert exact.cost == pytest.approx(extract_grammar(layout, "adp", 1, seed=0).cost)  # (no iteration but one)
    assert_reproduces(exact.text, layout)
