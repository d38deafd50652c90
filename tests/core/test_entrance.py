from hypothesis import given, settings, strategies as st

from citygen.entrance import enforce_entrance
from citygen.layout import FacadeLayout, Region, check_partition
from citygen.request import FacadeRequest, check_request
from tests.core.fakes import GridKind


def grid(w, h, entrance):
    req = FacadeRequest.preview(w, h, entrance=entrance)
    return GridKind().generate({"bay": 3.0, "window": 1.3}, req), req


@settings(max_examples=80, deadline=None)
@given(st.floats(2.0, 40.0), st.floats(3.0, 30.0))
def test_carved_door_keeps_the_partition(w, h):
    layout, _ = grid(w, h, entrance=False)  # a layout without a door...
    req = FacadeRequest.preview(w, h, entrance=True)  # ...on the entrance face
    fixed, note = enforce_entrance(layout, req)
    assert note and "carved" in note
    assert check_partition(fixed) == []
    assert fixed.count("door") == 1
    assert [p for p in check_request(fixed, req) if "door" in p] == []


def test_extra_doors_become_wall():
    layout, _ = grid(12, 9, entrance=True)
    fixed, note = enforce_entrance(layout, FacadeRequest.preview(12, 9, entrance=False))
    assert fixed.count("door") == 0 and "wall" in note
    assert check_partition(fixed) == []


def test_single_wall_gets_a_door():
    layout = FacadeLayout(6, 3, Region(0, 0, 6, 3, "Wall", "wall"))
    fixed, _ = enforce_entrance(layout, FacadeRequest.preview(6, 3, entrance=True))
    assert fixed.count("door") == 1 and check_partition(fixed) == []


def test_narrow_face_reports_no_room():
    layout = FacadeLayout(0.5, 3, Region(0, 0, 0.5, 3, "Wall", "wall"))
    fixed, note = enforce_entrance(layout, FacadeRequest.preview(0.5, 3, entrance=True))
    assert fixed is layout and "no room" in note


def test_layer_stack_gets_the_door_in_its_front_layer():
    """Regression: a door carved into a layer stack left a hole in every layer (per-layer partition broken)."""
    layers = tuple(Region(0, 0, 6, 4, name, layer=name, children=(Region(0, 0, 6, 4, "W", "wall", layer=name),))
                   for name in ("back", "front"))
    layout = FacadeLayout(6, 4, Region(0, 0, 6, 4, "Stack", children=layers))
    fixed, note = enforce_entrance(layout, FacadeRequest.preview(6, 4, entrance=True))
    assert "carved" in note and check_partition(fixed) == []
    doors = [r for r in fixed.leaves if r.label == "door"]
    assert [r.layer for r in doors] == ["front"]
    back = [r for r in fixed.leaves if r.layer == "back"]
    assert any(r.label is None and (r.x, r.w) == (doors[0].x, doors[0].w) for r in back)
