"""The plausibility check (citygen.plausible): each rule on a hand-made layout, the rules from a scene table, and the
builder holding generators to it (an implausible facade falls back through the scene's chain, counted in the
report)."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from citygen.errors import SceneError
from citygen.layout import FacadeLayout, Region, leaf
from citygen.plausible import (
    DEFAULT_RULES, PlausibilityRules, _suspect, _terminal_findings, check_plausible, plain_wall, summary,
)
from citygen.request import FacadeRequest
from citygen.scene import load_scene


def layout_of(width: float, height: float, *leaves: Region, **meta) -> FacadeLayout:
    """Leaves given, the rest of the face filled by wall strips beside and between them (a partition is not
    needed: the plausibility rules read terminals only)."""
    return FacadeLayout(width, height, Region(0, 0, width, height, "Facade", children=tuple(leaves)), meta=meta)


def codes(layout: FacadeLayout, request: FacadeRequest | None = None, rules=DEFAULT_RULES) -> list[str]:
    return [f.code for f in check_plausible(layout, request, rules)]


def test_a_plain_facade_of_decent_windows_is_plausible():
    request = FacadeRequest.preview(10, 10, 3.0, 4.0)
    windows = [leaf(1 + 3 * i, y + 0.9, 1.2, 1.5, "Window", "window") for i in range(3) for y in (4.0, 7.0)]
    door = leaf(4.4, 0, 1.2, 2.3, "Door", "door")
    assert check_plausible(layout_of(10, 10, *windows, door), request) == []


@pytest.mark.parametrize("region, code", [
    (leaf(1, 1, 1.77, 0.0, "W.G", "shop"), "zero-size"),                       # layers: a 0 m tall shop
    (leaf(1, 1, 0.19, 1.2, "Window2", "window"), "small-opening"),             # an extracted grammar's window
    (leaf(1, 1, 0.06, 1.0, "Balcony", "balcony"), "small-opening"),            # a balcony sliver
    (leaf(1, 0, 1.0, 0.49, "Door", "door"), "small-opening"),                  # a carved hatch
    (leaf(1, 1, 0.01, 3.05, "Wall", "wall"), "sliver"),
])
def test_each_rule_finds_its_degenerate_terminal(region, code):
    assert code in codes(layout_of(10, 10, region))


def test_thin_elements_are_not_slivers_and_transparent_regions_are_ignored():
    thin = [leaf(0, 1, 10, 0.02, "Sill", "sill"), leaf(0, 2, 10, 0.03, "Molding", "molding"),
            leaf(0, 3, 10, 0.0, "Gap", None)]
    assert codes(layout_of(10, 10, *thin)) == []


def test_doors_must_be_tall_enough_and_stand_on_their_floor():
    request = FacadeRequest.preview(10, 9, 3.0, 3.0)
    short = leaf(4, 0, 1.0, 1.79, "Door", "door")
    floating = leaf(4, 0.8, 1.0, 2.0, "Door", "door")
    assert "short-door" in codes(layout_of(10, 9, short), request)
    assert codes(layout_of(10, 9, floating), request) == ["floating-door"]
    # a door on an upper floor line stands on that floor
    assert codes(layout_of(10, 9, leaf(4, 3.0, 1.0, 2.0, "Door", "door")), request) == []


def test_an_upper_storey_without_openings_is_found():
    request = FacadeRequest.preview(8, 13, 3.0, 4.0)  # ground 0-4, storeys at 4, 7, 10
    windows = [leaf(1 + 3 * i, y + 0.9, 1.2, 1.5, "Window", "window") for i in range(2) for y in (4.0, 10.0)]
    found = check_plausible(layout_of(8, 13, *windows), request)
    assert [f.code for f in found] == ["empty-storey", "storey-height"]
    assert "storey 2 (7.00-10.00 m)" in found[0].message
    # faces too narrow for any window are fine: no storey has openings
    assert codes(layout_of(8, 13), request) == []


def test_a_generator_that_relabelled_openings_says_so():
    assert codes(layout_of(10, 10, relabelled=3)) == ["relabelled"]


def test_findings_are_capped_per_rule_with_a_count():
    slivers = [leaf(0.1 * i, 0, 0.01, 1, f"S{i}", "wall") for i in range(10)]
    found = check_plausible(layout_of(10, 10, *slivers))
    assert len(found) == 4 and found[-1].message == "... and 7 more"
    assert summary(found, 2).endswith("(2 more)")


def test_plain_wall_carries_the_reason_and_findings():
    request = FacadeRequest.preview(6, 7)
    found = check_plausible(layout_of(6, 7, leaf(1, 1, 0.1, 1, "W", "window")))
    wall = plain_wall(request, "implausible", found, kind="split")
    assert wall.meta["fallback"] == "implausible" and wall.meta["kind"] == "split"
    assert wall.meta["findings"] == [str(f) for f in found] and [r.label for r in wall.leaves] == ["wall"]


def test_rules_from_a_mapping_and_their_errors():
    rules = PlausibilityRules.from_mapping({"sliver": 0.2, "min_size": {"window": [0.5, 0.6]},
                                            "thin_labels": ["sill"], "storey_range": [0.4, 2]})
    assert rules.sliver == 0.2 and rules.min_size["window"] == (0.5, 0.6) and rules.min_size["door"] == (0.7, 1.9)
    assert rules.thin_labels == frozenset({"sill"}) and rules.storey_range == (0.4, 2.0)
    for bad in ({"slivr": 1}, {"sliver": -1}, {"min_size": {"window": 3}}, {"storey_range": [2, 3]}):
        with pytest.raises(SceneError):
            PlausibilityRules.from_mapping(bad)


def _scene(tmp_path: Path, extra: str) -> Path:
    city = [{"id": "way/1", "coordinates": [[[0, 0], [20, 0], [20, 12], [0, 12], [0, 0]]], "height": 12.0}]
    (tmp_path / "city.local.json").write_text(json.dumps(city))
    # windows 0.2 m wide on every bay: a grammar that parses and derives, but is not a facade anyone wants
    (tmp_path / "slits.grammar").write_text(
        "@start Facade\nFacade --> floors { 0: Ground | *: Floor }\nGround --> terminal(wall)\n"
        "Floor --> repeat(x) { ~3: Bay }\nBay --> split(x) { '1: Wall | 0.2: Slit | '1: Wall }\n"
        "Wall --> terminal(wall)\nSlit --> terminal(window)\n")
    (tmp_path / "plain.grammar").write_text(
        "@start Facade\nFacade --> floors { 0: Ground | *: Floor }\nGround --> terminal(wall)\n"
        "Floor --> repeat(x) { ~3: Bay }\nBay --> split(x) { '1: Wall | 1.2: Win | '1: Wall }\n"
        "Wall --> terminal(wall)\nWin --> split(y) { '1: Wall | 1.4: Glass | '1: Wall }\nGlass --> terminal(window)\n")
    (tmp_path / "scene.toml").write_text(
        '[scene]\nname = "p"\n[footprints]\npath = "city.local.json"\n[defaults]\nfloor_height = 3.0\n'
        f'[[assign]]\nruleset = "slits.grammar"\n{extra}\n[output]\npath = "out/p.usda"\n')
    return tmp_path / "scene.toml"


def test_an_implausible_facade_falls_back_through_the_scene_and_is_counted(tmp_path, test_registry):
    from citygen.pipeline import generate_city
    (tmp_path / "a").mkdir()
    plain = generate_city(load_scene(_scene(tmp_path / "a", "")), registry=test_registry)
    assert plain.faces["dressed"] == 0 and plain.faces["plain"] == 4 and plain.faces["finding:small-opening"] == 4
    assert any("implausible layout: small-opening: window Slit is 0.20" in w for w in plain.warnings)
    assert "facades: 0 dressed, 4 plain walls (implausible: small-opening 4)" in plain.summary()
    (tmp_path / "b").mkdir()
    fallen = generate_city(load_scene(_scene(tmp_path / "b", 'fallback = "plain.grammar"')), registry=test_registry)
    assert fallen.faces["fallback"] == 4 and fallen.faces["plain"] == 0
    assert any("dressed by the fallback plain.grammar" in w for w in fallen.warnings)
    # a scene that accepts narrow slits dresses every face with its own ruleset
    (tmp_path / "c").mkdir()
    path = _scene(tmp_path / "c", "")
    path.write_text(path.read_text() + '[plausibility]\nmin_size = { window = [0.1, 0.3] }\n')
    assert generate_city(load_scene(path), registry=test_registry).faces["dressed"] == 4


def test_a_bad_plausibility_table_names_its_line(tmp_path):
    (tmp_path / "a").mkdir()
    path = _scene(tmp_path / "a", "")
    path.write_text(path.read_text() + "[plausibility]\nsliver = 0.05\nmin_size = 3\n")
    with pytest.raises(SceneError, match=r"scene.toml:\d+: plausibility rule min_size = 3: not a table"):
        load_scene(path)



_LABELS = st.sampled_from(["wall", "window", "door", "shop", "balcony", "sill", "molding", "deco", "", None])


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(_LABELS, st.floats(0, 3), st.floats(0, 3), st.floats(0, 8)), min_size=1, max_size=12),
       st.sampled_from([DEFAULT_RULES, PlausibilityRules(sliver=0.5, min_extent=0.2, door_min_height=2.5)]))
def test_terminal_rules_are_never_skipped_when_one_of_them_reports(terminals, rules):
    """The one comparison that rules out most layouts (``_suspect``) holds whenever any per-terminal rule would
    report a terminal."""
    layout = layout_of(10, 10, *(leaf(1.0, y, w, h, f"T{i}", label) for i, (label, w, h, y) in enumerate(terminals)))
    x, y, w, h = layout.leaf_rects.T
    lines = np.asarray(FacadeRequest.preview(10, 10, 3.0).floor_lines, dtype=float)
    if _terminal_findings(layout, x, y, w, h, lines, rules):
        assert _suspect(layout, y, w, h, lines, rules)


def test_a_face_with_a_good_door_skips_the_per_terminal_rules():
    """The entrance face's door alone no longer makes every terminal rule run (it did for each entrance face);
    a floating door still does."""
    request = FacadeRequest.preview(10, 9, 3.0, 3.0)
    lines = np.asarray(request.floor_lines, dtype=float)
    for door, suspect in ((leaf(4, 0.0, 1.2, 2.3, "Door", "door"), False),
                          (leaf(4, 0.8, 1.2, 2.0, "Door", "door"), True)):
        layout = layout_of(10, 9, leaf(1, 4, 1.2, 1.5, "Window", "window"), door)
        x, y, w, h = layout.leaf_rects.T
        assert _suspect(layout, y, w, h, lines, DEFAULT_RULES) is suspect


@pytest.mark.parametrize("label, below, at, code", [
    ("window", (0.3 - 2e-6, 1.0), (0.3, 1.0), "small-opening"),
    ("window", (1.0, 0.3 - 2e-6), (1.0, 0.3), "small-opening"),
    ("door", (1.0, 1.9 - 2e-6), (1.0, 1.9), "short-door"), ("wall", (0.05 - 2e-6, 3.0), (0.05, 3.0), "sliver"),
    ("sill", (2.0, 0.0), (2.0, 0.01), "zero-size")])
def test_each_terminal_limit_is_found_just_below_it_and_not_at_it(label, below, at, code):
    request = FacadeRequest.preview(10, 10, 3.0, 3.0)
    assert code in codes(layout_of(10, 10, leaf(1.0, 0.0, *below, "T", label)), request)
    assert codes(layout_of(10, 10, leaf(1.0, 0.0, *at, "T", label)), request) == []
