import math

import numpy as np
import pytest
from hypothesis import given, settings
from shapely.geometry import Polygon, box
from shapely.geometry.polygon import orient

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


def test_t_shape_whose_stem_collapses_as_its_corners_meet_ends_the_stem_ridge_at_the_body():
    """Regression (roof_zoo): a stem thinner than the body collapses just as the two reflex corners meet below it;
    the spike left was folded onto one corner, leaving a zero-length edge whose ends moved together and never
    collapsed, so the stem's side face ran off into the body (every T shape with a thin stem: no roof)."""
    polygon = Polygon([(0, 0), (30, 0), (30, 10), (18, 10), (18, 20), (12, 20), (12, 10), (0, 10)])
    sk, faces = _faces(polygon)
    assert math.isclose(sum(f.area for f in faces), polygon.area)
    assert all(f.is_valid for f in faces)
    stem_sides = [sk.nodes[list(sk.faces[k])] for k in (3, 5)]
    assert all(len(side) == 4 and np.allclose(side[2:, 0], 15) for side in stem_sides)
    assert sorted(sk.nodes[sk.times > 0].round(9).tolist()) == [[5, 5], [15, 5], [15, 7], [15, 17], [25, 5]]

def test_two_reflex_vertices_meeting_each_other_split_the_ring_once():
    """Regression (benchmarks/roof_zoo.py, symmetric stars): two reflex vertices arriving at one point at once.
    The split left a piece of no length of the edge hit on the wrong side, which the other vertex split again,
    joining the rings, for ever ("no convergence after 416 events": every skeleton roof was flat). Now the two
    vertices meet (a vertex event) and a vertex at the end of an edge splits it only when it moves into it."""
    polygon = Polygon([(7.725424859373682, 23.77641290737884), (-12.135254915624214, 8.816778784387092),
                       (-25, -8.040613248383184e-15), (-23.24441214720628, -9.203113817116957),
                       (-3.644843137107058, -3.4227355296434436), (-4.684532864643116, -24.557181268217217),
                       (4.684532864643106, -24.557181268217217), (13.395669874474919, -21.108198137550374),
                       (4.648882429441257, -1.8406227634233894), (25, -6.123233995736766e-15)])
    sk, faces = _faces(polygon)
    assert all(f.is_valid for f in faces) and math.isclose(sum(f.area for f in faces), polygon.area)
    meet = set(sk.faces[3]) & set(sk.faces[4]) & set(sk.faces[7]) & set(sk.faces[8])  # the edges at corners 4, 8
    assert len(meet) == 1 and np.allclose(sk.nodes[meet.pop()], [-0.186, 0.974], atol=1e-3)

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


def _l_shape():
    """An L: body 10 x 4 m, arm 3 x 3 m on its left; edges 0 body top (right part), 1 arm's inner side, 2 arm top,
    3 left side, 4 bottom, 5 right side."""
    return orient(Polygon([(10, 4), (3, 4), (3, 7), (0, 7), (0, 0), (10, 0)]), 1.0)


def _in_plane(sk, faces, weights):
    """Every node of a face lies where its edge's wavefront passes at the node's time."""
    for e, face in faces:
        p = sk.nodes[list(face)]
        a, b = p[0], p[1]
        d = (b - a) / np.hypot(*(b - a))
        inward = (p - a) @ np.array([-d[1], d[0]])
        assert np.allclose(inward, weights[e] * sk.times[list(face)], atol=1e-9), e


