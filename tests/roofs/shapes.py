"""Hypothesis strategies for roof outlines: random simple polygons, L/U shapes and rectangles with courtyards,
cleaned like the pipeline cleans a mass outline."""
from __future__ import annotations

import math

from hypothesis import strategies as st
from shapely import affinity
from shapely.geometry import MultiPolygon, Polygon, box

from citygen.mass import clean_outline

dims = st.floats(4.0, 40.0)
turns = st.floats(0.0, 360.0)


def _placed(poly: Polygon, angle: float) -> Polygon:
    return clean_outline(affinity.rotate(poly, angle, origin=(0, 0)))


@st.composite
def star_polygons(draw) -> Polygon:
    """A random simple polygon: 3-12 vertices star-shaped around the origin (often concave)."""
    n = draw(st.integers(3, 12))
    gaps = draw(st.lists(st.floats(0.3, 1.0), min_size=n, max_size=n))
    radii = draw(st.lists(st.floats(5.0, 25.0), min_size=n, max_size=n))
    total, acc, pts = sum(gaps), 0.0, []
    for gap, r in zip(gaps, radii):
        acc += gap
        a = 2 * math.pi * acc / total
        pts.append((r * math.cos(a), r * math.sin(a)))
    return _placed(Polygon(pts), 0.0)


@st.composite
def l_u_shapes(draw) -> Polygon:
    """An L (one arm) or U (two arms) shaped block, rotated."""
    w, d, arm, depth = draw(dims), draw(dims), draw(st.floats(3.0, 12.0)), draw(st.floats(3.0, 25.0))
    body = box(0, 0, w + 2 * arm, d)
    arms = [box(0, d, arm, d + depth)]
    if draw(st.booleans()):
        arms.append(box(w + arm, d, w + 2 * arm, d + depth))
    shape = body.union(arms[0]) if len(arms) == 1 else body.union(arms[0]).union(arms[1])
    return _placed(Polygon(shape.exterior), draw(turns))


@st.composite
def courtyards(draw) -> Polygon:
    """A rectangle with a rectangular courtyard at least 2 m from every side, rotated."""
    w, d = draw(st.floats(12.0, 60.0)), draw(st.floats(12.0, 60.0))
    x0, y0 = draw(st.floats(2.0, w / 2 - 2.0)), draw(st.floats(2.0, d / 2 - 2.0))
    x1, y1 = draw(st.floats(w / 2 + 2.0, w - 2.0)), draw(st.floats(d / 2 + 2.0, d - 2.0))
    return _placed(box(0, 0, w, d).difference(box(x0, y0, x1, y1)), draw(turns))


@st.composite
def multipolygons(draw) -> MultiPolygon:
    """Two of the shapes above side by side, as one building."""
    first, second = draw(st.one_of(star_polygons(), l_u_shapes())), draw(st.one_of(star_polygons(), courtyards()))
    shift = first.bounds[2] - second.bounds[0] + draw(st.floats(1.0, 10.0))
    return MultiPolygon([first, affinity.translate(second, xoff=shift)])


polygons = st.one_of(star_polygons(), l_u_shapes(), courtyards())
outlines = st.one_of(polygons, multipolygons())
