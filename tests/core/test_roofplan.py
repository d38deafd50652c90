"""Walls and roof from the data's heights (``citygen.roofplan``) on the shipped real data: a building's ``height``
(OSM) or ``measuredHeight`` / solid extent (CityJSON) is its highest point; roofs from ``roof:height``,
``roof:angle`` and ``roof:levels``; untagged roofs capped at one storey and a quarter of the total."""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from citygen_footprints.heights import HeightSettings, parse_length, resolve_height
from shapely.geometry import box

from citygen.builder import Builder
from citygen.coordinator import plan_building
from citygen.footprints import Footprint
from citygen.mass import GRID, neighbour_cover
from citygen.pipeline import import_footprints
from citygen.registry import default_registry
from citygen.roofplan import (
    MAX_ROOF,
    MIN_STOREY,
    MIN_WALL_SHARE,
    ROOF_SHARE,
    ROOF_STOREYS,
    mass_plan,
    plan_mass,
    split_height,
)
from citygen.scene import load_scene

REPO = Path(__file__).resolve().parents[2]
STOCKMANN = "way/122595241"  # height = "39", no roof tags: the scene's hipped roof, capped


class City:
    """A scene's footprints planned (walls and roof) as the pipeline plans them, built one building at a time."""

    def __init__(self, scene_path: Path) -> None:
        self.scene = load_scene(scene_path)
        self.roofs = default_registry().roof_builders
        self.footprints = import_footprints(self.scene).footprints
        self.masses = [plan_mass(fp, self.scene, self.roofs)[0] for fp in self.footprints]
        self.cover = neighbour_cover(self.masses)
        self.index = {fp.id: k for k, fp in enumerate(self.footprints)}
        self.builder = Builder(self.scene, self.scene.seed)

    def build(self, fid: str, footprint: Footprint | None = None):
        """The building's stage record and its mass (``footprint``: the footprint replaced, e.g. with tags)."""
        k = self.index[fid]
        fp = footprint or self.footprints[k]
        mass = self.masses[k] if footprint is None else plan_mass(fp, self.scene, self.roofs)[0]
        outcome = self.builder.build(fp, mass, self.cover[k], "b", (0, 0))
        assert outcome.record is not None, outcome.skipped
        return outcome.record, mass


def top(geometry) -> float:
    """The highest point of a building's geometry (facade meshes and roof)."""
    meshes = [*geometry.meshes.values(), *([geometry.roof] if geometry.roof is not None else [])]
    return max(float(m.points[:, 2].max()) for m in meshes)


@pytest.fixture(scope="module")
def helsinki() -> City:
    return City(REPO / "scenes" / "helsinki.toml")


def test_every_height_tagged_helsinki_building_tops_out_at_its_height(helsinki):
    """Bug fixture (issue 22): walls were built to the OSM height and the roof added on top (Stockmann, 39 m,
    reached 56.2 m). Every building with a ``height`` tag: top of its geometry = ground + height, to 1 cm."""
    tagged = [fp for fp in helsinki.footprints if fp.attributes.get("height") not in (None, "")]
    assert len(tagged) == 17
    for fp in tagged:
        record, mass = helsinki.build(fp.id)
        ground = fp.base - fp.lift
        assert top(record.geometry) == pytest.approx(ground + parse_length(fp.attributes["height"]), abs=0.01), fp.id
        assert record.attributes["height"] == pytest.approx(mass.top - fp.base)
        assert mass.top == pytest.approx(ground + parse_length(fp.attributes["height"]))


def test_height_attributes_show_the_datas_metres(helsinki):
    """Bug fixture: the walls stand on a 2**-20 m grid, and the attributes a DCC shows read so (Hotelli Torni,
    ``height = "70"``: ``citygen:height`` 69.99999980926513, ``wallHeight`` 66.69999980926514). Every tagged
    building's height attribute is now the tag's value, and walls + roof add up to it, to the bit."""
    for fp in [fp for fp in helsinki.footprints if fp.attributes.get("height") not in (None, "")]:
        record, _ = helsinki.build(fp.id)
        attrs = record.attributes
        assert attrs["height"] == parse_length(fp.attributes["height"]) - fp.lift, fp.id
        assert attrs["wallHeight"] + attrs["roofHeight"] == attrs["height"], fp.id
    record, _ = helsinki.build("way/123525580")
    assert (record.attributes["height"], record.attributes["wallHeight"]) == (70.0, 66.7)


