"""LastSolve: generate then explain of one ruleset and request solve once; anything else solves again."""
from __future__ import annotations

import pickle
from dataclasses import replace
from pathlib import Path

from citygen.lastsolve import LastSolve
from citygen.registry import default_registry
from citygen.request import FacadeRequest

REPO = Path(__file__).resolve().parents[2]


def test_the_same_ruleset_and_request_solve_once():
    calls = []
    solve = LastSolve(lambda ruleset, request: calls.append((ruleset, request)) or len(calls))
    ruleset, request = object(), FacadeRequest.preview(10, 9)
    assert solve(ruleset, request) == solve(ruleset, FacadeRequest.preview(10, 9)) == 1
    assert solve(ruleset, FacadeRequest.preview(11, 9)) == 2  # another size
    assert solve(object(), FacadeRequest.preview(11, 9)) == 3  # another ruleset object
    assert solve(ruleset, replace(FacadeRequest.preview(11, 9), plausibility=object())) == 4  # other rules
    assert pickle.loads(pickle.dumps(LastSolve(max)))._last is None


def test_safe_and_relayout_explain_reuse_the_generated_solve():
    registry = default_registry()
    for name in ("cmp_b0035.safe", "cmp_b0035.relayout"):
        path = REPO / "rulesets" / name
        kind = type(registry.kind_for_path(path))()  # (a fresh kind: nothing remembered)
        memory = next(v for v in vars(kind).values() if isinstance(v, LastSolve))
        solve, calls = memory._solve, []
        memory._solve = lambda ruleset, request: calls.append(request) or solve(ruleset, request)
        ruleset, request = kind.load(path), FacadeRequest.preview(14, 12, seed=3)
        layout = kind.generate(ruleset, request)
        assert kind.explain(ruleset, request) and kind.generate(ruleset, request) is layout
        assert len(calls) == 1, name
