"""The OSM roof shapes built of planar pieces: saltbox, side_hipped, crosspitched, butterfly, sawtooth."""
import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import Polygon

from citygen.roof import RoofSpec, RoofWarning, roof_notes
from citygen_roofs.osm_shapes import (SALTBOX_RIDGE, SAWTOOTH_TOOTH, ButterflyRoof, CrosspitchedRoof, SaltboxRoof,
                                      SawtoothRoof, SideHippedRoof)
from citygen_roofs.pitched import GabledRoof, RoofError
from tests.roofs.shapes import polygons
from tests.roofs.test_builders import TOP, _normals, _open_edges, _outline_edges, _same_edges, _triangles

SHAPES = [SaltboxRoof(), SideHippedRoof(), CrosspitchedRoof(), ButterflyRoof(), SawtoothRoof()]
RECTANGLE = Polygon([(0, 0), (20, 0), (20, 10), (0, 10)])  # edges: 0 south, 1 east, 2 north, 3 west
SHED = Polygon([(0, 0), (30, 0), (30, 12), (0, 12)])
RISE = math.tan(math.radians(30))


def _build(builder, outline=RECTANGLE, **spec):
    mesh = builder.build(outline, TOP, RoofSpec(builder.id, spec.pop("pitch", 30.0), cap=spec.pop("cap", 15.0),
                                                **spec))
    p, tris = _triangles(mesh)
    edges, z = _open_edges(mesh)
    assert _same_edges(edges, _outline_edges(outline)) and np.allclose(z, TOP, atol=1e-4)
    return p, tris, _normals(p, tris)


def _unit(n):
    return n / np.linalg.norm(n, axis=1)[:, None]


def _walls(n):
    """Unit normals of the vertical triangles (not the zero-area ones joining a pinched wall's foot)."""
    real = np.linalg.norm(n, axis=1) > 1e-6
    return _unit(n[real & (np.abs(n[:, 2]) < 1e-6 * np.linalg.norm(n, axis=1))])


def _slopes(n):
    """Pitches (degrees) of the roof planes."""
    u = _unit(n[n[:, 2] > 1e-6 * np.linalg.norm(n, axis=1)])
    return np.unique(np.round(np.degrees(np.arccos(u[:, 2])), 4))


def test_saltbox_long_slope_faces_north_by_default_at_the_pitch():
    """20 x 10 m at 30 degrees, untagged: the ridge along the length, SALTBOX_RIDGE x 10 m in from the north eave;
    the long (north) slope at 30 degrees, the short one twice as steep in rise; a vertical gable at each end."""
    p, _tris, n = _build(SaltboxRoof())
    ridge = p[np.isclose(p[:, 2], p[:, 2].max())]
    run = SALTBOX_RIDGE * 10
    assert len(ridge) == 2 and np.allclose(ridge[:, 1], 10 - run) and np.ptp(ridge[:, 0]) == pytest.approx(20)
    assert p[:, 2].max() == pytest.approx(TOP + run * RISE, abs=1e-4)
    north = _unit(n[(n[:, 2] > 1e-6) & (n[:, 1] > 0)])
    south = _unit(n[(n[:, 2] > 1e-6) & (n[:, 1] < 0)])
    assert np.degrees(np.arccos(north[:, 2])) == pytest.approx(30.0, abs=1e-3)
    assert np.tan(np.arccos(south[:, 2])) == pytest.approx(2 * RISE, rel=1e-4)
    walls = _walls(n)
    assert sorted(np.round(walls[:, 0]).astype(int)) == [-1, 1]  # one gable at each end, facing out


def test_saltbox_long_slope_faces_roof_direction_and_orientation_turns_the_ridge():
    p, _, _ = _build(SaltboxRoof(), direction=180.0)
    assert np.allclose(p[np.isclose(p[:, 2], p[:, 2].max()), 1], SALTBOX_RIDGE * 10)  # the long slope faces south
    p, _, n = _build(SaltboxRoof(), orientation="across", direction=90.0)  # ridge across, long slope facing east
    ridge = p[np.isclose(p[:, 2], p[:, 2].max())]
    assert np.allclose(ridge[:, 0], 20 - SALTBOX_RIDGE * 20) and np.ptp(ridge[:, 1]) == pytest.approx(10)
    assert sorted(np.round(_walls(n)[:, 1]).astype(int)) == [-1, 1]  # the gables on the long sides


def test_saltbox_height_follows_roof_height_and_the_cap():
    assert _build(SaltboxRoof(), height=2.0)[0][:, 2].max() == pytest.approx(TOP + 2.0)
    assert _build(SaltboxRoof(), pitch=70.0, cap=4.0)[0][:, 2].max() == pytest.approx(TOP + 4.0)


