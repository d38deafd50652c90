"""A split grammar's stochastic rules are the building's choices: every face of a building draws the same
(``FacadeRequest.style_seed``), so its faces agree on shutters and on which floors have balconies."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from citygen.registry import default_registry
from citygen.request import FacadeRequest, FaceContext

REPO = Path(__file__).resolve().parents[2]


def building(ruleset: str, widths: list[float], height: float, seed: int) -> list:
    """The layouts of a building's faces of ``widths`` (no entrance), as the builder asks for them."""
    kind = default_registry().kind_for_path(REPO / "rulesets" / ruleset)
    grammar = kind.load(REPO / "rulesets" / ruleset)
    base = FacadeRequest.preview(widths[0], height, floor_height=3.0, entrance=False)
    requests = [replace(base, width=w, seed=(seed, "way/1", k), style_seed=(seed, "way/1"),
                        context=FaceContext(building_id="way/1", face_index=k, levels=len(base.floor_lines) - 1))
                for k, w in enumerate(widths)]
    return kind.generate_building(grammar, requests)


def floors_with(layout, label: str) -> frozenset[int]:
    """The floors (by the layout's floor lines: 3 m storeys) that hold a ``label`` terminal."""
    return frozenset(int(t.y // 3.0) for t in layout.terminals() if t.label == label)


@pytest.mark.parametrize("seed", range(12))
def test_a_houses_faces_agree_on_shutters(seed):
    """Bug fixture (visual audit, 4 Dec): house.grammar's ``BayStyle`` (50 %: shutters) was drawn per face, so a
    house had shutters on some faces and none on the others."""
    layouts = building("house.grammar", [9.7, 7.3, 9.7, 7.3], 6.0, seed)
    shuttered = [any(t.symbol == "Shutter" for t in layout.terminals()) for layout in layouts]
    assert len(set(shuttered)) == 1


@pytest.mark.parametrize("seed", range(12))
def test_an_apartment_blocks_faces_agree_on_its_balcony_floors(seed):
    """apartment.grammar's ``each 30%: BalconyFloor`` is drawn per floor: the same floors on every face (drawn per
    face before, so balconies stopped at the corners)."""
    layouts = building("apartment.grammar", [19.5, 12.1, 19.5, 12.1], 18.0, seed)
    assert len({floors_with(layout, "balcony") for layout in layouts}) == 1


def test_faces_still_differ_between_buildings():
    houses = [building("house.grammar", [9.7, 7.3], 6.0, seed) for seed in range(12)]
    assert len({any(t.symbol == "Shutter" for t in h[0].terminals()) for h in houses}) == 2
