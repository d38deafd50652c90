"""Module keys (``Region.key``): replicas of one symbol share a key, independent instances carry none."""
from __future__ import annotations

from collections import defaultdict

from citygen.layout import Region
from citygen.request import FacadeRequest, split_floors
from citygen_relayout import parse_model, relayout
from citygen_relayout.building import generate_building

ROWS = """model rows
root F 4 6
split F y Row:2 Row:2 Row:2
split Row x Cell:2 Cell:2
split Cell y Sill:0.2 Glass:1.8
terminal Sill sill
terminal Glass window
size Cell 0.8..3
repeat F : Row+
repeat Row : Cell+
"""


def _relative(region: Region) -> list:
    """The subtree relative to its origin, rounded to 1e-9 m (positions are sums of floats)."""
    return [(t.symbol, t.label, round(t.x - region.x, 9), round(t.y - region.y, 9), round(t.w, 9), round(t.h, 9))
            for t in region.terminals()]


def _keyed(root: Region) -> dict[int, list[Region]]:
    groups: dict[int, list[Region]] = defaultdict(list)
    stack = [root]
    while stack:
        r = stack.pop()
        if r.key is not None:
            groups[r.key].append(r)
        stack.extend(r.children)
    return groups


def test_replicas_share_a_key_and_an_identical_subtree():
    model = parse_model(ROWS, "rows.relayout")
    for seed in range(10):
        result = relayout(model, 5.0 + seed % 3, 7.0, seed=seed)
        assert result.success, result.message
        groups = _keyed(result.layout.root)
        rows = [r for r in result.layout.root.children if r.symbol.startswith("Row")]
        assert len({r.key for r in rows}) == 1 and rows[0].key is not None  # all Rows are replicas of one
        assert any(len(g) > 1 for g in groups.values())
        for regions in groups.values():
            assert all(_relative(r) == _relative(regions[0]) for r in regions)


def test_independent_instances_carry_no_key():
    model = parse_model(ROWS + "instances F Row 3..3\nfreq F Row 3..3\n", "rows.relayout")
    result = relayout(model, 4.0, 6.0, seed=1)
    assert result.success, result.message
    rows = [r for r in result.layout.root.children if r.symbol.startswith("Row")]
    assert len({r.symbol for r in rows}) == 3  # three distinct, independently relayouted instances
    assert all(r.key is None for r in rows)


def test_keys_differ_between_the_faces_of_a_building():
    model = parse_model(ROWS, "rows.relayout")
    lines = split_floors(6.0, 2.0)
    reqs = [FacadeRequest(4.0 + i, 6.0, lines, seed=(3, i)) for i in range(3)]
    faces = [_keyed(lay.root) for lay in generate_building(model, reqs)]
    assert all(faces)
    assert not set(faces[0]) & set(faces[1]) and not set(faces[1]) & set(faces[2])
