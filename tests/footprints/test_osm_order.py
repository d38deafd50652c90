"""OpenStreetMap files not in libosmium's order, read from a sorted copy: Overpass exports (ways before their
nodes), files saved by an editor (JOSM: negative ids of new objects, objects marked deleted)."""
from __future__ import annotations

import pytest
from citygen.errors import FootprintError

from .test_osm import LAT, LON, _osm, _read, _ring, _square

pytest.importorskip("osmium")
from citygen_footprints.osm_sorted import deleted_marks  # noqa: E402


def _josm(path, nodes, ways, relations=(), actions=None):
    """An editor's OSM XML (JOSM's header and quotes)."""
    return _osm(path, nodes, ways, relations, actions, generator="JOSM", q="'")


def _new(first, x, w=20):
    """Four nodes of a new (negative id) square, ids first, first - 1, ..."""
    return [(first - k, lon, lat) for k, (_, lon, lat) in enumerate(_square(0, x, 0, w, 10))]


def test_new_objects_with_negative_ids_are_buildings(tmp_path):
    # was: every building skipped with "5 of its 5 nodes are missing from the file" (libosmium's location index
    # holds no negative id)
    a, b = _new(-1, 0), _new(-5, 40)
    outer, inner = _new(-11, 80, 40), [(n - 20, lon, lat) for n, lon, lat in _square(0, 90, 3, 5, 4)]
    inner = [(-31 - k, lon, lat) for k, (_, lon, lat) in enumerate(inner)]
    old = _square(7, 160, 0, 10, 10)  # downloaded, positive ids, with a new way of the same number as a node
    path = _josm(tmp_path / "edit.osm", a + b + outer + inner + old, [
        (-100, _ring(a), {"building": "house", "height": "7"}),
        (-101, _ring(b), {"building": "yes"}),
        (-102, _ring(outer), {}), (-103, _ring(inner), {}),
        (-104, [n for n, *_ in old[:3]], {"building": "yes"}),  # open: skipped, named by its own id
        (7, [*_ring(old)], {"building": "shed"}),
    ], [(-200, [("w", -102, "outer"), ("w", -103, "inner")], {"type": "multipolygon", "building": "yes"})])
    result = _read(path)
    ids = [f.id for f in result.footprints]
    assert ids == ["way/-100", "way/-101", "way/7", "relation/-200"]
    fp = result.footprints[0]
    assert fp.height == 7.0 and fp.attributes["osm_id"] == -100 and fp.attributes["building"] == "house"
    assert result.footprints[3].polygon.area == pytest.approx(40 * 10 - 5 * 4, rel=0.01)
    (skip,) = result.skipped
    assert skip.id == "way/-104" and "not closed" in skip.reason and "way/-104" in skip.where


@pytest.mark.parametrize("name", ["edit.osm", "edit.osm.gz", "edit.osm.bz2"])
def test_objects_marked_deleted_by_the_editor_are_left_out(tmp_path, name):
    a, b, c = _square(1, 0, 0, 20, 10), _square(11, 40, 0, 20, 10), _new(-1, 80)
    deleted = {("w", 101): "delete", **{("n", n): "delete" for n, *_ in b}, ("w", -100): "delete",
               ("w", 100): "modify"}
    path = _josm(tmp_path / name, a + b + c, [(100, _ring(a), {"building": "yes"}),
                                              (101, _ring(b), {"building": "yes"}),
                                              (-100, _ring(c), {"building": "yes"})], actions=deleted)
    result = _read(path)
    assert [f.id for f in result.footprints] == ["way/100"] and result.skipped == ()


def test_deleted_marks_are_found_across_read_blocks(tmp_path):
    nodes = _square(1, 0, 0, 20, 10)
    marks = {("n", 3): "delete", ("w", 100): "delete", ("n", 1): "modify"}
    path = _josm(tmp_path / "a.osm", nodes, [(100, _ring(nodes), {"building": "yes"})], actions=marks)
    for chunk in (5, 17, 64, 1 << 20):
        assert deleted_marks(path, chunk) == {("n", 3), ("w", 100)}


def test_pbf_and_unreadable_files_are_not_scanned_for_marks(tmp_path):
    (tmp_path / "a.osm.pbf").write_bytes(b"action='delete'")
    (tmp_path / "b.osm.gz").write_bytes(b"not gzip")
    assert deleted_marks(tmp_path / "a.osm.pbf") == set() and deleted_marks(tmp_path / "b.osm.gz") == set()


