import math

import numpy as np
import pytest
from hypothesis import given, settings
from shapely.geometry import Polygon, box

from citygen_roofs.skeleton import SkeletonError, straight_skeleton
from tests.roofs.shapes import polygons


def _faces(polygon):
    sk = straight_skeleton(polygon)
    return sk, [Polygon(sk.face_polygon(k)) for k in range(len(sk.faces))]


def test_rectangle_has_two_triangles_two_trapezoids_and_a_ridge():
    sk, faces = _faces(box(0, 0, 20, 10))
    assert sorted(len(f) for f in sk.faces) == [3, 3, 4, 4]
    inner = sk.nodes[sk.times > 0]
    assert len(inner) == 2 and np.allclose(sorted(inner[:, 0]), [5, 15]) and np.allclose(inner[:, 1], 5)
    assert np.allclose(sk.times[sk.times > 0], 5)


def test_square_meets_in_its_centre():
    sk, _ = _faces(box(0, 0, 10, 10))
    assert np.allclose(sk.nodes[sk.times > 0], [[5, 5]]) and all(len(f) == 3 for f in sk.faces)


def test_courtyard_faces_slope_away_from_the_courtyard():
    polygon = box(0, 0, 30, 20).difference(box(8, 6, 22, 14))
    sk, faces = _faces(polygon)
    assert len(faces) == 8 and math.isclose(sum(f.area for f in faces), polygon.area)
    assert sk.times.max() == pytest.approx(4.0)  # half the width of the widest (8 m) side of the ring

def test_t_shape_split_event_leaves_a_ridge_along_the_stem():
    polygon = Polygon([(0, 0), (30, 0), (30, 6), (18, 6), (18, 20), (12, 20), (12, 6), (0, 6)])
    sk, faces = _faces(polygon)
    assert math.isclose(sum(f.area for f in faces), polygon.area)
    stem = sk.nodes[(sk.times > 0) & (sk.nodes[:, 1] > 6)]
    assert np.allclose(stem[:, 0], 15) and stem[:, 1].max() == pytest.approx(17)


def test_courtyard_ring_collapsing_at_once_has_no_t_junctions():
    """A ring strip collapsing along its length: the ridge has the same nodes seen from both sides."""
    polygon = Polygon([(0, 0), (11.998172341876696, 0.2094288772474021), (11.788743464629293, 12.207601219124099),
                       (-0.2094288772474021, 11.998172341876696)],
                      [[(7.859162309752862, 8.138400812749397), (7.963876748376563, 2.1393146418110507),
                        (1.9647905774382155, 2.0346002031873494), (1.8600761388145144, 8.033686374125697)]])
    sk, faces = _faces(polygon)
    sides = [(f[k], f[(k + 1) % len(f)]) for f in sk.faces for k in range(len(f))]
    outline_sides = {f[:2] for f in sk.faces}
    assert all((b, a) in sides for a, b in sides if (a, b) not in outline_sides)


def test_ring_shrinking_to_a_tiny_triangle_ends_in_one_node():
    """Regression: a wavefront ring shrunk below the area tolerance as a 0.1 mm triangle was finished with arcs
    along its sides, leaving an uncovered sliver (a hole at the top of roofs)."""
    polygon = Polygon([(3.964806500082834, 3.046360027459149), (0.8787586494050404, 4.92217261339907),
                       (-1.731780019264243, 4.690515746149578), (-3.866524108457731, 3.170172127616283),
                       (-4.9853906084442645, 0.3819430340191107), (-4.269190098725254, -2.6026939698985476),
                       (-3.1445278539914945, -3.887408465220968), (0.2648288447175807, -4.992981642566448),
                       (1.8572100376655796, -4.642280783838287), (4.65369648624512, -1.8284170787623444),
                       (5, 0)])
    sk, _ = _faces(polygon)
    sides = [(f[k], f[(k + 1) % len(f)]) for f in sk.faces for k in range(len(f))]
    outline_sides = {f[:2] for f in sk.faces}
    assert all((b, a) in sides for a, b in sides if (a, b) not in outline_sides)


def test_invalid_polygon_is_an_error():
    with pytest.raises(SkeletonError):
        straight_skeleton(Polygon([(0, 0), (10, 10), (10, 0), (0, 10)]))


@settings(max_examples=60)
@given(polygons)
def test_faces_partition_the_polygon(polygon):
    sk, faces = _faces(polygon)
    assert len(faces) == sum(len(r.coords) - 1 for r in (polygon.exterior, *polygon.interiors))
    assert all(f.is_valid and f.exterior.is_ccw for f in faces)
    assert math.isclose(sum(f.area for f in faces), polygon.area, rel_tol=1e-6)
    assert math.isclose(polygon.union(faces[0]).area, polygon.area, rel_tol=1e-6)
    # faces meet side to side: every side that is not an outline edge is the reverse side of exactly one other face
    sides = [(f[k], f[(k + 1) % len(f)]) for f in sk.faces for k in range(len(f))]
    outline_sides = {f[:2] for f in sk.faces}
    counts = {s: sides.count(s) for s in sides}
    assert all(counts.get((b, a)) == 1 for a, b in sides if (a, b) not in outline_sides)
    # a node's time is its distance to the edges of the faces it belongs to
    for k, face in enumerate(sk.faces):
        a, b = sk.nodes[face[0]], sk.nodes[face[1]]
        d = (b - a) / np.hypot(*(b - a))
        dist = (sk.nodes[list(face)] - a) @ np.array([-d[1], d[0]])
        assert np.allclose(dist, sk.times[list(face)], atol=1e-6 * max(1.0, sk.times.max()))
