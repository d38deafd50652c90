"""Bad footprints are skipped or repaired one by one with clear messages; bad files raise FootprintError."""
from __future__ import annotations

import pytest
from citygen.errors import FootprintError

from citygen_footprints.plugin import read_footprints

from .conftest import BAD, write_json


@pytest.fixture(scope="module")
def bad():
    return read_footprints(BAD, {})


def _footprint(result, fid):
    return next(f for f in result.footprints if f.id == fid)


def _skip(result, fid):
    return next(s for s in result.skipped if s.id == fid)


def _warnings(result, fid):
    return [w for w in result.warnings if w.startswith(f"{fid} (")]


def test_good_features_come_through(bad):
    assert [f.id for f in bad.footprints] == [
        "way/1", "way/2", "way/3", "way/4", "way/9", "way/11", "way/12", "way/14", "way/14#2", "way/16", "way/17",
        "way/18", "way/19", "way/20", "way/21", "way/23"]
    assert [s.id for s in bad.skipped] == ["way/5", "way/6", "way/7", "way/8", "way/10", "way/13", "way/15",
                                           "way/22", "feature/24"]  # file order
    hole = _footprint(bad, "way/2")
    assert len(hole.polygon.interiors) == 1 and hole.polygon.area == pytest.approx(400 - 25, rel=0.01)
    multi = _footprint(bad, "way/3")
    assert multi.polygon.geom_type == "MultiPolygon" and len(multi.polygon.geoms) == 2
    assert (multi.height, multi.height_source, multi.levels) == (13.5, "building:levels+roof:levels", 4)  # walls: 4
    assert _footprint(bad, "way/1").source == "bad_footprints.geojson#0"


@pytest.mark.parametrize("fid, line, words", [
    ("way/5", 7, ["Self-intersection", "keeps only 69%", "fix the ring"]),
    ("way/6", 8, ["empty geometry"]),
    ("way/7", 9, ["no geometry"]),
    ("way/8", 10, ["vertex 2 is NaN"]),
    ("way/10", 12, ["only 2 distinct point", "at least 3 corners"]),
    ("way/13", 15, ["Point geometry", "Polygon or MultiPolygon"]),
    ("way/15", 18, ["below min_area", "lower min_area"]),
    ("way/22", 25, ["LineString geometry"]),
    ("feature/24", 27, ["not a GeoJSON Feature"]),
])
def test_bad_features_are_skipped_with_where_and_what_to_do(bad, fid, line, words):
    skipped = _skip(bad, fid)
    assert skipped.where.startswith(f"bad_footprints.geojson:{line}, feature ")
    assert " -- " in skipped.reason
    for word in words:
        assert word in skipped.reason


def test_bowtie_is_repaired_into_its_two_triangles(bad):
    bowtie = _footprint(bad, "way/4")
    assert bowtie.polygon.geom_type == "MultiPolygon" and bowtie.polygon.is_valid
    assert bowtie.polygon.area == pytest.approx(50, rel=0.01)
    assert "repaired into 2 polygon(s)" in _warnings(bad, "way/4")[0]


def test_unclosed_ring_is_closed_with_a_warning(bad):
    assert _footprint(bad, "way/9").polygon.area == pytest.approx(100, rel=0.01)
    assert "was not closed" in _warnings(bad, "way/9")[0]


def test_degenerate_hole_is_dropped_with_a_warning(bad):
    assert not _footprint(bad, "way/23").polygon.interiors
    assert "dropped the hole" in _warnings(bad, "way/23")[0]


@pytest.mark.parametrize("fid, height, source, message", [
    ("way/11", 10.0, "default", "height='0'"),
    ("way/12", 6.0, "building:levels", "height='5000'"),
    ("way/21", 6.0, "building:levels", "height='unknown'"),
])
def test_implausible_heights_fall_back_with_a_warning(bad, fid, height, source, message):
    footprint = _footprint(bad, fid)
    assert (footprint.height, footprint.height_source) == (height, source)
    assert message in _warnings(bad, fid)[0]


def test_implausible_heights_can_skip_instead():
    result = read_footprints(BAD, {"bad_height": "skip"})
    for fid in ("way/11", "way/12", "way/21"):
        assert "unusable height data (height)" in _skip(result, fid).reason
    assert "way/1" in {f.id for f in result.footprints}


@pytest.mark.parametrize("fid, height, source", [
    ("way/16", 12.192, "height"), ("way/17", 10.0, "height"), ("way/18", 12.5, "height"),
    ("way/19", 12.0, "building:levels"), ("way/20", 12.0, "building:levels"),
])
def test_messy_heights_are_read(bad, fid, height, source):
    footprint = _footprint(bad, fid)
    assert (footprint.height, footprint.height_source) == (pytest.approx(height), source)


