"""The rows of windows checked against the floor period (citygen_photo.lattice): a strip squeezed between floors
dropped, rows put back where the intensity bands repeat, nothing done where the MI period disagrees; the band MI
of citygen_photo.symmetry on a striped image; and the learned path's floors with it on synthetic facades."""
from __future__ import annotations

import math

import numpy as np

from citygen_photo.lattice import confirms, lattice_rows, on_lattice
from citygen_photo.regular import regular_facade
from citygen_photo.symmetry import band_similarity, quantize
from tests.photo.test_learned import probabilities


def rows_at(*centres: float, height: float = 14.0) -> list[tuple[float, float]]:
    return [(c - height / 2, c + height / 2) for c in centres]


def centres(rows) -> list[float]:
    return [round((a + b) / 2, 1) for a, b in rows]


def test_the_period_confirms_the_pitch_or_a_multiple_of_it():
    assert confirms(30, 31) and confirms(30, 58) and confirms(30, 92)
    assert not confirms(30, 45) and not confirms(30, None) and not confirms(0, 30)


def test_a_strip_between_two_floors_is_dropped_a_long_spacing_is_kept():
    assert centres(on_lattice(rows_at(20, 50, 65, 80, 110), 30)) == [20, 50, 80, 110]
    # cmp_b0285: the lowest row, pulled down by the shop glass below it, lies 1.4 pitches below the next: kept
    assert centres(on_lattice(rows_at(12, 33, 48, 70, 95, 125), 21.5)) == [12, 33, 48, 70, 95, 125]
    # cmp_b0068: a strip 0.64 pitches below the lowest row is no floor
    assert centres(on_lattice(rows_at(32, 65, 98, 131, 152), 32.8)) == [32, 65, 98, 131]
    assert centres(on_lattice(rows_at(20, 30, 40), 30)) == [20, 30, 40]  # fewer than three left: unchanged


def test_rows_are_put_back_only_where_the_bands_repeat():
    rows = rows_at(65, 95, 125)
    above = lambda y0, y1, shift: 1.0 if shift > 0 else 0.0  # noqa: E731 (bands repeat upwards only)
    # 35's floor band [20, 50) fits in the photo, 5's would start above its top
    assert centres(lattice_rows(rows, 30, 30, above, bottom=150)) == [35, 65, 95, 125]
    weak = lambda y0, y1, shift: 0.5 if y0 < 50 else 1.0  # noqa: E731 (the band above the rows repeats less)
    assert centres(lattice_rows(rows, 30, 30, weak, bottom=150)) == [65, 95, 125]
    below = lambda y0, y1, shift: 1.0 if shift < 0 or y0 >= 50 else 0.0  # noqa: E731
    assert centres(lattice_rows(rows, 30, 30, below, bottom=150)) == [65, 95, 125]  # 155's band passes 150
    assert centres(lattice_rows(rows, 30, 30, below, bottom=200)) == [65, 95, 125, 155, 185]


def test_nothing_changes_without_a_confirming_period_or_three_rows():
    rows = rows_at(20, 50, 65, 80, 110)
    assert lattice_rows(rows, 30, 45, lambda *_: 1.0, bottom=200) == rows
    assert lattice_rows(rows, 30, None, lambda *_: 1.0, bottom=200) == rows
    assert lattice_rows(rows, 30, 30, None, bottom=200) == rows
    assert lattice_rows(rows_at(80, 110), 30, 30, lambda *_: 1.0, bottom=200) == rows_at(80, 110)


def test_band_mutual_information_peaks_at_the_stripes_period():
    y = np.arange(120)[:, None] * np.ones((1, 40))
    q = quantize(np.sin(2 * np.pi * y / 20) + 0.01 * np.random.default_rng(1).normal(size=y.shape))
    same, half = band_similarity(q, 20, 40, 20), band_similarity(q, 20, 40, 10)
    assert same > 1.0 and same > half
    assert math.isnan(band_similarity(q, 110, 130, 0)) and math.isnan(band_similarity(q, 0, 20, -5))


def test_the_learned_floors_gain_a_top_row_the_parser_missed_where_the_photo_repeats():
    prob = probabilities(floors=5, miss=tuple((0, j) for j in range(5)))  # the top row: closed shutters
    plain = regular_facade(prob, period=30.0)
    found = regular_facade(prob, period=30.0, similar=lambda *_: 1.0)
    assert len(found.floor_lines) == len(plain.floor_lines) + 1
    assert len([e for e in found.elements if e[1] == "window"]) == len(
        [e for e in plain.elements if e[1] == "window"])  # the new row's tiles are voted empty, not invented
    assert regular_facade(prob, period=30.0, similar=lambda *_: 0.0).floor_lines == plain.floor_lines
