"""The learned facade parser and the regular structure found in its probabilities (citygen_photo.regular,
.learned): synthetic probability maps with known floors, tiles, shops and a door; the shipped model on a synthetic
photo; the CLI's --labels and --png pictures."""
from __future__ import annotations

import numpy as np
import pytest

from citygen.layout import check_partition
from citygen_photo.labels import CMP_LABELS
from citygen_photo.regular import DOOR, SHOP, WINDOW, _fitted, facade_layout, regular_facade
from tests.photo.synthetic import facade


def probabilities(floors: int = 4, cols: int = 5, floor_h: int = 30, tile_w: int = 24, win=(14, 10),
                  ground_h: int = 0, shop: bool = False, miss: tuple[tuple[int, int], ...] = (),
                  jitter: float = 0.0, seed: int = 0) -> np.ndarray:
    """Label probabilities of a regular facade: windows ``win`` (h, w) in a grid, wall elsewhere; a ground floor
    with a shop front and a door; ``miss`` windows the parser 'missed'; window sizes jittered by ``jitter``."""
    rng = np.random.default_rng(seed)
    h, w = floors * floor_h + ground_h, cols * tile_w
    prob = np.zeros((h, w, len(CMP_LABELS)))
    prob[..., CMP_LABELS.index("facade")] = 1.0
    for i in range(floors):
        for j in range(cols):
            if (i, j) in miss:
                continue
            dh, dw = (rng.integers(-1, 2, size=2) * jitter).astype(int)
            r0, c0 = i * floor_h + 8, j * tile_w + 7
            prob[r0:r0 + win[0] + dh, c0:c0 + win[1] + dw] = np.eye(len(CMP_LABELS))[WINDOW]
    if ground_h:
        top = floors * floor_h
        if shop:
            prob[top + 6:, 4:40] = np.eye(len(CMP_LABELS))[SHOP]
        prob[top + 4:, 50:60] = np.eye(len(CMP_LABELS))[DOOR]
    return prob


def test_floors_tiles_and_one_window_size():
    facade_ = regular_facade(probabilities(jitter=1.0))
    assert len(facade_.floor_lines) - 1 == 4 and len(facade_.tile_lines) - 1 == 5
    windows = [b for b, label in facade_.elements if label == "window"]
    assert len(windows) == 20
    sizes = {(round(b[2] - b[0], 6), round(b[3] - b[1], 6)) for b in windows}
    assert len(sizes) == 1  # synchronised: one window size for the whole regular facade
    assert facade_.pitch == pytest.approx(30, abs=1)


def test_a_missed_window_is_voted_out_and_a_missed_row_put_back():
    facade_ = regular_facade(probabilities(floors=5, miss=((2, 0), (2, 1), (2, 2), (2, 3), (2, 4), (0, 3))))
    assert len(facade_.floor_lines) - 1 == 5  # the third floor's whole row was missed: the pitch puts its floor back
    # tiles vote on what the parser saw: the missed row's tiles and the one missed window stay wall
    assert sum(label == "window" for _, label in facade_.elements) == 25 - 5 - 1


def test_ground_floor_with_shop_and_door_keeps_its_own_columns():
    prob = probabilities(ground_h=40, shop=True)
    facade_ = regular_facade(prob)
    assert facade_.ground
    labels = [label for _, label in facade_.elements]
    assert labels.count("door") == 1 and labels.count("shop") == 1
    door = next(b for b, label in facade_.elements if label == "door")
    assert door[3] == prob.shape[0]  # the door stands on the ground
    layout = facade_layout(facade_, prob.shape[0], prob.shape[1], 0.1, {})
    assert check_partition(layout) == []
    ground = layout.root.children[0]
    assert ground.symbol == "Ground" and {r.label for r in ground.terminals()} == {"wall", "shop", "door"}


