"""Bad grammars found by fuzzing (benchmarks/fuzz_readers.py) give a ParseError or RulesetError, not a traceback."""
from __future__ import annotations

import pytest

from citygen.errors import RulesetError
from citygen_split import derive

from .conftest import grammar, parse_error, request


def test_number_beyond_float_range_is_a_parse_error():
    # was: 1e400 parsed as inf, and a depth of inf reached the layout (a size of inf: OverflowError in repeatABA)
    err = parse_error("Wall --> terminal(wall, depth: 1e400)\n")
    assert str(err.where) == "bad.grammar:1:32"
    assert "number 1e400 is too large" in str(err)


@pytest.mark.parametrize("depth, column", [("1e308", 32), ("-1e5", 33)])
def test_a_depth_beyond_100_m_is_a_parse_error(depth, column):
    # was (fuzz): depth 1e308 parsed, and the module search's round(depth * 100) raised OverflowError: the
    # building skipped with "internal error" instead of the grammar's line
    err = parse_error(f"Wall --> terminal(wall, depth: {depth})\n")
    assert str(err.where) == f"bad.grammar:1:{column}" and "is beyond +-100 m" in str(err)
    assert grammar("Deep --> terminal(balcony, depth: -100)\n")


@pytest.mark.parametrize("body", ["repeat(x) { ~1e-308: Wall }", "repeatABA(x) { 1e-308: Wall | 1e-308: Window }",
                                  "repeat(x) { 1e-9: Wall }"])
def test_repeat_of_tiles_too_small_to_count_is_a_ruleset_error(body):
    # was: OverflowError (cannot convert float infinity to integer) in repeat_count, or a list of 1e10 items
    with pytest.raises(RulesetError) as info:
        derive(grammar(f"X --> {body}\n"), request(12, 9))
    assert str(info.value.where) == "test.grammar:1:1"
    assert "repeat of rule X" in str(info.value) and "make the repeated sizes larger" in str(info.value)


@pytest.mark.parametrize(("condition", "column"), [("(" * 300 + "width" + ")" * 300 + " < 3", 49),
                                                   ("-" * 1000 + "width < 3", 49),
                                                   ("not " * 1000 + "width < 3", 145)])
def test_deeply_nested_conditions_are_a_parse_error(condition, column):
    """Was: RecursionError (300 nested parentheses, 1000 unary operators); 32 levels is the bound."""
    err = parse_error(f"Facade --> case {condition}: Wall\n           else: Wall\n"
                      "Wall --> terminal(wall)\n")
    assert str(err.where) == f"bad.grammar:1:{column}"
    assert "expression nested more than 32 levels deep" in str(err)


def test_conditions_nested_32_deep_still_parse():
    grammar("Facade --> case " + "(" * 31 + "width < 3" + ")" * 31 + ": Wall\n           else: Wall\n")


def test_a_division_by_zero_in_a_condition_names_file_line_and_column():
    """Was: the error named the rule but no file:line."""
    with pytest.raises(RulesetError, match="division by zero in a condition of rule X") as info:
        derive(grammar("X --> case 1 / (width - width) > 0: A\n      else: B\n"), request(12, 9))
    assert str(info.value.where) == "test.grammar:1:14"
