"""Relayout properties over many seeds and target sizes (bao2013 §7): partition + every hard constraint."""
from __future__ import annotations

import time

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from citygen_relayout import parse_model, relayout, validate, variations

SETTINGS = settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
# target sizes from well below to well above each input (townhouse 10 x 9.6, fig7 15 x 17, cmp 15.6 x 12)
SIZES = {"townhouse": (st.floats(4, 30), st.floats(5.7, 25)),
         "fig7_walkthrough": (st.floats(8, 30), st.floats(8, 24)),
         "cmp_b0035": (st.floats(8, 32), st.floats(8, 22))}


def check(model, width, height, seed):
    result = relayout(model, width, height, seed=seed, budget_s=10.0)
    assert result.success, result.message
    layout = result.layout
    assert (layout.width, layout.height) == (width, height)
    assert validate(layout, model) == []
    return layout


@pytest.mark.parametrize("name", list(SIZES))
def test_every_output_partitions_and_meets_every_constraint(models, name):
    w_strategy, h_strategy = SIZES[name]

    @SETTINGS
    @given(w_strategy, h_strategy, st.integers(0, 10_000))
    def run(width, height, seed):
        check(models[name], width, height, seed)

    run()


@pytest.mark.parametrize("name", list(SIZES))
def test_variations_for_one_size_differ(models, name):
    model = models[name]
    results = variations(model, model.width * 1.4, model.height * 1.2, 8, seed=3)
    assert all(r.success for r in results)
    distinct = {r.layout.dumps() for r in results}
    assert len(distinct) >= 6


@pytest.mark.parametrize("name", list(SIZES))
def test_same_seed_same_layout(models, name):
    model = models[name]
    a = relayout(model, 17.0, 13.0, seed=42)
    b = relayout(model, 17.0, 13.0, seed=42)
    assert a.success and a.layout.dumps() == b.layout.dumps()


def test_input_size_reproduces_a_valid_layout(models):
    for model in models.values():
        check(model, model.width, model.height, 0)


def test_too_small_target_names_the_bound_immediately(models):
    t = time.process_time()
    result = relayout(models["fig7_walkthrough"], 25.0, 5.0)
    assert not result.success and result.status == "infeasible"
    assert "height must lie in" in result.message
    assert time.process_time() - t < 0.5


def test_conflicting_constraints_report_what_blocked_within_budget():
    # every window must be 1.5 m wide and aligned with a 1.2 m wall: no arrangement can hold both
    text = """model clash
root F 6 6
split F y R:3 S:3
split R x W:1.5 A:3 W:1.5
split S x B:1.2 C:3.6 B:1.2
terminal W wall
terminal B wall
terminal A window
terminal C window
size A 2.9..3.1
size C 3.5..3.7
align A.min = C.min
"""
    model = parse_model(text, "clash.relayout")
    t = time.process_time()
    result = relayout(model, 6.0, 6.0, backtrack_budget=3000)
    assert time.process_time() - t < 3.0
    assert not result.success
    assert "align A.min = C.min (line 12)" in result.message
    assert result.blockers


SYMMETRIC = """model sym
root F 9 3
split F x P:1 W:1 Win:1 W:1 Mid:1 W:1 Win:1 W:1 Q:1
terminal P pillar
terminal Q pillar
terminal W wall
terminal Win window
terminal Mid door
mirror P Q
symmetric F
shuffle F : Win W Mid W Win
seq F : ^ P W
seq F : W Q $
size W 0.5..3
size Win 0.8..1.4
"""


@SETTINGS
@given(st.floats(5, 25), st.integers(0, 10_000))
def test_symmetric_regions_are_palindromes_with_mirrored_sizes(width, seed):
    model = parse_model(SYMMETRIC, "sym.relayout")
    result = relayout(model, width, 3.0, seed=seed)
    assert result.success, result.message
    assert validate(result.layout, model) == []
    kids = result.layout.root.children
    assert kids[0].symbol == "P" and kids[-1].symbol == "Q"
    assert abs(kids[0].w - kids[-1].w) < 1e-6


INSTANCES = """model inst
root F 10 3
split F x W:1 Bay:2 W:1 Bay:2 W:1 Bay:2 W:1
split Bay x Win:2
terminal W wall
terminal Win window
repeat F : W (Bay W)+
instances F Bay 2..3
size Bay 1..3
size Win 1..3
"""


@SETTINGS
@given(st.floats(8, 30), st.integers(0, 10_000))
def test_independent_instances_count_distinct_relayouts(width, seed):
    model = parse_model(INSTANCES, "inst.relayout")
    result = relayout(model, width, 3.0, seed=seed)
    assert result.success, result.message
    assert validate(result.layout, model) == []
    names = {c.symbol for c in result.layout.root.children if c.symbol.startswith("Bay")}
    assert 2 <= len(names) <= 3


def test_validator_catches_a_broken_layout(models):
    from dataclasses import replace
    model = models["townhouse"]
    layout = relayout(model, 12.0, 9.6, seed=1).layout
    ground = layout.root.children[0]
    moved = replace(ground, children=(replace(ground.children[0], w=ground.children[0].w + 0.3),
                                      *ground.children[1:]))
    broken = replace(layout, root=replace(layout.root, children=(moved, *layout.root.children[1:])))
    problems = validate(broken, model)
    assert problems and any("overlap" in p or "continue" in p for p in problems)
