import math

import numpy as np
import pytest
from hypothesis import given, settings
from shapely.geometry import Polygon, box

from citygen_roofs.skeleton import SkeletonError, straight_skeleton
from tests.roofs.shapes import outlines


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


def test_invalid_polygon_is_an_error():
    with pytest.raises(SkeletonError):
        straight_skeleton(Polygon([(0, 0), (10, 10), (10, 0), (0, 10)]))


@settings(max_examples=60)
@given(outlines)
def test_faces_partition_the_polygon(polygon):
    sk, faces = _faces(polygon)
    assert len(faces) == sum(len(r.coords) - 1 for r in (polygon.exterior, *polygon.interiors))
    assert all(f.is_valid and f.exterior.is_ccw for f in faces)
    assert math.isclose(sum(f.area for f in faces), polygon.area, rel_tol=1e-6)
    assert math.isclose(polygon.union(faces[0]).area, polygon.area, rel_tol=1e-6)
    # a node's time is its distance to the edges of the faces it belongs to
    for k, face in enumerate(sk.faces):
        a, b = sk.nodes[face[0]], sk.nodes[face[1]]
        d = (b - a) / np.hypot(*(b - a))
        dist = (sk.nodes[list(face)] - a) @ np.array([-d[1], d[0]])
        assert np.allclose(dist, sk.times[list(face)], atol=1e-6 * max(1.0, sk.times.max()))
