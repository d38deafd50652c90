"""The facade sweep: every shipped ruleset at sizes nobody tuned it for, each outcome classified.

A generator may dress a face (a plausible layout meeting the request) or say it cannot (a plain wall with
``meta["fallback"]``, so the scene's fallback chain takes over); what it may not do is return an implausible layout
or one breaking the request as if it had succeeded. ``tests/core/test_sweep.py`` runs a bounded grid,
``benchmarks/facade_sweep.py`` the full one.
"""
from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from citygen.cli import facade_outcome
from citygen.errors import CitygenError
from citygen.registry import Registry
from citygen.request import FacadeRequest

RULESETS = Path(__file__).resolve().parents[1] / "rulesets"
SHIPPED = tuple(sorted(p.name for p in RULESETS.iterdir() if p.suffix in (".grammar", ".layers", ".relayout", ".safe")))

#: The full grid: widths 2-60 m, heights 3-60 m, three storey heights (the ground floor max(storey, 4 m)).
WIDTHS = (2.0, 3.0, 4.0, 5.5, 7.0, 8.5, 10.0, 12.0, 13.7, 17.0, 20.0, 26.0, 33.0, 40.0, 50.0, 60.0)
HEIGHTS = (3.0, 4.5, 6.0, 7.0, 9.0, 12.0, 15.0, 19.5, 24.0, 31.0, 40.0, 50.0, 60.0)
STOREYS = (2.6, 3.0, 3.6)
#: A bounded grid for the test suite (odd sizes on purpose).
SMALL_WIDTHS = (2.0, 5.5, 8.5, 13.7, 26.0, 47.0)
SMALL_HEIGHTS = (3.0, 7.0, 13.5, 31.0)


@dataclass(frozen=True)
class Case:
    ruleset: str
    width: float
    height: float
    storey: float
    outcome: str            # dressed | fell-back | implausible | constraints-broken | error
    reasons: tuple[str, ...]

    @property
    def bad(self) -> bool:
        """A broken result reported as a success."""
        return self.outcome in ("implausible", "constraints-broken")


def request(width: float, height: float, storey: float, seed: int = 0) -> FacadeRequest:
    return FacadeRequest.preview(width, height, floor_height=storey, ground_height=max(storey, 4.0), seed=seed)


def run_case(registry: Registry, name: str, width: float, height: float, storey: float, seed: int = 0) -> Case:
    """One ruleset at one size, classified as ``citygen facade`` classifies it (``error``: the generator raised a
    citygen error, which the builder also turns into a fallback)."""
    kind, ruleset = _loaded(registry, name)
    return classify(kind, ruleset, name, width, height, storey, seed)


def classify(kind, ruleset, name: str, width: float, height: float, storey: float, seed: int = 0) -> Case:
    """One loaded ruleset of ``kind`` at one size (any ruleset: an extracted grammar too), classified."""
    req = request(width, height, storey, seed)
    try:
        layout = kind.generate(ruleset, req)
    except CitygenError as exc:
        return Case(name, width, height, storey, "error", (str(exc),))
    outcome, reasons = facade_outcome(layout, req)
    return Case(name, width, height, storey, outcome, tuple(reasons))


_LOADED: dict[tuple[int, str], tuple] = {}


def _loaded(registry: Registry, name: str) -> tuple:
    """(kind, parsed ruleset) of a shipped ruleset, parsed once per registry."""
    key = (id(registry), name)
    if key not in _LOADED:
        kind = registry.kind_for_path(RULESETS / name)
        _LOADED[key] = kind, kind.load(RULESETS / name)
    return _LOADED[key]


def sweep(registry: Registry, names=SHIPPED, widths=WIDTHS, heights=HEIGHTS, storeys=STOREYS) -> Iterator[Case]:
    for name in names:
        for storey in storeys:
            for height in heights:
                for width in widths:
                    yield run_case(registry, name, width, height, storey)
