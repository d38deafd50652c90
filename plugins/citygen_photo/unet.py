"""A small U-Net facade parser on the photo's own colours: per-pixel probabilities of the 12 CMP labels, numpy
inference.

The network sees the working image (longest side :data:`citygen_photo.features.WORK`) as its RGB standardised by
the photo's own mean and spread, the pixel's height in the facade and its distance from the nearer side (mirror
symmetric), and optionally the perceptrons' pixel features (:func:`citygen_photo.features.pixel_features`). Three
levels of two 3 x 3 convolutions, each level halved by a 2 x 2 max-pool, then three 3 x 3 convolutions dilated by
``BOTTOM_DILATIONS`` at an eighth of the resolution (the receptive field covers a window with its railing and the
tiles beside it), then back up: nearest-neighbour doubling, the level's own output appended (skip), one 3 x 3
convolution per level; a 1 x 1 convolution gives the label logits. Weights ship in ``model/facade_unet.npz``
(trained by :mod:`citygen_photo.train_unet` on CMP photos cmp_b0061-0300); nothing is downloaded.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from citygen_photo.fcn import conv3x3
from citygen_photo.features import WORK, pixel_features, working_image

#: Dilations of the 3 x 3 convolutions at the coarsest level.
BOTTOM_DILATIONS = (1, 2, 4)
#: The input planes besides the pixel features: standardised R, G, B, height, distance from the nearer side.
BASE_INPUTS = 5


def base_input(work: np.ndarray) -> np.ndarray:
    """``(H, W, BASE_INPUTS)`` float32: the working image ``work`` (H, W, 3) in 0..1 standardised by its own mean
    and standard deviation (over all pixels and channels, so colour ratios stay), the row position 0..1 from the
    top and ``min(x, 1 - x)`` of the column position."""
    h, w = work.shape[:2]
    rgb = (work - work.mean()) / (work.std() + 1e-6)
    rows, cols = np.mgrid[0:h, 0:w]
    xx = cols / max(w - 1, 1)
    return np.concatenate([rgb, (rows / max(h - 1, 1))[..., None], np.minimum(xx, 1 - xx)[..., None]],
                          axis=-1).astype(np.float32)


def layer_shapes(inputs: int, channels: tuple[int, ...], labels: int) -> list[tuple[int, int]]:
    """(in, out) channels of every convolution in order: per level two down, the bottom's dilated ones, per level
    one up (its input: the coarser output doubled and the level's skip), and the 1 x 1 output layer."""
    shapes, previous = [], inputs
    for c in channels[:-1]:
        shapes += [(previous, c), (c, c)]
        previous = c
    shapes += [(previous, channels[-1])] + [(channels[-1], channels[-1])] * (len(BOTTOM_DILATIONS) - 1)
    previous = channels[-1]
    for c in reversed(channels[:-1]):
        shapes.append((previous + c, c))
        previous = c
    return shapes + [(previous, labels)]


def _pool(x: np.ndarray) -> np.ndarray:
    h, w, c = x.shape
    return x.reshape(h // 2, 2, w // 2, 2, c).max(axis=(1, 3))


def _double(x: np.ndarray) -> np.ndarray:
    return x.repeat(2, axis=0).repeat(2, axis=1)


@dataclass(frozen=True)
class FacadeUNet:
    """The level widths ``channels`` (the last is the bottom's), the feature standardisation (empty without
    pixel features), the layers (3 x 3 kernels as (3, 3, in, out), the output as (in, out); stored as float16)
    and the prior that undoes the training loss's label weights."""

    channels: tuple[int, ...]
    feature_mean: np.ndarray
    feature_std: np.ndarray
    layers: tuple[tuple[np.ndarray, np.ndarray], ...]
    prior: np.ndarray

    def network_input(self, work: np.ndarray) -> np.ndarray:
        """The network's input planes for the working image ``work``."""
        x = base_input(work)
        if self.feature_mean.size:
            x = np.concatenate([x, (pixel_features(work) - self.feature_mean) / self.feature_std], axis=-1)
        return x

    def logits(self, x: np.ndarray) -> np.ndarray:
        """The label logits ``(H, W, 12)`` of the input planes ``x`` (H, W, C); H and W are padded with zeros to
        a multiple of the pooling and cropped back."""
        h, w = x.shape[:2]
        m = 2 ** (len(self.channels) - 1)
        x = np.pad(x, ((0, -h % m), (0, -w % m), (0, 0)))
        layers = iter(self.layers)
        skips = []
        for _ in self.channels[:-1]:
            for _ in range(2):
                x = np.maximum(conv3x3(x, *next(layers), 1), 0)
            skips.append(x)
            x = _pool(x)
        for d in BOTTOM_DILATIONS:
            x = np.maximum(conv3x3(x, *next(layers), d), 0)
        for skip in reversed(skips):
            x = np.maximum(conv3x3(np.concatenate([_double(x), skip], axis=-1), *next(layers), 1), 0)
        weight, bias = next(layers)
        return (x @ weight + bias)[:h, :w]

    def probabilities(self, rgb: np.ndarray, work: int = WORK) -> np.ndarray:
        """``(h, w, 12)`` label probabilities of the facade photo ``rgb`` (H, W, 3) in 0..1, at the working size
        (longest side ``work``)."""
        logits = self.logits(self.network_input(working_image(rgb, work)))
        logits -= logits.max(axis=-1, keepdims=True)
        prob = np.exp(logits) * self.prior
        return prob / prob.sum(axis=-1, keepdims=True)

    def arrays(self) -> dict[str, np.ndarray]:
        out = {"kind": np.array("unet"), "channels": np.array(self.channels), "feature_mean": self.feature_mean,
               "feature_std": self.feature_std, "prior": self.prior}
        for k, (w, b) in enumerate(self.layers):
            out[f"w{k}"], out[f"b{k}"] = w.astype(np.float16), b.astype(np.float16)
        return out

    @classmethod
    def from_arrays(cls, data: dict[str, np.ndarray]) -> FacadeUNet:
        count = sum(1 for key in data if key.startswith("w"))
        return cls(tuple(int(c) for c in data["channels"]), data["feature_mean"], data["feature_std"],
                   tuple((data[f"w{k}"].astype(np.float32), data[f"b{k}"].astype(np.float32))
                         for k in range(count)), data["prior"])
