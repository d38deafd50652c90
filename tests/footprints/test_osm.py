"""OpenStreetMap files: building ways, multipolygons, Simple 3D Buildings parts, and what cannot be a building."""
from __future__ import annotations

import bz2
import gzip
import sys
from pathlib import Path

import pytest
from citygen.errors import FootprintError
from citygen.registry import load_registry

from .conftest import ROOT

pytest.importorskip("osmium")
from citygen_footprints.plugin import OSMImporter  # noqa: E402

HELSINKI_PBF = ROOT / "scenes" / "data" / "helsinki.osm.pbf"
LON, LAT = 24.94, 60.17
DX, DY = 1 / 55_600, 1 / 111_300  # degrees per metre at 60 N


def _square(first: int, x: float, y: float, w: float, h: float) -> list[tuple[int, float, float]]:
    """Four nodes of a w x h metre rectangle with its lower left corner x, y metres from the reference."""
    return [(first + k, LON + (x + dx) * DX, LAT + (y + dy) * DY)
            for k, (dx, dy) in enumerate(((0, 0), (w, 0), (w, h), (0, h)))]


def _osm(path: Path, nodes, ways, relations=(), actions=None, generator="test", q='"') -> Path:
    """An OSM XML file: nodes (id, lon, lat); ways (id, node ids, tags); relations (id, [(type, ref, role)], tags);
    ``actions`` {(type letter, id): action} as an editor marks objects (JOSM: ``generator="JOSM", q="'"``, its
    quotes; new objects have negative ids and no version); a ``.gz`` / ``.bz2`` name is compressed."""
    actions = actions or {}

    def attrs(kind, i):
        action = actions.get((kind, i))
        return f"id={q}{i}{q}" + (f" action={q}{action}{q}" if action else "") + ("" if i < 0 else f" version={q}1{q}")

    def tags(t):
        return "".join(f"<tag k={q}{k}{q} v={q}{v}{q}/>" for k, v in t.items())
    lines = [f"<?xml version={q}1.0{q} encoding={q}UTF-8{q}?>", f"<osm version={q}0.6{q} generator={q}{generator}{q}>"]
    lines += [f"<node {attrs('n', i)} lat={q}{lat:.9f}{q} lon={q}{lon:.9f}{q}/>" for i, lon, lat in nodes]
    lines += [f"<way {attrs('w', i)}>" + "".join(f"<nd ref={q}{n}{q}/>" for n in refs) + tags(t) + "</way>"
              for i, refs, t in ways]
    lines += [f"<relation {attrs('r', i)}>" + "".join(f"<member type={q}{k}{q} ref={q}{r}{q} role={q}{role}{q}/>"
                                                      for k, r, role in members) + tags(t) + "</relation>"
              for i, members, t in relations]
    text = "\n".join([*lines, "</osm>"]) + "\n"
    opener = {".gz": gzip.compress, ".bz2": bz2.compress}.get(path.suffix)
    path.write_bytes(opener(text.encode()) if opener else text.encode())
    return path


def _ring(nodes) -> list[int]:
    ids = [n[0] for n in nodes]
    return [*ids, ids[0]]


def _read(path: Path, **options):
    return OSMImporter().read(path, options)


def test_a_closed_building_way_is_a_footprint_with_its_tags(tmp_path):
    nodes = _square(1, 0, 0, 20, 10)
    result = _read(_osm(tmp_path / "a.osm", nodes, [(100, _ring(nodes), {"building": "house", "height": "7"})]))
    (fp,) = result.footprints
    assert fp.id == "way/100" and fp.height == 7.0 and fp.height_source == "height"
    assert fp.attributes["building"] == "house"
    assert fp.attributes["osm_type"] == "way" and fp.attributes["osm_id"] == 100
    assert fp.polygon.area == pytest.approx(200.0, rel=0.01)
    assert result.skipped == () and result.georef.crs.endswith("4326")


def test_a_multipolygon_relation_keeps_its_courtyard(tmp_path):
    outer, inner = _square(1, 0, 0, 40, 30), _square(11, 10, 10, 20, 10)
    path = _osm(tmp_path / "block.osm", outer + inner,
                [(100, _ring(outer), {}), (101, _ring(inner), {})],
                [(500, [("way", 100, "outer"), ("way", 101, "inner")], {"type": "multipolygon", "building": "yes"})])
    (fp,) = _read(path).footprints
    assert fp.id == "relation/500"
    assert len(fp.polygon.interiors) == 1
    assert fp.polygon.area == pytest.approx(1200.0 - 200.0, rel=0.01)


