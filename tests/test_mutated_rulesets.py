"""Mutated copies of the shipped rulesets (split grammars, layer stacks, relayout models: ``tests/mutate.py``, the
bounded property of ``benchmarks/fuzz_readers.py``) load and generate a preview or raise a CitygenError, never
anything else; the regressions it found are named in each reader's ``test_bad_input.py``."""
from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from .mutate import fuzz_ruleset, scratch_rulesets

RULESETS = sorted(p for p in (Path(__file__).resolve().parents[1] / "rulesets").iterdir()
                  if p.suffix in (".grammar", ".layers", ".relayout"))


@pytest.fixture(scope="module")
def scratch(tmp_path_factory):
    return scratch_rulesets(tmp_path_factory.mktemp("fuzz"))


@settings(max_examples=90, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(path=st.sampled_from(RULESETS), seed=st.integers(0, 2 ** 32 - 1))
def test_mutated_shipped_rulesets_raise_only_citygen_errors(scratch, path, seed):
    fuzz_ruleset(scratch, path, seed)