def test_simple_3d_buildings_parts_top_out_at_their_height():
    """The OSM file's buildings and building parts with a ``height`` (29, the cathedral's drum among them; lifted
    parts too: ``min_height`` lifts the base, ``height`` is still measured from the ground) top out at ground +
    height."""
    pytest.importorskip("osmium")
    city = City(REPO / "scenes" / "helsinki_osm.toml")
    tagged = [fp for fp in city.footprints if fp.attributes.get("height") not in (None, "")]
    assert len(tagged) == 29 and sum(fp.lift > 0 for fp in tagged) >= 3
    for fp in tagged:
        record, _ = city.build(fp.id)
        assert top(record.geometry) == pytest.approx(fp.base - fp.lift + parse_length(fp.attributes["height"]),
                                                     abs=0.01), fp.id


def test_stockmann_is_39_m_with_a_one_storey_roof_and_floor_lines_on_its_walls(helsinki):
    record, mass = helsinki.build(STOCKMANN)
    assert top(record.geometry) == pytest.approx(39.0, abs=0.01)
    storey = helsinki.scene.defaults.floor_height
    assert (mass.roof.shape, mass.roof_source) == ("hipped", "pitch, capped")
    assert (mass.height, mass.roof.height) == (pytest.approx(39.0 - storey), pytest.approx(storey))
    k = helsinki.index[STOCKMANN]
    plan = plan_building(helsinki.footprints[k], mass, helsinki.cover[k], helsinki.scene.defaults, 1)
    assert plan.floor_lines[-1] == pytest.approx(mass.height)  # floors end where the roof begins
    assert record.attributes["wallHeight"] == pytest.approx(39.0 - storey)


def test_roof_height_tag_sets_the_roof_and_the_walls_take_the_rest(helsinki):
    """way/419479428: height = 13, roof:height = 6.66, hipped."""
    record, mass = helsinki.build("way/419479428")
    assert (mass.roof_source, mass.roof.height, mass.height) == ("roof:height", 6.66, pytest.approx(13.0 - 6.66))
    assert top(record.geometry) == pytest.approx(13.0, abs=0.01)
    assert float(record.geometry.roof.points[:, 2].min()) == pytest.approx(13.0 - 6.66, abs=0.01)


def test_roof_levels_are_in_the_roof_and_building_levels_in_the_walls(helsinki):
    """way/22907250: building:levels = 4, roof:levels = 1, gabled: four storeys of wall and one of roof."""
    k = helsinki.index["way/22907250"]
    fp = helsinki.footprints[k]
    record, mass = helsinki.build(fp.id)
    storey = helsinki.scene.defaults.floor_height
    assert (fp.levels, mass.roof.shape, mass.roof_source) == (4, "gabled", "roof:levels")
    assert (mass.height, mass.roof.height) == (pytest.approx(4 * storey), pytest.approx(storey))
    assert top(record.geometry) == pytest.approx(5 * storey, abs=0.01)
    assert record.attributes["levels"] == 4


def test_roof_angle_sets_the_roof_by_its_pitch_under_the_same_total(helsinki):
    """No shipped building has a roof:angle: Stockmann's footprint given one (gabled, 35 degrees)."""
    k = helsinki.index[STOCKMANN]
    fp = helsinki.footprints[k]
    angled = replace(fp, attributes={**fp.attributes, "roof:shape": "gabled", "roof:angle": "35"})
    record, mass = helsinki.build(STOCKMANN, angled)
    rise = helsinki.roofs["gabled"].rise(mass.outline, mass.roof)
    assert (mass.roof_source, mass.roof.pitch, mass.roof.height) == ("roof:angle", 35.0, pytest.approx(rise))
    assert rise > helsinki.scene.defaults.floor_height  # steeper than the untagged cap allows
    assert top(record.geometry) == pytest.approx(39.0, abs=0.01)


