"""Roofs of round towers: the onion dome (the outline scaled about its centroid, out past the walls and in to a
point) and the cone."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import Point, Polygon, box
from shapely.geometry.polygon import orient

from citygen.roof import RoofSpec
from citygen_roofs.onion import ONION_BANDS, ONION_HEIGHT, OnionRoof, onion_profile
from citygen_roofs.pitched import ConeRoof, DomeRoof, PyramidalRoof
from tests.roofs.shapes import outlines
from tests.roofs.test_builders import TOP, _normals, _open_edges, _outline_edges, _same_edges, _triangles


def _closed_on(mesh, outline):
    edges, z = _open_edges(mesh)
    return _same_edges(edges, _outline_edges(orient(outline, 1.0))) and np.allclose(z, TOP, atol=1e-4)


def test_onion_over_a_round_tower_bulges_past_the_walls_and_ends_in_a_point():
    """Worked example: a 16-gon of circumradius 4 m. Its centroid is 4 cos(pi/16) = 3.92 m from every wall, so the
    bulb is 3 x 3.92 = 11.77 m high; its widest ring is the outline scaled by the profile's widest scale."""
    tower = Point(0, 0).buffer(4.0, 4)
    mesh = OnionRoof().build(tower, TOP, RoofSpec("onion", cap=20.0))
    p, tris = _triangles(mesh)
    assert len(tris) == 16 * (2 * (ONION_BANDS - 1) + 1) and _closed_on(mesh, tower)
    run = 4.0 * math.cos(math.pi / 16)
    top = p[np.argmax(p[:, 2])]
    assert top == pytest.approx([0.0, 0.0, TOP + ONION_HEIGHT * run], abs=1e-4)
    levels, scales = onion_profile()
    assert np.hypot(p[:, 0], p[:, 1]).max() == pytest.approx(4.0 * scales.max(), rel=1e-5)
    assert np.unique(p[:, 2].round(4)) == pytest.approx(TOP + ONION_HEIGHT * run * levels, abs=1e-4)
    n = _normals(p, tris)
    assert n[:, 2].sum() / 2 == pytest.approx(tower.area, rel=1e-5)  # projected once, net of the overhang
    assert (n[:, 2] < 0).sum() == 16 * 2 * int(np.argmax(scales))  # the bulb's underside, below its widest ring
    volume = np.einsum("ij,ij->i", p[tris[:, 0]] - [0, 0, TOP], n).sum() / 6  # closed by the wall top: outward
    assert volume > 0


def test_onion_height_follows_roof_height_and_the_cap():
    tower = Point(0, 0).buffer(4.0, 4)
    tall = _triangles(OnionRoof().build(tower, TOP, RoofSpec("onion", height=6.0, cap=20.0)))[0]
    capped = _triangles(OnionRoof().build(tower, TOP, RoofSpec("onion", cap=5.0)))[0]
    assert tall[:, 2].max() == pytest.approx(TOP + 6.0) and capped[:, 2].max() == pytest.approx(TOP + 5.0)


@pytest.mark.parametrize("outline, party", [
    (Polygon([(0, 0), (12, 0), (12, 10), (8, 10), (8, 4), (4, 4), (4, 10), (0, 10)]), ()),  # a U: not star-shaped
    (box(0, 0, 12, 12).difference(box(4, 4, 8, 8)), ()),  # a courtyard
    (Point(0, 0).buffer(4.0, 4), (0, 1, 2)),  # party walls: the bulb would lean over the neighbour
])
def test_onion_that_cannot_stand_is_the_dome(outline, party):
    spec = RoofSpec("onion", cap=20.0, party=party)
    onion, dome = OnionRoof().build(outline, TOP, spec), DomeRoof().build(outline, TOP, spec)
    assert np.array_equal(onion.points, dome.points) and np.array_equal(onion.indices, dome.indices)


@settings(max_examples=40, deadline=None)
@given(outlines, st.floats(2.0, 30.0))
def test_onion_roofs_close_the_walls(outline, cap):
    """Property: on any outline (star-shaped or not, courtyards, several parts) the roof is closed on the outline
    at the wall top and stays within the cap."""
    mesh = OnionRoof().build(outline, TOP, RoofSpec("onion", cap=cap))
    p, tris = _triangles(mesh)
    edges, z = _open_edges(mesh)
    assert _same_edges(edges, _outline_edges(outline)) and np.allclose(z, TOP, atol=1e-4)
    assert p[:, 2].min() >= TOP - 1e-4 and p[:, 2].max() <= TOP + cap + 1e-3
    assert _normals(p, tris)[:, 2].sum() / 2 == pytest.approx(outline.area, rel=1e-5)


def test_cone_is_the_pyramidal_roof_over_a_round_tower():
    """OSM tags round towers ``roof:shape=cone``: one apex over the centroid, at the pitch."""
    tower = Point(0, 0).buffer(4.0, 4)
    cone = ConeRoof().build(tower, TOP, RoofSpec("cone", 40.0))
    pyramid = PyramidalRoof().build(tower, TOP, RoofSpec("pyramidal", 40.0))
    assert np.array_equal(cone.points, pyramid.points) and np.array_equal(cone.indices, pyramid.indices)
    p, _ = _triangles(cone)
    assert p[:, 2].max() == pytest.approx(TOP + 4.0 * math.cos(math.pi / 16) * math.tan(math.radians(40.0)), rel=1e-5)
