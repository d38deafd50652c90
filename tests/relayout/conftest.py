from __future__ import annotations

from pathlib import Path

import pytest

from citygen_relayout import load_model

RULESETS = Path(__file__).resolve().parents[2] / "rulesets"
MODELS = ("townhouse", "fig7_walkthrough", "cmp_b0035")


@pytest.fixture(scope="session")
def models():
    return {name: load_model(RULESETS / f"{name}.relayout") for name in MODELS}
