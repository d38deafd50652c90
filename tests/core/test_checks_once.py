"""A layout's checks run once however many callers ask (issue 24): the split kind checks its derivation, the
builder checks the same layout again with the scene's rules (equal to the defaults unless the scene says
otherwise); both get the answer of one computation, as a list of their own."""
from __future__ import annotations

from dataclasses import replace

from citygen import plausible, request as request_module
from citygen.layout import leaf
from citygen.plausible import DEFAULT_RULES, PlausibilityRules, check_plausible
from citygen.request import FacadeRequest, check_request
from tests.core.test_plausible import layout_of


def counting(monkeypatch, module, name):
    calls = []
    real = getattr(module, name)
    monkeypatch.setattr(module, name, lambda *a: calls.append(a) or real(*a))
    return calls


def test_plausibility_is_computed_once_per_layout_request_and_equal_rules(monkeypatch):
    calls = counting(monkeypatch, plausible, "_findings")
    request = FacadeRequest.preview(10, 10, 3.0, 4.0)
    layout = layout_of(10, 10, leaf(1, 1, 0.19, 1.2, "Window2", "window"))
    first = check_plausible(layout, request)
    again = check_plausible(layout, request, PlausibilityRules())  # a scene's own copy of the default rules
    assert [f.code for f in first] == [f.code for f in again] == ["small-opening"] and first is not again
    assert len(calls) == 1
    stricter = replace(DEFAULT_RULES, sliver=0.5)
    check_plausible(layout, request, stricter)  # other rules, another request, another layout: computed anew
    check_plausible(layout, FacadeRequest.preview(10, 10, 3.0, 4.0))
    check_plausible(layout_of(10, 10, leaf(1, 1, 0.19, 1.2, "Window2", "window")), request)
    assert len(calls) == 4


def test_request_problems_are_computed_once_per_layout_and_request(monkeypatch):
    calls = counting(monkeypatch, request_module, "_problems")
    request = FacadeRequest.preview(10, 10, 3.0, 4.0)
    layout = layout_of(8, 10)
    problems = check_request(layout, request)
    problems.append("a caller's own note")
    assert check_request(layout, request) == problems[:-1] and problems[0].startswith("layout is 8")
    assert len(calls) == 1