def test_saltbox_gables_stand_on_party_walls():
    """Party walls on the long sides (untagged): they are the ends, so the ridge runs across and they are the
    gables; party walls on both pairs: the gabled roof (which gables them all), with a note."""
    _, _, n = _build(SaltboxRoof(), party=(0, 2))
    assert sorted(np.round(_walls(n)[:, 1]).astype(int)) == [-1, 1]
    with pytest.warns(RoofWarning, match="party walls on both pairs of sides: the gabled roof instead"):
        mesh = SaltboxRoof().build(RECTANGLE, TOP, RoofSpec("saltbox", party=(0, 1)))
    gabled = GabledRoof().build(RECTANGLE, TOP, RoofSpec("gabled", party=(0, 1)))
    assert np.array_equal(mesh.points, gabled.points) and np.array_equal(mesh.indices, gabled.indices)


@pytest.mark.parametrize("builder", [SaltboxRoof(), SideHippedRoof(), CrosspitchedRoof()], ids=lambda b: b.id)
def test_rectangle_shapes_elsewhere_are_the_gabled_roof_with_a_note(builder):
    l_shape = Polygon([(0, 0), (20, 0), (20, 8), (8, 8), (8, 20), (0, 20)])
    with pytest.warns(RoofWarning, match="not rectangle-like"):
        mesh = builder.build(l_shape, TOP, RoofSpec(builder.id))
    gabled = GabledRoof().build(l_shape, TOP, RoofSpec("gabled"))
    assert np.array_equal(mesh.points, gabled.points) and np.array_equal(mesh.indices, gabled.indices)


def test_side_hipped_has_one_gable_and_a_hip_at_the_end_facing_roof_direction():
    p, _tris, n = _build(SideHippedRoof(), direction=270.0)  # the hip faces west
    walls = _walls(n)
    assert len(walls) == 1 and walls[0] @ [1, 0, 0] == pytest.approx(1.0)  # one gable triangle, on the east end
    ridge = p[np.isclose(p[:, 2], TOP + 5 * RISE)]
    assert sorted(ridge[:, 0]) == pytest.approx([5.0, 20.0]) and np.allclose(ridge[:, 1], 5.0)
    assert _slopes(n) == pytest.approx([30.0])  # hip and both sides at the pitch


def test_side_hipped_gable_goes_to_a_party_wall_and_two_party_ends_are_gabled():
    _, _, n = _build(SideHippedRoof(), direction=90.0, party=(1,))  # hip asked east, but the east end is a party wall
    walls = _walls(n)
    assert len(walls) == 1 and walls[0] @ [1, 0, 0] == pytest.approx(1.0)
    _, _, n = _build(SideHippedRoof(), party=(1, 3))
    assert sorted(np.round(_walls(n)[:, 0]).astype(int)) == [-1, 1]


def test_crosspitched_has_a_gable_on_every_side_and_one_ridge_height():
    p, _tris, n = _build(CrosspitchedRoof(), party=(0, 1, 2, 3))  # every wall a gable: party walls change nothing
    walls = _walls(n)
    assert len(walls) == 4 and sorted(map(tuple, np.round(walls[:, :2]).astype(int))) == [(-1, 0), (0, -1), (0, 1),
                                                                                             (1, 0)]
    top = p[np.isclose(p[:, 2], p[:, 2].max())]
    assert p[:, 2].max() == pytest.approx(TOP + 5 * RISE) and len(top) == 5  # the centre and the gable apexes
    assert sorted(map(tuple, np.round(top[:, :2], 6))) == [(0, 5), (10, 0), (10, 5), (10, 10), (20, 5)]
    assert _slopes(n) == pytest.approx([math.degrees(math.atan(RISE / 2)), 30.0], abs=1e-3)


def test_butterfly_valley_is_lower_than_both_eaves():
    p, _tris, n = _build(ButterflyRoof())
    valley = p[np.isclose(p[:, 1], 5.0)]
    assert np.allclose(valley[:, 2], TOP, atol=1e-5)  # the valley along the length, at the wall top
    for eave in (0.0, 10.0):
        assert np.allclose(p[np.isclose(p[:, 1], eave) & (p[:, 2] > TOP + 1e-6), 2], TOP + 5 * RISE)
    assert _slopes(n) == pytest.approx([30.0])
    p, _, _ = _build(ButterflyRoof(), orientation="across")
    assert np.allclose(p[np.isclose(p[:, 0], 10.0), 2], TOP, atol=1e-5)
    assert p[:, 2].max() == pytest.approx(TOP + 10 * RISE)


