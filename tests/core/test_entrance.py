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


DOORLESS = ("X --> floors { *: Row }\nRow --> repeat(x) { 3: Bay }\nBay --> split(x) { '1: Wall | 1.2: Win | '1: Wall }\n"
            "Win --> split(y) { '1: Wall | 1.4: Glass | '1: Wall }\nWall --> terminal(wall)\nGlass --> terminal(window)")


def _keyed(region: Region, out: dict) -> dict:
    """Every keyed region of ``region``'s tree: key -> the (label, offset, size) of the terminals below it."""
    if region.key is not None:
        rows = sorted((t.label, round(t.x - region.x, 9), round(t.y - region.y, 9), round(t.w, 9), round(t.h, 9))
                      for t in _terminals(region))
        out.setdefault(region.key, set()).add(tuple(rows))
    for child in region.children:
        _keyed(child, out)
    return out


def _terminals(region: Region) -> list[Region]:
    return [region] if not region.children else [t for c in region.children for t in _terminals(c)]


def test_a_carved_door_drops_the_module_hint_of_every_subtree_it_changes():
    """Subtrees alike on every face of a building share their key (the module search's hint) across faces, so the
    door carved into one face must not leave its key on the subtrees it changed: the module search then read that
    face's changed copy as the twin of the unchanged ones (IndexError: the building was skipped). Unchanged subtrees
    keep their objects and keys."""
    from citygen.geometry.modules import Signatures
    from citygen_split import derive, parse
    g = parse(DOORLESS, "doorless.grammar")

    def request(seed: int, entrance: bool) -> FacadeRequest:
        return FacadeRequest(width=12.0, height=9.0, floor_lines=(0.0, 3.0, 6.0, 9.0), entrance=entrance, seed=(seed,))

    front, side = derive(g, request(1, True)), derive(g, request(2, False))
    carved, note = enforce_entrance(front, request(1, True))
    assert note.startswith("carved") and carved.count("door") == 1
    keyed = _keyed(carved.root, _keyed(side.root, {}))
    assert len(keyed) >= 3 and all(len(contents) == 1 for contents in keyed.values())
    assert carved.root.children[2] is front.root.children[2]  # (the top storey, untouched)
    signatures = Signatures([carved.root, side.root])
    for layout in (carved, side):
        modules, loose = signatures.split(layout.root)
        assert sum(n for *_, n in modules) + len(loose) == len(layout.leaves)
