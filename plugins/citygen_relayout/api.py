"""Public entry points: one relayout, or several variations of one size."""
from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from citygen.layout import FacadeLayout
from citygen.plausible import check_plausible
from citygen.rng import derive_rng
from citygen_relayout.model import Model
from citygen_relayout.search import Constraints, RelayoutResult, Search


def relayout(model: Model, width: float, height: float, *, seed: int = 0, rng: np.random.Generator | None = None,
             constraints: Constraints | None = None, budget_s: float = 10.0, backtrack_budget: int = 12000,
             restarts: str = "luby", judge: Callable[[FacadeLayout], Sequence] | None = check_plausible
             ) -> RelayoutResult:
    """One variation of ``model`` for a ``width x height`` target (bao2013 §7); never raises on infeasibility.

    A complete layout is held to ``judge`` (default: :func:`citygen.plausible.check_plausible` without a request;
    ``None`` accepts any): one with findings is rejected and the search restarts within its budget.

    The search budget is counted in work (``backtrack_budget`` backtracks over all restarts; ``restarts`` is the
    cutoff schedule, ``"luby"`` or the paper's ``"fixed"`` 1000), so results do not depend on machine speed;
    ``budget_s`` (seconds of this process's CPU time, so a loaded machine does not trigger it) is a safety net.
    """
    if width <= 0 or height <= 0:
        return RelayoutResult(False, None, "invalid-size", f"target size {width:g} x {height:g} must be positive")
    if rng is None:
        rng = derive_rng("relayout", model.name, seed)
        if constraints is None:
            constraints = Constraints(key_salt=(seed,))
    return Search(model, width, height, rng, constraints, budget_s=budget_s, backtrack_budget=backtrack_budget,
                  restarts=restarts, judge=judge).run()


def variations(model: Model, width: float, height: float, count: int, *, seed: int = 0,
               budget_s: float = 10.0) -> list[RelayoutResult]:
    """``count`` variations for one size, each from its own derived random stream."""
    return [relayout(model, width, height, rng=derive_rng("relayout", model.name, seed, k), budget_s=budget_s)
            for k in range(count)]
