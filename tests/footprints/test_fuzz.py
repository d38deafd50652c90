"""Footprint files found bad by fuzzing (benchmarks/fuzz_readers.py): a bad number skips its building, a bad
file-level value is a FootprintError; never a traceback."""
from __future__ import annotations

import random

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from citygen.errors import FootprintError
from citygen_footprints.plugin import read_footprints

from ..mutate import mutate
from .conftest import BAD, ROOT, assert_read_or_refused, write_json

SQUARE = [[24.94, 60.17], [24.9402, 60.17], [24.9402, 60.1701], [24.94, 60.1701], [24.94, 60.17]]


def feature(fid: str, ring: list) -> dict:
    return {"type": "Feature", "id": fid, "properties": {"building": "yes", "height": 9},
            "geometry": {"type": "Polygon", "coordinates": [ring]}}


def cityjson(vertices: list, boundaries: list, transform: dict | None = None) -> dict:
    def building(first: int) -> dict:
        return {"type": "Building", "geometry": [{"type": "MultiSurface", "lod": "1", "boundaries": [
            [[first + i for i in b[0]]] for b in boundaries]}]}
    doc = {"type": "CityJSON", "version": "2.0", "metadata": {"referenceSystem": "EPSG:7415"},
           "CityObjects": {"a": building(0), "b": building(len(vertices))},
           "vertices": [list(v) for v in vertices + vertices]}
    if transform is not None:
        doc["transform"] = transform
    return doc


BOX = [[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0], [0, 0, 9], [10, 0, 9], [10, 10, 9], [0, 10, 9]]
FACES = [[[0, 3, 2, 1]], [[4, 5, 6, 7]], [[0, 1, 5, 4]], [[1, 2, 6, 5]], [[2, 3, 7, 6]], [[3, 0, 4, 7]]]


def test_geojson_coordinate_beyond_float_range_skips_one_building(tmp_path):
    # was: OverflowError (int too large to convert to float) for the whole file
    path = write_json(tmp_path / "c.geojson", {"type": "FeatureCollection", "features": [
        feature("ok", SQUARE),
        feature("huge", [[24.94, 60.17], [10 ** 400, 60.17], [24.9402, 60.1701], [24.94, 60.17]])]})
    result = read_footprints(path, {})
    assert [f.id for f in result.footprints] == ["ok"]
    assert [s.id for s in result.skipped] == ["huge"] and "malformed position" in result.skipped[0].reason


def test_cityjson_vertex_beyond_float_range_skips_only_the_buildings_using_it(tmp_path):
    # was: OverflowError in np.asarray(vertices) for the whole file
    doc = cityjson(BOX, FACES)
    doc["vertices"][len(BOX) + 6][0] = 10 ** 400
    result = read_footprints(write_json(tmp_path / "c.city.json", doc), {})
    assert [f.id for f in result.footprints] == ["a"]
    assert [s.id for s in result.skipped] == ["b"] and "NaN or infinite" in result.skipped[0].reason


def test_cityjson_boundary_index_infinite_skips_one_building(tmp_path):
    # was: OverflowError (cannot convert float infinity to integer) for the whole file
    doc = cityjson(BOX, FACES)
    doc["CityObjects"]["b"]["geometry"][0]["boundaries"][0][0][1] = float("inf")
    result = read_footprints(write_json(tmp_path / "c.city.json", doc), {})
    assert [f.id for f in result.footprints] == ["a"] and [s.id for s in result.skipped] == ["b"]


@pytest.mark.parametrize("transform", [{"scale": ["x", 1, 1], "translate": [0, 0, 0]},
                                       {"scale": [1, 1], "translate": [0, 0, 0]},
                                       {"scale": [1, 1, 1], "translate": [0, float("nan"), 0]}])
def test_cityjson_bad_transform_is_a_footprint_error(tmp_path, transform):
    # was: ValueError from numpy (could not convert string / operands could not be broadcast)
    with pytest.raises(FootprintError, match="transform needs scale and translate of 3 finite numbers"):
        read_footprints(write_json(tmp_path / "c.city.json", cityjson(BOX, FACES, transform)), {})


