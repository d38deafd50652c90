"""The floors at a facade's edges (citygen_photo.edges): an attic row kept by the window probability its band holds,
not by one pixel's peak; a ground floor kept by its height, its shop + door probability or its mutual information
with the band one floor up; and the median floor MI shared with the lattice check."""
from __future__ import annotations

import numpy as np
from citygen_photo.edges import cut_row_repeats, ground_floor, with_attic, with_basement
from citygen_photo.labels import CMP_LABELS
from citygen_photo.lattice import floor_similarity, part_similarity
from citygen_photo.regular import WINDOW, regular_facade

from tests.photo.test_learned import probabilities

N = len(CMP_LABELS)
FACADE, SHOP = CMP_LABELS.index("facade"), CMP_LABELS.index("shop")


def rows_at(*centres: float, height: float = 14.0) -> list[tuple[float, float]]:
    return [(c - height / 2, c + height / 2) for c in centres]


def wall(h: int, w: int) -> np.ndarray:
    prob = np.zeros((h, w, N))
    prob[..., FACADE] = 1.0
    return prob


def test_an_attic_band_holding_a_dormer_is_a_row_a_faint_haze_is_not():
    """Regression (validation cmp_b0297, b0300; round 8's flips): a haze of window probability at the photo's
    top peaking just over 0.4 was an attic with one parser and none with another; the band's integrated excess
    over ``ATTIC_BASE`` decides now, and a dormer holds far more of it than a haze."""
    window = np.zeros((150, 120))
    rows = rows_at(50, 80, 110)
    window[10:24, 55:65] = 0.9  # one dormer, 14 x 10 px
    found = with_attic(window, rows, 30.0)
    assert len(found) == 4 and 8 <= found[0][0] < found[0][1] <= 26
    haze = np.zeros((150, 120))
    haze[12:18, 50:70] = 0.55  # smoothed, a peak of 0.44-0.55 over 4 rows: an attic until round 8
    assert with_attic(haze, rows, 30.0) == rows
    assert with_attic(haze, rows, 0.0) == rows and with_attic(window, [], 30.0) == []


def test_an_attic_row_close_above_the_top_row_is_a_row_a_transom_on_it_is_not():
    """Regression (round 14, annotated label maps of cmp_b0227, b0219): a row of dormers 0.55-0.6 pitches above
    the top row's centre was cut in half by the search's old limit (0.6 pitches above that centre) and lost. The
    attic now only needs wall between it and the top row (``ATTIC_WALL`` of a row's height) and its centre
    ``ATTIC_GAP`` pitches up; a transom right on top of the row's windows is their glass, not a row."""
    rows = rows_at(60, 90, 120, height=16.0)  # top row 52-68, pitch 30
    window = np.zeros((140, 120))
    window[41:46, 20:40] = window[41:46, 70:90] = 0.9  # dormers 5 px tall, centre 43.5: 0.55 pitches up
    found = with_attic(window, rows, 30.0)
    assert len(found) == 4 and 40 <= found[0][0] and found[0][1] <= 47
    transom = np.zeros((140, 120))
    transom[46:51, 20:100] = 0.9  # a strip of glass 1 px above the row's windows
    assert with_attic(transom, rows, 30.0) == rows


def test_a_basement_row_below_the_bottom_row_is_a_row():
    """Regression (round 14, annotated label maps of cmp_b0130, b0231): a row of small cellar windows under the
    ground floor's windows was too little of the row profile for a run and fell into the floor above; the
    attic's test on the facade turned upside down finds it. Without it the rows stay."""
    rows = rows_at(20, 50, 80)
    window = np.zeros((120, 120))
    window[101:108, 10:30] = window[101:108, 90:110] = 0.9  # two windows 7 px tall, 24 px below the bottom row
    found = with_basement(window, rows, 30.0)
    assert found[:3] == rows and len(found) == 4 and 100 <= found[3][0] < found[3][1] <= 109
    assert with_basement(np.zeros((120, 120)), rows, 30.0) == rows


def test_a_thin_band_with_a_shop_front_is_a_ground_floor_a_bare_one_is_not():
    prob = wall(140, 120)
    rows = rows_at(20, 50, 80, 110)  # the band below the lowest row: 125 to 140, half a pitch
    assert ground_floor(prob, rows, 30.0, None) is None  # bare wall, no MI to ask
    prob[127:, 10:80, SHOP], prob[127:, 10:80, FACADE] = 1.0, 0.0
    assert ground_floor(prob, rows, 30.0, None) == 125.0
    tall = wall(170, 120)  # 45 px below: 1.5 pitches, a floor whatever it holds
    assert ground_floor(tall, rows, 30.0, None) == 125.0


def test_a_ground_band_is_a_floor_where_it_does_not_repeat_the_floor_above():
    """Regression (validation cmp_b0285; round 8's flips): a ground floor 0.4 pitches tall without shop or door
    probability was a floor with one parser (0.41 pitches) and none with another (0.39); the band's MI with the
    band one pitch above decides now -- the wall below a lowest row of windows repeats the wall below the row
    above it, a ground floor does not."""
    prob = wall(137, 120)
    rows = rows_at(20, 50, 80, 110)  # band from 125 to 137: 0.4 pitches
    repeats = lambda y0, y1, shift: 1.0
    differs = lambda y0, y1, shift: 0.1 if y1 > 125 else 1.0
    assert ground_floor(prob, rows, 30.0, None, repeats) is None
    assert ground_floor(prob, rows, 30.0, None, differs) == 125.0
    assert ground_floor(wall(132, 120), rows, 30.0, None, differs) is None  # 0.23 pitches: too thin to be a floor


