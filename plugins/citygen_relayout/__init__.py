"""Relayout models (bao2013): many constrained variations of one facade layout, on every face of a building.

The names below are imported on first use (PEP 562), so loading the plugin costs a city without relayout models
nothing."""
from __future__ import annotations

import importlib
from typing import Any

# (eager: its module has the same name, and importing that module would rebind a lazy name to it)
from citygen_relayout.validate import validate

_HOME = {"relayout": "api", "variations": "api", "Model": "model", "load_model": "parser", "parse_model": "parser",
         "Constraints": "search", "RelayoutResult": "search"}

__all__ = sorted([*_HOME, "validate"])


def __getattr__(name: str) -> Any:
    if name not in _HOME:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{_HOME[name]}"), name)