L_VALLEY = Polygon([(10, 4), (3, 4), (3, 8), (0, 8), (0, 0), (10, 0)])  # edge 0 on the 10 x 8 rectangle's middle


def test_regression_butterfly_valley_turns_off_a_party_wall():
    """Regression (hypothesis): the L outline's minimum rectangle is 10 x 8 m, so the valley ran along y = 4,
    which is the outline's edge 0; as a party wall the slope beside it came down onto the neighbour. The valley
    now turns across (x = 5), with a note; free, edge 0 keeps the valley."""
    with roof_notes() as notes:
        p, _, _ = _build(ButterflyRoof(), outline=L_VALLEY, party=(0,))
    assert any("the other middle line" in w for w in notes)
    assert np.allclose(p[np.isclose(p[:, 0], 5.0), 2], TOP, atol=1e-5)
    assert p[np.isclose(p[:, 1], 4.0) & np.isclose(p[:, 0], 10.0), 2].max() == pytest.approx(TOP + 5 * RISE)
    with roof_notes() as notes:
        p, _, _ = _build(ButterflyRoof(), outline=L_VALLEY)
    assert not notes and np.allclose(p[np.isclose(p[:, 1], 4.0), 2], TOP, atol=1e-5)


def test_butterfly_valley_on_party_walls_both_ways_is_gabled():
    """Edges of this L lie on both middle lines of its 10 x 8 m rectangle (y = 4 and x = 5): as party walls no
    valley stays off them, and the part gets the gabled roof with a note."""
    outline = Polygon([(0, 0), (10, 0), (10, 4), (5, 4), (5, 8), (0, 8)])
    assert outline.minimum_rotated_rectangle.equals(Polygon([(0, 0), (10, 0), (10, 8), (0, 8)]))
    with roof_notes() as notes:
        _build(ButterflyRoof(), outline=outline, party=(2, 3))
    assert any("either way" in w and "gabled" in w for w in notes)


PLUS = Polygon([(3, 0), (9, 0), (9, 3), (12, 3), (12, 9), (9, 9), (9, 12), (3, 12), (3, 9), (0, 9), (0, 3), (3, 3)])


def test_regression_sawtooth_with_a_gutter_on_a_party_wall_every_way_is_gabled():
    """Regression: the sawtooth roof's gabled fallback was called with one argument too many (a TypeError, never
    reached by the tests). The plus has walls 3 m (half a 6 m tooth) apart facing each way; with all but one of
    them party walls, every direction puts a gutter on one, with the teeth moved half a tooth or not."""
    with roof_notes() as notes:
        _build(SawtoothRoof(), outline=PLUS, party=tuple(k for k in range(12) if k != 1))
    assert any("every direction" in w and "gabled" in w for w in notes)


def test_sawtooth_teeth_count_heights_and_glazing():
    """30 x 12 m, slopes facing south: 12 m across the teeth, round(12 / 6) = 2 teeth 6 m wide, each 6 tan 30 high;
    the glazed walls (one between the teeth and the north wall of the first) face north."""
    p, _tris, n = _build(SawtoothRoof(), outline=SHED, direction=180.0)
    teeth = round(12 / SAWTOOTH_TOOTH)
    assert p[:, 2].max() == pytest.approx(TOP + 6 * RISE)
    assert sorted(np.unique(np.round(p[np.isclose(p[:, 2], TOP + 6 * RISE), 1], 6))) == [6.0, 12.0]
    assert sorted(np.unique(np.round(p[np.isclose(p[:, 2], TOP), 1], 6))) == [0.0, 6.0, 12.0]  # gutters and foot
    walls = _walls(n)
    glazed = walls[walls[:, 1] > 0.5]
    assert len(glazed) == 2 * teeth  # a rectangle (two triangles) per tooth
    assert _slopes(n) == pytest.approx([30.0])
    p, _, _ = _build(SawtoothRoof(), outline=SHED, direction=90.0, height=2.0)
    assert p[:, 2].max() == pytest.approx(TOP + 2.0)
    assert len(np.unique(np.round(p[np.isclose(p[:, 2], TOP + 2.0), 0], 6))) == 5  # 5 teeth of 6 m along x


def test_sawtooth_keeps_its_gutters_off_party_walls():
    """Untagged, the slopes face out over the longest free wall; a tagged direction whose last gutter would lie
    along a party wall moves the teeth half a tooth (the wall meets a tooth half way up) and keeps its direction."""
    p, _, _n = _build(SawtoothRoof(), outline=SHED, party=(0,))
    south = p[np.isclose(p[:, 1], 0.0) & (p[:, 2] > TOP + 1e-6)]
    assert len(south) == 2 and np.allclose(south[:, 2], TOP + 6 * RISE)  # the south party wall: high glazing
    with roof_notes() as notes:
        p, _, _ = _build(SawtoothRoof(), outline=SHED, party=(0,), direction=180.0)
    assert not notes
    south = p[np.isclose(p[:, 1], 0.0) & (p[:, 2] > TOP + 1e-6)]
    assert len(south) and np.allclose(south[:, 2], TOP + 3 * RISE, atol=1e-4)  # half a 6 m tooth