def test_untagged_roofs_are_capped_at_one_storey_and_a_quarter_of_the_total(helsinki):
    """Bug fixture (issue 22): untagged 18 m blocks got roofs up to 18 m tall (57 of 480 roofs 8 m or more)."""
    storey = helsinki.scene.defaults.floor_height
    untagged = [(fp, m) for fp, m in zip(helsinki.footprints, helsinki.masses)
                if not any(fp.attributes.get(t) not in (None, "")
                           for t in ("roof:shape", "roof:height", "roof:angle", "roof:levels"))]
    assert len(untagged) > 400
    for fp, mass in untagged:
        rise = mass.roof.height or 0.0
        assert rise <= min(ROOF_STOREYS * storey, ROOF_SHARE * (mass.height + rise)) + GRID, fp.id  # (walls on GRID)
        if fp.height_source == "default":  # the scene's 18 m is a total: the roof is inside it
            assert mass.height + rise == pytest.approx(helsinki.scene.defaults.default_height)
    assert max(m.roof.height or 0.0 for m in helsinki.masses) < 8.0


def test_an_untagged_roof_leaves_the_data_storeys_their_height(helsinki):
    """Bug fixture: way/396371524 (apartments, height = 18, building:levels = 6, untagged roof) had a 3.3 m roof
    over six 2.45 m storeys, too low for the apartment ground floor's door and transom: the face fell back to a
    plain wall. The roof now leaves each storey 2.8 m and the building still tops out at 18 m."""
    fid = "way/396371524"
    fp = helsinki.footprints[helsinki.index[fid]]
    record, mass = helsinki.build(fid)
    assert (fp.levels, fp.height) == (6, 18.0)
    assert mass.height == pytest.approx(6 * MIN_STOREY) and mass.roof_source == "pitch, capped"
    assert top(record.geometry) == pytest.approx(18.0, abs=0.01)
    low = [fp.id for fp, m in zip(helsinki.footprints, helsinki.masses)
           if fp.height_is_total and fp.levels and m.roof_source.startswith("pitch")
           and m.height / fp.levels < MIN_STOREY - 1e-9 and (m.roof.height or 0.0) > 0]
    assert low == []  # (a total too low for its storeys gets a flat roof: the data's height wins)


def test_a_part_that_is_all_roof_keeps_its_lifted_base():
    """Regression (Helsinki's OSM file, way/206520338): building:levels = 1, building:min_level = 1, roof:levels = 1
    is a roof standing on the level below; counting only the walls' level lost its base (the offset reached the
    top). The total holds the roof level; the walls keep MIN_WALL_SHARE of it."""
    tags = {"building:levels": "1", "building:min_level": "1", "roof:levels": "1", "roof:shape": "gabled"}
    height = resolve_height(tags, "way/206520338", HeightSettings(floor_height=3.3))
    assert (height.height, height.base_offset, height.total) == (pytest.approx(3.3), pytest.approx(3.3), True)
    scene = load_scene(REPO / "scenes" / "helsinki.toml")
    from shapely.geometry import box
    fp = Footprint("way/206520338", box(0, 0, 12, 8), height.height, height.source, height.levels,
                   height.base_offset, tags, lift=height.base_offset, height_is_total=height.total)
    split = split_height(fp, fp.polygon, scene, default_registry().roof_builders)
    assert split.walls == pytest.approx(MIN_WALL_SHARE * 3.3) and split.total == pytest.approx(3.3)


def test_cathedral_corner_domes_stand_on_their_lift_all_roof(helsinki):
    """Regression: Helsinki Cathedral's corner domes (min_height = 18, roof:height = 5, no height) got the scene's
    18 m default as walls on top of their 18 m lift (top 41 m, then 36 m); they are all roof: top 23 m."""
    domes = [fp for fp in helsinki.footprints if fp.height_source == "min_height+roof:height"]
    assert len(domes) == 4
    for fp in domes:
        record, mass = helsinki.build(fp.id)
        assert (fp.base, mass.roof.shape, mass.height) == (18.0, "dome", pytest.approx(0.5))
        assert top(record.geometry) == pytest.approx(23.0, abs=0.01)


