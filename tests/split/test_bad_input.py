"""Bad grammars found by fuzzing (benchmarks/fuzz_readers.py) give a ParseError or RulesetError, not a traceback."""
from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from citygen.errors import RulesetError
from citygen_split import derive

from ..mutate import fuzz_ruleset, scratch_rulesets
from .conftest import RULESETS, grammar, parse_error, request


def test_number_beyond_float_range_is_a_parse_error():
    # was: 1e400 parsed as inf, and a depth of inf reached the layout (a size of inf: OverflowError in repeatABA)
    err = parse_error("Wall --> terminal(wall, depth: 1e400)\n")
    assert str(err.where) == "bad.grammar:1:32"
    assert "number 1e400 is too large" in str(err)


@pytest.mark.parametrize("body", ["repeat(x) { ~1e-308: Wall }", "repeatABA(x) { 1e-308: Wall | 1e-308: Window }",
                                  "repeat(x) { 1e-9: Wall }"])
def test_repeat_of_tiles_too_small_to_count_is_a_ruleset_error(body):
    # was: OverflowError (cannot convert float infinity to integer) in repeat_count, or a list of 1e10 items
    with pytest.raises(RulesetError) as info:
        derive(grammar(f"X --> {body}\n"), request(12, 9))
    assert str(info.value.where) == "test.grammar:1:1"
    assert "repeat of rule X" in str(info.value) and "make the repeated sizes larger" in str(info.value)


@pytest.fixture(scope="module")
def scratch(tmp_path_factory):
    return scratch_rulesets(tmp_path_factory.mktemp("fuzz"))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(path=st.sampled_from(RULESETS), seed=st.integers(0, 2 ** 32 - 1))
def test_mutated_shipped_grammars_raise_only_citygen_errors(scratch, path, seed):
    fuzz_ruleset(scratch, path, seed)
