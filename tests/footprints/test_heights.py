"""Height and level parsing from real OSM values, and the order of height sources."""
from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from citygen_footprints.heights import HeightSettings, infer_height, parse_length, parse_levels, resolve_height

LENGTHS = [
    ("12.13 m", 12.13), ("12,5", 12.5), ("3.5", 3.5), ("~10", 10.0), ("40 ft", 12.192), ("40ft", 12.192),
    ("12 metres", 12.0), ("12m", 12.0), ("1200 cm", 12.0), ("12'6\"", 3.81), ("30'", 9.144), (" 7 ", 7.0),
    ("10;12", 12.0), ("10 m; 14 m", 14.0), ("8-10", 10.0), ("ca. 20", 20.0), (".5", 0.5), (18, 18.0),
    (12.5, 12.5), ("12+", 12.0), ("0", 0.0),
]
BAD_LENGTHS = ["-5", -5, "", "unknown", "yes", "12 parsecs", "m", None, True, float("nan"), float("inf"), [12], "1.2.3"]
LEVELS = [("3", 3.0), ("3.5", 3.5), ("4;5", 5.0), ("3-4", 4.0), ("IV", 4.0), ("iv", 4.0), ("XII", 12.0),
          ("2,5", 2.5), ("~6", 6.0), ("0", 0.0), (7, 7.0), ("5+", 5.0)]
BAD_LEVELS = ["", "many", "IIII", "-2", "400", None, False, "3 floors", "VX"]


@pytest.mark.parametrize("text, metres", LENGTHS)
def test_parse_length(text, metres):
    assert parse_length(text) == pytest.approx(metres)


@pytest.mark.parametrize("text", BAD_LENGTHS)
def test_parse_length_rejects(text):
    with pytest.raises(ValueError):
        parse_length(text)


@pytest.mark.parametrize("text, levels", LEVELS)
def test_parse_levels(text, levels):
    assert parse_levels(text) == pytest.approx(levels)


@pytest.mark.parametrize("text", BAD_LEVELS)
def test_parse_levels_rejects(text):
    with pytest.raises(ValueError):
        parse_levels(text)


@settings(max_examples=100, deadline=None)
@given(st.floats(0.01, 999, allow_nan=False))
def test_parse_length_reads_any_formatted_metres(value):
    assert parse_length(f"{value:.2f} m") == pytest.approx(round(value, 2))
    assert parse_length(f"{value:.2f}".replace(".", ",")) == pytest.approx(round(value, 2))


S = HeightSettings(default_height=10.0, floor_height=3.0)
RESOLVE = [
    ({"height": "12.13 m"}, 12.13, "height", None),
    ({"height": "18", "building:levels": "5"}, 18.0, "height", 5),
    ({"building:height": "21"}, 21.0, "building:height", None),
    ({"measuredHeight": 6.5}, 6.5, "measuredHeight", None),
    ({"building:levels": "4"}, 12.0, "building:levels", 4),
    ({"building:levels": "3.5", "roof:levels": "1"}, 13.5, "building:levels+roof:levels", 4),  # walls: 4 storeys
    ({"building:levels": "2", "roof:levels": "0"}, 6.0, "building:levels", 2),
    ({"storeysAboveGround": 3}, 9.0, "storeysAboveGround", 3),
    ({}, 10.0, "default", None),
    ({"building": "yes", "height": None}, 10.0, "default", None),
    ({"height": "0", "building:levels": "2"}, 6.0, "building:levels", 2),
    ({"height": "5000"}, 10.0, "default", None),
    ({"height": "unknown", "building:levels": "many"}, 10.0, "default", None),
    ({"building:levels": "0"}, 10.0, "default", None),
    ({"min_height": "18", "roof:height": "5"}, 5.0, "min_height+roof:height", None),  # a lifted dome: all roof
    ({"building:min_level": "2", "roof:height": "4"}, 4.0, "building:min_level+roof:height", None),
    # regression (found by hypothesis): 334 levels x 3 m passed as a 1002 m height
    ({"building:levels": 34, "roof:levels": 300}, 10.0, "default", None),
]


@pytest.mark.parametrize("tags, height, source, levels", RESOLVE)
def test_resolve_height(tags, height, source, levels):
    h = resolve_height(tags, "way/1", S)
    assert (h.height, h.source, h.levels) == (pytest.approx(height), source, levels)