def test_a_roof_taller_than_the_building_is_cut_with_a_warning(helsinki):
    k = helsinki.index["way/419479428"]
    fp = helsinki.footprints[k]
    wrong = replace(fp, attributes={**fp.attributes, "roof:height": "20"})
    split = split_height(wrong, helsinki.masses[k].outline, helsinki.scene, helsinki.roofs)
    assert (split.walls, split.roof.height) == (pytest.approx(1.3), pytest.approx(11.7))
    assert split.warnings == ("way/419479428: a 20.00 m roof (roof:height) is taller than the building's 13 m; the "
                              "roof is 11.70 m, the walls 1.30 m -- check its height tags",)


def test_delft_buildings_top_out_at_their_cityjson_height():
    """CityJSON: the LoD1 solid's extent (``cityjson_height = "geometry"``; ``measuredHeight`` otherwise) is the
    total; Delft's low terraces get gabled roofs inside it."""
    delft = City(REPO / "scenes" / "delft.toml")
    assert all(fp.height_is_total for fp in delft.footprints)
    pitched = 0
    for fp in delft.footprints[::4]:
        record, mass = delft.build(fp.id)
        assert top(record.geometry) == pytest.approx(fp.base + fp.height, abs=0.01), fp.id
        pitched += mass.roof.shape != "flat"
    assert pitched >= 10


def test_flat_and_unknown_roofs_leave_the_whole_height_to_the_walls(helsinki):
    flat = [m for fp, m in zip(helsinki.footprints, helsinki.masses) if fp.attributes.get("roof:shape") in
            ("flat", "9.0")]
    assert len(flat) >= 2
    assert all(m.roof.height is None and m.roof_source == "flat" for m in flat)
    assert math.isclose(np.mean([m.top - m.base - m.height for m in flat]), 0.0)


def test_delft_sheds_get_walls_a_door_fits_in_or_no_door(tmp_path):
    """Bug fixture: Delft's 2.2-2.9 m sheds and garages got a gable taking a quarter of their height, walls of
    1.5-2.1 m, and an entrance face: doors under 1.9 m or slivers of wall over them, so 44 of 627 faces fell back
    to plain walls and 19 buildings had no door where one was asked for. A roof at the scene's pitch now leaves a
    storey 2.8 m (flat roof when the total is lower), the coordinator asks no door of a building whose ground floor
    is under 1.9 m, and every face is dressed."""
    from citygen.coordinator import DOOR_STOREY, plan_building
    from citygen.pipeline import generate_city

    delft = City(REPO / "scenes" / "delft.toml")
    for fp, mass in zip(delft.footprints, delft.masses):
        if mass.roof_source.startswith("pitch"):
            assert mass.height >= min(fp.height, MIN_STOREY) - 1e-9, fp.id
        k = delft.index[fp.id]
        plan = plan_building(fp, mass, delft.cover[k], delft.scene.defaults, 1)
        if plan.floor_lines[1] - plan.floor_lines[0] < DOOR_STOREY:
            assert plan.entrance_face is None, fp.id
    scene = replace(delft.scene, output=replace(delft.scene.output, path=str(tmp_path / "delft.usdc")))
    report = generate_city(scene, jobs=1)
    assert report.faces["plain"] == 0 and report.faces["dressed"] > 600
    assert not [w for w in report.warnings if "door" in w]


def test_roof_tags_beyond_float_range_or_reason_give_a_finite_roof():
    """Fuzzing (an OSM city, seed 12): ``roof:levels`` of 401 digits on a part with ``building:levels = 3`` read as
    inf and gave the roof non-finite points; so did such a ``roof:height``. Digits beyond float range are no number;
    a finite but absurd roof from the data on walls of known height is capped at MAX_ROOF with a warning."""
    scene = load_scene(REPO / "scenes" / "helsinki.toml")
    roofs = default_registry().roof_builders
    huge = "1" + "0" * 400
    for tag, value in (("roof:levels", huge), ("roof:height", huge), ("roof:height", "1" + "0" * 40)):
        fp = Footprint("way/17425859", box(0, 0, 10, 8), 9.0, "building:levels", levels=3,
                       attributes={"building:levels": "3", "roof:shape": "gabled", tag: value})
        plan, notes = mass_plan(fp, scene, roofs)
        assert 0 < plan.roof.height <= MAX_ROOF and plan.height == 9.0
        assert bool(notes) == (value != huge) and all("check its roof tags" in n for n in notes)