def test_layout_partitions_in_metres():
    prob = probabilities()
    facade_ = regular_facade(prob)
    layout = facade_layout(facade_, prob.shape[0], prob.shape[1], 0.1, {"source": "synthetic"})
    assert check_partition(layout) == []
    assert layout.width == pytest.approx(12.0) and layout.height == pytest.approx(12.0)
    assert layout.count("window") == 20


def test_the_shipped_parser_finds_windows_on_a_synthetic_photo():
    from citygen_photo.learned import analyse_learned
    rgb, boxes, _ = facade(floors=5, cols=6)
    result = analyse_learned(rgb, "synthetic", floor_height=3.0)
    assert check_partition(result.layout) == []
    assert result.probabilities.shape[-1] == len(CMP_LABELS)
    assert len(result.floor_lines) - 1 == 5
    assert result.layout.count("window") >= 20


def test_cli_writes_the_label_map_and_the_overlay(tmp_path, capsys):
    from PIL import Image

    from citygen.cli import main
    rgb, _, _ = facade(floors=4, cols=5)
    photo = tmp_path / "f.png"
    Image.fromarray(np.round(rgb * 255).astype(np.uint8)).save(photo)
    out, labels, overlay = tmp_path / "f.json", tmp_path / "pics" / "labels.png", tmp_path / "pics" / "over.png"
    assert main(["layout", "from-photo", str(photo), "-o", str(out), "--labels", str(labels),
                 "--png", str(overlay)]) == 0
    with Image.open(labels) as a, Image.open(overlay) as b:
        assert a.size == b.size == (rgb.shape[1], rgb.shape[0])
    assert "windows" in capsys.readouterr().err


def test_an_attic_row_of_few_dormers_is_a_floor():
    """Regression (validation photos cmp_b0264, b0298): a gable's or attic's one or two windows are too few for
    the row mean, and the attic was merged into the floor below."""
    prob = probabilities(floors=4)
    n = len(CMP_LABELS)
    attic = np.zeros((30, prob.shape[1], n))
    attic[..., CMP_LABELS.index("facade")] = 1.0
    attic[8:22, 55:65] = np.eye(n)[WINDOW]  # one dormer in a 120 px wide facade
    facade_ = regular_facade(np.concatenate([attic, prob]))
    assert len(facade_.floor_lines) - 1 == 5
    assert any(box[1] < 30 for box, label in facade_.elements if label == "window")


def test_a_row_of_windows_cut_by_the_crops_top_is_a_floor():
    """Regression (validation cmp_b0274, balcony fold): the crop's top cuts the highest row to a sliver under half a
    window tall where the parser sees one window; an attic run of a quarter of the rows' height is a floor
    (``ATTIC_LEAST``; 0.4 before round 5)."""
    prob = probabilities(floors=4)
    n = len(CMP_LABELS)
    top = np.zeros((12, prob.shape[1], n))
    top[..., CMP_LABELS.index("facade")] = 1.0
    top[2:6, 55:65] = np.eye(n)[WINDOW]  # the lower 4 of a window's 14 rows
    facade_ = regular_facade(np.concatenate([top, prob]))
    assert len(facade_.floor_lines) - 1 == 5 and 6 <= facade_.floor_lines[1] <= 20


def test_shop_windows_are_the_ground_floor_not_a_row_of_windows():
    """A band of shops standing on the ground whose glass the parser also calls window is the ground floor: its
    shop windows are not a row of windows of the floors above (nor cut by their tile lines)."""
    prob = probabilities(floors=4, ground_h=40)
    top = 4 * 30
    prob[top + 6:, 4:40] = 0.5 * (np.eye(len(CMP_LABELS))[SHOP] + np.eye(len(CMP_LABELS))[WINDOW])
    prob[top + 6:, 64:110] = 0.5 * (np.eye(len(CMP_LABELS))[SHOP] + np.eye(len(CMP_LABELS))[WINDOW])
    facade_ = regular_facade(prob)
    assert facade_.ground and len(facade_.floor_lines) - 1 == 5
    assert top - 8 < facade_.floor_lines[-2] <= top + 6
    assert not any(box[1] > top for box, label in facade_.elements if label == "window")
    assert sum(label == "shop" for _, label in facade_.elements) == 2


