"""Bad structure-aware edit rulesets and layouts found by fuzzing (benchmarks/fuzz_readers.py) give a ParseError
naming the .safe line and the layout's problem, not a traceback."""
from __future__ import annotations

import json
import random
import shutil
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from citygen.errors import ParseError
from citygen_safe.ruleset import load_ruleset

from ..mutate import fuzz_ruleset, load_and_generate, mutate, scratch_rulesets

RULESETS = Path(__file__).resolve().parents[2] / "rulesets"
SAFE = "safe s\nlayout \"f.layout.json\"\n"


def write_layout(tmp_path: Path, region: dict) -> Path:
    layout = {"schema_version": 1, "width": 2, "height": 3, "root": {
        "x": 0, "y": 0, "w": 2, "h": 3, "symbol": "F", "children": [
            {"x": 0, "y": 0, "w": 2, "h": 3, "symbol": "Wall", "label": "wall", **region}]}}
    (tmp_path / "f.layout.json").write_text(json.dumps(layout))
    (tmp_path / "s.safe").write_text(SAFE)
    return tmp_path / "s.safe"


@pytest.mark.parametrize("region, words", [
    ({"label": {}}, "root.children[0] has label = {}, not a string"),   # was: TypeError unhashable 'dict'
    ({"w": 10 ** 400}, "root.children[0] has w = 1000"),                 # was: OverflowError
    ({"depth": float("inf")}, "root.children[0] has depth = inf"),      # was: an inf depth in the edited layout
])
def test_malformed_layout_of_a_safe_ruleset_is_a_parse_error(tmp_path, region, words):
    with pytest.raises(ParseError) as info:
        load_ruleset(write_layout(tmp_path, region))
    assert str(info.value.where) == f"{tmp_path / 's.safe'}:2:8" and words in str(info.value)


def test_layout_without_root_is_a_parse_error(tmp_path):
    (tmp_path / "f.layout.json").write_text('{"schema_version": 1, "width": 2, "height": 3}')  # was: KeyError
    (tmp_path / "s.safe").write_text(SAFE)
    with pytest.raises(ParseError, match="layout has no root region"):
        load_ruleset(tmp_path / "s.safe")


@pytest.fixture(scope="module")
def scratch(tmp_path_factory):
    return scratch_rulesets(tmp_path_factory.mktemp("fuzz"))


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2 ** 32 - 1))
def test_mutated_shipped_safe_ruleset_raises_only_citygen_errors(scratch, seed):
    fuzz_ruleset(scratch, RULESETS / "cmp_b0035.safe", seed)


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2 ** 32 - 1))
def test_mutated_layout_of_the_safe_ruleset_raises_only_citygen_errors(scratch, seed):
    layout = scratch / "cmp_b0035.layout.json"
    try:
        layout.write_text(mutate((RULESETS / layout.name).read_text(), "json", random.Random(seed)))
        load_and_generate(scratch / "cmp_b0035.safe")
    finally:
        shutil.copy(RULESETS / layout.name, layout)


def test_layout_path_with_a_nul_byte_is_a_parse_error(tmp_path):
    (tmp_path / "s.safe").write_text('safe s\nlayout "f\x00.layout.json"\n')  # was: ValueError embedded null byte
    with pytest.raises(ParseError) as info:
        load_ruleset(tmp_path / "s.safe")
    assert str(info.value.where) == f"{tmp_path / 's.safe'}:2:8" and "cannot read layout" in str(info.value)


def test_ruleset_that_is_not_utf8_is_a_parse_error(tmp_path):
    (tmp_path / "s.safe").write_bytes(b"safe s\xff\n")  # was: UnicodeDecodeError
    with pytest.raises(ParseError, match=r"not UTF-8 text \(byte 0xff at offset 6\).*save the file as UTF-8"):
        load_ruleset(tmp_path / "s.safe")


def test_a_layout_that_is_not_a_partition_is_a_parse_error(tmp_path):
    """Was: accepted (a window overlapping the wall it sits on, a gap), and the edits moved broken regions."""
    from citygen.layout import FacadeLayout, Region
    overlapping = FacadeLayout(10.0, 6.0, Region(0.0, 0.0, 10.0, 6.0, "Facade", children=(
        Region(0.0, 0.0, 10.0, 6.0, "Wall", "wall"), Region(2.0, 2.0, 1.0, 1.5, "Window", "window"))))
    (tmp_path / "f.layout.json").write_text(overlapping.dumps())
    (tmp_path / "s.safe").write_text(SAFE)
    with pytest.raises(ParseError, match="layout 'f.layout.json' is not a partition: ") as info:
        load_ruleset(tmp_path / "s.safe")
    assert str(info.value.where).endswith("s.safe:2:8")
