"""The last solve of a ruleset kind, kept so that ``generate`` and ``explain`` of the same ruleset and request (what
``citygen facade --explain`` and the studio's preview ask one after the other) solve once."""
from __future__ import annotations

from collections.abc import Callable
from typing import Any, Generic, TypeVar

from citygen.request import FacadeRequest

Result = TypeVar("Result")


class LastSolve(Generic[Result]):
    """``solve(ruleset, request)`` remembering its last answer: asked again for the same ruleset object and an equal
    request (same plausibility rules object too; the field is not compared), it answers from memory. One entry,
    replaced whole, so threads sharing it at worst solve twice. ``solve`` must be deterministic for its inputs."""

    def __init__(self, solve: Callable[[Any, FacadeRequest], Result]) -> None:
        self._solve = solve
        self._last: tuple[Any, FacadeRequest, Result] | None = None

    def __call__(self, ruleset: Any, request: FacadeRequest) -> Result:
        last = self._last
        if (last is not None and last[0] is ruleset and last[1] == request
                and last[1].plausibility is request.plausibility):
            return last[2]
        result = self._solve(ruleset, request)
        self._last = (ruleset, request, result)
        return result

    def __getstate__(self) -> dict[str, Any]:  # (a kind pickled for a worker process travels without its memory)
        return {"_solve": self._solve, "_last": None}
