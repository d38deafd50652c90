"""§4 element matching (mueller2007 Eq. 7/8): the rendered library and the region type by mutual information."""
from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from citygen.geometry.prototypes import ProtoKey
from citygen_inverse.photo import analyse
from citygen_inverse.photo_elements import cluster_type, context, library, render
from citygen_inverse.photo_tiles import EdgeImage, Node, _element_labels, match_elements
from tests.photo.synthetic import facade

LABELS = ("window", "balcony", "door", "shop", "wall")


def element(name: str):
    return next(e for e in library() if e.name == name)


def paste(gray: np.ndarray, name: str, rect: tuple[int, int, int, int], seed: int = 0) -> None:
    """Draw library element ``name`` (with its wall margin, plus noise) so that its box is ``rect``."""
    (g0, g1, h0, h1), _ = context(rect, gray.shape)
    view = element(name).view.astype(np.float32)
    resized = np.asarray(Image.fromarray(view).resize((h1 - h0, g1 - g0), Image.Resampling.BILINEAR))
    gray[g0:g1, h0:h1] = resized + 0.03 * np.random.default_rng(seed).standard_normal(resized.shape)


def wall(shape=(200, 400), seed=1) -> np.ndarray:
    return 0.7 + 0.03 * np.random.default_rng(seed).standard_normal(shape)


def test_library_renders_are_deterministic_and_not_empty():
    lib = library()
    assert {e.label for e in lib} == set(LABELS)
    assert len({e.name for e in lib}) == len(lib)
    for e in lib[:-1]:
        assert e.view.ndim == 2 and min(e.view.shape) >= 30 and np.isfinite(e.view).all()
        assert np.unique(np.round(e.view, 3)).size >= 3, e.name  # wall, frame and glass / leaf at least
    assert np.ptp(lib[-1].view) == 0  # the wall renders flat: its MI is 0
    parts = [(ProtoKey("window", "frame_white", 14, 20, -22), 0.0, 0.0)]
    assert np.array_equal(render(parts, (1.4, 2.0)), render(parts, (1.4, 2.0)))
    assert np.array_equal(render(parts, (1.4, 2.0)), element("window_14x20").view)


def test_rendered_window_shows_frame_glass_mullion_and_wall():
    view = element("window_14x20").view  # 1.4 m wide: a mullion; 2.0 m high: a transom at 0.7 h
    rows, cols = view.shape
    wall_value = view[1, 1]
    middle = view[rows // 2]
    assert middle[0] == wall_value and middle[cols // 2] != middle[cols // 4]  # the mullion crosses the glass
    assert view[rows // 2, cols // 4] < wall_value  # recessed glass is darker than the wall


@pytest.mark.parametrize("name", ["window_14x20", "window_shutters_10x15", "balcony_10x22", "door_16x25",
                                  "shop_40x26"])
def test_eq7_region_rendered_from_an_element_is_matched_to_it(name):
    e = element(name)
    h = 60
    w = int(round(h / e.aspect))
    gray = wall()
    rect = (60, 60 + h, 100, 100 + w)
    paste(gray, name, rect)
    best, score = cluster_type(gray, [rect], LABELS)
    assert best.name == name and score > 0.3


def test_eq7_plain_wall_is_wall():
    best, score = cluster_type(wall(), [(60, 120, 100, 140)], LABELS)
    assert best.label == "wall" and score == 0.0


def test_eq8_cluster_vote_overrides_a_noisy_region():
    """Four regions show a door, one (noise, a shop front pasted in its place) looks like a shop: Eq. 7 gives that
    region the shop, Eq. 8 gives the whole cluster the door."""
    gray = wall((200, 600))
    rects = [(60, 150, 20 + 110 * k, 60 + 110 * k) for k in range(5)]
    for k, rect in enumerate(rects):
        paste(gray, "door_9x21", rect, seed=k)
    paste(gray, "shop_25x22", rects[2], seed=9)
    assert cluster_type(gray, [rects[2]], LABELS)[0].label == "shop"
    assert cluster_type(gray, rects[:2], LABELS)[0].label == "door"
    assert cluster_type(gray, rects, LABELS)[0].label == "door"
    # match_elements applies Eq. 8 to the leaf's members: one label for all five
    tiles = tuple((0, 200, 110 * k, 110 * (k + 1)) for k in range(5))
    leaf = Node(tuple(rects), "window")
    tree = Node(tiles, None, (Node(tuple((0, 60, c0, c1) for _, _, c0, c1 in tiles), "wall"), leaf))
    matched = match_elements(EdgeImage.of(gray), tree, ground=False)
    assert matched.children[1].label == "window"  # above the ground floor a door is not a candidate
    assert matched.children[1].element is not None and matched.children[0].element is None


def test_element_labels_follow_the_position_in_the_tile():
    """A region touching its tile's sides is no element; on the ground floor's bottom edge it is a door only when
    plausible (at least ``DOOR_ASPECT`` high, group of at most ``MAX_DOORS`` tiles), else a shop front."""
    tile = (0, 80, 0, 50)
    door = Node(((20, 80, 10, 40),))
    assert _element_labels(door, (tile,) * 2, ground=True) == ("door", "shop", "wall")
    assert _element_labels(door, (tile,) * 3, ground=True) == ("shop", "wall")
    assert _element_labels(door, (tile,), ground=False) == ()
    low = Node(((50, 80, 10, 40),))  # 30 x 30: too low for a door
    assert _element_labels(low, (tile,), ground=True) == ("shop", "wall")
    assert _element_labels(Node(((10, 40, 10, 40),)), (tile,), ground=False) == ("window", "balcony", "wall")
    assert _element_labels(Node(((10, 40, 0, 40),)), (tile,), ground=False) == ()
    assert _element_labels(Node(((10, 14, 10, 14),)), (tile,), ground=False) == ()  # under MIN_AREA


def test_matched_elements_are_carried_into_the_layout():
    image, truth, door = facade(ground_h=90)
    result = analyse(image)
    windows = [r for r in result.layout.terminals() if r.label == "window"]
    assert len(windows) == len(truth)
    allowed = {(e.depth, e.material) for e in library() if e.label == "window"}
    assert all((r.depth, r.material) in allowed for r in windows) and windows[0].depth == -0.22
    doors = [r for r in result.layout.terminals() if r.label == "door"]
    assert len(doors) == 1 and (doors[0].depth, doors[0].material) == (-0.28, "door_wood")
