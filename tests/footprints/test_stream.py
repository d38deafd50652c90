"""The GeoJSON importer's stream (issue 24, planning in bounded memory): a FeatureCollection read twice, a chunk of
text at a time, gives the footprints, skips (with their lines) and warnings of the whole read, in the same order."""
from __future__ import annotations

import json

import pytest
from citygen_footprints import jsonload
from citygen_footprints.plugin import read_footprints, stream_footprints

from citygen.errors import FootprintError

from .conftest import BAD, DELFT, HELSINKI, write_json


def _feature(fid, ring, **properties):
    return {"type": "Feature", "properties": {"id": fid, **properties},
            "geometry": {"type": "Polygon", "coordinates": [ring]}}


def _square(x, y, size=10.0):
    return [[x, y], [x + size, y], [x + size, y + size], [x, y + size], [x, y]]


def _lonlat(x, y):
    return [[x, y], [x + 2e-4, y], [x + 2e-4, y + 1e-4], [x, y + 1e-4], [x, y]]


def _far_projected(tmp_path):
    """Four buildings in EPSG:3067, one 1e15 units away, the crs member after the features."""
    features = [_feature(f"b{k}", _square(385_000 + x, 6_672_000)) for k, x in enumerate((0, 20, 1e15, 40))]
    return {"type": "FeatureCollection", "features": features,
            "crs": {"type": "name", "properties": {"name": "EPSG:3067"}}}


def _odd_lonlat(tmp_path):
    """A lon/lat file with a duplicate id, a stray coordinate, a building 2,000 km away and a bad geometry."""
    features = [_feature("a", _lonlat(24.95, 60.17), height=12), _feature("a", _lonlat(24.951, 60.17)),
                _feature("stray", [[24.95, 60.17], [1e9, 60.17], [24.9502, 60.1702], [24.95, 60.17]]),
                _feature("far", _lonlat(-10.0, 40.0)),
                _feature("c", _lonlat(24.952, 60.171), **{"building:levels": "x"}),
                {"type": "Feature", "properties": {"id": "line"}, "geometry": {"type": "LineString",
                                                                              "coordinates": [[0, 0], [1, 1]]}},
                _feature("d", _lonlat(24.953, 60.171))]
    return {"type": "FeatureCollection", "features": features}


@pytest.mark.parametrize("chunk", [64, 4096, jsonload.CHUNK])
@pytest.mark.parametrize("source", ["helsinki", "bad", "far_projected", "odd_lonlat", "empty"])
def test_a_streamed_feature_collection_is_the_whole_read(tmp_path, monkeypatch, source, chunk):
    """The stream's footprints, skipped features (their lines too) and warnings are the whole read's, whatever
    the chunk of text read at a time (64 characters: every feature crosses a chunk's end)."""
    monkeypatch.setattr(jsonload, "CHUNK", chunk)
    if source == "helsinki":
        path = HELSINKI
    elif source == "bad":
        path = BAD
    else:
        doc = {"far_projected": _far_projected, "odd_lonlat": _odd_lonlat,
               "empty": lambda _: {"type": "FeatureCollection", "features": []}}[source](tmp_path)
        path = tmp_path / "city.geojson"
        path.write_text(json.dumps(doc, indent=1))  # (a feature over several lines: their lines are reported)
    whole = read_footprints(path, {})
    stream = stream_footprints(path, {})
    assert stream.georef == whole.georef
    streamed = stream.collected()
    assert [f.id for f in streamed.footprints] == [f.id for f in whole.footprints]
    assert streamed == whole
    if source == "odd_lonlat":
        assert {s.id for s in whole.skipped} == {"stray", "far", "line"}
        assert any("duplicate id" in w for w in whole.warnings)


def test_a_file_that_is_not_a_feature_collection_is_read_whole(tmp_path):
    """CityJSON, a single Feature, a bare Polygon: not streamed, the whole read handed over."""
    feature = write_json(tmp_path / "one.geojson", _feature("x", _lonlat(24.95, 60.17)))
    polygon = write_json(tmp_path / "bare.geojson", {"type": "Polygon", "coordinates": [_lonlat(24.95, 60.17)]})
    for path in (DELFT, feature, polygon):
        if path.exists():
            assert stream_footprints(path, {}).collected() == read_footprints(path, {})


@pytest.mark.parametrize("text", ['{"type": "FeatureCollection", "features": [{"type": "Feature",}]}',
                                  '{"type": "FeatureCollection", "features": []} trailing',
                                  '{"type": "FeatureCollection", "features": [1 2]}'])
def test_a_file_that_does_not_decode_raises_the_whole_reads_error(tmp_path, text):
    path = tmp_path / "bad.geojson"
    path.write_text(text)
    with pytest.raises(FootprintError) as whole:
        read_footprints(path, {})
    with pytest.raises(FootprintError) as streamed:
        stream_footprints(path, {})
    assert str(streamed.value) == str(whole.value)


