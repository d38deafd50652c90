"""Parser: every construct, and every error kind with its file:line:column."""
from __future__ import annotations

import pytest

from citygen_split import load, parse
from citygen_split.ast import (
    Attr, Binary, Case, Choice, Const, Floors, FloorItem, Grid, Item, Rename, Repeat, RepeatABA, Size, Split,
    SymSplit, Terminal, Unary, Var,
)

from .conftest import TERMINALS, grammar, parse_error


def body(text: str):
    return grammar(f"X --> {text}\n").rule("X").body


def test_split_sizes_and_axis():
    assert body("split(y) { 2.5: A | '1.5: B | ~1.2: C }") == Split(
        "y", (Item(Size("abs", 2.5), "A"), Item(Size("rel", 1.5), "B"), Item(Size("float", 1.2), "C")))


def test_omitted_size_means_relative_one():
    assert body("split(x) { A | B | 2: A }").items == (
        Item(Size("rel", 1.0), "A"), Item(Size("rel", 1.0), "B"), Item(Size("abs", 2.0), "A"))


def test_each_operator():
    assert body("repeat(x) { ~3: A | 1: B }") == Repeat("x", (Item(Size("float", 3), "A"), Item(Size("abs", 1), "B")))
    assert body("repeatABA(y) { 1: A | 2: B }") == RepeatABA("y", Item(Size("abs", 1), "A"), Item(Size("abs", 2), "B"))
    assert body("symsplit(x) { 1: A | 2: B }") == SymSplit("x", (Item(Size("abs", 1), "A"), Item(Size("abs", 2), "B")))
    assert body("floors { 0: A | -1: B | *: C }") == Floors(
        (FloorItem(0, "A"), FloorItem(-1, "B"), FloorItem(None, "C")))
    assert body("A") == Rename("A")


def test_grid_cells_and_spans():
    grid = body("grid { cols: 1 | '2 ; rows: 0.5 | ~3 ; A < / B C }")
    assert grid == Grid((Size("abs", 1), Size("rel", 2)), (Size("abs", 0.5), Size("float", 3)),
                        (("A", "<"), ("B", "C")))
    assert grid.regions == (("A", 0, 0, 2, 1), ("B", 0, 1, 1, 2), ("C", 1, 1, 2, 2))
    vertical = body("grid { cols: 1 | 1 ; rows: 1 | 1 ; A B / v C }")
    assert vertical.regions == (("A", 0, 0, 1, 2), ("B", 1, 0, 2, 1), ("C", 1, 1, 2, 2))


def test_terminal_keys():
    g = parse('T --> terminal(window, depth: -0.25, material: glass, asset: "a/b.usda")\n'
              'U --> terminal(none)\nV --> terminal(wall, material: "red brick")')
    assert g.rule("T").body == Terminal("window", -0.25, "glass", "a/b.usda")
    assert g.rule("U").body == Terminal(None)
    assert g.rule("V").body == Terminal("wall", material="red brick")


def test_case_and_expressions():
    case = body('case floor == 0 and entrance: A\n case not (width < 2.5 or street): B\n'
                ' case attr("building") == "church" and -face_width * 2 + 1 / levels >= 3: C\n else: A')
    assert isinstance(case, Case)
    cond0, cond1, cond2 = (c for c, _ in case.branches)
    assert cond0 == Binary("and", Binary("==", Var("floor"), Const(0.0)), Var("entrance"))
    assert cond1 == Unary("not", Binary("or", Binary("<", Var("width"), Const(2.5)), Var("street")))
    assert cond2 == Binary("and", Binary("==", Attr("building"), Const("church")),
                           Binary(">=", Binary("+", Binary("*", Unary("-", Var("face_width")), Const(2.0)),
                                               Binary("/", Const(1.0), Var("levels"))), Const(3.0)))
    assert case.otherwise == Rename("A")


def test_stochastic_rules():
    assert body("60%: A 30%: B else: C") == Choice(((60.0, Rename("A")), (30.0, Rename("B"))), Rename("C"), False)
    assert body("each 50%: A") == Choice(((50.0, Rename("A")),), None, True)


def test_pragmas_and_start():
    g = parse('@name "Demo"\n@size 12 9.5\nA --> B\n@start B\nB --> terminal(wall)')
    assert (g.name, g.size, g.start) == ("Demo", (12.0, 9.5), "B")
    assert parse("A --> B\nB --> terminal(wall)").start == "A"


def test_comments_and_free_layout():
    g = parse("# heading\nA -->  # body on next lines\n split(x)\n {\n 1: B # first\n | 2: B }\nB --> terminal(wall)")
    assert len(g.rule("A").body.items) == 2


def test_corner_is_builtin():
    assert parse("A --> split(x) { 1: Corner | '1: B }\nB --> terminal(wall)").start == "A"


def test_load_records_source(tmp_path):
    path = tmp_path / "g.grammar"
    path.write_text("A --> terminal(wall)\n")
    assert load(path).source == str(path)


# ---- errors: message and file:line:column ------------------------------------------------------------------