def test_building_parts_replace_their_outline_and_take_its_other_tags(tmp_path):
    outline, low, tower = _square(1, 0, 0, 30, 20), _square(11, 0, 0, 20, 20), _square(21, 20, 0, 10, 20)
    ways = [(100, _ring(outline), {"building": "church", "height": "30", "name": "St X", "roof:shape": "gabled"}),
            (101, _ring(low), {"building:part": "yes", "height": "12"}),
            (102, _ring(tower), {"building:part": "yes", "height": "30", "min_height": "12"})]
    path = _osm(tmp_path / "church.osm", outline + low + tower, ways)
    result = _read(path)
    parts = {fp.id: fp for fp in result.footprints}
    assert set(parts) == {"way/101", "way/102"}
    tower = parts["way/102"]
    assert tower.base == pytest.approx(12.0) and tower.height == pytest.approx(18.0)
    assert tower.lift == pytest.approx(12.0) and parts["way/101"].lift == 0.0  # the coordinator gives it no door
    assert tower.attributes["building"] == "church" and tower.attributes["name"] == "St X"
    assert tower.attributes["building:outline"] == "way/100"
    assert "roof:shape" not in tower.attributes  # the outline's shape and height are not the part's
    assert parts["way/101"].height == pytest.approx(12.0)
    assert any("1 building outlines are drawn by their 2 building:part areas" in w for w in result.warnings)
    kept = _read(path, osm_parts="ignore")
    assert [fp.id for fp in kept.footprints] == ["way/100"]


def test_a_part_outside_every_outline_stands_alone(tmp_path):
    alone = _square(1, 100, 100, 10, 10)
    result = _read(_osm(tmp_path / "p.osm", alone, [(100, _ring(alone), {"building:part": "yes", "height": "5"})]))
    assert [fp.id for fp in result.footprints] == ["way/100"]


def test_what_cannot_be_a_building_is_skipped_by_id_with_what_to_do(tmp_path):
    good, open_, cut, member = (_square(1, 0, 0, 10, 10), _square(11, 20, 0, 10, 10), _square(21, 40, 0, 10, 10),
                                _square(31, 60, 0, 10, 10))
    nodes = good + open_ + cut[:3] + member  # node 24 of the cut way is not in the file
    ways = [(100, _ring(good), {"building": "yes"}),
            (101, [n[0] for n in open_], {"building": "yes"}),  # not closed
            (102, _ring(cut), {"building": "yes"}),
            (103, _ring(member), {}),
            (104, _ring(good), {"building": "no"})]  # not a building: ignored, not reported
    relations = [(500, [("way", 103, "outer"), ("way", 999, "outer")], {"type": "multipolygon", "building": "yes"})]
    result = _read(_osm(tmp_path / "bad.osm", nodes, ways, relations))
    assert [fp.id for fp in result.footprints] == ["way/100"]
    reasons = {s.id: s for s in result.skipped}
    assert set(reasons) == {"way/101", "way/102", "relation/500"}
    assert "not closed" in reasons["way/101"].reason
    assert "1 of its 5 nodes are missing" in reasons["way/102"].reason
    assert "complete_ways" in reasons["way/102"].reason
    assert "could not be assembled" in reasons["relation/500"].reason
    assert reasons["relation/500"].where == "bad.osm, relation/500"


def test_without_pyosmium_the_error_names_the_extra(tmp_path, monkeypatch):
    nodes = _square(1, 0, 0, 10, 10)
    path = _osm(tmp_path / "a.osm", nodes, [(100, _ring(nodes), {"building": "yes"})])
    monkeypatch.setitem(sys.modules, "osmium", None)
    with pytest.raises(FootprintError, match=r"pip install 'citygen\[osm\]'"):
        _read(path)


def test_a_file_that_is_not_osm_is_an_error_naming_it(tmp_path):
    path = tmp_path / "broken.osm"
    path.write_text("this is not OSM XML")
    with pytest.raises(FootprintError, match="cannot read the OpenStreetMap file") as err:
        _read(path)
    assert str(path) in str(err.value)


@pytest.mark.parametrize("name", ["city.osm", "city.osm.pbf", "CITY.OSM.PBF", "city.osm.bz2"])
def test_osm_files_reach_the_osm_importer(name):
    assert load_registry().importer_for(Path(name)).id == "osm"