def test_windows_behind_railings_share_one_balcony_cut():
    """The balcony group (wu2014 §3.3's synchronised sizes): windows whose lower part the parser calls balcony
    stop at one railing height, with a balcony terminal below them in the same column; the others keep their
    height."""
    prob = probabilities(floors=4, jitter=0.0)
    n = len(CMP_LABELS)
    balcony = CMP_LABELS.index("balcony")
    for i in (1, 2):  # railings over the lower 5 rows of the 14-row windows of the 2nd and 3rd floors
        for j in range(5):
            r0, c0 = i * 30 + 8, j * 24 + 7
            prob[r0 + 9:r0 + 14, c0:c0 + 10] = np.eye(n)[balcony]
    facade_ = regular_facade(prob)
    windows = [b for b, label in facade_.elements if label == "window"]
    balconies = [b for b, label in facade_.elements if label == "balcony"]
    assert len(windows) == 20 and len(balconies) == 10
    railed = [b for b in windows if 30 <= b[1] < 90]
    assert len(railed) == 10 and len({round(b[3] - b[1], 6) for b in railed}) == 1
    assert all(b[3] == pytest.approx(30 * (1 + (b[1] >= 60)) + 8 + 9, abs=1.0) for b in railed)  # at the railing
    assert all(any(r[0] == b[0] and r[1] == b[3] for r in balconies) for b in railed)
    layout = facade_layout(facade_, prob.shape[0], prob.shape[1], 0.1, {})
    assert check_partition(layout) == [] and layout.count("balcony") == 10 and layout.count("window") == 20


def test_a_door_in_the_lowest_floor_of_windows_replaces_the_window_it_overlaps():
    """Without a ground floor of its own (the lowest floor has windows too) the entrance door is looked for in the
    lowest floor: it stands on the ground and the window of its tile gives way."""
    prob = probabilities(floors=4)
    n = len(CMP_LABELS)
    prob[90 + 4:, 55:65] = np.eye(n)[DOOR]  # in the lowest floor's third tile (its window at 55..65 too)
    facade_ = regular_facade(prob)
    assert not facade_.ground and len(facade_.floor_lines) - 1 == 4
    doors = [b for b, label in facade_.elements if label == "door"]
    assert len(doors) == 1 and doors[0][3] == prob.shape[0] and doors[0][0] == pytest.approx(55, abs=1)
    assert sum(label == "window" for _, label in facade_.elements) == 19
    layout = facade_layout(facade_, prob.shape[0], prob.shape[1], 0.1, {})
    assert check_partition(layout) == [] and layout.count("door") == 1


def test_a_sliver_of_door_probability_beside_the_lowest_windows_is_no_door():
    """Regression (test_cli_from_photo's synthetic facade): a 5 px run of door probability between the lowest
    floor's windows replaced a window; a door there is at least ``DOOR_WIDTH`` of the windows' width."""
    prob = probabilities(floors=4)
    prob[90 + 10:, 118:120] = np.eye(len(CMP_LABELS))[DOOR]
    facade_ = regular_facade(prob)
    assert not any(label == "door" for _, label in facade_.elements)
    assert sum(label == "window" for _, label in facade_.elements) == 20


def test_a_floor_line_lies_in_the_wall_band_not_in_a_railing():
    """Regression (round 2): the floor line between two rows of windows was the middle of the gap between them,
    which a railing below the upper row fills; it now sits in the wall band the window, balcony and door
    probabilities leave between the railing and the next row."""
    prob = probabilities(floors=4, jitter=0.0)
    balcony = CMP_LABELS.index("balcony")
    for i in range(3):  # a railing over the upper 10 of the 16 wall rows below every window row but the last
        prob[i * 30 + 22:i * 30 + 32, :] = np.eye(len(CMP_LABELS))[balcony]
    lines = regular_facade(prob).floor_lines
    assert len(lines) == 5
    for k, y in enumerate(lines[1:-1]):  # the wall band of floor k: rows 32..38 below its top
        assert k * 30 + 32 <= y <= k * 30 + 38
        assert prob[int(y), :, [WINDOW, balcony]].sum() == 0