SOURCES = [BAD, ROOT / "scenes" / "data" / "roofs_demo.geojson"]


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(path=st.sampled_from(SOURCES), seed=st.integers(0, 2 ** 32 - 1))
def test_mutated_footprint_files_raise_only_footprint_errors(tmp_path_factory, path, seed):
    target = tmp_path_factory.getbasetemp() / "fuzz.geojson"
    target.write_text(mutate(path.read_text(), "json", random.Random(seed)))
    assert_read_or_refused(lambda p: read_footprints(p, {}), target)


@pytest.mark.parametrize("fid", [float("inf"), float("nan")])
def test_osm_id_that_is_not_a_finite_number_is_kept_as_text(tmp_path, fid):
    # was: OverflowError / ValueError from int(id) for the whole file
    item = feature("x", SQUARE)
    item["properties"]["osm_type"] = "way"
    item["id"] = fid
    result = read_footprints(write_json(tmp_path / "c.geojson", {"type": "FeatureCollection", "features": [item]}), {})
    assert [f.id for f in result.footprints] == [str(fid)]


def test_levels_beyond_float_range_fall_back_to_the_next_height_source(tmp_path):
    # was: OverflowError in math.isfinite for the whole file
    item = feature("x", SQUARE)
    del item["properties"]["height"]
    item["properties"]["building:levels"] = 10 ** 400
    result = read_footprints(write_json(tmp_path / "c.geojson", {"type": "FeatureCollection", "features": [item]}), {})
    (footprint,) = result.footprints
    assert footprint.height_source == "default"
    (warning,) = [w for w in result.warnings if "building:levels" in w]
    assert "is too large" in warning and "trying the next height source" in warning and len(warning) < 300


@pytest.mark.parametrize("key, value", [("attributes", 3.5), ("parents", 3.5), ("parents", [7])])
def test_cityjson_object_with_malformed_attributes_or_parents_skips_one_building(tmp_path, key, value):
    # was: TypeError ('float' object is not iterable) for the whole file
    doc = cityjson(BOX, FACES)
    doc["CityObjects"]["b"][key] = value
    result = read_footprints(write_json(tmp_path / "c.city.json", doc), {})
    if value == [7]:  # an id that is not a string names no parent: ignored like a missing one
        assert [f.id for f in result.footprints] == ["a", "b"]
        return
    assert [f.id for f in result.footprints] == ["a"]
    assert [s.id for s in result.skipped] == ["b"] and "attributes must be a JSON object" in result.skipped[0].reason


@pytest.mark.parametrize("metadata", [float("inf"), {"referenceSystem": [7415, 0]}])
def test_cityjson_metadata_that_is_not_an_object_is_a_footprint_error(tmp_path, metadata):
    # was: AttributeError ('float' object has no attribute 'get') / TypeError (unhashable list) for the whole file
    doc = cityjson(BOX, FACES)
    doc["metadata"] = metadata
    with pytest.raises(FootprintError, match="metadata must be an object whose referenceSystem is a CRS name"):
        read_footprints(write_json(tmp_path / "c.city.json", doc), {})


def test_cityjson_buildings_whose_footprint_collapses_are_skipped(tmp_path):
    # was: ValueError (need at least one array to concatenate) when no building had a footprint left
    # y = 1e30 swallows the 10 m: rounding leaves the triangle a Newell area but no polygon
    doc = cityjson([[1.1, 0, 0], [7.7, 0, 0], [3.3, 10, 0]], [[[0, 1, 2]]],
                   {"scale": [1, 1, 1], "translate": [0, 1e30, 0]})
    result = read_footprints(write_json(tmp_path / "c.city.json", doc), {})
    assert result.footprints == () and [s.id for s in result.skipped] == ["a", "b"]
    assert "footprint has no area" in result.skipped[0].reason and "transform" in result.skipped[0].reason


