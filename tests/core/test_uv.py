"""Texture coordinates in metres, each polygon mapped onto its own plane (citygen.usd.uv)."""
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from citygen.usd.uv import planar_st


def test_a_wall_quad_maps_to_its_width_and_height_seen_from_outside():
    # a 4 x 3 m wall at y = 0 facing -y (counter-clockwise seen from -y): u runs along +x, v up
    points = np.array([[0, 0, 0], [4, 0, 0], [4, 0, 3], [0, 0, 3]], float)
    uv = planar_st(points, np.array([4]), np.array([0, 1, 2, 3]))
    assert np.allclose(uv - uv[0], [[0, 0], [4, 0], [4, 3], [0, 3]])


def test_a_roof_slope_maps_to_its_true_length_up_the_slope():
    run, pitch = 5.0, 30.0
    rise = run * math.tan(math.radians(pitch))
    points = np.array([[0, 0, 0], [10, 0, 0], [10, run, rise], [0, run, rise]], float)
    uv = planar_st(points, np.array([4]), np.array([0, 1, 2, 3]))
    assert np.allclose(uv - uv[0], [[0, 0], [10, 0], [10, math.hypot(run, rise)], [0, math.hypot(run, rise)]],
                       atol=1e-5)


def test_a_flat_roof_maps_to_x_and_y_and_shared_corners_get_a_value_per_face():
    # a box corner: the top (flat) and a side wall share two points but not their texture coordinates
    points = np.array([[0, 0, 3], [2, 0, 3], [2, 1, 3], [0, 1, 3], [0, 0, 0], [2, 0, 0]], float)
    counts = np.array([4, 4])
    indices = np.array([0, 1, 2, 3, 4, 5, 1, 0])
    uv = planar_st(points, counts, indices)
    assert np.allclose(uv[:4] - uv[0], [[0, 0], [2, 0], [2, 1], [0, 1]])
    assert np.allclose(uv[4:] - uv[4], [[0, 0], [2, 0], [2, 3], [0, 3]])
    assert len(uv) == len(indices) and uv.dtype == np.float32


@settings(max_examples=50)
@given(st.floats(0, 2 * math.pi), st.floats(-80, 80), st.floats(0.5, 30), st.floats(0.5, 30))
def test_every_rectangle_keeps_its_edge_lengths(yaw, tilt, w, h):
    """A w x h rectangle in any orientation maps to a w x h rectangle (the map is an isometry of its plane)."""
    a, t = yaw, math.radians(tilt)
    along = np.array([math.cos(a), math.sin(a), 0.0])
    up = np.array([-math.sin(a) * math.sin(t), math.cos(a) * math.sin(t), math.cos(t)])
    points = np.array([np.zeros(3), w * along, w * along + h * up, h * up]) + [100.0, -50.0, 7.0]
    uv = planar_st(points, np.array([4]), np.arange(4)).astype(float)
    sides = np.linalg.norm(np.roll(uv, -1, axis=0) - uv, axis=1)
    assert sides == pytest.approx([w, h, w, h], rel=1e-4, abs=1e-3)
