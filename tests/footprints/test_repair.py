"""Geometry checks and repairs on their own: any ring soup gives a valid oriented polygon or a reason."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from citygen_footprints.repair import FeatureProblem, build_polygon, clean_rings


def _closed(points):
    points = np.asarray(points, dtype=float)
    return np.vstack([points, points[:1]])


rings = st.lists(st.tuples(st.integers(-20, 20), st.integers(-20, 20)), min_size=3, max_size=9)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(rings, min_size=1, max_size=3))
def test_any_rings_give_a_valid_oriented_polygon_or_a_reason(ring_list):
    try:
        cleaned = clean_rings([[[list(map(float, p)) for p in r]] for r in ring_list])
        polygon, _ = build_polygon(cleaned.parts, min_area=1.0, min_part_area=1.0, repair_ratio=0.9)
    except FeatureProblem as problem:
        assert " -- " in str(problem)
        return
    assert polygon.is_valid and polygon.area >= 1.0
    for part in getattr(polygon, "geoms", [polygon]):
        assert part.exterior.is_ccw and all(not hole.is_ccw for hole in part.interiors)


def test_a_bow_tie_whose_kept_part_is_under_min_area_is_a_sliver():
    """Regression (found by the property test above): a self-crossing ring of 1.25 m² repaired into two parts under
    min_part_area kept the larger, 0.75 m², under min_area."""
    cleaned = clean_rings([[[[0.0, 0.0], [0.0, -1.0], [2.0, 3.0], [1.0, 0.0]]]])
    with pytest.raises(FeatureProblem, match="area 0.75 m² is below min_area = 1 m² once its parts smaller than 1 m² "
                                             "are dropped"):
        build_polygon(cleaned.parts, min_area=1.0, min_part_area=1.0, repair_ratio=0.9)


def test_parts_whose_union_floating_point_leaves_with_nested_shells_give_a_valid_polygon():
    """Regression (found by the property test above): three self-crossing rings repaired into parts whose union
    ended a sliver 1e-16 m off the large part's edge, an invalid MultiPolygon ("nested shells")."""
    ring_list = [[(0, 0), (0, 1), (1, 3)], [(0, 6), (0, 0), (0, -1), (1, 0), (-3, -3)],
                 [(0, 6), (-4, 3), (0, -4), (0, 0), (-3, -3)]]
    cleaned = clean_rings([[[list(map(float, p)) for p in r]] for r in ring_list])
    polygon, _ = build_polygon(cleaned.parts, min_area=1.0, min_part_area=1.0, repair_ratio=0.9)
    assert polygon.is_valid and polygon.area == pytest.approx(22.336, abs=1e-3)


def test_clockwise_input_is_reoriented():
    polygon, notes = build_polygon([[_closed([(0, 0), (0, 10), (10, 10), (10, 0)])]], 1.0, 1.0, 0.9)
    assert polygon.exterior.is_ccw and notes == ()


def test_hole_is_clockwise():
    shell = _closed([(0, 0), (10, 0), (10, 10), (0, 10)])
    hole = _closed([(2, 2), (4, 2), (4, 4), (2, 4)])  # given counter-clockwise
    polygon, _ = build_polygon([[shell, hole]], 1.0, 1.0, 0.9)
    assert not polygon.interiors[0].is_ccw and polygon.area == 96


def test_repeated_vertices_are_dropped_silently():
    cleaned = clean_rings([[[[0, 0], [0, 0], [10, 0], [10, 10], [10, 10], [0, 10], [0, 0]]]])
    assert len(cleaned.parts[0][0]) == 5 and cleaned.warnings == ()


def test_spike_is_cut_off():
    # a zero-width spike out of a square: make_valid keeps the square
    ring = _closed([(0, 0), (10, 0), (10, 5), (20, 5), (10, 5), (10, 10), (0, 10)])
    polygon, notes = build_polygon([[ring]], 1.0, 1.0, 0.9)
    assert polygon.area == pytest.approx(100) and "repaired" in notes[0]


def test_repair_ratio_is_an_option():
    star = _closed([(10 * np.cos(a), 10 * np.sin(a)) for a in np.pi / 2 + np.arange(5) * 4 * np.pi / 5])
    with pytest.raises(FeatureProblem, match="keeps only 69%"):
        build_polygon([[star]], 1.0, 1.0, 0.9)
    polygon, _ = build_polygon([[star]], 1.0, 1.0, 0.5)
    assert polygon.area == pytest.approx(0.528 * 146.95, rel=0.01)