def test_a_window_off_its_column_moves_to_its_glass_keeping_the_group_size():
    """Synchronised sizes (wu2014 §3.3) with positions per element: a window 3 px right of its column keeps the
    group's size and moves onto its glass."""
    prob = probabilities(floors=3, jitter=0.0)
    n = len(CMP_LABELS)
    r0, c0 = 30 + 8, 2 * 24 + 7  # the middle floor's third window
    prob[r0:r0 + 14, c0:c0 + 10] = np.eye(n)[CMP_LABELS.index("facade")]
    prob[r0:r0 + 14, c0 + 3:c0 + 13] = np.eye(n)[WINDOW]
    windows = [b for b, label in regular_facade(prob).elements if label == "window"]
    assert len(windows) == 15 and len({(round(b[2] - b[0], 6), round(b[3] - b[1], 6)) for b in windows}) == 1
    moved = [b for b in windows if r0 - 2 <= b[1] <= r0 + 2 and c0 - 2 <= b[0] <= c0 + 6]
    assert len(moved) == 1 and moved[0][0] == pytest.approx(c0 + 3, abs=0.5)
    others = [b for b in windows if b is not moved[0]]
    assert all(abs(b[0] - (round((b[0] - 7) / 24) * 24 + 7)) <= 0.5 for b in others)


def test_a_window_stays_in_its_column_for_a_small_gain_of_glass():
    """A window moves off its synchronised column only for ``FIT_GAIN`` more glass probability: a frame or a
    shadow that shifts the glass mass by a few per cent does not move it (on the balcony-heavy photos of the
    training range moving for any gain lost matched windows); a clear offset does."""
    glass = np.zeros((40, 40))
    glass[10:20, 12:22] = 1.0
    glass[10:20, 10:12] = 0.9  # 2 % more glass two pixels right
    box = (10.0, 10.0, 20.0, 20.0)
    assert _fitted(glass, [(box, "window")]) == [(box, "window")]
    glass[10:20, 10:12] = 0.0  # 25 % more: moved onto the glass, its size kept
    assert _fitted(glass, [(box, "window")]) == [((12.0, 10.0, 22.0, 20.0), "window")]


def test_a_dark_window_above_a_wall_band_is_not_the_door():
    """Regression (round 3): the ensemble parser gives the dark windows of a synthetic facade's lowest row some door
    probability, and the door looked for in the lowest floor replaced one of them, though wall lies below it."""
    eye = np.eye(len(CMP_LABELS))
    prob = probabilities(floors=4)
    prob[98:112, 31:41] = 0.6 * eye[WINDOW] + 0.4 * eye[DOOR]  # the lowest row's second window, 8 px of wall below
    assert [label for _, label in regular_facade(prob).elements].count("door") == 0
    prob[98:, 31:41] = 0.6 * eye[WINDOW] + 0.4 * eye[DOOR]  # reaching the ground: the entrance
    door = [box for box, label in regular_facade(prob).elements if label == "door"]
    assert len(door) == 1 and door[0][3] == prob.shape[0]


def test_a_voted_window_of_closed_shutters_or_behind_a_railing_takes_that_label():
    """The tile vote decides the label too (round 5): a window box holding more blind (balcony) probability than
    ``RELABEL`` times its glass is a blind (a balcony: a French window behind a railing, as CMP labels it)."""
    prob = probabilities(floors=4)
    n = len(CMP_LABELS)
    blind, balcony = CMP_LABELS.index("blind"), CMP_LABELS.index("balcony")
    shutters = 0.45 * np.eye(n)[WINDOW] + 0.55 * np.eye(n)[blind]  # voted (window + blind) but mostly shutter
    for j in range(5):
        prob[38:52, j * 24 + 7:j * 24 + 17] = shutters  # the second floor's windows
    prob[68:82, 7:17] = 0.3 * np.eye(n)[WINDOW] + 0.7 * np.eye(n)[balcony]  # one French window behind a railing
    facade_ = regular_facade(prob)
    labels = [label for _, label in facade_.elements]
    assert labels.count("blind") == 5 and labels.count("balcony") == 1 and labels.count("window") == 14
    assert all(30 <= box[1] < 60 for box, label in facade_.elements if label == "blind")
    layout = facade_layout(facade_, prob.shape[0], prob.shape[1], 0.1, {})
    assert check_partition(layout) == [] and layout.count("blind") == 5 and layout.count("window") == 14


