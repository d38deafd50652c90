import numpy as np
import pytest
from shapely.geometry import Polygon

from citygen.footprints import Footprint
from citygen.mass import build_mass, clean_ring, neighbour_cover


def fp(coords, holes=(), height=10.0, id="b"):
    return Footprint(id=id, polygon=Polygon(coords, holes), height=height, height_source="height")


def test_rectangle_faces_have_outward_frames():
    mass = build_mass(fp([(0, 0), (10, 0), (10, 4), (0, 4)]))
    assert [round(f.width, 6) for f in mass.faces] == [10, 4, 10, 4]
    south = mass.faces[0]
    assert south.origin == (0.0, 0.0, 0.0) and south.u == (1.0, 0.0, 0.0)
    assert south.normal == (0.0, -1.0, 0.0)  # outward from a CCW ring
    assert all(f.corner_angles == pytest.approx((90.0, 90.0)) for f in mass.faces)
    # u x v == normal: a right-handed frame
    for f in mass.faces:
        assert np.allclose(np.cross(f.u, f.v), f.normal)


def test_clockwise_input_is_oriented():
    mass = build_mass(fp([(0, 0), (0, 4), (10, 4), (10, 0)]))
    centroid = np.array([5.0, 2.0])
    for f in mass.faces:
        assert np.dot(f.midpoint(0.0) - centroid, f.normal[:2]) > 0


def test_courtyard_faces_point_into_the_courtyard():
    mass = build_mass(fp([(0, 0), (30, 0), (30, 30), (0, 30)], [[(10, 10), (20, 10), (20, 20), (10, 20)]]))
    court = [f for f in mass.faces if f.is_courtyard]
    assert len(court) == 4
    for f in court:
        assert np.dot(np.array([15.0, 15.0]) - f.midpoint(0.0), f.normal[:2]) > 0


def test_nearly_collinear_edges_merge_and_short_edges_are_absorbed():
    coords = [(0, 0), (8, 0.03), (16, 0), (16, 10), (8.05, 10), (8, 10.1), (0, 10)]
    mass = build_mass(fp(coords))
    assert len(mass.faces) == 4
    assert min(f.width for f in mass.faces) > 9


def test_clean_ring_keeps_real_corners():
    ring = np.array([(0, 0), (5, 0), (5, 5), (3, 5), (3, 3), (0, 3)], float)
    assert len(clean_ring(ring, 0.1, 0.8)) == 6


def test_party_walls_detected_between_touching_buildings():
    a = build_mass(fp([(0, 0), (10, 0), (10, 10), (0, 10)], id="a"))
    b = build_mass(fp([(10, 0), (20, 0), (20, 10), (10, 10)], id="b"))
    pa, pb = neighbour_cover([a, b])
    assert pa.shape == (4, 10) and pa.max(axis=1).tolist() == [0, a.height, 0, 0] and pa[1].min() == a.height
    assert pb.max(axis=1).tolist() == [0, 0, 0, b.height] and pb[3].min() == b.height


def test_neighbour_cover_is_the_lowest_neighbour_top():
    """A wall against lower neighbours is covered up to the lowest of their tops (it is seen above them); one
    against a taller neighbour is covered to its own top."""
    tall = build_mass(fp([(0, 0), (10, 0), (10, 10), (0, 10)], id="tall", height=18.0))
    low = build_mass(fp([(10, 0), (20, 0), (20, 6), (10, 6)], id="low", height=3.3))
    lower = build_mass(fp([(10, 6), (20, 6), (20, 10), (10, 10)], id="lower", height=6.6))
    ct, cl, cr = neighbour_cover([tall, low, lower])
    assert ct.max(axis=1).tolist() == [0, 6.6, 0, 0] and ct[[0, 2, 3]].max() == 0
    # the east wall (u runs from y = 0 to 10): its first 6 m stand against low, its last 4 m against lower
    assert ct[1].tolist() == [3.3] * 6 + [6.6] * 4
    assert cl.max() == 3.3 and cr.max() == 6.6  # the lower buildings' west walls are covered to their own tops


def test_a_neighbour_along_part_of_a_wall_covers_only_those_bins():
    """Bug fixture: a wall half covered by a taller neighbour was a party wall over its whole width (a blank
    slab where the rest is seen) or, under half, not covered at all (windows and doors inside the neighbour)."""
    wide = build_mass(fp([(0, 0), (10, 0), (10, 20), (0, 20)], id="wide", height=12.0))
    short = build_mass(fp([(10, 0), (20, 0), (20, 8), (10, 8)], id="short", height=15.0))
    cw, _ = neighbour_cover([wide, short])
    east = cw[1]  # runs from y = 0 to 20: the neighbour stands along its first 8 m
    assert east.tolist() == [12.0] * 4 + [0.0] * 6


def test_neighbour_cover_queried_in_chunks_is_the_same(monkeypatch):
    """The sample points are made into geometries a chunk at a time (memory of big cities): any chunk size gives
    the same cover."""
    from citygen import mass as mass_module
    masses = [build_mass(fp([(x, y), (x + 10, y), (x + 10, y + 8), (x, y + 8)], id=f"{x}-{y}", height=6.0 + x / 5))
              for x in (0, 10, 20) for y in (0, 8)]
    whole = neighbour_cover(masses)
    monkeypatch.setattr(mass_module, "COVER_CHUNK", 7)
    for a, b in zip(whole, neighbour_cover(masses)):
        assert np.array_equal(a, b)
    assert any(c.max() > 0 for c in whole)
