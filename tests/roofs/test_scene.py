import math

import numpy as np
import pytest
from pxr import Usd, UsdGeom

from citygen.cli import main
from citygen.errors import SceneError
from citygen.pipeline import generate_city
from citygen.roof import roof_spec
from citygen.scene import load_scene
from citygen_roofs.pitched import HippedRoof, RoofError
from tests.conftest import REPO

SCENE = REPO / "scenes" / "roofs.toml"


def _roofs(path):
    """Per source id: (triangles, gable triangles, lowest z, highest z) of each building's roof. The roof's
    vertical faces (gables) are wall: triangles in the building's wall meshes (whose facade faces are quads);
    the roof mesh itself has none."""
    stage = Usd.Stage.Open(str(path))
    out = {}
    for prim in stage.Traverse():
        if prim.GetName() == "Roof":
            mesh = UsdGeom.Mesh(prim)
            p = np.array(mesh.GetPointsAttr().Get(), float)
            t = np.array(mesh.GetFaceVertexIndicesAttr().Get()).reshape(-1, 3)
            n = np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]])
            assert not np.any(np.abs(n[:, 2]) < 1e-4 * np.linalg.norm(n, axis=1)), prim.GetPath()
            facade = prim.GetParent().GetChild("Facade")
            walls = [c for c in facade.GetChildren() if c.GetName().startswith("wall_")] if facade else []
            gables = sum(int(np.sum(np.array(UsdGeom.Mesh(w).GetFaceVertexCountsAttr().Get()) == 3)) for w in walls)
            out[prim.GetParent().GetAttribute("citygen:sourceId").Get()] = (len(t), gables, p[:, 2].min(),
                                                                             p[:, 2].max())
    return out


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    out = tmp_path_factory.mktemp("roofs") / "roofs.usda"
    report = generate_city(load_scene(SCENE), out=out)
    return report, out


def test_roof_demo_scene_is_valid_with_every_shape(demo, capsys):
    report, out = demo
    assert report.written == 17 and not report.skipped and not report.warnings
    assert main(["validate", str(out)]) == 0
    roofs = _roofs(out)
    assert roofs["way/1"][1] == 2 and roofs["way/6"][1] == 2  # gabled rectangle and U: a gable at each ridge end
    assert roofs["way/2"][1] == 0 and roofs["way/5"][1] == 0  # hipped L and courtyard block
    assert roofs["way/5"][3] - roofs["way/5"][2] == pytest.approx(4.0, abs=1e-4)  # roof:height = "4 m"
    assert roofs["way/3"][0] == 4  # pyramid over a square
    assert roofs["way/7"][2] == roofs["way/7"][3]  # flat
    assert roofs["way/8"][0] == 16 * 23  # onion over a 16-gon: 11 bands of quads and the tip
    # height = 14 is the total: the tagged onion (3 x its 4.5 m radius at will) takes half of it, walls the rest
    assert (roofs["way/8"][2], roofs["way/8"][3]) == (pytest.approx(7.0, abs=1e-4), pytest.approx(14.0, abs=1e-4))
    assert roofs["way/9"][1] == 2  # untagged house: gabled by its [[assign]] rule
    assert roofs["way/12"][1] == 6  # gambrel: two five-sided gables
    assert roofs["way/10"][0] > 24 * 6 and roofs["way/11"][1] == 0  # a dome in bands over the 24-gon; mansard
    assert roofs["way/13"][3] - roofs["way/13"][2] == pytest.approx(6 * math.tan(math.radians(25)), abs=0.01)  # 3 teeth
    assert roofs["way/14"][1] == 2 and roofs["way/15"][1] == 1  # saltbox: two gables; side_hipped: one
    assert roofs["way/16"][1] > 4 and roofs["way/17"][1] >= 4  # butterfly: walls up to its eaves; 4 cross gables


def test_a_shape_no_builder_makes_gives_a_flat_roof_and_a_warning(tmp_path):
    import json
    (tmp_path / "z.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": [
        _feature(1, [(0, 0), (10, 0), (10, 8), (0, 8)], **{"roof:shape": "zakomar"})]}))
    (tmp_path / "z.toml").write_text(
        f'[scene]\nseed = 1\n[footprints]\npath = "z.geojson"\n'
        f'[[assign]]\nruleset = "{(REPO / "rulesets" / "house.grammar").as_posix()}"\n')
    out = tmp_path / "z.usda"
    report = generate_city(load_scene(tmp_path / "z.toml"), out=out)
    assert report.written == 1
    assert report.warnings == ["way/1: flat roof instead of roof:shape='zakomar', which no roof builder makes "
                               "(known: butterfly, cone, crosspitched, dome, flat, gabled, gambrel, half-hipped, "
                               "hipped, mansard, onion, pyramidal, round, saltbox, sawtooth, side_hipped, skillion)"]
    roofs = _roofs(out)
    assert roofs["way/1"][2] == roofs["way/1"][3]


def test_untagged_buildings_keep_flat_roofs_by_default(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE.read_text().replace('roof_shape = "gabled"\n', "").replace(
        'path = "data/', f'path = "{(SCENE.parent / "data").as_posix()}/').replace(
        '"../rulesets/', f'"{(REPO / "rulesets").as_posix()}/'))
    out = tmp_path / "s.usda"
    generate_city(load_scene(scene), out=out)
    assert _roofs(out)["way/9"][1:] == (0, 6.0, 6.0)


