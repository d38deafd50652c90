"""The solved layouts of each direction as lazily produced, kept sequences, and which direction a plausibility
finding blames.

A request is answered by a pair (horizontal, vertical) of direction solutions. The solver yields them in its
order (:func:`citygen_layers.solver.direction_solutions`); the generator takes the first pair and, while the
composed layout has :mod:`citygen.plausible` findings, advances the direction the findings blame.
"""
from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field

from citygen.plausible import DEFAULT_RULES, Finding, PlausibilityRules
from citygen_layers.model import Ruleset
from citygen_layers.solver import DirectionSolution

#: Findings that only the vertical direction (storeys, floor lines) can cause.
VERTICAL_CODES = frozenset({"short-door", "floating-door", "empty-storey", "storey-height"})


@dataclass
class Kept:
    """The solutions of one direction produced so far, and whether the sequence has ended."""

    ruleset: Ruleset
    solutions: list[DirectionSolution] = field(default_factory=list)
    complete: bool = False


#: Kept direction sequences per process, most recently used last: the faces of a building share their height and
#: floor lines (so their vertical solve), opposite faces often their width. A solve is deterministic, so a kept
#: solution is exactly what solving again would return; sequences cut by the CPU-time limit are not kept.
_KEPT: OrderedDict[tuple, Kept] = OrderedDict()
KEEP = 256


def clear_solved() -> None:
    """Forget the kept direction solutions (benchmarks of cold solves, tests of the solver itself)."""
    _KEPT.clear()


class Alternatives:
    """One direction's solutions by index, solved on demand: ``get(i)`` is the i-th or None past the last.

    Within one request the solver's generator is resumed; a later request that needs more than was kept starts a
    new one and skips what is kept (the sequence is deterministic)."""

    def __init__(self, ruleset: Ruleset, key: tuple | None, start: Callable[[], Iterator[DirectionSolution]]):
        self._start, self._live, self._key = start, None, key
        kept = _KEPT.get(key) if key is not None else None
        if kept is None or kept.ruleset is not ruleset:
            kept = Kept(ruleset)
            if key is not None:
                _KEPT[key] = kept
                if len(_KEPT) > KEEP:
                    _KEPT.popitem(last=False)
        elif key is not None:
            _KEPT.move_to_end(key)
        self.kept = kept

    def get(self, index: int) -> DirectionSolution | None:
        kept = self.kept
        while len(kept.solutions) <= index and not kept.complete:
            if self._live is None:
                self._live = self._start()
                for _ in range(len(kept.solutions)):
                    next(self._live)
            solution = next(self._live, None)
            if solution is None:
                kept.complete = True
                break
            kept.solutions.append(solution)
            if solution.timed_out and self._key is not None:   # depends on timing: not kept for later requests
                _KEPT.pop(self._key, None)
                self._key = None
        return kept.solutions[index] if index < len(kept.solutions) else None


def blamed_axes(findings: Iterable[Finding], rules: PlausibilityRules = DEFAULT_RULES) -> set[str]:
    """The directions (``"x"``, ``"y"``) whose solution a layout's findings point at: a terminal too narrow is the
    horizontal solve's, too low the vertical's; doors and storeys are the vertical's; a finding without a
    terminal (a relabelled opening, a count) blames both."""
    axes: set[str] = set()
    for finding in findings:
        region = finding.region
        if finding.code in VERTICAL_CODES:
            axes.add("y")
        elif region is None:
            if not finding.message.startswith("..."):
                axes |= {"x", "y"}
        else:
            min_w, min_h = _minimum(finding.code, region.label, rules)
            if region.w < min_w - 1e-6:
                axes.add("x")
            if region.h < min_h - 1e-6:
                axes.add("y")
            if not (region.w < min_w - 1e-6 or region.h < min_h - 1e-6):
                axes |= {"x", "y"}
    return axes


def _minimum(code: str, label: str | None, rules: PlausibilityRules) -> tuple[float, float]:
    if code == "zero-size":
        return rules.min_extent, rules.min_extent
    if code == "sliver":
        return rules.sliver, rules.sliver
    return rules.min_size.get(label or "", (0.0, 0.0))
