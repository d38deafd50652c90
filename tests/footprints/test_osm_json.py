"""OSM JSON (Overpass API [out:json]): the elements read as an OpenStreetMap file."""
from __future__ import annotations

import json
import random

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from citygen_footprints.plugin import read_footprints

from ..mutate import mutate_json
from .conftest import assert_read_or_refused, write_json
from .test_osm import _ring, _square

pytest.importorskip("osmium")


def _node(i, lon, lat):
    return {"type": "node", "id": i, "lat": lat, "lon": lon}


def _way(i, refs, tags):
    return {"type": "way", "id": i, "nodes": refs, "tags": tags}


def _doc(*elements):
    return {"version": 0.6, "generator": "Overpass API 0.7.62", "osm3s": {"copyright": "ODbL"},
            "elements": list(elements)}


A, B = _square(1, 0, 0, 20, 10), _square(11, 40, 0, 20, 10)
OUTER, INNER = _square(21, 80, 0, 40, 10), _square(31, 90, 3, 5, 4)
DEFAULT_EXPORT = _doc(  # Overpass Turbo's `out body; >; out skel qt;`: ways and relations, then nodes and members
    _way(100, _ring(A), {"building": "house", "building:levels": "3"}),
    _way(200, _ring(B), {"building": "yes", "height": "12"}),
    {"type": "relation", "id": 300, "tags": {"type": "multipolygon", "building": "yes"},
     "members": [{"type": "way", "ref": 202, "role": "outer"}, {"type": "way", "ref": 203, "role": "inner"}]},
    *[_node(*n) for n in sorted(A + B + OUTER + INNER, key=lambda n: (n[0] * 7919) % 101)],
    _way(202, _ring(OUTER), {}), _way(203, _ring(INNER), {}))


def test_an_overpass_json_export_reads_as_osm(tmp_path):
    # was: "neither GeoJSON nor CityJSON (top-level type is None)"
    result = read_footprints(write_json(tmp_path / "export.json", DEFAULT_EXPORT), {})
    assert [f.id for f in result.footprints] == ["way/100", "way/200", "relation/300"]
    a, b, c = result.footprints
    assert a.height == 9.0 and a.attributes["building"] == "house" and a.attributes["osm_id"] == 100
    assert b.height == 12.0 and a.polygon.area == pytest.approx(200.0, rel=0.01)
    assert c.polygon.area == pytest.approx(40 * 10 - 5 * 4, rel=0.01)
    assert result.skipped == () and result.warnings == ()


def test_out_geom_coordinates_on_ways_and_members_are_enough(tmp_path):
    def geometry(nodes):
        return [{"lat": lat, "lon": lon} for _, lon, lat in [*nodes, nodes[0]]]
    way = {**_way(100, _ring(A), {"building": "yes"}), "geometry": geometry(A)}
    way["geometry"][1] = None  # (`out geom(bbox)`: a point outside the box)
    relation = {"type": "relation", "id": 300, "tags": {"type": "multipolygon", "building": "yes"}, "members": [
        {"type": "way", "ref": 202, "role": "outer", "geometry": geometry(OUTER)},
        {"type": "way", "ref": 203, "role": "inner", "geometry": geometry(INNER)}]}
    doc = _doc(way, _node(*A[1]), relation)
    result = read_footprints(write_json(tmp_path / "geom.json", doc), {})
    assert [f.id for f in result.footprints] == ["way/100", "relation/300"]
    assert result.footprints[1].polygon.area == pytest.approx(40 * 10 - 5 * 4, rel=0.01)


def test_malformed_elements_are_left_out_by_name_and_the_rest_is_read(tmp_path):
    doc = _doc(_way(100, _ring(A), {"building": "yes"}), *[_node(*n) for n in A],
               _way(200, "1 2 3", {"building": "yes"}), {"type": "way", "id": "x"}, 7,
               {"type": "node", "id": 5, "lat": "60", "lon": 24.9},
               {"type": "relation", "id": 9, "members": [{"type": "way"}]},
               {"type": "way", "id": 201, "nodes": [], "tags": ["building"]}, {"type": "area", "id": 36000})
    result = read_footprints(write_json(tmp_path / "bad.json", doc), {})
    assert [f.id for f in result.footprints] == ["way/100"]
    text = "\n".join(result.warnings)
    for words in ("element 5 (way 200): \"nodes\" is not a list", "element 6 (way 'x')", "element 7 is not an object",
                  "element 9 (relation 9)", "element 10 (way 201)"):
        assert words in text
    assert "area" not in text


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2 ** 32 - 1))
def test_mutated_osm_json_raises_only_footprint_errors(tmp_path_factory, seed):
    path = tmp_path_factory.getbasetemp() / "fuzz_osm.json"
    path.write_text(mutate_json(json.dumps(DEFAULT_EXPORT), random.Random(seed), rounds=3))
    assert_read_or_refused(lambda p: read_footprints(p, {}), path)
