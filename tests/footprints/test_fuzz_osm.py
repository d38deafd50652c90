"""OpenStreetMap and CityJSONSeq files found bad by fuzzing (benchmarks/fuzz_readers.py --readers osm cityjsonseq):
a malformed file is a FootprintError naming it and what to do, a bad building is skipped; never a traceback."""
from __future__ import annotations

import json
import random
import warnings
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from citygen.errors import FootprintError
from citygen_footprints.plugin import read_footprints

from ..mutate import mutate_bytes, mutate_jsonl, mutate_osm, osm_model, write_osm
from .conftest import ROOT, assert_read_or_refused
from .test_osm import LON, _osm, _read, _ring, _square

pytest.importorskip("osmium")


def _one_way(tmp_path, name="a.osm"):
    nodes = _square(1, 0, 0, 20, 10)
    return _osm(tmp_path / name, nodes, [(100, _ring(nodes), {"building": "yes", "height": "7"})])


@pytest.mark.parametrize("old, new, words", [
    ('version="1"', 'version="1e308"', "illegal version"),  # was: ValueError from pyosmium
    ('lat="60.17', 'lat="-inf', "wrong format for coordinate"),  # was: osmium.InvalidLocationError
])
def test_osm_xml_with_a_malformed_attribute_is_a_footprint_error(tmp_path, old, new, words):
    path = _one_way(tmp_path)
    path.write_text(path.read_text().replace(old, new, 1))
    with pytest.raises(FootprintError, match=words) as err:
        _read(path)
    assert str(path) in str(err.value) and "corrupt" in str(err.value)


def test_osm_file_with_an_id_twice_is_read_once_from_a_sorted_copy(tmp_path):
    # was: refused ("Way IDs twice in input"; libosmium stops at a repeated object, as in concatenated extracts)
    path = _one_way(tmp_path)
    way = next(line for line in path.read_text().splitlines() if line.startswith("<way"))
    path.write_text(path.read_text().replace(way, way + "\n" + way))
    result = _read(path)
    assert [f.id for f in result.footprints] == ["way/100"]
    assert any("copy sorted" in w and "repeated" in w for w in result.warnings)


def test_osm_building_with_a_node_thousands_of_km_off_is_skipped_and_the_frame_stays_on_the_rest(tmp_path):
    # found by fuzz_readers --readers osm-city: a node moved to lon -180 made its building a 6,500 km sliver (kept:
    # lon/lat files had no distance check) whose corner dragged the frame's centre 3,400 km away from central
    # Helsinki, where the other buildings' hipped roofs fell back to flat
    nodes = _square(1, 0, 0, 20, 10) + _square(11, 30, 0, 10, 10) + _square(21, 60, 0, 10, 10)
    nodes[-1] = (24, -180.0, nodes[-1][2])
    ways = [(100 + k, _ring(nodes[4 * k:4 * k + 4]), {"building": "yes"}) for k in range(3)]
    result = _read(_osm(tmp_path / "a.osm", nodes, ways))
    assert [f.id for f in result.footprints] == ["way/100", "way/101"]
    (skip,) = result.skipped
    assert skip.id == "way/102" and skip.reason.startswith("its corner at (-180, 60.17")
    assert "km from the other buildings (more than 1,000 km) -- fix its coordinates" in skip.reason
    assert result.georef.origin[0] == pytest.approx(LON, abs=1e-3)
    assert all(abs(v) < 50 for f in result.footprints for v in f.polygon.bounds)


HEADER = {"type": "CityJSON", "version": "2.0", "transform": {"scale": [0.5, 0.5, 1], "translate": [10, 20, 0]},
          "metadata": {"referenceSystem": "EPSG:7415"}, "CityObjects": {}, "vertices": []}
BOX = [[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0], [0, 0, 9], [10, 0, 9], [10, 10, 9], [0, 10, 9]]
FACES = [[[0, 3, 2, 1]], [[4, 5, 6, 7]], [[0, 1, 5, 4]], [[1, 2, 6, 5]], [[2, 3, 7, 6]], [[3, 0, 4, 7]]]


def _feature(oid: str, dx: float) -> dict:
    return {"type": "CityJSONFeature", "id": oid, "vertices": [[x + dx, y, z] for x, y, z in BOX], "CityObjects": {
        oid: {"type": "Building", "geometry": [{"type": "Solid", "lod": "1", "boundaries": [FACES]}]}}}


def test_cityjsonseq_line_without_vertices_reads_the_other_lines(tmp_path):
    # was: ValueError (operands could not be broadcast together with shapes (0,) (3,)) for the whole file
    path = tmp_path / "a.city.jsonl"
    path.write_text("\n".join(json.dumps(line) for line in (HEADER, HEADER, _feature("a", 0))) + "\n")
    result = read_footprints(path, {})
    assert [f.id for f in result.footprints] == ["a"] and result.footprints[0].height == 9