def test_duplicate_ids_get_a_deterministic_suffix(bad):
    assert "renamed to way/14#2" in _warnings(bad, "way/14")[0]
    assert _footprint(bad, "way/14#2").source == "bad_footprints.geojson#14"


def test_min_area_keeps_the_sliver_when_lowered():
    assert "way/15" in {f.id for f in read_footprints(BAD, {"min_area": 0.01}).footprints}


def test_import_is_deterministic():
    a, b = read_footprints(BAD, {}), read_footprints(BAD, {})
    assert [(f.id, f.polygon.wkb, f.height) for f in a.footprints] == [(f.id, f.polygon.wkb, f.height)
                                                                        for f in b.footprints]
    assert a.skipped == b.skipped and a.warnings == b.warnings


def test_json_syntax_error_names_line_and_column(tmp_path):
    path = tmp_path / "broken.geojson"
    path.write_text('{"type": "FeatureCollection",\n "features": [\n  {"type": "Feature",, }\n]}')
    with pytest.raises(FootprintError) as err:
        read_footprints(path, {})
    assert f"{path}:3:22" in str(err.value) and "not valid JSON" in str(err.value)


@pytest.mark.parametrize("doc, message", [
    ({"type": "Topology"}, "top-level type is 'Topology'"),
    ([1, 2], "top-level type is 'list'"),
    ({"type": "FeatureCollection", "features": {}}, "not a GeoJSON FeatureCollection"),
    ({"type": "CityJSON", "vertices": []}, "without a CityObjects"),
])
def test_wrong_document_types_raise(tmp_path, doc, message):
    path = write_json(tmp_path / "wrong.json", doc)
    with pytest.raises(FootprintError, match=message) as err:
        read_footprints(path, {})
    assert "wrong.json" in str(err.value)


def test_unreadable_files_raise(tmp_path):
    with pytest.raises(FootprintError, match="cannot read"):
        read_footprints(tmp_path / "missing.geojson", {})
    path = tmp_path / "latin1.geojson"
    path.write_bytes('{"name": "Töölö"}'.encode("latin-1"))
    with pytest.raises(FootprintError, match="not UTF-8"):
        read_footprints(path, {})


def test_trailing_garbage_is_a_syntax_error(tmp_path):
    path = tmp_path / "extra.geojson"
    path.write_text('{"type": "FeatureCollection", "features": []}\n}')
    with pytest.raises(FootprintError, match=r"extra.geojson:2:1: not valid JSON: Extra data"):
        read_footprints(path, {})


def test_empty_collection_imports_nothing(tmp_path):
    path = write_json(tmp_path / "empty.geojson", {"type": "FeatureCollection", "features": []})
    result = read_footprints(path, {})
    assert result.footprints == () and result.skipped == ()


def _one(tmp_path, geometry):
    doc = {"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"@id": "way/1"}, "geometry": geometry}]}
    return read_footprints(write_json(tmp_path / "one.geojson", doc), {"origin": [24.94, 60.17]})


def _sq(x, y, size):
    d = 1e-4 / 5.55  # about a metre of longitude at lat 60; latitude degrees are twice as long
    x0, y0, s = 24.94 + x * d, 60.17 + y * d / 2, size * d
    return [[x0, y0], [x0 + s, y0], [x0 + s, y0 + s / 2], [x0, y0 + s / 2], [x0, y0]]


def test_overlapping_multipolygon_parts_are_merged(tmp_path):
    result = _one(tmp_path, {"type": "MultiPolygon", "coordinates": [[_sq(0, 0, 10)], [_sq(5, 0, 10)]]})
    polygon = result.footprints[0].polygon
    assert polygon.geom_type == "Polygon" and polygon.area == pytest.approx(150, rel=0.01)


def test_degenerate_multipolygon_part_is_dropped_with_a_warning(tmp_path):
    line = [_sq(20, 0, 10)[0], _sq(20, 0, 10)[1], _sq(20, 0, 10)[0]]
    result = _one(tmp_path, {"type": "MultiPolygon", "coordinates": [[_sq(0, 0, 10)], [line]]})
    assert result.footprints[0].polygon.geom_type == "Polygon"
    assert "part 1 exterior ring has only 2 distinct point(s), not an area; dropped the part" in result.warnings[0]


@pytest.mark.parametrize("coordinates, words", [
    ([[["a", "b"], [1, 2], [2, 2], ["a", "b"]]], "malformed position"),
    ([[[24.94], [24.95], [24.96], [24.94]]], "fewer than 2 numbers"),
    ([[[True, 60.1], [24.95, 60.1], [24.95, 60.2], [True, 60.1]]], "malformed position"),
    ([[]], "exterior ring is empty"),
    ([5], "exterior ring is empty or not a list"),
])
def test_malformed_coordinates_are_skipped(tmp_path, coordinates, words):
    result = _one(tmp_path, {"type": "Polygon", "coordinates": coordinates})
    assert result.footprints == () and words in result.skipped[0].reason