ERRORS = [
    ("A --> terminal(wall)\n$", "bad.grammar:2:1", "unexpected character '$'"),
    ('A --> terminal(wall, asset: "x)', "bad.grammar:1:29", "unterminated string"),
    ("A --> split(z) { 1: A }", "bad.grammar:1:13", "expected an axis x or y, found 'z'"),
    ("A --> split(x) { 1 A }", "bad.grammar:1:20", "expected ':', found 'A'"),
    ("A --> split(x) { 1: B", "bad.grammar:1:22", "expected '}', found end of file"),
    ("A split(x)", "bad.grammar:1:3", "expected '-->' after the symbol A"),
    ("A --> ", "bad.grammar:1:7", "expected a rule body"),
    ("wall --> A", "bad.grammar:1:1", "expected a rule 'Symbol --> ...' or a pragma"),
    ("@foo\nA --> terminal(wall)", "bad.grammar:1:1", "unknown pragma @foo"),
    ("@start A\n@start A\nA --> terminal(wall)", "bad.grammar:2:1", "duplicate pragma @start"),
    ("# nothing", "bad.grammar:1:10", "the grammar has no rules"),
    ("A --> terminal(wall)\n\nA --> terminal(door)", "bad.grammar:3:1",
     "duplicate rule for A (first defined at line 1)"),
    ("A --> split(x) { 1: B | 2: Missing }\nB --> terminal(wall)", "bad.grammar:1:28", "undefined symbol Missing"),
    ("@start Nope\nA --> terminal(wall)", "bad.grammar:1:8", "undefined start symbol Nope"),
    ("A --> B\nB --> C\nC --> A", "bad.grammar:1:1", "rename cycle A --> B --> C --> A"),
    ("A --> split(x) { 0: A }", "bad.grammar:1:18", "a size must be positive"),
    ("A --> 60%: B\n  50%: B\nB --> terminal(wall)", "bad.grammar:2:3", "percentages add up to 110%"),
    ("A --> case width > 1: 50%: B else: B\nB --> terminal(wall)", "bad.grammar:1:23", "expected a rule body"),
    ("A --> case width > 1: case floor == 0: B\nB --> terminal(wall)", "bad.grammar:1:23", "'case' cannot be nested"),
    ("A --> repeatABA(x) { 1: B }\nB --> terminal(wall)", "bad.grammar:1:7", "repeatABA takes exactly two items"),
    ("A --> floors { 0: B | 1: B }\nB --> terminal(wall)", "bad.grammar:1:7", "floors needs a catch-all item"),
    ("A --> floors { 0: B | 0: B | *: B }\nB --> terminal(wall)", "bad.grammar:1:23", "duplicate floor selector 0"),
    ("A --> floors { 1.5: B | *: B }\nB --> terminal(wall)", "bad.grammar:1:16", "must be a whole number"),
    ("A --> grid { cols: 1 | 1 ; rows: 1 ; B }\nB --> terminal(wall)", "bad.grammar:1:38",
     "grid row 1 has 1 cells, expected 2"),
    ("A --> grid { cols: 1 ; rows: 1 | 1 ; B }\nB --> terminal(wall)", "bad.grammar:1:7",
     "grid has 1 rows of cells, expected 2"),
    ("A --> grid { cols: 1 | 1 ; rows: 1 | 1 ;\n B < / B v }\nB --> terminal(wall)", "bad.grammar:2:8",
     "do not form a rectangle"),
    ("A --> grid { cols: 1 | 1 ; rows: 1 | 1 ;\n B C / v < }\nB --> terminal(wall)\nC --> terminal(wall)",
     "bad.grammar:2:4", "do not form a rectangle"),
    ("A --> grid { cols: 1 ; rows: 1 ; < }", "bad.grammar:1:34", "'<' in the first column"),
    ("A --> grid { cols: 1 ; rows: 1 ; v }", "bad.grammar:1:34", "'v' in the bottom row"),
    ("A --> grid { cols: 1 ; rows: 1 ; B }", "bad.grammar:1:34", "undefined symbol B"),
    ("A --> terminal(wall, colour: red)", "bad.grammar:1:22", "unknown terminal key 'colour'"),
    ("A --> terminal(wall, depth: 1, depth: 2)", "bad.grammar:1:32", "duplicate terminal key 'depth'"),
    ("A --> terminal(Wall)", "bad.grammar:1:16", "expected a lower-case label"),
    ("A --> case flor == 0: B\nB --> terminal(wall)", "bad.grammar:1:12", "unknown variable 'flor'"),
    ("A --> case 1 < width < 3: B\nB --> terminal(wall)", "bad.grammar:1:22", "comparisons cannot be chained"),
    ("A --> case (width > 1: B\nB --> terminal(wall)", "bad.grammar:1:22", "expected ')', found ':'"),
]


@pytest.mark.parametrize(("text", "where", "message"), ERRORS, ids=[e[2][:40] for e in ERRORS])
def test_error_names_location_and_problem(text, where, message):
    err = parse_error(text)
    assert str(err.where) == where
    assert message in err.message
    assert err.hint


def test_error_text_renders_location_first():
    assert str(parse_error("A --> split(z) { 1: A }")).startswith("bad.grammar:1:13: expected an axis")


def test_terminals_fixture_is_valid():
    assert grammar("X --> A").start == "X"
    assert "Wall" in TERMINALS


def test_regression_size_must_be_followed_by_colon():
    # the first parser accepted "1 A" as "1: A" because the colon was only required before a non-symbol
    assert "expected ':'" in parse_error("A --> split(x) { 1 B }\nB --> terminal(wall)").message