def test_weighted_skeleton_ends_in_a_plateau_where_standing_edges_wall_in_the_rest():
    """Bug fixture (way/28775756, Helsinki): a round tower with party walls (weight 0) on all but one short edge
    stuck the wavefront once that edge was swept away ("wavefront stuck at time 2.382 with 12 vertices"). The
    region nothing reaches is a plateau at the time its last moving edge vanished. Here the arm's top (edge 2)
    sweeps the arm and the body's left 3 m, reaching the bottom at time 7; the rest of the body, walled in by
    standing edges and the wall left by the arm's inner side (next test), is a plateau at time 7."""
    weights = np.array([0, 0, 1, 0, 0, 0], dtype=float)
    sk = straight_skeleton(_l_shape(), weights=weights)
    assert len(sk.flats) == 1 and np.allclose(sk.times[list(sk.flats[0])], 7.0)
    flat = Polygon(sk.nodes[list(sk.flats[0])])
    assert flat.exterior.is_ccw and flat.equals(box(3, 0, 10, 4))
    assert Polygon(sk.face_polygon(2)).area + flat.area == pytest.approx(_l_shape().area)
    _in_plane(sk, enumerate(sk.faces), weights)


def test_a_standing_edge_between_parallel_edges_of_different_speeds_turns_round():
    """Bug fixture (found by a property test of party-wall roofs): when the arm's inner side (standing) is swept
    to nothing, its neighbours -- the body's top (standing) and the arm's top (moving) -- are parallel with
    different speeds, so no vertex can join them. The roof came out cracked (a face out of its plane). The
    standing edge turns round instead: a wall along its line grows between the two as the arm's top moves on."""
    weights = np.array([0, 0, 1, 0, 0, 1], dtype=float)
    sk = straight_skeleton(_l_shape(), weights=weights)
    _in_plane(sk, enumerate(sk.faces), weights)
    assert len(sk.walls) == 1 and not sk.flats
    wall = sk.nodes[list(sk.walls[0])]
    assert np.allclose(wall[:, 0], 3.0) and wall[1, 1] < wall[0, 1]  # on x = 3, its foot running down the line
    assert sorted(np.round(sk.times[list(sk.walls[0])], 9)) == [3.0, 7.0, 7.0]
    covered = sum(Polygon(sk.face_polygon(k)).area for k in (2, 5))
    assert covered == pytest.approx(_l_shape().area)


def _same_skeleton(a, b):
    """Bit for bit: node coordinates (their sign of zero too), times, faces, plateaus and walls."""
    return (a.nodes.tobytes() == b.nodes.tobytes() and a.times.tobytes() == b.times.tobytes()
            and (a.faces, a.flats, a.walls) == (b.faces, b.flats, b.walls))


@settings(max_examples=40)
@given(polygons)
def test_small_wavefront_search_in_python_finds_the_events_numpy_finds(polygon):
    """A small wavefront's next event is searched in plain Python floats (speed); the numpy search of a big one must
    give the very same skeleton, to the last bit, or a building's roof would change with its size class."""
    from citygen_roofs import skeleton
    weights = np.where(np.arange(sum(len(r.coords) - 1 for r in (polygon.exterior, *polygon.interiors))) % 5 == 2,
                       0.0, 1.0)
    for w in (None, weights):
        try:
            python = straight_skeleton(polygon, weights=w)
        except SkeletonError as exc:
            python = str(exc)
        small = skeleton.SMALL_FRONT
        skeleton.SMALL_FRONT = 0
        try:
            numpy = straight_skeleton(polygon, weights=w)
        except SkeletonError as exc:
            numpy = str(exc)
        finally:
            skeleton.SMALL_FRONT = small
        assert python == numpy if isinstance(python, str) else _same_skeleton(python, numpy)


def test_edge_event_node_sums_from_positive_zero_like_numpys_mean():
    """Found when the edge event's meeting point stopped using ``np.mean``: in this roof-zoo star a node on the y
    axis came out at x = -0.0 (the plain sum of two -0.0), where numpy's mean, summing from +0.0, gave +0.0 -- the
    same roof, different bytes. The node stays at +0.0."""
    star = Polygon([(17.67766952966369, 17.677669529663685), (9.18485099360515e-16, 15),
                    (-17.677669529663685, 17.67766952966369), (-17.677669529663692, -17.677669529663685),
                    (3.535533905932737, -3.5355339059327386), (25, -6.123233995736766e-15)])
    sk = straight_skeleton(star)
    on_axis = sk.nodes[sk.nodes[:, 0] == 0.0]
    assert len(on_axis) and not np.signbit(on_axis[:, 0]).any()
