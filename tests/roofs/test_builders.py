import math
from collections import Counter

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import MultiPolygon, Polygon, box

from citygen.roof import RoofSpec
from citygen_roofs.pitched import HippedRoof, GabledRoof, PyramidalRoof, RoofError, SkillionRoof, hip_faces
from citygen_roofs.plugin import FlatRoof
from tests.roofs.shapes import outlines

TOP = 12.0
BUILDERS = [HippedRoof(), GabledRoof(), PyramidalRoof(), SkillionRoof(), FlatRoof()]


def _triangles(mesh):
    assert np.all(mesh.counts == 3)
    return mesh.points.astype(float), mesh.indices.reshape(-1, 3)


def _normals(p, tris):
    return np.cross(p[tris[:, 1]] - p[tris[:, 0]], p[tris[:, 2]] - p[tris[:, 0]])


def _outline_edges(outline):
    parts = outline.geoms if isinstance(outline, MultiPolygon) else [outline]
    edges = []
    for part in parts:
        for ring in (part.exterior, *part.interiors):
            c = np.asarray(ring.coords)[:, :2]
            edges += [np.r_[a, b] for a, b in zip(c[:-1], c[1:])]
    return np.array(edges)


def _open_edges(mesh):
    """Directed edges of the mesh used once with no twin (its boundary) as rows x0 y0 x1 y1, and their z."""
    p, tris = _triangles(mesh)
    directed = Counter((int(a), int(b)) for t in tris for a, b in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0])))
    assert max(directed.values()) == 1, "an edge is used twice in the same direction (non-manifold or flipped)"
    loose = [(a, b) for a, b in directed if (b, a) not in directed]
    return np.array([np.r_[p[a, :2], p[b, :2]] for a, b in loose]), np.array([p[[a, b], 2] for a, b in loose])


def _same_edges(found, expected):
    """Every expected edge is found once (within a millimetre: mesh points are float32) and nothing else."""
    gap = np.abs(found[:, None, :] - expected[None, :, :]).max(axis=2)
    return len(found) == len(expected) and np.all(gap.min(axis=0) < 1e-3) and np.all(gap.min(axis=1) < 1e-3)


def test_hipped_rectangle_worked_example():
    length, width, pitch = 20.0, 8.0, 35.0
    mesh = HippedRoof().build(box(0, 0, length, width), TOP, RoofSpec("hipped", pitch))
    p, tris = _triangles(mesh)
    ridge = p[np.isclose(p[:, 2], TOP + width / 2 * math.tan(math.radians(pitch)))]
    assert len(ridge) == 2 and np.ptp(ridge[:, 0]) == pytest.approx(length - width)
    points, faces = hip_faces(box(0, 0, length, width), TOP, RoofSpec("hipped", pitch))
    assert len(faces) == 4


def test_gabled_rectangle_ridge_spans_the_length_and_gables_are_vertical():
    length, width = 20.0, 8.0
    mesh = GabledRoof().build(box(0, 0, length, width), TOP, RoofSpec("gabled", 30.0))
    p, tris = _triangles(mesh)
    height = TOP + width / 2 * math.tan(math.radians(30))
    ridge = p[np.isclose(p[:, 2], height)]
    assert len(ridge) == 2 and np.allclose(ridge[:, 1], width / 2) and np.ptp(ridge[:, 0]) == pytest.approx(length)
    n = _normals(p, tris)
    walls = n[np.isclose(n[:, 2], 0)]
    assert len(walls) == 2 and sorted(np.sign(walls[:, 0])) == [-1, 1]  # one gable at each end, facing out


def test_pyramidal_square_apex_over_the_centroid():
    mesh = PyramidalRoof().build(box(2, 3, 12, 13), TOP, RoofSpec("pyramidal", 45.0))
    p, _ = _triangles(mesh)
    apex = p[np.argmax(p[:, 2])]
    assert np.allclose(apex, [7, 8, TOP + 5])


def test_roof_height_wins_over_pitch_and_is_capped():
    mesh = HippedRoof().build(box(0, 0, 20, 10), TOP, RoofSpec("hipped", 30.0, height=2.0))
    assert mesh.points[:, 2].max() == pytest.approx(TOP + 2.0)
    mesh = HippedRoof().build(box(0, 0, 20, 10), TOP, RoofSpec("hipped", 75.0, cap=4.0))
    assert mesh.points[:, 2].max() == pytest.approx(TOP + 4.0)


def test_skillion_falls_towards_its_direction():
    mesh = SkillionRoof().build(box(0, 0, 10, 6), TOP, RoofSpec("skillion", 30.0, direction=90.0))  # faces east
    p, _ = _triangles(mesh)
    assert p[p[:, 0] == 0, 2].max() == pytest.approx(TOP + 10 * math.tan(math.radians(30)), rel=1e-5)
    assert np.allclose(p[p[:, 0] == 10, 2], TOP)


def test_self_intersecting_outline_raises_roof_error():
    with pytest.raises(RoofError):
        GabledRoof().build(Polygon([(0, 0), (10, 10), (10, 0), (0, 10)]), TOP, RoofSpec("gabled"))


@settings(max_examples=40)
@given(outlines, st.sampled_from(BUILDERS), st.floats(10.0, 60.0), st.one_of(st.none(), st.floats(0.0, 359.0)))
def test_roofs_cover_the_outline_and_close_the_walls(outline, builder, pitch, direction):
    spec = RoofSpec(builder.id, pitch, direction=direction, cap=15.0)
    mesh = builder.build(outline, TOP, spec)
    p, tris = _triangles(mesh)
    n = _normals(p, tris)
    assert np.all(n[:, 2] >= -1e-4 * np.linalg.norm(n, axis=1)), "a roof face points down"
    assert n[:, 2].sum() / 2 == pytest.approx(outline.area, rel=1e-6)  # the projection covers the outline once
    assert np.all(p[:, 2] >= TOP - 1e-4) and np.all(p[:, 2] <= TOP + 15.0 + 1e-4)
    edges, z = _open_edges(mesh)
    assert _same_edges(edges, _outline_edges(outline)) and np.allclose(z, TOP, atol=1e-4)  # eaves = wall tops, no gaps


@settings(max_examples=40)
@given(outlines, st.floats(10.0, 60.0))
def test_hipped_faces_are_planes_at_the_pitch(outline, pitch):
    points, faces = hip_faces(outline, TOP, RoofSpec("hipped", pitch))
    slope = math.tan(math.radians(pitch))
    for face in faces:
        a, b = points[face[0], :2], points[face[1], :2]
        d = (b - a) / np.hypot(*(b - a))
        inward = (points[face, :2] - a) @ np.array([-d[1], d[0]])
        assert np.allclose(points[face, 2], TOP + inward * slope, atol=1e-6)
