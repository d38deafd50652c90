"""The U-Net facade parser (citygen_photo.unet, numpy inference) and its training script's data pipeline
(citygen_photo.train_unet; the network itself needs PyTorch)."""
from __future__ import annotations

import argparse

import numpy as np
import pytest

from citygen_photo.features import FEATURES, pixel_features
from citygen_photo.labels import CMP_LABELS
from citygen_photo.photo import luminance
from citygen_photo.train_fcn import COLUMN, label_weights
from citygen_photo.train_unet import DARK, boosted, dark_photos, draw_batch, draw_weights, jittered, parse_boost
from citygen_photo.unet import BASE_INPUTS, BOTTOM_DILATIONS, base_input, layer_shapes
from tests.photo.synthetic import labelled_photos


def test_base_input_is_standardised_colour_and_mirror_symmetric_position():
    work = np.random.default_rng(0).random((20, 31, 3))
    x = base_input(work)
    assert x.shape == (20, 31, BASE_INPUTS)
    assert abs(x[..., :3].mean()) < 1e-5 and abs(x[..., :3].std() - 1) < 1e-3
    assert np.allclose(x[:, 0, 3], np.linspace(0, 1, 20))
    assert np.allclose(x[0, :, 4], x[0, ::-1, 4]) and x[0, 15, 4] == pytest.approx(0.5)


def test_layer_shapes_chain_down_the_bottom_and_up_with_the_skips():
    shapes = layer_shapes(5, (8, 16, 32), 12)
    assert shapes == [(5, 8), (8, 8), (8, 16), (16, 16), (16, 32), *[(32, 32)] * (len(BOTTOM_DILATIONS) - 1),
                      (32 + 16, 16), (16 + 8, 8), (8, 12)]


