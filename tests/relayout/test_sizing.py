"""The sizing QP (bao2013 §7.2) and its rows: both solvers agree, start-position rows merge like explicit ones."""
from __future__ import annotations

import numpy as np
import pytest

from citygen_relayout import sizing
from citygen_relayout.arrange import Row


@pytest.fixture(params=["daqp", "quadprog"])
def method(request, monkeypatch):
    monkeypatch.setattr(sizing, "METHOD", request.param)
    return request.param


def test_solver_keeps_equalities_inequalities_and_bounds(method):
    # three sizes near (2, 3, 4): x0 = x2 - 1 (equality), x0 + x1 + x2 <= 8 (the total), 1 <= x <= 3.5
    x = sizing.solve_sizes(np.array([2.0, 3.0, 4.0]), [1.0, 1.0, 1.0], [3.5, 3.5, 3.5],
                           [[1.0, 0.0, -1.0], [1.0, 1.0, 1.0]], [-1.0, 8.0], 1, np.ones(3))
    assert x is not None
    assert x[0] - x[2] == pytest.approx(-1.0, abs=1e-9)
    assert x.sum() <= 8.0 + 1e-9
    assert np.all(x >= 1.0) and np.all(x <= 3.5)


def test_solver_reports_infeasible_rows_and_crossed_bounds(method):
    assert sizing.solve_sizes(np.array([2.0, 2.0]), [1.0, 1.0], [3.0, 3.0], [[1.0, 1.0]], [7.0], 1) is None
    assert sizing.solve_sizes(np.array([2.0]), [2.0], [1.0], [[1.0]], [5.0], 0) is None


def test_start_position_rows_are_the_explicit_rows():
    # x_1's start is x_0; "start of 1 minus x_0's copy is zero" is a merge of two variables, as a dict row is
    prefixed = Row({1: 1.0}, 0.0, True, "t", prefix=1, sign=-1)
    explicit = Row({0: -1.0, 1: 1.0}, 0.0, True, "t")
    assert prefixed.pair == explicit.pair == (0, 1)
    assert Row({}, 0.0, True, "t", prefix=2).pair is None  # x_0 + x_1 = 0 merges nothing
    assert Row({}, 0.0, False, "t", prefix=1, sign=-1).pair is None  # inequalities never merge
