"""Per-pixel features of a facade photo for the learned facade parser (:mod:`citygen_photo.parser`).

The photo (RGB in 0..1, already cropped to the facade) is reduced to ``WORK`` pixels on its longest side; every
pixel gets ``FEATURES`` numbers: its colour and chromaticity, luminance normalised by the photo's own statistics
(lighting invariance); at each of the ``SCALES`` the local means of luminance, colour and chroma, the local
contrast (standard deviation), the gradient energies across and along each axis, and the pixel's offset from the
local mean (texture); edge energies of elongated boxes (a window's frame is a long vertical or horizontal edge);
its position in the facade; and the profile of its row and column (windows repeat in rows and columns: the
profiles carry that context to each pixel). All filters are separable box and Sobel filters (scipy.ndimage),
O(pixels).
"""
from __future__ import annotations

import numpy as np
from scipy.ndimage import sobel, uniform_filter, zoom

#: Longest side (pixels) the features are computed at.
WORK = 192
#: Box filter sizes (working pixels) of the local statistics.
SCALES = (3, 7, 15, 31)
#: Length (working pixels) of the elongated edge boxes.
EDGE_RUN = 15
FEATURES = 9 + 10 * len(SCALES) + 4 + 3 + 7


def working_image(rgb: np.ndarray, work: int = WORK) -> np.ndarray:
    """``rgb`` (H, W, 3) in 0..1 resampled (linear) so its longest side is ``work`` pixels. Edge pixels are
    repeated beyond the border: zoom's default constant mode made the last row or column black on some sizes
    (round 6)."""
    h, w = rgb.shape[:2]
    shape = working_shape(h, w, work)
    return np.clip(zoom(rgb, (shape[0] / h, shape[1] / w, 1), order=1, mode="nearest"), 0.0, 1.0)


def working_shape(h: int, w: int, work: int = WORK) -> tuple[int, int]:
    """The ``(rows, columns)`` of an ``h x w`` image resampled so its longest side is ``work`` pixels."""
    f = work / max(h, w)
    return max(8, round(h * f)), max(8, round(w * f))


def pixel_features(rgb: np.ndarray) -> np.ndarray:
    """``(H, W, FEATURES)`` float32 features of a working image ``rgb`` (H, W, 3) in 0..1."""
    h, w = rgb.shape[:2]
    lum = rgb @ np.array([0.299, 0.587, 0.114])
    z = (lum - lum.mean()) / (lum.std() + 1e-6)
    chroma = rgb.max(axis=2) - rgb.min(axis=2)
    total = rgb.sum(axis=2) + 1e-3
    gx, gy = np.abs(sobel(z, axis=1)), np.abs(sobel(z, axis=0))
    colour = [rgb[..., c] - rgb[..., c].mean() for c in range(3)]
    planes = [*colour, z, chroma, gx, gy, rgb[..., 0] / total, rgb[..., 2] / total]
    for s in SCALES:
        mean = uniform_filter(z, s, mode="reflect")
        var = uniform_filter(z * z, s, mode="reflect") - mean * mean
        planes += [mean, np.sqrt(np.clip(var, 0, None)), uniform_filter(gx, s, mode="reflect"),
                   uniform_filter(gy, s, mode="reflect"), z - mean, uniform_filter(chroma, s, mode="reflect"),
                   *(uniform_filter(c, s, mode="reflect") for c in colour), np.abs(z - mean)]
    planes += [uniform_filter(gx, (EDGE_RUN, 3), mode="reflect"), uniform_filter(gy, (3, EDGE_RUN), mode="reflect"),
               uniform_filter(gx, (3, EDGE_RUN), mode="reflect"), uniform_filter(gy, (EDGE_RUN, 3), mode="reflect")]
    rows, cols = np.mgrid[0:h, 0:w]
    yy, xx = rows / max(h - 1, 1), cols / max(w - 1, 1)
    planes += [yy, xx, np.minimum(xx, 1 - xx)]
    planes += [np.broadcast_to(z.mean(axis=1, keepdims=True), (h, w)),
               np.broadcast_to(gy.mean(axis=1, keepdims=True), (h, w)),
               np.broadcast_to(gx.mean(axis=1, keepdims=True), (h, w)),
               np.broadcast_to(z.mean(axis=0, keepdims=True), (h, w)),
               np.broadcast_to(gx.mean(axis=0, keepdims=True), (h, w)),
               np.broadcast_to(gy.mean(axis=0, keepdims=True), (h, w)),
               z - np.broadcast_to(np.median(z, axis=1, keepdims=True), (h, w))]
    out = np.stack(planes, axis=-1).astype(np.float32)
    assert out.shape[-1] == FEATURES
    return out
