"""roof:orientation on rectangle-like outlines: the ridge along the longest side (default) or across it."""
import math

import numpy as np
import pytest
from shapely import affinity
from shapely.geometry import Polygon, box

from citygen.roof import RoofSpec, rectangle_like, roof_notes, roof_spec
from citygen_roofs.pitched import GabledRoof, GambrelRoof, HippedRoof, MansardRoof
from tests.roofs.test_builders import TOP, _normals, _open_edges, _outline_edges, _same_edges, _triangles

SLOPE = math.tan(math.radians(30))
LENGTH, WIDTH = 20.0, 8.0


def _walls(mesh):
    p, tris = _triangles(mesh)
    n = _normals(p, tris)
    return n[np.abs(n[:, 2]) < 1e-4 * np.linalg.norm(n, axis=1)]


def _ridge(mesh, z):
    return mesh.points[np.isclose(mesh.points[:, 2], z, atol=1e-5)]


def test_gabled_across_puts_the_gables_on_the_long_sides():
    mesh = GabledRoof().build(box(0, 0, LENGTH, WIDTH), TOP, RoofSpec("gabled", 30.0, orientation="across"))
    ridge = _ridge(mesh, TOP + LENGTH / 2 * SLOPE)
    assert len(ridge) == 2 and np.allclose(ridge[:, 0], LENGTH / 2) and np.ptp(ridge[:, 1]) == pytest.approx(WIDTH)
    walls = _walls(mesh)
    assert len(walls) == 2 and sorted(np.sign(walls[:, 1])) == [-1, 1] and np.allclose(walls[:, 0], 0)


def test_gabled_along_is_the_untagged_roof():
    plain = GabledRoof().build(box(0, 0, LENGTH, WIDTH), TOP, RoofSpec("gabled", 30.0))
    along = GabledRoof().build(box(0, 0, LENGTH, WIDTH), TOP, RoofSpec("gabled", 30.0, orientation="along"))
    assert np.allclose(np.sort(plain.points, axis=0), np.sort(along.points, axis=0))
    assert len(plain.indices) == len(along.indices)


def test_hipped_across_has_its_ridge_across_and_steeper_hips():
    """The ridge runs across at half the length x the pitch; it is as long relative to the width (60%) as the
    along ridge is relative to the length: the hips on the long sides have weight (8/20)^2."""
    mesh = HippedRoof().build(box(0, 0, LENGTH, WIDTH), TOP, RoofSpec("hipped", 30.0, orientation="across"))
    ridge = _ridge(mesh, TOP + LENGTH / 2 * SLOPE)
    hip = (WIDTH / LENGTH) ** 2 * LENGTH / 2
    assert len(ridge) == 2 and np.allclose(ridge[:, 0], LENGTH / 2)
    assert sorted(ridge[:, 1]) == pytest.approx([hip, WIDTH - hip], abs=1e-5)
    assert np.ptp(ridge[:, 1]) / WIDTH == pytest.approx((LENGTH - WIDTH) / LENGTH)
    assert len(_walls(mesh)) == 0
    edges, z = _open_edges(mesh)
    assert _same_edges(edges, _outline_edges(box(0, 0, LENGTH, WIDTH))) and np.allclose(z, TOP, atol=1e-4)


def test_gambrel_and_mansard_across():
    outline = box(0, 0, LENGTH, WIDTH)
    walls = _walls(GambrelRoof().build(outline, TOP, RoofSpec("gambrel", 30.0, orientation="across")))
    assert len(walls) == 6 and np.allclose(walls[:, 0], 0)  # two five-sided gables on the long sides
    mesh = MansardRoof().build(outline, TOP, RoofSpec("mansard", 30.0, orientation="across"))
    run = LENGTH / 2
    top = run / 3 * math.tan(math.radians(60)) + 2 * run / 3 * SLOPE
    assert mesh.points[:, 2].max() == pytest.approx(TOP + top, abs=1e-4)
    assert np.allclose(_ridge(mesh, mesh.points[:, 2].max())[:, 0], LENGTH / 2)


def test_rotated_trapezoid_is_rectangle_like():
    quad = affinity.rotate(Polygon([(0, 0), (20, 0), (20, 8.5), (0, 7.5)]), 33, origin=(0, 0))
    assert rectangle_like(quad) and not rectangle_like(Polygon([(0, 0), (20, 0), (10, 8), (0, 8)]))
    mesh = GabledRoof().build(quad, TOP, RoofSpec("gabled", 30.0, orientation="across"))
    edges, z = _open_edges(mesh)
    assert _same_edges(edges, _outline_edges(quad)) and np.allclose(z, TOP, atol=1e-4)
    assert len(_walls(mesh)) == 2