@pytest.mark.parametrize("tags, total", [
    ({"height": "18", "building:levels": "5"}, True), ({"measuredHeight": 6.5}, True), ({}, True),
    ({"building:levels": "4"}, False), ({"building:levels": "4", "roof:levels": "1"}, True),
])
def test_heights_say_whether_they_include_the_roof(tags, total):
    """Issue 22: ``height`` is a total (Simple 3D Buildings), ``building:levels`` count the walls' storeys; with
    ``roof:levels`` the level count is a total again, its roof those levels (``citygen.roofplan``)."""
    assert resolve_height(tags, "way/1", S).total is total
    assert infer_height(resolve_height({"building": "kiosk"}, "way/1", S), {"building": "kiosk"}, 5.0, S).total is False


def test_unusable_values_warn_naming_feature_tag_and_value():
    h = resolve_height({"height": "5000", "building:levels": "lots"}, "way/77", S)
    assert h.rejected == ("building:levels", "height")
    assert any("way/77" in w and "building:levels='lots'" in w for w in h.warnings)
    assert any("way/77" in w and "height='5000'" in w and "plausible" in w for w in h.warnings)


def test_clean_values_give_no_warnings():
    assert resolve_height({"height": "12", "building:levels": "4"}, "way/1", S).warnings == ()


def test_min_height_lifts_the_base_and_shortens_the_wall():
    h = resolve_height({"height": "18", "min_height": "16", "building:levels": "5", "building:min_level": "3"},
                       "way/1", S)
    assert (h.height, h.base_offset, h.levels) == (pytest.approx(2.0), 16.0, 2)


def test_min_level_offsets_by_floor_height():
    h = resolve_height({"building:levels": "8", "building:min_level": "7"}, "relation/1", S)
    assert (h.height, h.base_offset, h.levels) == (pytest.approx(3.0), 21.0, 1)


def test_offset_above_the_top_is_ignored_with_a_warning():
    h = resolve_height({"height": "4", "min_height": "6"}, "way/1", S)
    assert (h.height, h.base_offset) == (4.0, 0.0)
    assert "not below the top" in h.warnings[0]


def test_base_offsets_can_be_switched_off():
    h = resolve_height({"height": "18", "min_height": "16"}, "way/1", HeightSettings(base_offsets=False))
    assert (h.height, h.base_offset) == (18.0, 0.0)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.dictionaries(st.sampled_from(["height", "building:height", "building:levels", "roof:levels",
                                        "min_height", "building:min_level"]),
                       st.one_of(st.text(max_size=8), st.floats(), st.integers(-5, 2000), st.none())))
def test_resolve_height_always_gives_a_positive_finite_height(tags):
    h = resolve_height(tags, "way/1", S)
    assert math.isfinite(h.height) and 0 < h.height <= 1000
    assert h.levels is None or h.levels >= 1
    assert math.isfinite(h.base_offset) and h.base_offset >= 0


def _inferred(tags, width, **settings):
    s = HeightSettings(default_height=18.0, floor_height=3.3, **settings)
    return infer_height(resolve_height(tags, "way/1", s), tags, width, s)


def test_low_building_types_get_their_levels_without_height_data():
    h = _inferred({"building": "kiosk"}, 20.0)
    assert (h.height, h.levels, h.source) == (pytest.approx(3.3), 1, "building=kiosk")
    assert _inferred({"building": "house"}, 20.0).levels == 2
    h = _inferred({"building": "kiosk", "height": "5"}, 20.0)  # data wins over the type
    assert (h.height, h.source) == (5.0, "height")
    h = _inferred({"building": "kiosk", "building:levels": "3"}, 20.0)
    assert (h.levels, h.source) == (3, "building:levels")
    assert _inferred({"building": "kiosk"}, 20.0, type_levels=(("kiosk", 2.0),)).levels == 2


@pytest.mark.parametrize("width, levels", [(0.5, 1), (2.0, 1), (2.3, 2), (4.0, 3), (5.9, 5)])
def test_untagged_default_is_capped_by_the_least_width(width, levels):
    h = _inferred({"building": "yes"}, width)
    assert (h.levels, h.source) == (levels, "default, capped by width")
    assert h.height == pytest.approx(3.3 * levels) and h.height <= max(3.0 * width, 3.3)


@pytest.mark.parametrize("tags, width, settings", [
    ({"building": "yes"}, 6.0, {}),  # 3 x 6 m reaches the default
    ({"building": "tower"}, 2.0, {}),  # slender by nature
    ({"building": "church"}, 3.0, {}),
    ({"building": "yes"}, 2.0, {"slenderness": 0.0}),  # cap off
    ({"building": ["yes", "no"]}, 20.0, {}),  # not a string: no type
])
def test_default_height_stays_where_nothing_is_inferred(tags, width, settings):
    h = _inferred(tags, width, **settings)
    assert (h.height, h.levels, h.source) == (18.0, None, "default")
