"""Mutated relayout models (benchmarks/fuzz_readers.py) give a CitygenError, never a traceback."""
from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ..mutate import fuzz_ruleset, scratch_rulesets

RULESETS = sorted((Path(__file__).resolve().parents[2] / "rulesets").glob("*.relayout"))


@pytest.fixture(scope="module")
def scratch(tmp_path_factory):
    return scratch_rulesets(tmp_path_factory.mktemp("fuzz"))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(path=st.sampled_from(RULESETS), seed=st.integers(0, 2 ** 32 - 1))
def test_mutated_shipped_relayout_models_raise_only_citygen_errors(scratch, path, seed):
    fuzz_ruleset(scratch, path, seed)