SEQ = "\n".join(json.dumps(line) for line in (HEADER, _feature("a", 0), _feature("b", 40))) + "\n"


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2 ** 32 - 1))
def test_mutated_cityjsonseq_files_raise_only_footprint_errors(tmp_path_factory, seed):
    path = tmp_path_factory.getbasetemp() / "fuzz.city.jsonl"
    path.write_text(mutate_jsonl(SEQ, random.Random(seed)))
    assert_read_or_refused(lambda p: read_footprints(p, {}), path)


SEED = osm_model({n: (lon, lat) for n, lon, lat in _square(1, 0, 0, 20, 10) + _square(11, 30, 0, 10, 10)},
                 [(100, [1, 2, 3, 4, 1], {"building": "yes", "height": "7"}),
                  (101, [11, 12, 13, 14, 11], {"building:part": "yes"}),
                  (102, [11, 12, 13], {}), (103, [13, 14, 11], {})],
                 [(500, [("w", 102, "outer"), ("w", 103, "outer")], {"type": "multipolygon", "building": "yes"})])


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(suffix=st.sampled_from([".osm", ".opl", ".osm.pbf", "_overpass.osm", "_overpass.json"]),
       seed=st.integers(0, 2 ** 32 - 1))
def test_mutated_osm_files_raise_only_footprint_errors(tmp_path_factory, suffix, seed):
    """Also as the Overpass API writes them (ways before their nodes, and OSM JSON): read from a sorted copy."""
    rng = random.Random(seed)
    path = tmp_path_factory.getbasetemp() / f"fuzz{suffix}"
    write_osm(mutate_osm(mutate_osm(SEED, rng), rng), path)
    if suffix == ".osm.pbf" and rng.random() < 0.5:
        path.write_bytes(mutate_bytes(path.read_bytes(), rng))
    assert_read_or_refused(lambda p: read_footprints(p, {}) if suffix.endswith(".json") else _read(p), path)


#: a small city: an outline drawn by its lifted part, a multipolygon, a house; roof and height tags on each
CITY = osm_model({n: (lon, lat) for n, lon, lat in _square(1, 0, 0, 20, 10) + _square(11, 30, 0, 10, 10)
                  + _square(21, 2, 1, 8, 8) + _square(31, 0, 20, 12, 8)},
                 [(100, [1, 2, 3, 4, 1], {"building": "yes", "height": "12", "roof:shape": "gabled"}),
                  (101, [21, 22, 23, 24, 21], {"building:part": "yes", "height": "15", "min_height": "3",
                                               "building:levels": "4", "roof:shape": "hipped"}),
                  (102, [11, 12, 13], {}), (103, [13, 14, 11], {}),
                  (104, [31, 32, 33, 34, 31], {"building": "house", "building:levels": "2", "roof:shape": "pyramidal",
                                               "roof:height": "2"})],
                 [(500, [("w", 102, "outer"), ("w", 103, "outer")],
                   {"type": "multipolygon", "building": "apartments", "roof:shape": "skillion"})])


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(suffix=st.sampled_from([".osm", ".osm.pbf", "_overpass.json"]), seed=st.integers(0, 2 ** 32 - 1))
def test_mutated_osm_files_generate_valid_cities(tmp_path_factory, suffix, seed):
    """fuzz_readers --readers osm-city in small: a mutated file the importer reads (any number of footprints)
    generates a city without raising, with zero validation errors, finite points and every footprint written or
    skipped with a reason that is no internal error, and no numpy or shapely RuntimeWarning on the way."""
    from citygen.scene import load_scene

    from ..mutate import city_of_footprints
    rng = random.Random(seed)
    directory = tmp_path_factory.getbasetemp()
    model = CITY
    for _ in range(rng.choice((1, 2, 3))):
        model = mutate_osm(model, rng)
    path = directory / f"city{suffix}"
    write_osm(model, path)
    if suffix == ".osm.pbf" and rng.random() < 0.5:
        path.write_bytes(mutate_bytes(path.read_bytes(), rng))
    apartment, house = ((ROOT / "rulesets" / name).as_posix() for name in ("apartment.grammar", "house.grammar"))
    (directory / "city.toml").write_text(
        f'[footprints]\npath = "{path.name}"\n[defaults]\nroof_shape = "hipped"\n'
        f'[[assign]]\nwhen = {{ building = ["apartments"] }}\nruleset = "{apartment}"\nfallback = "{house}"\n'
        f'[[assign]]\nruleset = "{house}"\n[output]\npath = "city.usda"\nground = true\n')
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RuntimeWarning)
        try:
            city_of_footprints(load_scene(directory / "city.toml"), directory / "city.usda")
        except FootprintError:
            return  # the file refused, naming it
    noise = [f"{Path(w.filename).name}:{w.lineno}: {w.message}" for w in caught
             if issubclass(w.category, RuntimeWarning)]
    assert not noise, noise  # numpy / shapely messages among the skip reasons
