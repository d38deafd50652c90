"""Closed shutters made from a training photo's own open shutters (citygen_photo.shutters)."""
from __future__ import annotations

import numpy as np
import pytest

from citygen_photo.shutters import BLIND, WINDOW, closed_shutters, shutter_parts
from citygen_photo.train_unet import draw_batch, train
from tests.photo.synthetic import labelled_photos


def _with_open_shutters() -> tuple[np.ndarray, np.ndarray]:
    """A synthetic facade whose first window has a green open shutter on its left."""
    work, lab = labelled_photos(1)[0]
    work, lab = work.copy(), lab.copy()
    parts = shutter_parts(lab)
    rows, cols = parts.windows[0]
    left = slice(max(cols.start - 5, 0), cols.start)
    lab[rows, left] = BLIND
    work[rows, left] = (0.1, 0.6, 0.2)
    return work, lab


def test_parts_are_the_blind_and_window_components():
    work, lab = _with_open_shutters()
    parts = shutter_parts(lab)
    assert len(parts.blinds) == 1 and len(parts.windows) == 12  # 3 floors x 4 columns
    assert all((lab[box] == WINDOW).any() for box in parts.windows)


def test_every_window_closed_takes_the_shutters_colour_and_the_blind_label():
    work, lab = _with_open_shutters()
    out, out_lab = closed_shutters(work, lab, shutter_parts(lab), np.random.default_rng(0), share=1.0)
    assert not (out_lab == WINDOW).any()
    assert np.allclose(out[lab == WINDOW], (0.1, 0.6, 0.2))
    assert np.array_equal(out[lab != WINDOW], work[lab != WINDOW])  # wall and the open shutter untouched
    assert (lab == WINDOW).any() and np.array_equal(lab, _with_open_shutters()[1])  # inputs not changed


def test_a_share_closes_some_windows_and_a_photo_without_shutters_comes_back_as_it_was():
    work, lab = _with_open_shutters()
    _, out_lab = closed_shutters(work, lab, shutter_parts(lab), np.random.default_rng(1), share=0.5)
    closed = [box for box in shutter_parts(lab).windows if (out_lab[box] == BLIND).all() or
              not (out_lab[box] == WINDOW).any()]
    assert 0 < len(closed) < 12
    plain, plain_lab = labelled_photos(1)[0]
    same, same_lab = closed_shutters(plain, plain_lab, shutter_parts(plain_lab), np.random.default_rng(0), 1.0)
    assert same is plain and same_lab is plain_lab


def test_a_batch_with_closed_shutters_has_blind_labels_and_none_without():
    photo = _with_open_shutters()
    parts = [shutter_parts(photo[1])]
    _, closed = draw_batch([photo], None, np.ones(1), np.random.default_rng(2), 4, 64, shutters=parts, close=1.0)
    _, kept = draw_batch([photo], None, np.ones(1), np.random.default_rng(2), 4, 64)
    blind, window = BLIND - 1, WINDOW - 1  # the batch's labels are ids - 1
    assert (closed == window).sum() == 0 and (closed == blind).sum() > (kept == blind).sum()
    assert (kept == window).sum() > 0


def test_a_share_outside_zero_to_one_or_with_pixel_features_is_refused_before_training():
    photos = labelled_photos(1)
    with pytest.raises(ValueError, match="from 0 to 1"):
        train(photos, close=1.5, steps=1)
    with pytest.raises(ValueError, match="without --features"):
        train(photos, close=0.5, features=True, steps=1)
