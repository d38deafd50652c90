"""Relayout models (bao2013): many constrained variations of one facade layout, on every face of a building."""
from __future__ import annotations

from citygen_relayout.api import relayout, variations
from citygen_relayout.model import Model
from citygen_relayout.parser import load_model, parse_model
from citygen_relayout.search import Constraints, RelayoutResult
from citygen_relayout.validate import validate

__all__ = ["Constraints", "Model", "RelayoutResult", "load_model", "parse_model", "relayout", "validate",
           "variations"]