def test_the_floor_similarity_is_the_median_over_the_rows_that_fit():
    rows = rows_at(20, 50, 80, 110)
    mi = lambda y0, y1, shift: float("nan") if y0 < 0 else y0 / 100
    assert floor_similarity(rows, 30.0, mi) == 0.35  # bands from 5, 35 and 65: 0.05, 0.35, 0.65
    assert floor_similarity(rows_at(10, 40, 70), 30.0, mi) == 0.25  # (the first band leaves the photo)
    assert floor_similarity(rows, 30.0, lambda *_: 0.0) is None
    assert floor_similarity(rows[:1], 30.0, mi) is None


def test_the_learned_floors_keep_a_dormer_attic_and_a_ground_floor_of_shops():
    prob = probabilities(floors=4, ground_h=16, shop=True)  # a shop band half a pitch tall
    attic = wall(30, prob.shape[1])
    attic[8:22, 55:65] = np.eye(N)[WINDOW]
    facade = regular_facade(np.concatenate([attic, prob]))
    assert facade.ground and len(facade.floor_lines) - 1 == 6


def test_a_sliver_of_window_probability_reaching_into_the_shop_band_is_not_a_row():
    """Regression (balcony fold cmp_b0221 with the closed-shutter U-Nets of round 8): a 3 px run of window
    probability straddling the top of the shop band, its centre just above it, was a row of windows of its own
    between the upper floors and the ground floor; a row lies wholly above the shop band."""
    prob = probabilities(floors=4, ground_h=40, shop=True)
    prob[121:128, 64:110] = np.eye(N)[WINDOW]  # the shops' glass reaching above the band's top (126)
    facade = regular_facade(prob)
    assert facade.ground and len(facade.floor_lines) - 1 == 5


def sliver_window() -> tuple[np.ndarray, list[tuple[float, float]]]:
    """Rows of windows at 40, 70 and 100 (pitch 30) below a row the crop's top cuts: rows 0-4 of weak window
    probability, 0.02-0.08 row heights of excess over ``ATTIC_BASE`` -- too little for an attic."""
    window = np.zeros((130, 100))
    window[0:5, 40:60] = 0.4
    return window, rows_at(40, 70, 100)


def test_a_row_the_crops_top_cuts_is_a_floor_where_its_visible_part_repeats_the_floor_below():
    """Regression (validation cmp_b0274, fold b0158 with round 9's full retraining): the row the crop's top cuts to a
    sliver held less window probability than ``ATTIC_MASS`` and was lost; its floor band leaves the photo, so the
    visible part is compared with the same part of the floor below."""
    window, rows = sliver_window()
    assert with_attic(window, rows, 30.0) == rows  # by the window probability alone: too little
    repeats = lambda y0, y1, shift: 1.0  # noqa: E731
    found = with_attic(window, rows, 30.0, repeats)
    assert len(found) == 4 and found[0][0] == 0.0 and found[0][1] <= 5
    differs = lambda y0, y1, shift: 0.2 if y0 == 0.0 else 1.0  # noqa: E731 (the cut band repeats weakly)
    assert with_attic(window, rows, 30.0, differs) == rows


def test_the_cut_row_rule_needs_a_band_that_leaves_the_photo_and_a_run_inside_it():
    window, rows = sliver_window()
    repeats = lambda y0, y1, shift: 1.0  # noqa: E731
    assert cut_row_repeats(rows, 30.0, repeats, 0)
    assert not cut_row_repeats(rows, 30.0, repeats, 25)  # the run starts below the band's visible part
    lower = rows_at(60, 90, 120)  # the band one pitch up, [15, 45), lies inside the photo: the lattice's business
    assert not cut_row_repeats(lower, 30.0, repeats, 0)
    assert with_attic(np.concatenate([window, np.zeros((20, 100))]), lower, 30.0, repeats) == lower
    assert abs(part_similarity(rows, -10.0, 15.0, lambda y0, y1, shift: y0 / 100) - 0.45) < 1e-12  # from 30, 60


def test_a_ground_band_under_a_pitch_needs_shops_or_a_floor_that_does_not_repeat():
    """Regression (validation cmp_b0280 with round 9's full retraining): a bare band 0.72 pitches below the lowest
    row, no floor in the annotation, was a ground floor by its height alone; under a pitch it now needs shop + door
    probability (``TALL_SHOPS`` from 0.7 pitches on: b0264, b0281 hold 0.10-0.15 pitches of it) or the MI."""
    rows = rows_at(20, 50, 80, 110)  # the band below the lowest row starts at 125
    assert ground_floor(wall(149, 120), rows, 30.0, None) is None  # 0.8 pitches of bare wall
    assert ground_floor(wall(155, 120), rows, 30.0, None) == 125.0  # a pitch: a floor whatever it holds
    shops = wall(149, 120)
    shops[125:, :, SHOP], shops[125:, :, FACADE] = 0.12, 0.88  # 0.096 pitches of shop + door probability
    assert ground_floor(shops, rows, 30.0, None) == 125.0
    thin = wall(140, 120)
    thin[125:, :, SHOP], thin[125:, :, FACADE] = 0.12, 0.88  # half a pitch: 0.06, under GROUND_SHOPS
    assert ground_floor(thin, rows, 30.0, None) is None
    differs = lambda y0, y1, shift: 0.1 if y1 > 125 else 1.0  # noqa: E731
    assert ground_floor(wall(149, 120), rows, 30.0, None, differs) == 125.0
