"""The learned facade parser: per-pixel probabilities of the 12 CMP labels for a facade photo.

Stages of auto-context (Tu & Bai 2010): stage 1 is a small multilayer perceptron on
:func:`citygen_photo.features.pixel_features`; every further stage another one on the same features plus the
previous stage's probabilities averaged over two neighbourhoods, at a few offsets above, below, left and right of
the pixel, and profiled along the pixel's row and column, so a pixel learns from the labels around it (a window
pane between window frames, a door below a window column, a row of windows at the pitch above). Weights ship in ``model/facade_parser.npz`` (trained by
:mod:`citygen_photo.train` on CMP photos cmp_b0061-0300; CMP Facade Database, Tylecek & Sara, GCPR 2013); inference
is numpy only and nothing is downloaded. The shipped parser (``SHIPPED``, :class:`Ensemble`) averages these
probabilities with those of the U-Net of :mod:`citygen_photo.unet`; the dilated network of :mod:`citygen_photo.fcn`
can be a member too.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.ndimage import uniform_filter, zoom

from citygen.errors import LayoutError
from citygen_photo.fcn import FacadeFCN
from citygen_photo.features import WORK, pixel_features, working_image
from citygen_photo.labels import CMP_LABELS
from citygen_photo.unet import FacadeUNet

MODEL_PATH = Path(__file__).resolve().parent / "model" / "facade_parser.npz"
FCN_PATH = Path(__file__).resolve().parent / "model" / "facade_fcn.npz"
UNET_PATH = Path(__file__).resolve().parent / "model" / "facade_unet.npz"
#: The shipped parser: the ensemble of the perceptrons and the U-Net (round 4; the dilated network of round 3,
#: ``FCN_PATH``, stays loadable as a member through ``load_parser``).
SHIPPED = (MODEL_PATH, UNET_PATH)
#: Working sizes (longest side, pixels) at which the shipped ensemble parses a photo; the probabilities of the
#: larger ones are resampled to the first's grid and averaged (multi-scale inference, round 6).
SCALES = (WORK, 256)
#: Neighbourhoods (working pixels) over which a stage's probabilities are averaged for the next stage.
CONTEXT = (7, 21)
#: Offsets (share of the longest working side) at which the next stage sees them above, below, left and right.
OFFSETS = (0.04, 0.1)
#: Context features a stage adds per label.
CONTEXT_FEATURES = len(CONTEXT) + 2 + 4 * len(OFFSETS)


@dataclass(frozen=True)
class Stage:
    """One perceptron: feature standardisation and (weights, bias) per layer; ReLU between, softmax at the end."""

    mean: np.ndarray
    std: np.ndarray
    layers: tuple[tuple[np.ndarray, np.ndarray], ...]

    def arrays(self, prefix: str) -> dict[str, np.ndarray]:
        out = {f"{prefix}_mean": self.mean, f"{prefix}_std": self.std}
        for k, (w, b) in enumerate(self.layers):
            out[f"{prefix}_w{k}"], out[f"{prefix}_b{k}"] = w, b
        return out

    @classmethod
    def from_arrays(cls, data, prefix: str) -> Stage:
        count = sum(1 for key in data if key.startswith(f"{prefix}_w"))
        return cls(data[f"{prefix}_mean"], data[f"{prefix}_std"],
                   tuple((data[f"{prefix}_w{k}"], data[f"{prefix}_b{k}"]) for k in range(count)))


def predict_stage(stage: Stage, features: np.ndarray) -> np.ndarray:
    """Label probabilities ``(..., 12)`` for ``features`` ``(..., F)``."""
    shape = features.shape[:-1]
    x = (features.reshape(-1, features.shape[-1]) - stage.mean) / stage.std
    for k, (w, b) in enumerate(stage.layers):
        x = x @ w + b
        if k < len(stage.layers) - 1:
            np.maximum(x, 0, out=x)
    x -= x.max(axis=1, keepdims=True)
    np.exp(x, out=x)
    x /= x.sum(axis=1, keepdims=True)
    return x.reshape(*shape, len(CMP_LABELS))


def context_features(prob: np.ndarray) -> np.ndarray:
    """A later stage's extra features ``(H, W, 12 * CONTEXT_FEATURES)``: the probabilities averaged over each of
    ``CONTEXT`` pixels, the smaller average shifted by each of ``OFFSETS`` up, down, left and right (edge pixels
    repeated), and the means along the pixel's row and column."""
    h, w, n = prob.shape
    local = [uniform_filter(prob, size=(s, s, 1), mode="nearest") for s in CONTEXT]
    planes = [*local, np.broadcast_to(prob.mean(axis=1, keepdims=True), (h, w, n)),
              np.broadcast_to(prob.mean(axis=0, keepdims=True), (h, w, n))]
    padded = np.pad(local[0], ((h, h), (w, w), (0, 0)), mode="edge")
    for share in OFFSETS:
        d = max(1, round(share * max(h, w)))
        planes += [padded[h - d:2 * h - d, w:2 * w], padded[h + d:2 * h + d, w:2 * w],
                   padded[h:2 * h, w - d:2 * w - d], padded[h:2 * h, w + d:2 * w + d]]
    return np.concatenate(planes, axis=-1).astype(np.float32)