def test_orientation_tag_wins_over_party_walls():
    """A gable-fronted terrace house (roof:orientation=along, party walls on its long sides): gables front and
    back, slopes down to the party walls as tagged."""
    house = Polygon([(0, 0), (6, 0), (6, 15), (0, 15)])
    mesh = GabledRoof().build(house, TOP, RoofSpec("gabled", 30.0, orientation="along", party=(1, 3)))
    walls = _walls(mesh)
    assert len(walls) == 2 and np.allclose(walls[:, 0], 0)  # gables face -y and +y
    assert mesh.points[:, 2].max() == pytest.approx(TOP + 3 * SLOPE, rel=1e-6)


def test_orientation_is_ignored_where_not_rectangle_like():
    l_shape = Polygon([(0, 0), (20, 0), (20, 8), (8, 8), (8, 20), (0, 20)])
    plain = HippedRoof().build(l_shape, TOP, RoofSpec("hipped", 30.0))
    across = HippedRoof().build(l_shape, TOP, RoofSpec("hipped", 30.0, orientation="across"))
    assert np.array_equal(plain.points, across.points)


def test_roof_spec_reads_orientation():
    assert roof_spec({"roof:orientation": " Across"}, 9.0).orientation == "across"
    assert roof_spec({"roof:orientation": "along"}, 9.0).orientation == "along"
    assert roof_spec({"roof:orientation": "diagonal"}, 9.0).orientation is None  # unknown: the default
    assert roof_spec({}, 9.0, party=(1, 3)).party == (1, 3)


@pytest.mark.parametrize("direction,orientation", [(0.0, "along"), (180.0, "along"), (90.0, "across"),
                                                   (275.0, "across"), (20.0, "along")])
def test_roof_direction_sets_the_ridge_when_orientation_is_untagged(direction, orientation):
    """roof:direction (the main face's downslope compass direction, OSM's alternative to roof:orientation): the
    ridge runs parallel to the side facing it -- on a 20 x 8 m house facing north or south, along the long sides."""
    outline = box(0, 0, LENGTH, WIDTH)
    by_direction = GabledRoof().build(outline, TOP, RoofSpec("gabled", 30.0, direction=direction))
    tagged = GabledRoof().build(outline, TOP, RoofSpec("gabled", 30.0, orientation=orientation))
    assert np.allclose(np.sort(by_direction.points, axis=0), np.sort(tagged.points, axis=0))


def test_roof_direction_turns_the_ridge_of_a_square_house():
    """A square house has no long side for roof:orientation: only roof:direction tells where the ridge runs."""
    for direction, ridge_axis in ((90.0, 0), (0.0, 1), (270.0, 0)):  # slopes facing east-west: ridge north-south
        mesh = GabledRoof().build(box(0, 0, 10, 10), TOP, RoofSpec("gabled", 30.0, direction=direction))
        ridge = _ridge(mesh, TOP + 5 * SLOPE)
        assert len(ridge) == 2 and np.allclose(ridge[:, ridge_axis], 5.0), direction
        assert np.ptp(ridge[:, 1 - ridge_axis]) == pytest.approx(10.0)


def test_roof_orientation_wins_over_roof_direction_and_direction_over_party_walls():
    rotated = affinity.rotate(box(0, 0, LENGTH, WIDTH), 90, origin=(0, 0))  # long sides facing east and west
    both = GabledRoof().build(rotated, TOP, RoofSpec("gabled", 30.0, orientation="along", direction=0.0))
    along = GabledRoof().build(rotated, TOP, RoofSpec("gabled", 30.0, orientation="along"))
    assert np.allclose(np.sort(both.points, axis=0), np.sort(along.points, axis=0))
    house = Polygon([(0, 0), (6, 0), (6, 15), (0, 15)])  # party walls on the long sides, main face to the east
    untagged = GabledRoof().build(house, TOP, RoofSpec("gabled", 30.0, party=(1, 3)))
    assert np.allclose(_walls(untagged)[:, 1], 0)  # a terrace house: gables on the party walls
    mesh = GabledRoof().build(house, TOP, RoofSpec("gabled", 30.0, direction=90.0, party=(1, 3)))
    assert np.allclose(_walls(mesh)[:, 0], 0)  # gables face -y and +y: the slopes come down to the party walls
    l_shape = Polygon([(0, 0), (20, 0), (20, 8), (8, 8), (8, 20), (0, 20)])  # not rectangle-like: no effect
    plain = HippedRoof().build(l_shape, TOP, RoofSpec("hipped", 30.0))
    with roof_notes() as notes:
        turned = HippedRoof().build(l_shape, TOP, RoofSpec("hipped", 30.0, direction=90.0))
    assert np.array_equal(plain.points, turned.points)
    assert notes == ["roof:direction=90 sets the ridge of rectangle-like parts only; elsewhere the ridge follows "
                     "the straight skeleton"]
