"""CityJSON import: the shipped Delft buildings, ground-surface footprints, heights, odd objects."""
from __future__ import annotations

import json

import pytest
import shapely

from citygen.errors import FootprintError

from citygen_footprints.plugin import read_footprints

from .conftest import DELFT, SHARED, write_json


def test_delft_160_buildings(delft):
    assert len(delft.footprints) == 160 and delft.skipped == ()
    assert delft.georef.crs == "EPSG:7415" and delft.georef.proj == ""
    assert delft.georef.origin == (84941.0, 447540.0)
    for f in delft.footprints:
        assert f.polygon.is_valid and f.polygon.area > 1
        assert f.height_source == "geometry" and f.attributes["cityjson:type"] == "Building" and f.height_is_total
        # 3dfier writes measuredHeight as the absolute roof elevation: it equals base + height (the total)
        assert f.base + f.height == pytest.approx(f.attributes["measuredHeight"], abs=1e-6)
    heights = [f.height for f in delft.footprints]
    assert min(heights) == pytest.approx(0.73) and max(heights) == pytest.approx(8.29)
    measured = [f.attributes["measuredHeight"] for f in delft.footprints]
    assert (min(measured), max(measured)) == (0.75, 8.57)
    assert any("no ground surface" in w for w in delft.warnings)


def test_delft_frame_is_local(delft):
    minx, miny, maxx, maxy = shapely.union_all([f.polygon for f in delft.footprints]).bounds
    assert 200 < maxx - minx < 260 and 150 < maxy - miny < 190
    assert abs(minx + maxx) < 2 and abs(miny + maxy) < 2


def test_delft_attribute_heights_on_request():
    result = read_footprints(DELFT, {"cityjson_height": "attribute"})
    heights = sorted(f.height for f in result.footprints)
    assert (heights[0], heights[-1]) == (0.75, 8.57)
    assert {f.height_source for f in result.footprints} == {"measuredHeight"}


@pytest.mark.skipif(not (SHARED / "cityjson_delft" / "delft.json").exists(), reason="shared data absent")
def test_full_delft_file_gives_the_same_buildings(delft):
    full = read_footprints(SHARED / "cityjson_delft" / "delft.json", {})
    assert len(full.footprints) == 160
    ours = {f.id: f.polygon.area for f in delft.footprints}
    for f in full.footprints:  # the local origin differs (the full file is bigger): compare areas
        assert f.polygon.area == pytest.approx(ours[f.id], rel=1e-9)


def _box(x0, y0, size, z0, z1, top_size=None):
    """Vertices and Solid surfaces of a box; the top face may be larger (an overhang)."""
    t = top_size or size
    pad = (t - size) / 2
    v = [[x0, y0, z0], [x0 + size, y0, z0], [x0 + size, y0 + size, z0], [x0, y0 + size, z0],
         [x0 - pad, y0 - pad, z1], [x0 + size + pad, y0 - pad, z1], [x0 + size + pad, y0 + size + pad, z1],
         [x0 - pad, y0 + size + pad, z1]]
    faces = [[[0, 3, 2, 1]], [[4, 5, 6, 7]], [[0, 1, 5, 4]], [[1, 2, 6, 5]], [[2, 3, 7, 6]], [[3, 0, 4, 7]]]
    return v, faces


def _doc(objects, vertices, crs="https://www.opengis.net/def/crs/EPSG/0/7415"):
    doc = {"type": "CityJSON", "version": "2.0", "CityObjects": objects,
           "transform": {"scale": [0.001, 0.001, 0.001], "translate": [85000.0, 447000.0, 0.0]},
           "vertices": [[round(c * 1000) for c in v] for v in vertices]}
    if crs:
        doc["metadata"] = {"referenceSystem": crs}
    return doc


def _solid(faces, offset=0, lod="1"):
    return {"type": "Solid", "lod": lod, "boundaries": [[[[i + offset for i in r] for r in f] for f in faces]]}


def test_ground_surface_is_the_footprint_not_the_overhang(tmp_path):
    v, faces = _box(0, 0, 10, 1.0, 7.0, top_size=12)
    doc = _doc({"b1": {"type": "Building", "attributes": {"storeysAboveGround": 2},
                       "geometry": [_solid(faces)]}}, v)
    f = read_footprints(write_json(tmp_path / "box.city.json", doc), {}).footprints[0]
    assert f.polygon.area == pytest.approx(100.0)
    assert (f.base, f.height, f.levels) == (1.0, 6.0, 2)


