"""§4 element matching (mueller2007 Eq. 7/8): the rendered library and the region type by mutual information."""
from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from citygen.geometry.prototypes import ProtoKey
from citygen_photo.photo import analyse
from citygen_photo.elements import cluster_type, context, library, render
from citygen_photo.tiles import EdgeImage, Node, _element_labels, match_elements
from tests.photo.synthetic import facade

LABELS = ("window", "door", "shop", "wall")


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


@pytest.mark.parametrize("name", ["window_14x20", "window_shutters_10x15", "window_24x10", "door_10x22",
                                  "door_double_16x22", "door_fanlight_10x27", "shop_40x26"])
def test_eq7_region_rendered_from_an_element_is_matched_to_it(name):
    """Among the elements the pipeline compares for such a region (a window anywhere, a door or shop front on the
    ground): doors and windows share the opening prototype's structure, so their position decides between them."""
    e = element(name)
    labels = ("window", "wall") if e.label == "window" else ("door", "shop", "wall")
    h = 60
    w = int(round(h / e.aspect))
    gray = wall()
    rect = (60, 60 + h, 100, 100 + w)
    paste(gray, name, rect)
    best, score = cluster_type(gray, [rect], labels)
    assert best.name == name and score > 0.3


def test_eq8_cluster_vote_overrides_a_noisy_region():
    """Five regions show a plain door, one of them (noise: a door with a fanlight pasted in its place) looks like
    the fanlight door: Eq. 7 gives that region the fanlight door, Eq. 8 gives the whole cluster the plain door,
    and :func:`match_elements` labels a leaf by its members (two tiles: a plausible door)."""
    gray = wall((240, 600))
    rects = [(100, 190, 20 + 110 * k, 60 + 110 * k) for k in range(5)]
    for k, rect in enumerate(rects):
        paste(gray, "door_10x22", rect, seed=k)
    paste(gray, "door_fanlight_10x27", rects[2], seed=9)
    labels = ("door", "shop", "wall")
    assert cluster_type(gray, [rects[2]], labels)[0].name == "door_fanlight_10x27"
    assert all(cluster_type(gray, [r], labels)[0].name == "door_10x22" for k, r in enumerate(rects) if k != 2)
    assert cluster_type(gray, rects, labels)[0].name == "door_10x22"
    tiles = tuple((0, 190, 110 * k, 110 * (k + 1)) for k in range(2))
    for members in ([0, 1], [3, 4]):
        tree = Node(tiles, None, (Node(tuple((0, 100, c0, c1) for _, _, c0, c1 in tiles), "wall"),
                                  Node(tuple(rects[k] for k in members), "door")))
        matched = match_elements(EdgeImage.of(gray), tree)
        assert (matched.children[1].label, matched.children[1].element) == ("door", "door_10x22")
        assert matched.children[0].element is None


def test_eq7_clear_match_and_plain_wall():
    gray = wall()
    assert cluster_type(gray, [(60, 120, 100, 140)], LABELS)[0].label == "wall"


def test_element_labels_follow_the_contrast_prior():
    """A region the contrast test took for a door is a door only when plausible (at least ``DOOR_ASPECT`` high,
    group of at most ``MAX_DOORS`` tiles), else a shop front; any other element a window."""
    tile = (0, 80, 0, 50)
    door = Node(((20, 80, 10, 40),), "door")
    assert _element_labels(door, (tile,) * 2) == ("door", "shop")  # 60 x 30
    assert _element_labels(door, (tile,) * 3) == ("shop",)
    assert _element_labels(Node(((50, 80, 10, 40),), "door"), (tile,)) == ("shop",)  # 30 x 30: too low
    assert _element_labels(Node(((20, 80, 10, 40),), "window"), (tile,)) == ("window",)


def test_matched_elements_are_carried_into_the_layout():
    image, truth, door = facade(ground_h=80)
    result = analyse(image)
    windows = [r for r in result.layout.terminals() if r.label == "window"]
    assert len(windows) == len(truth)
    allowed = {(e.depth, e.material) for e in library() if e.label == "window"}
    assert all((r.depth, r.material) in allowed for r in windows) and windows[0].depth == -0.22
    doors = [r for r in result.layout.terminals() if r.label == "door"]
    assert len(doors) == 1 and (doors[0].depth, doors[0].material) == (-0.28, "door_wood")