def _projected(tmp_path, far_x: float):
    features = [feature(f"b{k}", [[385_000 + x, 6_672_000], [385_010 + x, 6_672_000], [385_010 + x, 6_672_010],
                                  [385_000 + x, 6_672_010], [385_000 + x, 6_672_000]])
                for k, x in enumerate((0, 20, 40, far_x))]
    doc = {"type": "FeatureCollection", "crs": {"type": "name", "properties": {"name": "EPSG:3067"}},
           "features": features}
    return read_footprints(write_json(tmp_path / "p.geojson", doc), {})


def test_a_building_far_from_the_others_is_skipped_and_the_frame_stays_on_the_rest(tmp_path):
    # was: the whole file refused (its bbox centre outside EPSG:3067's area of use) or, without a CRS, every
    # building 5e14 m from the origin
    result = _projected(tmp_path, 1e15)
    assert [f.id for f in result.footprints] == ["b0", "b1", "b2"]
    (skip,) = result.skipped
    assert skip.id == "b3" and "lie 1e+15 units of the file's CRS from the other buildings" in skip.reason
    assert result.georef.origin == (385_025.0, 6_672_005.0)


def test_a_building_whose_base_is_beyond_reach_is_skipped(tmp_path):
    # was: written at z = 1e300, which the stage's float32 points turn into inf
    doc = cityjson(BOX, FACES)
    for vertex in doc["vertices"][len(BOX):]:
        vertex[2] += 1e300
    result = read_footprints(write_json(tmp_path / "c.city.json", doc), {})
    assert [f.id for f in result.footprints] == ["a"]
    assert [s.id for s in result.skipped] == ["b"] and "base z = 1e+300 m" in result.skipped[0].reason


def test_cityjson_transform_overflow_skips_the_buildings_quietly(tmp_path, recwarn):
    # was: numpy RuntimeWarnings (overflow in multiply, invalid value in reduceat) printed among the reasons
    doc = cityjson(BOX, FACES, {"scale": [1e308, 1, 1], "translate": [0, 0, 0]})
    result = read_footprints(write_json(tmp_path / "c.city.json", doc), {})
    assert [s.id for s in result.skipped] == ["a", "b"] and "after the transform" in result.skipped[0].reason
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


@pytest.mark.parametrize("key, value", [("geometry", 3.5), ("children", 3.5), ("children", [[1]])])
def test_cityjson_object_with_malformed_geometry_or_children_skips_one_building(tmp_path, key, value):
    # was: TypeError ('float' object is not iterable / unhashable type: 'list') for the whole file
    doc = cityjson(BOX, FACES)
    doc["CityObjects"]["b"][key] = value
    result = read_footprints(write_json(tmp_path / "c.city.json", doc), {})
    if key == "children":  # no usable children: the building is drawn by its own geometry
        assert [f.id for f in result.footprints] == ["a", "b"]
        return
    assert [f.id for f in result.footprints] == ["a"]
    assert [s.id for s in result.skipped] == ["b"] and "no Solid or MultiSurface geometry" in result.skipped[0].reason


def test_cityjson_wall_of_huge_height_falls_back_quietly(tmp_path, recwarn):
    # was: a numpy RuntimeWarning (overflow in np.linalg.norm of the wall normals)
    doc = cityjson(BOX, FACES)
    for vertex in doc["vertices"][len(BOX) + 4:]:
        vertex[2] = 1e300
    result = read_footprints(write_json(tmp_path / "c.city.json", doc), {})
    assert [f.id for f in result.footprints] == ["a", "b"] and result.footprints[1].height_source == "default"
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


def test_cityjson_buildings_too_large_to_measure_are_skipped_quietly(tmp_path, recwarn):
    # was: "area inf m² is below min_area = 1 m² (a sliver)" and numpy / shapely RuntimeWarnings (divide, unary_union)
    doc = cityjson([[x * 1e200, y * 1e200, z] for x, y, z in BOX], FACES)
    del doc["metadata"]  # no CRS: the coordinates are not refused as outside a CRS's area of use
    result = read_footprints(write_json(tmp_path / "c.city.json", doc), {})
    assert result.footprints == () and [s.id for s in result.skipped] == ["a", "b"]
    assert "its area is inf m² (coordinates too large to measure it)" in result.skipped[0].reason
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]
