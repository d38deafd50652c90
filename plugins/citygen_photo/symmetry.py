"""Translational symmetry of a facade image by mutual information and the irreducible facade (mueller2007 §2.1-§2.3).

``S(y, h) = MI(I(R_{y,h}), I(R_{y-h,h}))`` (Eq. 2) compares the band of rows ``[y, y+h)`` with the band right
above it (image rows, y down). Intensities are quantised to ``bins`` equal-population levels; for one ``h`` the
joint histograms of all ``y`` come from one ``bincount`` of the row-pair codes and a cumulative sum, so the
exhaustive search over ``y`` and ``h`` costs O(rows x columns x heights). The horizontal direction is the same
computation on the transposed image. The irreducible facade (:func:`irreducible`) stacks the symmetric bands
along one axis as §2.3 describes; it validates the period of the line-averaged scores (:func:`validated_period`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Quantisation levels of the joint histograms.
BINS = 8
#: A repetition is detected when the period's line-averaged MI rises this much (nats) over the trough between
#: half the period and the period.
MIN_PROMINENCE = 0.01
#: §2.3: stacking stops when no line's ``S_max`` exceeds this fraction of the best score ``tau_max``.
STOP = 0.75
#: A period ``k`` times the irreducible facade's first stacking shift (k = 2..4) within this fraction is ``k``
#: floors (tiles) taken as one.
MULTIPLE = 0.1
#: ... provided the shift's line-averaged rise is at least this fraction of the period's.
SUPPORT = 0.55


@dataclass(frozen=True)
class Symmetry:
    """Result of the symmetry search along one axis (pixels of the analysed image).

    ``s_max[y]`` and ``h_max[y]`` are Eq. 2's best score and period per line over the shifts where ``S(y, .)``
    peaks (0 where no period fits);
    ``period`` is the repetition the lines agree on and ``prominence`` how far its line-averaged score rises over
    the trough at shorter shifts (0 = no repetition); ``rises[h]`` is that rise for every shift ``h`` searched
    (-inf elsewhere)."""

    s_max: np.ndarray
    h_max: np.ndarray
    period: int
    prominence: float
    rises: np.ndarray

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


def band_similarity(q: np.ndarray, y0: int, y1: int, shift: int, bins: int = BINS) -> float:
    """Eq. 1 between the quantised bands of rows ``[y0, y1)`` and ``[y0 + shift, y1 + shift)`` of ``q``; NaN when
    either band is empty or leaves the image."""
    rows = q.shape[0]
    if y1 <= y0 or min(y0, y0 + shift) < 0 or max(y1, y1 + shift) > rows:
        return float("nan")
    codes = q[y0:y1] * bins + q[y0 + shift:y1 + shift]
    return float(mutual_information(np.bincount(codes.ravel(), minlength=bins * bins).astype(float), bins))


def detect_symmetry(q: np.ndarray, lo: int, hi: int, bins: int = BINS) -> Symmetry:
    """Best period per line (§2.2) and the period of the repetition (our simplification of §2.3)."""
    rows = q.shape[0]
    hi = min(hi, rows // 2)
    if hi < max(lo, 2):
        return Symmetry(np.zeros(rows + 1), np.zeros(rows + 1, dtype=int), 0, 0.0, np.full(1, -np.inf))
    lo = max(lo, 2)
    heights = np.arange(max(lo // 2, 1), hi + 1)
    scores = symmetry_scores(q, heights, bins)
    valid = np.isfinite(scores)
    # a line's period is a peak of S(y, .): the range's lower bound cuts the slope that vertical pilasters give
    # every small shift (the paper's 3-5.5 m range has no such bound; ours is in fractions of the photo)
    both = np.where(valid, scores, -np.inf)
    peak = np.zeros_like(valid)
    peak[1:-1] = (both[1:-1] >= both[:-2]) & (both[1:-1] >= both[2:])
    filled = np.where(peak & valid & (heights >= lo)[:, None], scores, -np.inf)
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
    rises = np.concatenate([np.full(heights[0], -np.inf), prominence])
    return Symmetry(s_max, h_max, period, rise, rises)


def _fundamental(profile: np.ndarray, heights: np.ndarray, period: int) -> int:
    """The smallest integer fraction ``period/k`` that repeats about as well as ``period`` (MI of two floors
    against two floors is as high as of one against one)."""
    base = profile[period - heights[0]]
    for k in (4, 3, 2):
        h = int(round(period / k))
        if h >= heights[0] and profile[h - heights[0]] >= 0.85 * base:
            return h
    return period


@dataclass(frozen=True)
class Stacking:
    """The irreducible facade along one axis (§2.3): ``lines[k]`` are the original lines (rows or columns)
    stacked at line ``k`` of the collage, ``steps`` the ``(y, h, S_max)`` of each stacking in order (``y`` an
    original line)."""

    lines: tuple[tuple[int, ...], ...]
    steps: tuple[tuple[int, int, float], ...]

    @property
    def period(self) -> int:
        """The shift of the first (most similar) stacking, 0 when nothing was stacked."""
        return self.steps[0][1] if self.steps else 0


def irreducible(sym: Symmetry, stop: float = STOP) -> Stacking:
    """§2.3: starting from the image, repeatedly take the line ``y = argmax S_max(y)`` and shift the band
    ``R(y - h_max(y), h_max(y))`` over ``R(y, h_max(y))`` (its lines join the stacks below; the collage shrinks by
    ``h``); a stacked line keeps the minimum ``S_max`` (and its ``h_max``) of the two. Stops when no line whose
    bands fit in the collage exceeds ``stop * tau_max``."""
    n = sym.s_max.size - 1
    lines = [(y,) for y in range(n)]
    score, shift = list(sym.s_max[:n]), list(sym.h_max[:n])
    floor = stop * max(score, default=0.0)
    steps = []
    while True:
        fits = [k for k in range(len(lines)) if shift[k] > 0 and shift[k] <= k and k + shift[k] <= len(lines)
                and score[k] > floor]
        if not fits:
            return Stacking(tuple(lines), tuple(steps))
        k = max(fits, key=lambda j: score[j])
        h = int(shift[k])
        steps.append((lines[k][0], h, float(score[k])))
        for j in range(k, k + h):
            lines[j] = lines[j] + lines[j - h]
            if score[j - h] < score[j]:
                score[j], shift[j] = score[j - h], shift[j - h]
        del lines[k - h:k], score[k - h:k], shift[k - h:k]


def validated_period(sym: Symmetry, stack: Stacking) -> int:
    """The repetition's period checked against the irreducible facade: a prominence period ``k`` times (k = 2..4,
    within ``MULTIPLE``) the first stacking's shift spans ``k`` floors (tiles) and is replaced by that shift
    (a facade whose floors differ in detail repeats best over several of them on average, while its most similar
    pair of adjacent bands is one floor apart) -- provided the shift repeats across the facade too: its
    line-averaged rise is at least ``SUPPORT`` times the period's (the stripes of a roller shutter or blind stack
    best at a fraction of the floor but repeat only where they are)."""
    h = stack.period
    if 0 < h < sym.rises.size and sym.rises[h] >= SUPPORT * sym.prominence:
        for k in (2, 3, 4):
            if abs(sym.period - k * h) <= MULTIPLE * sym.period:
                return h
    return sym.period