@pytest.mark.parametrize("builder", SHAPES, ids=lambda b: b.id)
def test_self_intersecting_outline_raises_roof_error(builder):
    with pytest.raises(RoofError):
        builder.build(Polygon([(0, 0), (10, 10), (10, 0), (0, 10)]), TOP, RoofSpec(builder.id))


def test_butterfly_over_touching_courtyards_and_collinear_points_closes():
    """Regression (benchmarks/roof_zoo.py): a piece with courtyards was ear-clipped with its holes, which drops
    collinear outline points: 14 open edges, a RoofError. Every courtyard now gets a cut, so no piece surrounds
    one. (The courtyards touch each other and the outer wall: walls meeting there share vertical edges, so the
    mesh is checked by its projection and its heights.)"""
    rings = json.loads((Path(__file__).parent / "data" / "butterfly_courtyards.json").read_text())
    outline = Polygon(rings[0], rings[1:])
    mesh = ButterflyRoof().build(outline, TOP, RoofSpec("butterfly", 30.0))
    p, tris = _triangles(mesh)
    assert _normals(p, tris)[:, 2].sum() / 2 == pytest.approx(outline.area, rel=1e-6)
    assert p[:, 2].min() == pytest.approx(TOP)


def test_butterfly_valley_along_an_outline_edge_closes():
    """Regression (roof_zoo): the valley line ran along an outline edge; the cut, computed to rounding beside it,
    left the walk round the outline stuck ("the roof's pieces do not follow the outline")."""
    outline = Polygon([(6, 6), (6, 0), (9, 0), (9, 3), (20, 3), (20, 0), (26, 0), (26, 22), (0, 22), (0, 11),
                       (6, 11), (6, 16), (9, 16), (9, 6)], [[(15, 16), (20, 16), (20, 6), (15, 6)]])
    _build(ButterflyRoof(), outline=outline, orientation="along")


@settings(max_examples=60, deadline=None)
@given(polygons, st.sampled_from(SHAPES), st.data())
def test_no_slope_comes_down_onto_a_party_wall(outline, builder, data):
    """Property: with random party walls the roof is closed and, unless the builder noted otherwise, no roof plane
    comes down to the wall top along a party wall (a neighbour stands against vertical walls only)."""
    edges = _outline_edges(outline)
    party = tuple(sorted(data.draw(st.sets(st.integers(0, len(edges) - 1), max_size=len(edges) - 1))))
    with roof_notes() as notes:
        p, tris, n = _build(builder, outline=outline, party=party)
    if notes:
        return
    slope = n[:, 2] > 0.01 * np.linalg.norm(n, axis=1)  # a roof plane, not a wall tilted by float32 rounding
    for k in party:
        a, b = edges[k, :2], edges[k, 2:]
        d = (b - a) / np.linalg.norm(b - a)
        along = (p[:, :2] - a) @ d
        on = (np.abs((p[:, :2] - a) @ [-d[1], d[0]]) < 1e-4) & (along > -1e-4) & (along < np.linalg.norm(b - a) + 1e-4)
        foot = on & np.isclose(p[:, 2], TOP, atol=1e-4)
        eave = foot[tris].sum(axis=1) == 2  # a side along the party wall's foot (three: a zero-area joining triangle)
        assert not np.any(eave & slope), f"{builder.id} slopes onto party wall {k}"


def test_crosspitched_far_from_the_origin_stays_manifold_in_float32():
    """Regression (Helsinki way/30779524, 380 m out): the crosspitched roof's creases cross within float32 rounding
    of each other near the centre; welding the float32 points made an edge used twice the same way (11 of the
    Helsinki rectangles). The cut is snap-rounded to a few float32 units, so such crossings are one vertex."""
    outline = Polygon([(377.29766440608194, -23.177230177666136), (377.7925740199258, -31.5333189147348),
                       (385.22547802942864, -31.098026190635395), (384.7305491943796, -22.719655415384803)])
    mesh = CrosspitchedRoof().build(outline, TOP, RoofSpec("crosspitched", 30.0, cap=10.0))
    edges, z = _open_edges(mesh)  # asserts no edge is used twice the same way
    assert _same_edges(edges, _outline_edges(outline)) and np.allclose(z, TOP, atol=1e-4)
