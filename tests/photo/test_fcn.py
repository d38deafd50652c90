"""The convolutional facade parser (citygen_photo.fcn, numpy inference) and its training script
(citygen_photo.train_fcn, needs PyTorch)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import correlate

from citygen_photo.fcn import FacadeFCN, conv3x3
from citygen_photo.features import pixel_features
from tests.photo.synthetic import labelled_photos


def test_dilated_convolution_is_torch_cross_correlation_with_zero_padding():
    rng = np.random.default_rng(0)
    x, weight, bias = rng.standard_normal((9, 11, 2)), rng.standard_normal((3, 3, 2, 3)), rng.standard_normal(3)
    out = conv3x3(x, weight, bias, dilation=2)
    kernel = np.zeros((5, 5, 2, 3))
    kernel[::2, ::2] = weight  # the dilated kernel
    for k in range(3):
        want = sum(correlate(x[..., c], kernel[..., c, k], mode="constant") for c in range(2)) + bias[k]
        assert np.allclose(out[..., k], want)


def test_column_channel_is_the_column_position():
    """Regression guard: training mirrors crops and flips this channel, so it must be the column position."""
    from citygen_photo.train_fcn import COLUMN
    features = pixel_features(np.random.default_rng(1).random((20, 30, 3)))
    assert np.allclose(features[0, :, COLUMN], np.linspace(0, 1, 30), atol=1e-6)


def test_training_is_reproducible_exports_what_numpy_runs_and_learns_windows(tmp_path):
    pytest.importorskip("torch")
    from citygen_photo.parser import load_parser
    from citygen_photo.train import confusion
    from citygen_photo.train_fcn import train
    photos = labelled_photos(3)
    a = train(photos, width=8, steps=120, batch=2, crop=48, seed=3)
    b = train(photos, width=8, steps=120, batch=2, crop=48, seed=3)
    assert all(np.array_equal(wa, wb) for (wa, _), (wb, _) in zip(a.layers, b.layers))
    path = tmp_path / "fcn.npz"
    np.savez_compressed(path, **a.arrays())
    loaded = load_parser(path)
    assert isinstance(loaded, FacadeFCN)
    assert np.allclose(loaded.probabilities(photos[0][0]), a.probabilities(photos[0][0]), atol=1e-6)
    matrix = confusion(a, photos)
    assert matrix[2, 2] / matrix[2].sum() > 0.8  # the synthetic windows are learned
