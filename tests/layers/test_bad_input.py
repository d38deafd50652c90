"""Bad layer stacks found by fuzzing (benchmarks/fuzz_readers.py) give a ParseError, not a traceback."""
from __future__ import annotations

import pytest

from citygen.errors import ParseError
from citygen_layers.parser import parse

HEAD = "symbol A size=1 opaque\nsymbol B size=1\ncounter k\n"


@pytest.mark.parametrize("line, where", [
    ("symbol C size=nan\n", ":4:10"),    # was: ValueError "arange: cannot compute length" in sample_sizes
    ("symbol C size=inf\n", ":4:10"),
    ("pattern P = A (B A)^k\nlayer l x=P y=P depth=nan\n", ":5:17"),  # was: a NaN depth in the generated layout
    ("pattern P = A (B A)^k\nlayer l x=P y=P depth=-inf\n", ":5:17"),
])
def test_nan_and_inf_are_not_numbers_of_a_layer_stack(line, where):
    with pytest.raises(ParseError) as info:
        parse(HEAD + line, "stack.layers")
    assert f"stack.layers{where}" in str(info.value) and "expected a finite number" in str(info.value)


@pytest.mark.parametrize("line, where", [
    ("symbol C size=1 depth=1e308\n", ":4:17"),  # was (as in grammars): OverflowError in the module search
    ("pattern P = A (B A)^k\nlayer l x=P y=P depth=-1e5\n", ":5:17"),
])
def test_a_depth_beyond_100_m_is_a_parse_error(line, where):
    with pytest.raises(ParseError) as info:
        parse(HEAD + line, "stack.layers")
    assert f"stack.layers{where}" in str(info.value) and "is beyond +-100 m" in str(info.value)


def test_layer_stack_that_is_not_utf8_is_a_parse_error(tmp_path):
    from citygen_layers.parser import load
    (tmp_path / "s.layers").write_bytes(HEAD.encode() + b"# caf\xe9\n")  # was: UnicodeDecodeError
    with pytest.raises(ParseError, match=r"s.layers: ruleset is not UTF-8 text \(byte 0xe9 at offset"):
        load(tmp_path / "s.layers")


def test_patterns_nested_past_the_bound_are_a_parse_error():
    """Was: RecursionError at 400 nested groups; 32 levels is the bound."""
    parse(HEAD + "pattern P = " + "(" * 31 + "A B" + ")" * 31 + "\nlayer l x=P y=P\n")
    with pytest.raises(ParseError, match="pattern nested more than 32 levels deep") as info:
        parse(HEAD + "pattern P = " + "(" * 400 + "A B" + ")" * 400 + "\n")
    assert str(info.value.where) == "<string>:4:45"  # the 33rd "("
