import math
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from shapely.geometry import Polygon

from citygen.coordinator import plan_building, plan_floor_lines
from citygen.footprints import Footprint
from citygen.mass import build_mass, on_grid
from citygen.scene import Defaults


def test_floor_lines_use_levels_from_data_and_a_taller_ground_floor():
    lines = plan_floor_lines(18.0, 5, Defaults(ground_floor_height=4.2))
    assert len(lines) == 6 and lines[0] == 0.0 and lines[-1] == 18.0
    heights = np.diff(lines)
    assert heights[0] > heights[1] and np.allclose(heights[1:], heights[1])


@given(st.floats(0.5, 200.0), st.one_of(st.none(), st.integers(1, 60)))
def test_floor_lines_always_cover_the_wall(height, levels):
    lines = np.array(plan_floor_lines(height, levels, Defaults()))
    assert lines[0] == 0.0 and abs(lines[-1] - height) < 1e-9
    assert np.all(np.diff(lines) > 0)
    assert len(lines) == 2 or np.all(np.diff(lines) >= 2.4 - 1e-5)  # (the lowest storey within micrometres)


@given(st.floats(5.0, 200.0), st.one_of(st.none(), st.integers(2, 60)), st.booleans())
def test_storeys_above_the_lowest_are_equal_to_the_last_bit(height, levels, lifted):
    """Equal storeys derive once and are copied (issue 24): on walls of a height on the grid (as every planned mass
    is, :func:`citygen.roofplan.mass_plan`) the storeys above the lowest are bit-equal, and the lines still end
    exactly at the wall's top."""
    height = on_grid(height)
    lines = plan_floor_lines(height, levels, Defaults(ground_floor_height=4.2), lifted)
    storeys = {b - a for a, b in zip(lines[1:], lines[2:])}
    assert lines[-1] == height and len(storeys) <= 1


@settings(max_examples=60, deadline=None)
@given(st.floats(4, 60), st.floats(4, 60), st.floats(3, 60), st.integers(0, 10_000))
def test_plan_agrees_across_faces(w, d, h, seed):
    foot = Footprint(id="b", polygon=Polygon([(0, 0), (w, 0), (w, d), (0, d)]), height=h, height_source="height")
    mass = build_mass(foot)
    plan = plan_building(foot, mass, np.zeros(len(mass.faces), bool), Defaults(), seed)
    assert {r.floor_lines for r in plan.requests} == {plan.floor_lines}
    assert sum(r.entrance for r in plan.requests) == 1
    entrance = next(r for r in plan.requests if r.entrance)
    assert entrance.width == max(r.width for r in plan.requests)
    by_face = {r.context.face_index: r for r in plan.requests}
    for r in plan.requests:  # both faces at a corner reserve the same strip
        right_neighbour = by_face[r.context.neighbours[1]]
        assert r.corner_widths[1] == right_neighbour.corner_widths[0]


def test_party_walls_get_no_request_and_no_door():
    foot = Footprint(id="b", polygon=Polygon([(0, 0), (30, 0), (30, 8), (0, 8)]), height=9, height_source="height")
    mass = build_mass(foot)
    cover = np.array([9.0, 0, 0, 0])  # the long south wall is shared
    plan = plan_building(foot, mass, cover, Defaults(), 1)
    assert 0 in plan.plain_faces and all(r.context.face_index != 0 for r in plan.requests)
    assert plan.entrance_face == 2
    assert plan.party_faces == (0,)  # the roof builder gets them from the plan


def test_a_wall_above_a_lower_neighbour_gets_a_facade_but_no_door():
    """Bug fixture: a wall against a lower neighbour was a plain party wall over its whole height, a blank slab
    above the neighbour's roof (Helsinki demo). It gets a facade now; its foot is hidden, so no entrance."""
    foot = Footprint(id="b", polygon=Polygon([(0, 0), (30, 0), (30, 8), (0, 8)]), height=18, height_source="height")
    mass = build_mass(foot)
    plan = plan_building(foot, mass, np.array([6.6, 0, 0, 0]), Defaults(), 1)
    south = next(r for r in plan.requests if r.context.face_index == 0)
    assert not south.entrance and not south.context.street_facing and plan.entrance_face == 2
    plan = plan_building(foot, mass, np.array([17.5, 0, 0, 0]), Defaults(), 1)  # within PARTY_RISE of the top
    assert 0 in plan.plain_faces


def test_a_tower_rising_from_a_lower_block_has_no_entrance():
    """Bug fixture (way/28775756, Helsinki): a tower whose every wall stands on a lower building got its door on a
    hidden foot; with no free foot there is no entrance."""
    foot = Footprint(id="t", polygon=Polygon([(0, 0), (6, 0), (6, 6), (0, 6)]), height=18, height_source="height")
    mass = build_mass(foot)
    plan = plan_building(foot, mass, np.full(len(mass.faces), 6.6), Defaults(), 1)
    assert plan.entrance_face is None and len(plan.requests) == 4 and not any(r.entrance for r in plan.requests)


def test_a_building_part_lifted_off_the_ground_has_no_door_and_no_tall_ground_floor():
    """Bug fixture (Helsinki, OSM min_height 16 / building:min_level parts): an upper part standing on others got a
    street door and a tall ground floor in mid-air."""
    foot = Footprint(id="p", polygon=Polygon([(0, 0), (20, 0), (20, 10), (0, 10)]), height=12, height_source="height",
                     levels=4, base=16.0, lift=16.0)
    mass = build_mass(foot)
    plan = plan_building(foot, mass, np.zeros(len(mass.faces)), Defaults(ground_floor_height=4.4), 1)
    assert plan.entrance_face is None and len(plan.requests) == 4
    assert not any(r.entrance or r.context.street_facing for r in plan.requests)
    assert plan.floor_lines == pytest.approx((0.0, 3.0, 6.0, 9.0, 12.0))
    grounded = Footprint(id="g", polygon=foot.polygon, height=12, height_source="height", levels=4, base=16.0)
    plan = plan_building(grounded, build_mass(grounded), np.zeros(4), Defaults(ground_floor_height=4.4), 1)
    assert plan.entrance_face is not None and plan.floor_lines[1] > 3.0


def test_a_non_finite_wall_height_passes_the_grid_unchanged():
    """Bug fixture: ``on_grid`` raised OverflowError / ValueError on inf / NaN, which a reader's footprint may carry
    to :func:`citygen.roofplan.mass_plan` before the checks that name the building."""
    assert on_grid(float("inf")) == float("inf") and math.isnan(on_grid(float("nan")))
    assert on_grid(3.3) == round(3.3 * 2 ** 20) / 2 ** 20