def test_every_door_on_the_ground_is_a_door_and_cuts_the_shop_it_stands_in():
    """Regression (round 14): the ground floor had one door, the most probable. 55 of the 200 training photos have
    more than one (a house door beside the shops, a door per shop); on their annotated label maps the layout found
    65 of their 210 doors, 166 now."""
    prob = probabilities(floors=4, cols=6, ground_h=30, shop=True)  # shop 4-40, door 50-60
    eye = np.eye(len(CMP_LABELS))
    prob[124:, 90:100] = eye[DOOR]  # a second door, right of the first
    prob[126:, 104:140] = eye[SHOP]  # a second shop ...
    prob[124:, 118:126] = eye[DOOR]  # ... with its own door in the middle
    facade_ = regular_facade(prob)
    doors = sorted(box for box, label in facade_.elements if label == "door")
    assert [(round(b[0]), round(b[2])) for b in doors] == [(50, 60), (90, 100), (118, 126)]
    assert all(b[3] == prob.shape[0] for b in doors)
    shops = sorted((round(b[0]), round(b[2])) for b, label in facade_.elements if label == "shop")
    assert shops == [(4, 40), (104, 118), (126, 140)]
    layout = facade_layout(facade_, prob.shape[0], prob.shape[1], 0.1, {})
    assert check_partition(layout) == [] and layout.count("door") == 3


def test_twin_windows_a_mullion_apart_are_two_windows():
    """Regression (round 14): columns of windows closer than a quarter of their width were joined, so twin
    windows a mullion apart became one box over both; CMP annotates them as two, and on the training photos'
    annotated label maps 26 % of the windows lay inside such a larger box. Columns now join only under
    ``COLUMN_JOIN`` of their width (a gap of a pixel or two at the working size: a frame)."""
    n = len(CMP_LABELS)
    prob = np.zeros((90, 120, n))
    prob[..., CMP_LABELS.index("facade")] = 1.0
    for top in (8, 38, 68):
        for left in range(0, 120, 30):
            prob[top:top + 14, left + 4:left + 14] = np.eye(n)[WINDOW]  # twin windows 10 px wide,
            prob[top:top + 14, left + 16:left + 26] = np.eye(n)[WINDOW]  # a 2 px mullion between them
    windows = [box for box, label in regular_facade(prob).elements if label == "window"]
    assert len(windows) == 24
    assert all(9 <= box[2] - box[0] <= 11 for box in windows)


def test_an_opening_on_the_ground_wider_than_tall_is_no_door():
    """Regression (round 14, cmp_b0277): the mirror-axis door reached above the ground floor's top line and, cut
    to it, was a box 46 px wide and 32 px tall over the entrance and two windows; the layout's door was 4.6 m
    wide. A door is taller than wide: a wider opening on the ground is a shop front, a gate or an arcade."""
    prob = probabilities(floors=4, cols=6, ground_h=30)  # its door: 50-60, 26 px tall
    wide = (40.0, 124.0, 100.0, 150.0)  # 60 x 26 px, found by other means
    facade_ = regular_facade(prob, door=lambda top: wide)
    doors = [box for box, label in facade_.elements if label == "door"]
    assert doors and all(b[2] - b[0] <= b[3] - b[1] for b in doors)
    assert wide not in doors and [(round(b[0]), round(b[2])) for b in doors] == [(50, 60)]