@pytest.mark.parametrize("quad_tiles", [False, True])
def test_an_overpass_export_with_ways_before_their_nodes_is_read(tmp_path, quad_tiles):
    # was: every building skipped with "5 of its 5 nodes are missing from the file": Overpass Turbo's
    # `out body; >; out skel qt;` writes the ways and relations first (by id), then the nodes (by id or in
    # quad-tile order) and the relations' member ways
    a, b = _square(1, 0, 0, 20, 10), _square(11, 40, 0, 20, 10)
    outer, inner = _square(21, 80, 0, 40, 10), _square(31, 90, 3, 5, 4)
    nodes = sorted(a + b + outer + inner, key=lambda n: (n[0] * 7919) % 101 if quad_tiles else n[0])
    path = tmp_path / "export.osm"
    _josm(path, [], [(100, _ring(a), {"building": "house"}), (200, _ring(b), {"building": "yes"})],
          [(300, [("w", 202, "outer"), ("w", 203, "inner")], {"type": "multipolygon", "building": "yes"})])
    tail = _josm(tmp_path / "tail.osm", nodes, [(202, _ring(outer), {}), (203, _ring(inner), {})])
    body = [line for line in tail.read_text().splitlines() if line.startswith(("<node", "<way", "<relation"))]
    text = path.read_text().replace("</osm>", "\n".join(body) + "\n</osm>")
    path.write_text(text.replace("generator='JOSM'", "generator='Overpass API 0.7.62'"))
    result = _read(path)
    assert [f.id for f in result.footprints] == ["way/100", "way/200", "relation/300"]
    assert result.footprints[2].polygon.area == pytest.approx(40 * 10 - 5 * 4, rel=0.01)
    assert result.skipped == () and any("copy sorted" in w and "Overpass" in w for w in result.warnings)


def test_a_file_in_order_is_read_without_a_copy(tmp_path, monkeypatch):
    import citygen_footprints.osm as osm
    monkeypatch.setattr(osm, "sorted_copy", None)  # (a call would fail)
    nodes = _square(1, 0, 0, 20, 10)
    result = _read(_josm(tmp_path / "a.osm", nodes, [(100, _ring(nodes), {"building": "yes"})]))
    assert [f.id for f in result.footprints] == ["way/100"] and not result.warnings


def test_a_marked_file_that_cannot_be_read_names_the_file_not_its_copy(tmp_path):
    nodes = _square(1, 0, 0, 20, 10)
    path = _josm(tmp_path / "edit.osm", nodes, [(100, _ring(nodes), {"building": "yes"})],
                 actions={("n", 2): "delete"})
    path.write_text(path.read_text().replace("lat='", "lat='x", 1))
    with pytest.raises(FootprintError, match="coordinate") as err:
        _read(path)
    assert str(err.value).startswith(str(path)) and "citygen-osm-" not in str(err.value)


def test_the_sorted_copy_of_a_sorted_file_reads_the_same(tmp_path):
    import osmium
    from citygen_footprints.osm import _objects, _scan
    from citygen_footprints.osm_sorted import plain, sorted_copy

    from .test_osm import HELSINKI_PBF
    copy = tmp_path / "copy.osm.pbf"
    names = sorted_copy(osmium, plain(_objects(osmium, HELSINKI_PBF, areas=False)), copy)
    direct, via_copy = _scan(osmium, HELSINKI_PBF, HELSINKI_PBF), _scan(osmium, copy, HELSINKI_PBF, names)
    assert direct[3] is None and via_copy[3] is None and len(direct[1]) == 572

    def areas(scan):
        return [(a.id, a.tags, a.polygons) for a in map(scan[0].load, scan[1])]
    assert areas(direct) == areas(via_copy)
    assert [s for _, s in direct[2]] == [s for _, s in via_copy[2]]  # (the same order; places count other ways)


def test_negative_ids_too_far_from_the_others_to_renumber_are_an_error_naming_the_file(tmp_path):
    nodes = [(-(1 << 62) - k, lon, lat) for k, (_, lon, lat) in enumerate(_square(0, 0, 0, 20, 10))]
    nodes.append((1 << 62, LON, LAT))
    path = _josm(tmp_path / "far.osm", nodes, [(100, _ring(nodes[:4]), {"building": "yes"})])
    with pytest.raises(FootprintError, match="too far apart") as err:
        _read(path)
    assert str(err.value).startswith(str(path)) and "osmium renumber" in str(err.value)


def test_objects_libosmium_reads_as_deleted_are_left_out(tmp_path):
    # was: built -- a way in an osmChange <delete> block, or visible="false" (the last version in a history file)
    a, b = _square(1, 0, 0, 20, 10), _square(11, 40, 0, 20, 10)
    ways = [(100, _ring(a), {"building": "yes"}), (101, _ring(b), {"building": "yes"})]
    change = _osm(tmp_path / "c.osm", a + b, ways).read_text().replace('<osm version="0.6" generator="test">',
                                                                       '<osmChange version="0.6"><create>')
    deleted = next(line for line in change.splitlines() if line.startswith('<way id="101"'))
    change = change.replace(deleted, "</create><delete>" + deleted + "</delete>").replace("</osm>", "</osmChange>")
    (tmp_path / "c.osc").write_text(change)
    history = _osm(tmp_path / "h.osm", a + b, ways).read_text()
    history = history.replace(deleted, deleted + "\n" + deleted.replace('version="1"', 'version="2" visible="false"'))
    (tmp_path / "h.osm").write_text(history)
    for name in ("c.osc", "h.osm"):
        result = _read(tmp_path / name)
        assert [f.id for f in result.footprints] == ["way/100"] and result.skipped == (), name
