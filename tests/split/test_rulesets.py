"""The shipped grammars: partition and coordinator constraints for any size and floor set-up; the plugin."""
from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from citygen.layout import check_partition
from citygen.registry import load_registry
from citygen.request import FaceContext, FacadeRequest, check_request, split_floors
from citygen_split import derive, load

from .conftest import RULESETS

GRAMMARS = {path.stem: load(path) for path in RULESETS}


def test_at_least_four_grammars_shipped():
    assert {"apartment", "office", "house", "historic"} <= set(GRAMMARS)


@st.composite
def requests(draw) -> FacadeRequest:
    width = draw(st.floats(0.5, 80))
    height = draw(st.floats(1.0, 60))
    floor_height = draw(st.floats(2.6, 4.0))
    ground = draw(st.one_of(st.none(), st.floats(3.0, 5.5)))
    lines = split_floors(height, floor_height, ground)
    limit = min(1.0, 0.25 * width)
    corners = (draw(st.floats(0, limit)), draw(st.floats(0, limit)))
    context = FaceContext(building_id=draw(st.sampled_from(["b1", "w/42"])), face_index=draw(st.integers(0, 9)),
                          levels=len(lines) - 1, street_facing=draw(st.booleans()),
                          is_courtyard=draw(st.booleans()))
    return FacadeRequest(width=width, height=height, floor_lines=lines, entrance=draw(st.booleans()),
                         corner_widths=corners, context=context, seed=(draw(st.integers(0, 2**32)),))


@pytest.mark.parametrize("name", sorted(GRAMMARS))
@settings(max_examples=40, deadline=None)
@given(request=requests())
@example(request=FacadeRequest(  # regression: the partition check lost a 1e-6 m corner strip (house)
    1.0, 1.0, (0.0, 1.0), False, (0.12044295167792646, 1e-06), FaceContext("b1", 0, 1), (0,)))
def test_partition_and_request_constraints_hold_for_any_face(name, request):
    layout = derive(GRAMMARS[name], request)
    assert check_partition(layout) == []
    assert check_request(layout, request) == []


@pytest.mark.parametrize("name", sorted(GRAMMARS))
@pytest.mark.parametrize(("width", "height"), [(0.5, 1.0), (0.5, 60), (80, 1.0), (2.9, 3.1), (3.0, 4.0), (80, 60)])
def test_extreme_faces(name, width, height):
    for entrance in (False, True):
        request = FacadeRequest.preview(width, height, entrance=entrance)
        layout = derive(GRAMMARS[name], request)
        assert check_partition(layout) == [] and check_request(layout, request) == []


def preview(width: float, entrance: bool, **kw) -> FacadeRequest:
    return FacadeRequest.preview(width, 13.0, ground_height=4.0, entrance=entrance, **kw)


@pytest.mark.parametrize("name", sorted(GRAMMARS))
def test_entrance_ground_and_narrow_faces_differ(name):
    g = GRAMMARS[name]
    wide, door = derive(g, preview(20, False)), derive(g, preview(20, True))
    assert door.count("door") == 1 and wide.count("door") == 0
    ground = [t.label for t in wide.terminals() if t.y < 4.0 - 1e-9]
    upper = [t.label for t in wide.terminals() if 4.0 <= t.y < 7.0]
    assert ground != upper  # the ground floor has its own rule
    request = preview(2.5, False)
    narrow = derive(g, request)
    upper_lines = request.floor_lines[1:]
    per_floor = [sum(1 for t in narrow.terminals() if t.label == "window" and lo <= t.y < hi)
                 for lo, hi in zip(upper_lines[:-1], upper_lines[1:])]
    assert max(per_floor) <= 1  # narrow faces: plain wall or one window per floor
    assert derive(g, preview(1.0, False)).count("window") == 0


def test_apartment_has_shops_balconies_cornice_and_parapet():
    labels = set()
    for seed in range(6):
        labels |= set(derive(GRAMMARS["apartment"], preview(24, True, seed=seed)).labels())
    assert {"shop", "door", "window", "sill", "balcony", "cornice"} <= labels


def test_office_is_a_grid_of_panes_between_pillars():
    layout = derive(GRAMMARS["office"], preview(30, False))
    assert layout.count("pillar") > 10 and layout.count("window") > 50 and layout.count("frame") > 50


def test_kind_is_registered_by_entry_point():
    registry = load_registry()
    kind = registry.kind_for_path(Path("x.grammar"))
    assert kind.id == "split" and registry.ruleset_kind("split") is kind
    g = kind.load(RULESETS[0])
    request = FacadeRequest.preview(12, 9)
    assert kind.generate(g, request) == derive(g, request)
    assert kind.explain(g, request).splitlines()[0].startswith("Facade 12.000 x 9.000 at (0.000, 0.000)")