def test_helsinki_pbf_buildings_courtyards_and_parts():
    result = _read(HELSINKI_PBF)
    # 521: the cathedral's drum (way/234870674, building=church, building:part=yes) and way/675858716 are their own
    # buildings since a part inside nested outlines goes to the outline that is no part (test_a_part_inside_...)
    assert len(result.footprints) == 521 and len(result.skipped) == 62
    ids = [fp.id for fp in result.footprints]
    assert len(set(ids)) == len(ids)
    assert sum(fp.id.startswith("relation/") for fp in result.footprints) == 68
    assert sum(len(fp.polygon.interiors) > 0 for fp in result.footprints if fp.polygon.geom_type == "Polygon") >= 60
    assert sum(fp.base > 0 for fp in result.footprints) == 82  # parts lifted by min_height / building:min_level
    cut = [s for s in result.skipped if "missing from the file" in s.reason]
    assert len(cut) == 54  # buildings the extract's edge cuts through
    assert _read(HELSINKI_PBF).footprints == result.footprints  # the same file reads the same


def test_a_part_inside_nested_outlines_belongs_to_the_outline_that_is_no_part(tmp_path):
    """Helsinki Cathedral: its drum (way/234870674) is tagged building=church *and* building:part=yes, and stands
    inside the cathedral's outline; two small parts lie wholly inside both. The part went to whichever outline the
    spatial index listed last -- the drum, which vanished from the OSM city, drawn by a 2 m part. A part now goes
    to the outline holding the most of it; on a tie to one that is no part itself, then to the smallest."""
    cathedral, drum, lantern = _square(1, 0, 0, 40, 40), _square(11, 10, 10, 20, 20), _square(21, 15, 15, 4, 4)
    annex, hall, kiosk = _square(31, 60, 0, 20, 20), _square(41, 58, -2, 30, 24), _square(51, 62, 2, 3, 3)
    ways = [(100, _ring(cathedral), {"building": "cathedral", "height": "13"}),
            (101, _ring(drum), {"building": "church", "building:part": "yes", "height": "38"}),
            (102, _ring(lantern), {"building:part": "yes", "height": "40", "min_height": "38"}),
            (103, _ring(annex), {"building": "yes", "height": "6"}),
            (104, _ring(hall), {"building": "retail", "height": "8"}),
            (105, _ring(kiosk), {"building:part": "yes", "height": "3"})]
    result = _read(_osm(tmp_path / "nested.osm", cathedral + drum + lantern + annex + hall + kiosk, ways))
    outline = {fp.id: fp.attributes.get("building:outline") for fp in result.footprints}
    assert outline == {"way/101": None, "way/102": "way/100", "way/104": None, "way/105": "way/103"}


def test_a_scene_reads_an_osm_file_and_writes_a_valid_stage(tmp_path):
    from citygen.cli import main
    from citygen.pipeline import generate_city
    from citygen.scene import load_scene
    from pxr import Usd

    outline, low, tower = _square(1, 0, 0, 30, 20), _square(11, 0, 0, 20, 20), _square(21, 20, 0, 10, 20)
    ways = [(100, _ring(outline), {"building": "church", "height": "30", "building:colour": "#ffffff"}),
            (101, _ring(low), {"building:part": "yes", "height": "12", "roof:colour": "#b4c9b3"}),
            (102, _ring(tower), {"building:part": "yes", "height": "30", "min_height": "12",
                                 "building:colour": "brown"})]
    _osm(tmp_path / "church.osm", outline + low + tower, ways)
    (tmp_path / "scene.toml").write_text(
        f'[footprints]\npath = "church.osm"\n[[assign]]\n'
        f'ruleset = "{(ROOT / "rulesets" / "historic.grammar").as_posix()}"\n'
        '[output]\npath = "church.usda"\n')
    report = generate_city(load_scene(tmp_path / "scene.toml"), jobs=1)
    assert report.written == 2 and not report.skipped
    assert main(["validate", str(tmp_path / "church.usda")]) == 0
    stage = Usd.Stage.Open(str(tmp_path / "church.usda"))
    bases = {p.GetAttribute("citygen:sourceId").Get(): p.GetAttribute("citygen:base").Get()
             for p in stage.Traverse() if p.HasAttribute("citygen:sourceId")}
    assert bases == {"way/101": 0.0, "way/102": pytest.approx(12.0)}
    # colour tags: the low part takes the outline's white walls and has its own roof colour; the tower is brown
    looks = {p.GetName() for p in stage.GetPrimAtPath("/Materials").GetAllChildren()}
    assert {"colour_ffffff", "colour_a52a2a", "colour_b4c9b3"} <= looks
    assert not any(name.startswith("plaster_") for name in looks)  # no palette wall where the data has a colour
    parts = {p.GetAttribute("citygen:sourceId").Get(): p for p in stage.Traverse()
             if p.HasAttribute("citygen:sourceId")}
    roofs = [parts[i].GetChild("Roof").GetRelationship("material:binding").GetTargets()[0].name
             for i in ("way/101", "way/102")]
    assert roofs == ["colour_b4c9b3", "roof_dark"]
