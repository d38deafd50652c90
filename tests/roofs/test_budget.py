"""Roofs over many courtyards (issue 23 #2): the straight skeleton's split-event search over near pairs finds what
the dense scan finds, and a roof over its time budget is built flat with a warning."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from shapely.geometry.polygon import orient

import citygen.roofmesh
import citygen_roofs.skeleton as skeleton
from citygen.pipeline import generate_city
from citygen.roof import RoofBudgetExceeded, check_budget, roof_budget
from citygen.scene import load_scene

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from roof_courtyards import courtyards  # noqa: E402


@pytest.mark.parametrize("holes", [12, 40])
def test_the_near_pair_search_gives_the_dense_scans_skeleton(holes, monkeypatch):
    """Was: every reflex vertex against every edge at every event (500 courtyards: 730 s); now a k-d tree limits
    the pairs to those that can meet before a first guess of the next event, with the same result."""
    polygon = orient(courtyards(holes, seed=holes), 1.0)
    monkeypatch.setattr(skeleton, "DENSE_PAIRS", 10**12)
    dense = skeleton.straight_skeleton(polygon)
    monkeypatch.setattr(skeleton, "DENSE_PAIRS", 0)
    near = skeleton.straight_skeleton(polygon)
    assert near.faces == dense.faces and np.array_equal(near.nodes, dense.nodes)


def test_check_budget_raises_only_inside_an_exhausted_budget():
    check_budget()  # no budget: nothing
    with roof_budget(60.0):
        check_budget()
    with roof_budget(0.0), pytest.raises(RoofBudgetExceeded, match="over the roof time budget of 0 s"):
        check_budget()


def test_a_roof_over_its_time_budget_is_built_flat_with_a_warning(small_scene, test_registry, monkeypatch):
    small_scene.write_text(small_scene.read_text().replace("[defaults]\n", '[defaults]\nroof_shape = "hipped"\n'))
    monkeypatch.setattr(citygen.roofmesh, "ROOF_BUDGET", 0.0)
    report = generate_city(load_scene(small_scene), registry=test_registry)
    assert report.written == 3
    flat = [w for w in report.warnings if "flat roof instead of hipped: RoofBudgetExceeded: over the roof time "
                                          "budget of 0 s" in w]
    assert len(flat) == 3
