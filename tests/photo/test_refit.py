"""The layout carries the full-resolution window boxes (``photo_refit.carry``) and stays a partition."""
from __future__ import annotations

import pytest

from citygen.layout import FacadeLayout, Region, check_partition
from citygen_photo.photo import analyse
from citygen_photo.refit import at, carry
from citygen_photo.score import layout_boxes
from tests.photo.synthetic import facade

#: Window edges between work pixels: a 1015 x 1026 crop is reduced 2.57 times (no edge on the work grid).
OFF_GRID = dict(floors=5, cols=6, floor_h=203, tile_w=171, win=(101, 73), off=(47, 49), seed=4)
EPS = 1e-9


def by_position(boxes):
    return sorted(boxes, key=lambda b: (round(b[1]), b[0]))


def test_layout_window_terminals_carry_the_refined_boxes():
    """Regression: the layout kept the window terminals at the work image's resolution (4.9 crop px off the
    truth on this facade, 0 for the refined element boxes): users got worse boxes than the evaluated ones."""
    image, truth, _ = facade(**OFF_GRID)
    result = analyse(image)
    layout = result.layout
    assert check_partition(layout) == []
    m = layout.meta["metres_per_pixel"]
    windows = sorted((r for r in layout.leaves if r.label == "window"), key=lambda r: (-r.y, r.x))
    assert len(windows) == len(truth)
    for r, (x0, y0, x1, y1) in zip(windows, by_position(truth)):
        want = (x0 * m, layout.height - y1 * m, x1 * m, layout.height - y0 * m)  # metres, y up
        got = (r.x, r.y, r.x + r.w, r.y + r.h)
        assert all(abs(g - w) <= 1.0 * m for g, w in zip(got, want)), (got, want)
    assert layout.meta["refined_sides"] == {"moved": 120, "refined": 120}


def test_layout_windows_equal_the_refined_element_boxes():
    image, _, _ = facade(**OFF_GRID)
    result = analyse(image)
    for got, want in zip(by_position(layout_boxes(result.layout)), by_position(result.boxes("window"))):
        assert got == pytest.approx(want, abs=1e-6)


def tile(*strips: Region) -> Region:
    """Facade -> floor -> tile (depth 2) -> ``strips``, the tile 0..10 x 0..6 m."""
    t = Region(0, 0, 10, 6, "Tile", children=strips)
    return Region(0, 0, 10, 6, "Facade", children=(Region(0, 0, 10, 6, "Floor", children=(t,)),))


def wall(x, y, w, h):
    return Region(x, y, w, h, "Wall", "wall")


def window(x, y, w, h):
    return Region(x, y, w, h, "Window", "window")


def box(r):
    return (r.x, r.y, r.x + r.w, r.y + r.h)


def partition(root):
    return check_partition(FacadeLayout(root.w, root.h, root)) == []


def test_carry_moves_the_walls_of_a_box_split_tile():
    """wall | strip (wall / window / wall) | wall: the side walls absorb the horizontal change, the strip's walls
    the vertical one."""
    root = tile(wall(0, 0, 3, 6), Region(3, 0, 4, 6, "Strip", children=(wall(3, 0, 4, 1), window(3, 1, 4, 3),
                                                                         wall(3, 4, 4, 2))), wall(7, 0, 3, 6))
    path = (0, 0, 1, 1)
    new, moved, wanted = carry(root, [path], (3, 1, 7, 4), (2.6, 1.2, 7.3, 4.5), 2, 0.05, EPS)
    assert (moved, wanted) == (4, 4)
    assert box(at(new, path)) == pytest.approx((2.6, 1.2, 7.3, 4.5))
    assert at(new, (0, 0, 0)).w == pytest.approx(2.6) and at(new, (0, 0, 2)).x == pytest.approx(7.3)
    assert partition(new)


def test_carry_keeps_a_side_that_is_not_on_wall():
    """A side whose line also bounds another element keeps its work-image position: with a door under the window
    in its strip, the bottom line and the strip's left and right lines bound the door; only the top moves. So does
    a side on the tile's boundary."""
    root = tile(wall(0, 0, 3, 6), Region(3, 0, 4, 6, "Strip", children=(Region(3, 0, 4, 1, "Door", "door"),
                                                                         window(3, 1, 4, 3), wall(3, 4, 4, 2))),
                wall(7, 0, 3, 6))
    path = (0, 0, 1, 1)
    new, moved, wanted = carry(root, [path], (3, 1, 7, 4), (2.8, 1.3, 7.2, 4.2), 2, 0.05, EPS)
    assert (moved, wanted) == (1, 4)
    assert box(at(new, path)) == pytest.approx((3, 1, 7, 4.2))
    assert partition(new)
    edge = tile(window(0, 0, 4, 6), wall(4, 0, 6, 6))  # the window's left side is the tile's
    new, moved, _ = carry(edge, [(0, 0, 0)], (0, 0, 4, 6), (0.3, 0, 4.2, 6), 2, 0.05, EPS)
    assert moved == 1 and box(at(new, (0, 0, 0))) == pytest.approx((0, 0, 4.2, 6)) and partition(new)


def test_carry_refuses_a_move_past_the_wall():
    """The wall beside the window must keep ``least`` metres: a refined side beyond it is not carried."""
    root = tile(wall(0, 0, 3, 6), Region(3, 0, 4, 6, "Strip", children=(wall(3, 0, 4, 1), window(3, 1, 4, 3),
                                                                         wall(3, 4, 4, 2))), wall(7, 0, 3, 6))
    new, moved, wanted = carry(root, [(0, 0, 1, 1)], (3, 1, 7, 4), (0.02, 1, 7, 4), 2, 0.05, EPS)
    assert (moved, wanted) == (0, 1) and new == root


def test_carry_moves_a_window_of_two_terminals_together():
    """A window split at its mullion (window | wall | window in one element region) is one element box: its top
    moves both terminals and the mullion; its left side only the left terminal."""
    element = Region(2, 1, 6, 3, "Element", children=(window(2, 1, 2.5, 3), wall(4.5, 1, 1, 3), window(5.5, 1, 2.5, 3)))
    root = tile(wall(0, 0, 2, 6), Region(2, 0, 6, 6, "Strip", children=(wall(2, 0, 6, 1), element, wall(2, 4, 6, 2))),
                wall(8, 0, 2, 6))
    members = [(0, 0, 1, 1, 0), (0, 0, 1, 1, 2)]
    new, moved, wanted = carry(root, members, (2, 1, 8, 4), (1.7, 1, 8, 4.4), 2, 0.05, EPS)
    assert (moved, wanted) == (2, 2)
    assert box(at(new, members[0])) == pytest.approx((1.7, 1, 4.5, 4.4))
    assert box(at(new, members[1])) == pytest.approx((5.5, 1, 8, 4.4))
    assert at(new, (0, 0, 1, 1, 1)).h == pytest.approx(3.4) and partition(new)
