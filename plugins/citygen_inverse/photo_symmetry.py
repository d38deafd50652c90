"""Translational symmetry of a facade image by mutual information (mueller2007 §2.1-§2.3).

``S(y, h) = MI(I(R_{y,h}), I(R_{y-h,h}))`` (Eq. 2) compares the band of rows ``[y, y+h)`` with the band right
above it (image rows, y down). Intensities are quantised to ``bins`` equal-population levels; for one ``h`` the
joint histograms of all ``y`` come from one ``bincount`` of the row-pair codes and a cumulative sum, so the
exhaustive search over ``y`` and ``h`` costs O(rows x columns x heights). The horizontal direction is the same
computation on the transposed image.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Quantisation levels of the joint histograms.
BINS = 8
#: A repetition is detected when the period's line-averaged MI rises this much (nats) over the trough between
#: half the period and the period.
MIN_PROMINENCE = 0.01


@dataclass(frozen=True)
class Symmetry:
    """Result of the symmetry search along one axis (pixels of the analysed image).

    ``s_max[y]`` and ``h_max[y]`` are Eq. 2's best score and period per line (0 where no period fits);
    ``period`` is the repetition the lines agree on and ``prominence`` how far its line-averaged score rises over the trough at shorter shifts (0 = no repetition)."""

    s_max: np.ndarray
    h_max: np.ndarray
    period: int
    prominence: float

    @property
    def found(self) -> bool:
        return self.period > 0 and self.prominence >= MIN_PROMINENCE


def quantize(gray: np.ndarray, bins: int = BINS) -> np.ndarray:
    """Equal-population intensity levels ``0..bins-1`` (robust to exposure and contrast)."""
    edges = np.quantile(gray, np.linspace(0, 1, bins + 1)[1:-1])
    return np.searchsorted(edges, gray, side="right").astype(np.int64)


def mutual_information(joint: np.ndarray, bins: int = BINS) -> np.ndarray:
    """Eq. 1 for stacked joint histograms ``(..., bins*bins)`` of counts, less the Miller-Madow bias
    ``(B_ab - B_a - B_b + 1) / 2N`` of the histogram estimate (small bands would otherwise win)."""
    n = joint.sum(axis=-1, keepdims=True)
    p = joint / np.maximum(n, 1)
    p3 = p.reshape(*p.shape[:-1], bins, bins)
    pa, pb = p3.sum(axis=-1, keepdims=True), p3.sum(axis=-2, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        terms = np.where(p3 > 0, p3 * np.log(p3 / (pa * pb)), 0.0)
    occupied = (p3 > 0).sum(axis=(-1, -2)) - (pa > 0).sum(axis=(-1, -2)) - (pb > 0).sum(axis=(-1, -2)) + 1
    return terms.sum(axis=(-1, -2)) - occupied / (2 * np.maximum(n[..., 0], 1))


def symmetry_scores(q: np.ndarray, heights: np.ndarray, bins: int = BINS) -> np.ndarray:
    """``S[i, y]`` = Eq. 2 for ``h = heights[i]`` (NaN where the two bands do not fit in the image)."""
    rows, cols = q.shape
    k2 = bins * bins
    scores = np.full((heights.size, rows + 1), np.nan)
    for i, h in enumerate(heights):
        if 2 * h > rows:
            continue
        codes = q[h:] * bins + q[:-h] + (np.arange(rows - h) * k2)[:, None]
        per_row = np.bincount(codes.ravel(), minlength=(rows - h) * k2).reshape(rows - h, k2)
        cum = np.vstack([np.zeros((1, k2)), np.cumsum(per_row, axis=0)])
        joint = cum[h: rows - h + 1] - cum[: rows - 2 * h + 1]
        scores[i, h: rows - h + 1] = mutual_information(joint, bins)
    return scores


def detect_symmetry(q: np.ndarray, lo: int, hi: int, bins: int = BINS) -> Symmetry:
    """Best period per line (§2.2) and the period of the repetition (our simplification of §2.3)."""
    rows = q.shape[0]
    hi = min(hi, rows // 2)
    if hi < max(lo, 2):
        return Symmetry(np.zeros(rows + 1), np.zeros(rows + 1, dtype=int), 0, 0.0)
    lo = max(lo, 2)
    heights = np.arange(max(lo // 2, 1), hi + 1)
    scores = symmetry_scores(q, heights, bins)
    valid = np.isfinite(scores)
    filled = np.where(valid & (heights >= lo)[:, None], scores, -np.inf)
    best = filled.argmax(axis=0)
    fits = np.isfinite(filled).any(axis=0)
    s_max = np.where(fits, filled.max(axis=0), 0.0)
    h_max = np.where(fits, heights[best], 0)
    # the period most lines agree on: the line-averaged score's most prominent peak over the trough between
    # h/2 and h (bands shifted by half a floor differ; vertical pilasters make every small shift look alike),
    # reduced to its fundamental
    profile = np.where(valid.any(axis=1), np.nanmean(np.where(valid, scores, np.nan), axis=1), -np.inf)
    prominence = np.array([profile[i] - profile[max(i - (h + 1) // 2, 0): i + 1].min() if h >= lo else -np.inf
                           for i, h in enumerate(heights)])
    period = _fundamental(prominence, heights, int(heights[np.argmax(prominence)]))
    rise = float(prominence[period - heights[0]])
    return Symmetry(s_max, h_max, period, rise)


def _fundamental(profile: np.ndarray, heights: np.ndarray, period: int) -> int:
    """The smallest integer fraction ``period/k`` that repeats about as well as ``period`` (MI of two floors
    against two floors is as high as of one against one)."""
    base = profile[period - heights[0]]
    for k in (4, 3, 2):
        h = int(round(period / k))
        if h >= heights[0] and profile[h - heights[0]] >= 0.85 * base:
            return h
    return period
