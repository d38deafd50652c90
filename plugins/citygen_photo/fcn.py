"""A small fully convolutional facade parser: per-pixel probabilities of the 12 CMP labels, numpy inference.

The network sees the same pixel features as the perceptron parser (:func:`citygen_photo.features.pixel_features`)
and adds learned context: a 1 x 1 convolution to ``width`` channels, then 3 x 3 convolutions dilated by
``DILATIONS`` (receptive field 63 working pixels, a third of the facade), each added to its input (residual), and a
1 x 1 convolution to the label logits. Weights ship in ``model/facade_fcn.npz`` (trained by
:mod:`citygen_photo.train_fcn` on CMP photos cmp_b0061-0300); inference is numpy only and nothing is downloaded.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from citygen_photo.features import WORK, pixel_features, working_image

#: Dilations of the 3 x 3 convolutions, in order.
DILATIONS = (1, 2, 4, 8, 16)


def conv3x3(x: np.ndarray, weight: np.ndarray, bias: np.ndarray, dilation: int) -> np.ndarray:
    """``x`` (H, W, C) convolved with ``weight`` (3, 3, C, K) dilated by ``dilation``, zero padded to the same size
    (cross-correlation, as torch's ``conv2d``)."""
    h, w, _ = x.shape
    d = dilation
    padded = np.pad(x, ((d, d), (d, d), (0, 0)))
    out = np.broadcast_to(bias, (h, w, bias.size)).copy()
    for i in range(3):
        for j in range(3):
            out += padded[i * d:i * d + h, j * d:j * d + w] @ weight[i, j]
    return out


@dataclass(frozen=True)
class FacadeFCN:
    """Feature standardisation, the 1 x 1 input layer, the dilated residual layers and the 1 x 1 output layer
    (weights as (in, out) matrices, 3 x 3 kernels as (3, 3, in, out); stored as float16), and the prior that
    undoes the training loss's label weights."""

    mean: np.ndarray
    std: np.ndarray
    layers: tuple[tuple[np.ndarray, np.ndarray], ...]  # input, one per dilation, output
    prior: np.ndarray

    def probabilities(self, rgb: np.ndarray, work: int = WORK) -> np.ndarray:
        """``(h, w, 12)`` label probabilities of the facade photo ``rgb`` (H, W, 3) in 0..1, at the working size
        (longest side ``work``)."""
        x = (pixel_features(working_image(rgb, work)) - self.mean) / self.std
        (w0, b0), *hidden, (wn, bn) = self.layers
        x = np.maximum(x @ w0 + b0, 0)
        for (w, b), d in zip(hidden, DILATIONS):
            x = x + np.maximum(conv3x3(x, w, b, d), 0)
        logits = x @ wn + bn
        logits -= logits.max(axis=-1, keepdims=True)
        prob = np.exp(logits) * self.prior
        return prob / prob.sum(axis=-1, keepdims=True)

    def arrays(self) -> dict[str, np.ndarray]:
        out = {"kind": np.array("fcn"), "mean": self.mean, "std": self.std, "prior": self.prior}
        for k, (w, b) in enumerate(self.layers):
            out[f"w{k}"], out[f"b{k}"] = w.astype(np.float16), b.astype(np.float16)
        return out

    @classmethod
    def from_arrays(cls, data: dict[str, np.ndarray]) -> FacadeFCN:
        count = sum(1 for key in data if key.startswith("w"))
        return cls(data["mean"], data["std"], tuple((data[f"w{k}"].astype(np.float32), data[f"b{k}"].astype(
            np.float32)) for k in range(count)), data["prior"])