def test_the_stream_keeps_no_feature_text(tmp_path, monkeypatch):
    """The first pass decodes a chunk at a time: the reader's buffer holds at most about two chunks or twice the
    longest feature, never the file."""
    longest = []
    grow = jsonload._Reader.more

    def more(reader):
        found = grow(reader)
        longest.append(len(reader.buf))
        return found

    monkeypatch.setattr(jsonload, "CHUNK", 1024)
    monkeypatch.setattr(jsonload._Reader, "more", more)
    stream_footprints(HELSINKI, {})
    features = json.loads(HELSINKI.read_text(encoding="utf-8"))["features"]
    feature = max(len(json.dumps(f)) for f in features)  # (about: the file's spacing may differ)
    assert max(longest) <= 2 * (feature + 1024) < HELSINKI.stat().st_size / 20


def test_a_cityjson_sequence_streams_a_line_at_a_time(tmp_path, monkeypatch):
    """CityJSONSeq (3D BAG's download format) is read a line at a time, never whole, and gives the buildings of the
    same CityJSON file."""
    if not DELFT.exists():
        pytest.skip("Delft CityJSON fixture not present")
    from .test_cityjson import _as_sequence
    path = _as_sequence(json.loads(DELFT.read_text()), tmp_path / "delft.city.jsonl")
    longest = max(len(line) for line in path.read_text().splitlines())
    decoded = []
    loads = json.loads
    monkeypatch.setattr(jsonload, "_read_text", lambda *_: pytest.fail("the sequence was read whole"))
    monkeypatch.setattr(jsonload.json, "loads", lambda text, **kw: decoded.append(len(text)) or loads(text, **kw))
    stream = stream_footprints(path, {})
    streamed = stream.collected()
    monkeypatch.undo()
    assert max(decoded) <= longest + 1 < path.stat().st_size / 20
    whole = read_footprints(DELFT, {})
    assert stream.georef == whole.georef
    assert [(f.id, f.polygon.wkb, f.height, f.base) for f in streamed.footprints] == [
        (f.id, f.polygon.wkb, f.height, f.base) for f in whole.footprints]


def test_a_cityjson_sequence_line_is_cut_only_at_a_newline(tmp_path):
    """A CityJSONSeq line holding U+2028 in a name (valid JSON, written unescaped) was cut there by
    ``str.splitlines``: "not valid JSON" for a good file. Lines now end at newlines only; CRLF endings and a byte
    order mark are read too, and a byte that is not UTF-8 names its line and offset."""
    header = {"type": "CityJSON", "version": "2.0", "transform": {"scale": [1, 1, 1], "translate": [0, 0, 0]},
              "CityObjects": {}, "vertices": []}
    solid = {"type": "Solid", "lod": "1", "boundaries": [[[[0, 3, 2, 1]], [[4, 5, 6, 7]], [[0, 1, 5, 4]],
                                                           [[1, 2, 6, 5]], [[2, 3, 7, 6]], [[3, 0, 4, 7]]]]}
    box = [[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0], [0, 0, 9], [10, 0, 9], [10, 10, 9], [0, 10, 9]]
    feature = {"type": "CityJSONFeature", "id": "b1", "vertices": box, "CityObjects": {
        "b1": {"type": "Building", "attributes": {"name": "Hof\u2028van Delft"}, "geometry": [solid]}}}
    text = json.dumps(header) + "\r\n" + json.dumps(feature, ensure_ascii=False) + "\r\n"
    path = tmp_path / "odd.city.jsonl"
    path.write_bytes(b"\xef\xbb\xbf" + text.encode())
    read = read_footprints(path, {"crs": "EPSG:28992"})
    assert [(f.id, f.attributes["name"], f.height) for f in read.footprints] == [("b1", "Hof\u2028van Delft", 9.0)]
    path.write_bytes(text.encode() + b'{"type": "CityJSONFeature", "id": "\xff"}\n')
    with pytest.raises(FootprintError, match=r"odd.city.jsonl:3: not UTF-8 text \(byte \d+\)"):
        read_footprints(path, {})


def test_an_osm_stream_holds_no_area_until_its_footprints_are_used():
    """OpenStreetMap files stream: the building areas libosmium assembles, then their features, are put aside in a
    temporary file as they come (a 40,000-building .osm.pbf: +71 MB instead of +188 MB), and the stream gives the
    whole read's footprints."""
    import gc

    from citygen_footprints.assemble import RawFeature
    from citygen_footprints.osm import _Area
    from citygen_footprints.plugin import OSMImporter

    from citygen.footprints import Footprint

    from .test_osm import HELSINKI_PBF

    def alive() -> int:
        gc.collect()
        return sum(isinstance(o, _Area | RawFeature | Footprint) for o in gc.get_objects())

    before = alive()
    stream = OSMImporter().stream(HELSINKI_PBF, {})
    assert alive() == before
    assert stream.collected() == OSMImporter().read(HELSINKI_PBF, {})