def test_a_failing_builder_gives_a_flat_roof_and_a_warning(tmp_path, monkeypatch):
    def broken(self, outline, top, spec=None):
        raise RoofError("no straight skeleton: test")

    monkeypatch.setattr(HippedRoof, "build", broken)
    out = tmp_path / "r.usda"
    report = generate_city(load_scene(SCENE), out=out)
    assert report.written == 17
    assert [w for w in report.warnings if "flat roof instead of hipped" in w] == [
        "way/2: flat roof instead of hipped: RoofError: no straight skeleton: test",
        "way/5: flat roof instead of hipped: RoofError: no straight skeleton: test"]
    roofs = _roofs(out)
    assert roofs["way/2"][2] == roofs["way/2"][3]


@pytest.mark.parametrize("table, line", [("[defaults]\nroof_shape = \"gambrl\"\n", 6),
                                          ("[[assign]]\nruleset = \"r.grammar\"\nroof_shape = \"gambrl\"\n", 7)])
def test_unknown_roof_shape_names_file_line_and_choices(tmp_path, table, line):
    (tmp_path / "r.grammar").write_text("")
    text = '[scene]\nseed = 1\n[footprints]\npath = "x.geojson"\n' + table
    if "[[assign]]" not in table:
        text += '[[assign]]\nruleset = "r.grammar"\n'
    (tmp_path / "s.toml").write_text(text)
    with pytest.raises(SceneError) as err:
        load_scene(tmp_path / "s.toml", roof_shapes=["flat", "gabled", "hipped"])
    assert f"s.toml:{line}" in str(err.value) and "'gambrl'" in str(err.value)
    assert "valid shapes: flat, gabled, hipped" in str(err.value)


def test_roof_pitch_must_be_an_angle(tmp_path):
    (tmp_path / "r.grammar").write_text("")
    (tmp_path / "s.toml").write_text('[scene]\n[footprints]\npath = "x.geojson"\n[defaults]\nroof_pitch = 95\n'
                                     '[[assign]]\nruleset = "r.grammar"\n')
    with pytest.raises(SceneError, match=r"s.toml:5: roof_pitch must be"):
        load_scene(tmp_path / "s.toml")


def test_roof_spec_reads_osm_tags():
    spec = roof_spec({"roof:shape": "Gabled ", "roof:angle": "42", "roof:height": "3.5 m", "roof:direction": "SW"},
                     wall_height=9.0)
    assert (spec.shape, spec.pitch, spec.height, spec.direction) == ("gabled", 42.0, 3.5, 225.0)
    assert roof_spec({"roof:direction": "370", "roof:angle": "89.9"}, 9.0).direction == 10.0
    assert roof_spec({"roof:angle": "89.9"}, 9.0).pitch == 75.0  # clamped
    assert roof_spec({"roof:angle": "steep"}, 9.0, pitch=33.0).pitch == 33.0  # unparsable: the default
    assert roof_spec({"roof:height": "40"}, 9.0).height == 9.0  # never taller than the walls
    assert roof_spec({"roof:height": "40"}, 2.5).cap == 4.0 and math.isinf(roof_spec({}, 9.0).height or math.inf)


def _feature(fid, xy, **tags):
    """A footprint from local metres (east, north) near the demo's origin."""
    ring = [[24.94 + x / 55700.0, 60.17 + y / 111320.0] for x, y in xy + xy[:1]]
    return {"type": "Feature", "properties": {"id": fid, "osm_type": "way", "building": "house", **tags},
            "geometry": {"type": "Polygon", "coordinates": [ring]}}


def test_terrace_of_hipped_houses_gets_gables_on_its_party_walls(tmp_path):
    """Three attached houses, hipped by the scene: gables on the party walls (two mid-terrace, one at each end),
    no slope down onto a neighbour; the stage validates. An L tagged roof:orientation=across warns and keeps its
    skeleton ridge."""
    import json
    houses = [_feature(k + 1, [(x, 0), (x + w, 0), (x + w, 12), (x, 12)], **{"building:levels": "2"})
              for k, (x, w) in enumerate([(0, 6), (6, 7), (13, 6)])]
    l_shape = _feature(4, [(40, 0), (60, 0), (60, 8), (48, 8), (48, 20), (40, 20)],
                       **{"roof:shape": "gabled", "roof:orientation": "across"})
    (tmp_path / "t.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": houses + [l_shape]}))
    (tmp_path / "t.toml").write_text(
        f'[scene]\nseed = 1\n[footprints]\npath = "t.geojson"\n[defaults]\nroof_shape = "hipped"\n'
        f'[[assign]]\nruleset = "{(REPO / "rulesets" / "house.grammar").as_posix()}"\n')
    out = tmp_path / "t.usda"
    report = generate_city(load_scene(tmp_path / "t.toml"), out=out)
    assert report.written == 4 and not report.skipped
    assert report.warnings == ["way/4: roof:orientation=across ignored where the outline is not rectangle-like; the "
                               "ridge follows the straight skeleton"]
    assert main(["validate", str(out)]) == 0
    roofs = _roofs(out)
    assert [roofs[f"way/{k}"][1] for k in (1, 2, 3)] == [1, 2, 1]  # gable triangles on the party walls
    assert roofs["way/4"][1] == 2  # the L as without the tag: a gable at the end of each arm