def test_parts_children_and_odd_objects(tmp_path):
    v1, faces = _box(0, 0, 10, 0, 3)
    v2, _ = _box(20, 0, 5, 0, 6)
    flat = [[30, 0, 0], [40, 0, 0], [40, 10, 0], [30, 10, 0]]
    objects = {
        "parent": {"type": "Building", "children": ["part"], "attributes": {"yearOfConstruction": 1900},
                   "geometry": [{"type": "MultiSurface", "lod": "0", "boundaries": [[[0, 1, 2, 3]]]}]},
        "part": {"type": "BuildingPart", "parents": ["parent"], "geometry": [_solid(faces)]},
        "lod0": {"type": "Building", "attributes": {"measuredHeight": 4.5},
                 "geometry": [{"type": "MultiSurface", "lod": "0", "boundaries": [[[16, 17, 18, 19]]]}]},
        "two_lods": {"type": "Building", "geometry": [
            {"type": "MultiSurface", "lod": "0", "boundaries": [[[16, 17, 18, 19]]]}, _solid(faces, 8)]},
        "nothing": {"type": "Building"},
        "broken": {"type": "Building", "geometry": [_solid([[[0, 1, 999]]])]},
        "nan": {"type": "Building", "geometry": [_solid([[[0, 1, 20]]])]},
        "road": {"type": "Road", "geometry": [_solid(faces)]},
    }
    doc = _doc(objects, v1 + v2 + flat)
    doc["vertices"].append([float("nan"), 0, 0])  # vertex 20
    result = read_footprints(write_json(tmp_path / "mixed.json", doc), {})
    got = {f.id: f for f in result.footprints}
    assert set(got) == {"part", "lod0", "two_lods"}
    assert got["part"].attributes["cityjson:parent"] == "parent"  # the parent is represented by its part
    assert got["part"].attributes["yearOfConstruction"] == 1900
    assert (got["lod0"].height, got["lod0"].height_source) == (4.5, "measuredHeight")
    assert got["two_lods"].polygon.area == pytest.approx(25.0)  # the LoD1 solid wins over the LoD0 surface
    skipped = {s.id: s.reason for s in result.skipped}
    assert set(skipped) == {"nothing", "broken", "nan"}
    assert "no Solid or MultiSurface" in skipped["nothing"] and "vertex index" in skipped["broken"]
    assert "NaN" in skipped["nan"]


def test_missing_reference_system_warns(tmp_path):
    v, faces = _box(0, 0, 10, 0, 3)
    doc = _doc({"b": {"type": "Building", "geometry": [_solid(faces)]}}, v, crs=None)
    result = read_footprints(write_json(tmp_path / "nocrs.city.json", doc), {})
    assert result.georef.crs == "" and len(result.footprints) == 1
    assert any("no referenceSystem" in w for w in result.warnings)


def test_wrong_reference_system_is_a_clear_error(tmp_path):
    v, faces = _box(0, 0, 10, 0, 3)
    doc = _doc({"b": {"type": "Building", "geometry": [_solid(faces)]}}, v, crs="EPSG:3067")
    with pytest.raises(Exception, match="outside the area of use of EPSG:3067"):
        read_footprints(write_json(tmp_path / "wrong.city.json", doc), {})


def _as_sequence(doc, path):
    """Write a CityJSON document as CityJSONSeq: a header line, then one CityJSONFeature per building."""
    header = {k: v for k, v in doc.items() if k not in ("CityObjects", "vertices")}
    lines = [json.dumps({**header, "CityObjects": {}, "vertices": []})]
    for oid, obj in doc["CityObjects"].items():
        used = {}

        def remap(b, used=used):
            return [remap(x) for x in b] if isinstance(b, list) else used.setdefault(b, len(used))
        geometry = [{**g, "boundaries": remap(g["boundaries"])} for g in obj["geometry"]]
        vertices = [doc["vertices"][i] for i in sorted(used, key=used.get)]
        lines.append(json.dumps({"type": "CityJSONFeature", "id": oid, "vertices": vertices,
                                 "CityObjects": {oid: {**obj, "geometry": geometry}}}))
    path.write_text("\n".join(lines) + "\n")
    return path


def test_cityjson_seq_gives_the_same_buildings(tmp_path, delft):
    path = _as_sequence(json.loads(DELFT.read_text()), tmp_path / "delft.city.jsonl")
    seq = read_footprints(path, {})
    assert seq.georef == delft.georef
    assert [(f.id, round(f.polygon.area, 6), f.height) for f in seq.footprints] == [
        (f.id, round(f.polygon.area, 6), f.height) for f in delft.footprints]
    assert seq.footprints[0].source == "delft.city.jsonl#0"


def test_cityjson_seq_errors_name_the_line(tmp_path):
    path = tmp_path / "bad.city.jsonl"
    path.write_text('{"type": "CityJSON", "version": "2.0", "transform": {"scale": [1, 1, 1], "translate": [0, 0, 0]}}'
                    '\n{"type": "CityJSONFeature", oops}\n')
    with pytest.raises(FootprintError, match=r"bad.city.jsonl:2:29: not valid JSON"):
        read_footprints(path, {})
    path.write_text('{"type": "CityJSONFeature"}\n')
    with pytest.raises(FootprintError, match="must start with a CityJSON header"):
        read_footprints(path, {})