def test_balcony_and_blind_photos_are_drawn_more_often():
    photos = labelled_photos(3)
    lab = photos[1][1].copy()
    lab[: lab.shape[0] // 2][lab[: lab.shape[0] // 2] == 3] = CMP_LABELS.index("balcony") + 1
    photos[1] = (photos[1][0], lab)
    weights = draw_weights(photos)
    assert weights.sum() == pytest.approx(1)
    assert weights[1] > 2 * weights[0] and weights[0] == pytest.approx(weights[2])  # the others still drawn
    assert np.allclose(draw_weights(labelled_photos(2)), 0.5)  # no balcony anywhere: even


def test_photos_darker_than_dark_are_drawn_the_dark_factor_more_often():
    photos = labelled_photos(3)
    mean = [luminance(work).mean() for work, _ in photos]
    photos[1] = (photos[1][0] * (0.9 * DARK / mean[1]), photos[1][1])  # a crop darker than DARK on average
    photos[2] = (photos[2][0] * (1.1 * DARK / mean[2]), photos[2][1])
    assert dark_photos(photos).tolist() == [mean[0] < DARK, True, False]
    even, tripled = draw_weights(photos), draw_weights(photos, dark=3.0)
    assert tripled.sum() == pytest.approx(1)
    assert tripled[1] / tripled[2] == pytest.approx(3 * even[1] / even[2])
    assert np.array_equal(draw_weights(photos, dark=1.0), even)  # the default draw is unchanged


def test_jitter_keeps_the_range_and_changes_the_colours():
    work = labelled_photos(1)[0][0]
    out = jittered(work, np.random.default_rng(0))
    assert out.shape == work.shape and 0 <= out.min() and out.max() <= 1 and not np.allclose(out, work)


def test_a_batch_pads_small_photos_with_ignored_labels_and_mirrors_image_and_labels_together():
    rng = np.random.default_rng(1)
    work = np.zeros((12, 40, 3))
    work[:, :10] = 1.0  # a bright left strip, labelled window
    lab = np.full((12, 40), 2, np.uint8)
    lab[:, :10] = 3
    x, y = draw_batch([(work, lab)], None, np.ones(1), rng, 16, 16)
    assert x.shape == (16, BASE_INPUTS, 16, 16) and y.shape == (16, 16, 16) and x.dtype == np.float32
    assert (y[:, 12:] == -100).all() and (x[:, :, 12:] == 0).all()  # the 12-row photo is padded below
    inside = y >= 0
    bright = x[:, 0][inside] > 0  # standardised red above the mean: the strip
    assert np.array_equal(bright, y[inside] == 2)  # the labels moved with the pixels, mirrored or not


def test_a_mirrored_batch_has_the_column_position_of_the_mirrored_photo():
    """The features' column position is flipped with the crop, so it reads 0..1 left to right either way."""
    rng = np.random.default_rng(2)
    work = np.random.default_rng(3).random((16, 16, 3))
    work[:, :4] = 1.0  # a bright left strip shows which samples were mirrored
    lab = np.full((16, 16), 2, np.uint8)
    feats = pixel_features(work)
    mean, std = feats.reshape(-1, FEATURES).mean(axis=0), feats.reshape(-1, FEATURES).std(axis=0) + 1e-6
    standard = (feats - mean) / std
    x, _ = draw_batch([(work, lab)], [standard], np.ones(1), rng, 8, 16, (float(mean[COLUMN]), float(std[COLUMN])))
    column = x[:, BASE_INPUTS + COLUMN] * std[COLUMN] + mean[COLUMN]
    assert np.allclose(column, np.linspace(0, 1, 16), atol=1e-5)
    mirrored = x[:, 0, :, -1].mean(axis=1) > x[:, 0, :, 0].mean(axis=1)  # the strip on the right
    assert 0 < mirrored.sum() < len(mirrored)


def test_numpy_inference_is_the_torch_network_and_training_is_reproducible(tmp_path):
    torch = pytest.importorskip("torch")
    from citygen_photo.parser import load_parser
    from citygen_photo.train import confusion
    from citygen_photo.train_unet import build_network, exported, train
    from citygen_photo.unet import FacadeUNet
    torch.manual_seed(0)
    net = build_network(BASE_INPUTS, (4, 6, 8))
    with torch.no_grad():  # float16 weights, as stored
        for conv in net.convs:
            conv.weight.copy_(conv.weight.half().float())
            conv.bias.copy_(conv.bias.half().float())
    model = exported(net, (4, 6, 8), np.zeros(0, np.float32), np.zeros(0, np.float32), np.ones(12, np.float32))
    x = np.random.default_rng(0).standard_normal((20, 26, BASE_INPUTS)).astype(np.float32)
    padded = np.pad(x, ((0, 0), (0, 2), (0, 0)))  # numpy pads to a multiple of 4 itself
    want = net(torch.from_numpy(padded.transpose(2, 0, 1)[None].copy()))[0].detach().numpy().transpose(1, 2, 0)
    assert np.allclose(model.logits(x), want[:, :26], atol=1e-4)

    photos = labelled_photos(3)
    a = train(photos, channels=(8, 8, 8), steps=100, batch=2, crop=48, seed=3)
    b = train(photos, channels=(8, 8, 8), steps=100, batch=2, crop=48, seed=3)
    assert all(np.array_equal(wa, wb) for (wa, _), (wb, _) in zip(a.layers, b.layers))
    path = tmp_path / "unet.npz"
    np.savez_compressed(path, **a.arrays())
    loaded = load_parser(path)
    assert isinstance(loaded, FacadeUNet)
    assert np.allclose(loaded.probabilities(photos[0][0]), a.probabilities(photos[0][0]), atol=1e-6)
    matrix = confusion(a, photos)
    assert matrix[2, 2] / matrix[2].sum() > 0.8  # the synthetic windows are learned


def test_the_shipped_unet_is_small_and_parses_a_synthetic_facade():
    """The shipped U-Net (``model/facade_unet.npz``) loads without PyTorch, is under 1 MiB, and its
    probabilities favour a synthetic facade's windows over its wall."""
    from citygen_photo.parser import UNET_PATH, load_parser
    from citygen_photo.unet import FacadeUNet
    from tests.photo.synthetic import facade
    assert UNET_PATH.stat().st_size < 1024 * 1024
    model = load_parser(UNET_PATH)
    assert isinstance(model, FacadeUNet) and model.feature_mean.size == 0
    rgb, boxes, _ = facade(floors=4, cols=5)
    prob = model.probabilities(rgb)
    assert max(prob.shape[:2]) == 192 and np.allclose(prob.sum(axis=-1), 1.0, atol=1e-4)
    f = prob.shape[0] / rgb.shape[0]
    inside = np.zeros(prob.shape[:2], bool)
    for x0, y0, x1, y1 in boxes:
        inside[round(y0 * f) + 1:round(y1 * f) - 1, round(x0 * f) + 1:round(x1 * f) - 1] = True
    window = prob[..., CMP_LABELS.index("window")]
    assert window[inside].mean() > 2 * window[~inside].mean()


def test_per_kind_draws_give_the_rarer_kind_the_same_mass_as_the_commoner():
    photos = labelled_photos(4)
    balcony, blind = CMP_LABELS.index("balcony") + 1, CMP_LABELS.index("blind") + 1
    for i, (kind, rows) in enumerate(((balcony, 8), (blind, 2)), start=1):  # balconies 4 times the blinds' share
        lab = photos[i][1].copy()
        lab[:rows] = kind
        photos[i] = (photos[i][0], lab)
    pooled, per_kind = draw_weights(photos, even=0.0), draw_weights(photos, even=0.0, per_kind=True)
    assert pooled[1] > 2 * pooled[2]  # pooled shares: the balcony photo dominates
    assert per_kind[1] == pytest.approx(per_kind[2]) and per_kind[0] == pytest.approx(0, abs=1e-6)


def test_a_boost_multiplies_only_the_named_labels_loss_weight():
    photos = labelled_photos(2)
    weight = label_weights(photos, 0.5)
    out = boosted(weight, {"blind": 3.0, "balcony": 2.0})
    factor = np.ones(len(CMP_LABELS))
    factor[CMP_LABELS.index("blind")], factor[CMP_LABELS.index("balcony")] = 3.0, 2.0
    assert np.allclose(out, weight * factor)
    assert np.array_equal(boosted(weight, {}), weight)
    with pytest.raises(ValueError, match="shutter"):
        boosted(weight, {"shutter": 2.0})


def test_boost_option_reads_label_and_factor_and_names_the_labels_on_bad_input():
    assert parse_boost("blind=3") == ("blind", 3.0)
    for bad in ("blind", "blind=x", "blind=0", "shutter=2"):
        with pytest.raises(argparse.ArgumentTypeError, match="LABEL=FACTOR"):
            parse_boost(bad)


def test_training_from_a_trained_network_starts_at_its_weights_and_refuses_other_widths():
    pytest.importorskip("torch")
    from citygen_photo.train_unet import train
    photos = labelled_photos(2)
    first = train(photos, channels=(8, 8, 8), steps=20, batch=2, crop=48, seed=3)
    same = train(photos, channels=(8, 8, 8), steps=0, batch=2, crop=48, init=first, seed=5)
    assert all(np.array_equal(wa, wb) and np.array_equal(ba, bb)
               for (wa, ba), (wb, bb) in zip(first.layers, same.layers))
    tuned = train(photos, channels=(8, 8, 8), steps=5, batch=2, crop=48, lr=1e-3, init=first, seed=5)
    assert not all(np.array_equal(wa, wb) for (wa, _), (wb, _) in zip(first.layers, tuned.layers))
    with pytest.raises(ValueError, match="widths"):
        train(photos, channels=(8, 8, 16), steps=1, batch=2, crop=48, init=first)
