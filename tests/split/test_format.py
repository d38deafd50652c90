"""Canonical text: parse(format_grammar(g)) == g, over the shipped grammars and generated ones."""
from __future__ import annotations

import re

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from citygen_split import format_grammar, grammar_cost, load, parse
from citygen_split.ast import (
    Attr, Binary, Case, Choice, Const, Floors, FloorItem, Grammar, Grid, Item, Rename, Repeat, RepeatABA, Rule,
    Size, Split, SymSplit, Terminal, Unary, Var,
)
from citygen_split.parser import VARIABLES

from .conftest import REPO, RULESETS

numbers = st.floats(1e-4, 1e4, allow_nan=False, allow_infinity=False)
sizes = st.builds(Size, st.sampled_from(["abs", "rel", "float"]), numbers)
text = st.text(st.characters(blacklist_categories=("Cc", "Cs")), max_size=12)
words = st.from_regex(r"[a-z][a-z0-9_]{0,6}", fullmatch=True)


SYMBOLS = [f"S{i}" for i in range(5)]
successors = st.sampled_from([*SYMBOLS, "Wall", "Win"])
axes = st.sampled_from(["x", "y"])
item_lists = st.lists(st.builds(Item, sizes, successors), min_size=1, max_size=4).map(tuple)
leaf_exprs = st.one_of(st.builds(Const, st.floats(0, 1e6)), st.builds(Const, st.booleans()), st.builds(Const, text),
                       st.builds(Var, st.sampled_from(VARIABLES)), st.builds(Attr, text))
expressions = st.recursive(leaf_exprs, lambda inner: st.one_of(
    st.builds(Unary, st.sampled_from(["-", "not"]), inner),
    st.builds(Binary, st.sampled_from(["or", "and", "==", "!=", "<", "<=", ">", ">=", "+", "-", "*", "/"]),
              inner, inner)), max_leaves=6)


@st.composite
def grids(draw) -> Grid:
    cols = draw(st.lists(sizes, min_size=1, max_size=3).map(tuple))
    rows = draw(st.lists(sizes, min_size=1, max_size=3).map(tuple))
    cells = tuple(tuple(draw(successors) if c == 0 else draw(st.one_of(st.just("<"), successors))
                        for c in range(len(cols))) for _ in rows)
    return Grid(cols, rows, cells)


floors = st.builds(lambda ks, syms, last: Floors(tuple(FloorItem(k, s) for k, s in zip(ks, syms))
                                                 + (FloorItem(None, last),)),
                   st.lists(st.integers(-5, 5), unique=True, max_size=3), st.lists(successors, min_size=3, max_size=3),
                   successors)
simple_bodies = st.one_of(
    st.builds(Split, axes, item_lists), st.builds(Repeat, axes, item_lists), st.builds(SymSplit, axes, item_lists),
    st.builds(RepeatABA, axes, st.builds(Item, sizes, successors), st.builds(Item, sizes, successors)),
    grids(), floors, st.builds(Rename, st.sampled_from(["Wall", "Win"])),  # renames to terminals: no cycles
    st.builds(Terminal, st.one_of(st.none(), words), st.floats(-5, 5), st.one_of(st.none(), words, text),
              st.one_of(st.none(), text)))
bodies = st.one_of(
    simple_bodies,
    st.builds(Case, st.lists(st.tuples(expressions, simple_bodies), min_size=1, max_size=3).map(tuple),
              st.one_of(st.none(), simple_bodies)),
    st.builds(Choice, st.lists(st.tuples(st.floats(0, 30), simple_bodies), min_size=1, max_size=3).map(tuple),
              st.one_of(st.none(), simple_bodies), st.booleans()))
grammars = st.builds(
    lambda bs, start, size, name: Grammar(
        tuple(Rule(sym, b) for sym, b in zip(SYMBOLS, bs))
        + (Rule("Wall", Terminal("wall")), Rule("Win", Terminal("window", -0.25, "glass"))), start, size, name),
    st.lists(bodies, min_size=len(SYMBOLS), max_size=len(SYMBOLS)), st.sampled_from(SYMBOLS),
    st.one_of(st.none(), st.tuples(numbers, numbers)), st.one_of(st.none(), text))


@settings(max_examples=200, deadline=None)
@given(grammars)
def test_round_trip_of_generated_grammars(g):
    out = format_grammar(g)
    again = parse(out, "<formatted>")
    assert again == g
    assert format_grammar(again) == out
    assert grammar_cost(again) == pytest.approx(grammar_cost(g))


@pytest.mark.parametrize("path", RULESETS, ids=[p.stem for p in RULESETS])
def test_round_trip_of_shipped_grammars(path):
    g = load(path)
    assert parse(format_grammar(g)) == g


def test_canonical_text_of_a_small_grammar():
    g = parse("@size 12 9\nA --> case not (width < 2.5 or street) and floor == 1 - 1: split(x) { B | ~1.25: B }\n"
              " else: B\nB --> terminal(wall, depth: -0.25, material: \"red brick\")")
    assert format_grammar(g) == (
        "@size 12 9\n@start A\n\n"
        "A --> case not (width < 2.5 or street) and floor == 1 - 1: split(x) { '1: B | ~1.25: B }\n"
        "      else: B\n"
        'B --> terminal(wall, depth: -0.25, material: "red brick")\n')


def test_docs_worked_example_parses_and_costs_15():
    doc = (REPO / "docs" / "grammar.md").read_text()
    section = doc[doc.index("## Worked example"):]
    example = re.search(r"```\n(.*?)```", section, re.S).group(1)
    g = parse(example, "docs/grammar.md")
    assert grammar_cost(g) == pytest.approx(15.0)
