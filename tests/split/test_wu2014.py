"""wu2014's example grammars (§3.1, Fig. 9 / §4.6, §4.7) in the citygen language, and their costs (Eq. 1-2)."""
from __future__ import annotations

import pytest

from citygen.layout import check_partition
from citygen_split import derive, grammar_cost, parse, rule_cost

from .conftest import request

F1_F2 = """
F1 --> split(x) { 1: A | 2: B | 1: A }
F2 --> repeat(x) { 1: A | 2: B }
A --> terminal(wall)
B --> terminal(window)
"""

# §4.6: the grammar of Fig. 9, sizes left out as in the paper (each successor then weighs '1)
FIG9 = """
NT1 --> split(y) { Wall1 | NT2 | NT3 | Wall1 | NT4 | Wall1 }
NT2 --> repeat(y) { NT5 }
NT3 --> split(x) { NT6 | Wall1 | Window1 | Wall2 | Window1 | NT7 }
NT4 --> split(x) { NT6 | Wall2 | Wall1 | NT8 | Wall2 | Window2 | Wall1 | NT9 }
NT5 --> split(y) { NT10 | Wall1 }
NT6 --> split(x) { Wall1 | Window1 }
NT7 --> split(x) { Wall1 | Window2 | Wall2 | NT9 }
NT8 --> split(x) { Window1 | Wall1 | Window1 }
NT9 --> split(x) { Window1 | Wall1 }
NT10 --> split(x) { NT6 | Wall2 | NT8 | NT7 }
"""
TERMINALS = """
Wall1 --> terminal(wall)
Wall2 --> terminal(wall, material: brick)
Window1 --> terminal(window, depth: -0.25)
Window2 --> terminal(window, depth: -0.2)
"""

# §4.7: repeatABA replaces NT2/NT5 (NT5 disappears), symsplit shortens NT8
FIG11 = FIG9.replace("NT1 --> split(y) { Wall1 | NT2 | NT3 | Wall1 | NT4 | Wall1 }",
                     "NT1 --> split(y) { NT2 | NT3 | Wall1 | NT4 | Wall1 }") \
            .replace("NT2 --> repeat(y) { NT5 }", "NT2 --> repeatABA(y) { Wall1 | NT10 }") \
            .replace("NT5 --> split(y) { NT10 | Wall1 }\n", "") \
            .replace("NT8 --> split(x) { Window1 | Wall1 | Window1 }", "NT8 --> symsplit(x) { Window1 | Wall1 }")


def test_costs_of_f1_and_f2_from_section_3_2():
    g = parse(F1_F2)
    assert rule_cost(g.rule("F1")) == pytest.approx(3.1)
    assert rule_cost(g.rule("F2")) == pytest.approx(2.5)
    assert grammar_cost(g) == pytest.approx(5.6)  # terminals cost nothing


def test_f1_and_f2_layouts_match_fig4():
    g = parse(F1_F2)
    f1 = derive(g, request(4, 1))
    assert [(t.symbol, t.x, t.w) for t in f1.terminals()] == [("A", 0, 1), ("B", 1, 2), ("A", 3, 1)]
    g2 = parse("@start F2\n" + F1_F2)
    f2 = derive(g2, request(9, 1))
    assert [t.symbol for t in f2.terminals()] == ["A", "B"] * 3
    assert [t.w for t in f2.terminals()] == pytest.approx([1, 2] * 3)


def test_fig9_grammar_parses_and_derives():
    g = parse(FIG9 + TERMINALS)
    assert len(g.rules) == 10 + 4 and g.start == "NT1"
    layout = derive(g, request(20, 15))
    assert check_partition(layout) == []
    assert {"wall", "window"} == set(layout.labels())
    # ten rules: 6.1 + 1.5 + 6.1 + 8.1 + 2.1 + 2.1 + 4.1 + 3.1 + 2.1 + 4.1
    assert grammar_cost(g) == pytest.approx(39.4)


def test_section_4_7_extensions_lower_the_cost():
    g9, g11 = parse(FIG9 + TERMINALS), parse(FIG11 + TERMINALS)
    assert "NT5" not in g11.table
    assert rule_cost(g11.rule("NT2")) == pytest.approx(2.5) and rule_cost(g11.rule("NT8")) == pytest.approx(2.1)
    assert grammar_cost(g11) == pytest.approx(36.3)
    assert grammar_cost(g11) < grammar_cost(g9)
    layout = derive(g11, request(20, 15))
    assert check_partition(layout) == []
    nt8 = next(r for r in _regions(layout.root) if r.symbol == "NT8")
    assert [c.symbol for c in nt8.children] == ["Window1", "Wall1", "Window1"]
    nt2 = next(r for r in _regions(layout.root) if r.symbol == "NT2")
    symbols = [c.symbol for c in nt2.children]
    assert symbols[0] == symbols[-1] == "Wall1" and symbols[1::2] == ["NT10"] * (len(symbols) // 2)


def _regions(region):
    yield region
    for child in region.children:
        yield from _regions(child)