def stage_input(features: np.ndarray, previous: np.ndarray | None) -> np.ndarray:
    """A stage's input: the pixel features, and after stage 1 the previous stage's context."""
    return features if previous is None else np.concatenate([features, context_features(previous)], axis=-1)


@dataclass(frozen=True)
class FacadeParser:
    """The trained stages, applied in turn."""

    stages: tuple[Stage, ...]
    prior: np.ndarray  # label share in the photos / share in the training sample (see citygen_photo.train)

    def probabilities(self, rgb: np.ndarray, work: int = WORK) -> np.ndarray:
        """``(h, w, 12)`` label probabilities of the facade photo ``rgb`` (H, W, 3) in 0..1, at the working size
        (longest side ``work``)."""
        features = pixel_features(working_image(rgb, work))
        prob = None
        for stage in self.stages:
            prob = predict_stage(stage, stage_input(features, prob))
        prob *= self.prior
        return prob / prob.sum(axis=-1, keepdims=True)


@dataclass(frozen=True)
class Ensemble:
    """Parsers whose probabilities are averaged (the shipped parser: the perceptrons and the U-Net, which err on
    different pixels), each at every working size of ``scales`` (the first sets the output's grid)."""

    members: tuple[FacadeParser | FacadeFCN | FacadeUNet, ...]
    scales: tuple[int, ...] = (WORK,)

    def probabilities(self, rgb: np.ndarray) -> np.ndarray:
        """The mean ``(h, w, 12)`` label probabilities of ``rgb`` (H, W, 3) in 0..1 over the members and scales,
        on the grid of the working size ``scales[0]``."""
        out = None
        for work in self.scales:
            mean = sum(m.probabilities(rgb, work) for m in self.members) / len(self.members)
            out = mean if out is None else out + upsampled(mean, out.shape[:2])
        return out / len(self.scales)


@functools.lru_cache(maxsize=4)
def load_parser(*paths: Path) -> FacadeParser | FacadeFCN | FacadeUNet | Ensemble:
    """The parser whose weights are in ``paths`` (several: their ensemble at the working sizes ``SCALES``; none: the
    shipped one, ``SHIPPED``)."""
    models = tuple(_load_one(path) for path in (paths or SHIPPED))
    return models[0] if len(models) == 1 else Ensemble(models, SCALES)


def _load_one(path: Path) -> FacadeParser | FacadeFCN | FacadeUNet:
    """The dilated network (:mod:`citygen_photo.fcn`) or the U-Net (:mod:`citygen_photo.unet`) where the file says
    so, else the auto-context perceptrons."""
    try:
        with np.load(path) as data:
            arrays = {k: data[k] for k in data.files}
    except (OSError, ValueError) as exc:
        raise LayoutError(f"cannot read the facade parser's weights ({exc})", where=str(path),
                          hint="reinstall citygen, or train the models with python -m citygen_photo.train, "
                               "python -m citygen_photo.train_unet (or train_fcn)") from None
    if "kind" in arrays and str(arrays["kind"]) == "fcn":
        return FacadeFCN.from_arrays(arrays)
    if "kind" in arrays and str(arrays["kind"]) == "unet":
        return FacadeUNet.from_arrays(arrays)
    count = sum(1 for key in arrays if key.endswith("_mean"))
    return FacadeParser(tuple(Stage.from_arrays(arrays, f"s{k}") for k in range(1, count + 1)), arrays["prior"])


def upsampled(prob: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """``prob`` (h, w, n) resampled (linear, edge pixels repeated) to ``shape`` pixels, each pixel's
    probabilities summing to 1."""
    out = zoom(prob, (shape[0] / prob.shape[0], shape[1] / prob.shape[1], 1), order=1, mode="nearest")
    return out / out.sum(axis=-1, keepdims=True)


def load_labels(jpg: Path) -> tuple[np.ndarray, np.ndarray]:
    """A CMP photo cropped to its annotated facade box (RGB in 0..1) and its label map (ids 1..12) of the same
    crop."""
    from PIL import Image

    from citygen_photo.photo import load_photo
    from citygen_photo.score import cmp_boxes, facade_box
    with Image.open(jpg.with_suffix(".png")) as image:
        labels = np.asarray(image)
    boxes = cmp_boxes(jpg.with_suffix(".xml"), (labels.shape[1], labels.shape[0]))
    x0, y0, x1, y1 = (round(v) for v in facade_box(boxes))
    return load_photo(jpg, (x0, y0, x1, y1)), labels[y0:y1, x0:x1]
