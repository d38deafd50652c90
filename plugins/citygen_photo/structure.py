"""Floors and tiles: splitting lines from edge interest functions (mueller2007 §2.4, Eq. 3-6).

Horizontal splitting lines go where horizontal edges are dense and vertical edges rare (minima of ``Ver(y)``),
vertical ones in the opposite case (minima of ``Hor(x)``). Among the local minima the subset with the lowest
mean interest whose spacing fits the detected repetition is found exhaustively by dynamic programming (Eq. 5/6);
the first and last gap may differ (an irregular ground floor, attic or facade margin).
"""
from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d

#: Eq. 3: weight of the full gradient subtracted from one directional derivative.
ALPHA = 0.9
#: Eq. 4: weight of the perpendicular edge density.
BETA = 0.1
#: Interior gaps must lie within this fraction of the detected period (the paper's 3-5.5 m floor range).
GAP_TOLERANCE = 0.25
#: The first and last gap may be up to this many periods (irregular ground floor / attic / margin).
END_GAP = 1.6


def edge_functions(gray: np.ndarray, alpha: float = ALPHA) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 3: ``hor(x, y)`` and ``ver(x, y)``, the horizontal- and vertical-edge responses."""
    gy, gx = np.gradient(gray)
    g2 = gx * gx + gy * gy
    return np.maximum(gy * gy - alpha * g2, 0.0), np.maximum(gx * gx - alpha * g2, 0.0)


def interest(along: np.ndarray, across: np.ndarray, sigma: float) -> np.ndarray:
    """Eq. 4 for one axis: ``along`` is the edge response that forbids a line there (summed over the other axis
    already), ``across`` the one that favours it."""
    return gaussian_filter1d(along, sigma, mode="nearest") - BETA * gaussian_filter1d(across, sigma, mode="nearest")


def local_minima(values: np.ndarray) -> np.ndarray:
    inner = (values[1:-1] <= values[:-2]) & (values[1:-1] < values[2:])
    return np.flatnonzero(inner) + 1


def split_lines(values: np.ndarray, period: int, lo: int = 0, hi: int | None = None,
                min_end: int = 1) -> np.ndarray:
    """Eq. 5/6: interior splitting lines in ``(lo, hi)`` minimising the mean of ``values``.

    Candidates are the local minima of ``values`` and the best-phase lattice of ``period`` (so a solution always
    exists); consecutive lines are ``period * (1 +- GAP_TOLERANCE)`` apart, the first and last gap (to ``lo`` and
    ``hi``) between ``min_end`` and ``END_GAP * period``. Returns sorted positions including ``lo`` and ``hi``."""
    hi = values.size if hi is None else hi
    span = hi - lo
    if period <= 0 or span < 2 * min_end + 1:
        return np.array([lo, hi])
    cand = local_minima(values[lo:hi]) + lo
    phase = min(range(period), key=lambda p: values[lo + p: hi: period].mean() if lo + p < hi else np.inf)
    cand = np.unique(np.concatenate([cand, np.arange(lo + phase, hi, period)]))
    cand = cand[(cand - lo >= min_end) & (hi - cand >= min_end)]
    if cand.size == 0:
        return np.array([lo, hi])
    v = values[cand]
    gap = cand[None, :] - cand[:, None]
    ok = (gap >= (1 - GAP_TOLERANCE) * period) & (gap <= (1 + GAP_TOLERANCE) * period)
    start = cand - lo <= END_GAP * period
    end = hi - cand <= END_GAP * period
    n = cand.size
    kmax = int(span / ((1 - GAP_TOLERANCE) * period)) + 2
    best = np.where(start, v, np.inf)
    back = []
    result, best_mean = None, np.inf
    for k in range(1, kmax + 1):
        if np.isfinite(best).any():
            finals = np.where(end, best, np.inf)
            j = int(np.argmin(finals))
            if np.isfinite(finals[j]) and finals[j] / k <= best_mean + 1e-12:  # ties: more lines
                best_mean, result = finals[j] / k, (k, j)
        trans = np.where(ok, best[:, None], np.inf)
        prev = trans.argmin(axis=0)
        best = trans[prev, np.arange(n)] + v
        back.append(prev)
    if result is None:
        return np.array([lo, hi])
    k, j = result
    chosen = [j]
    for step in range(k - 1, 0, -1):
        j = int(back[step - 1][j])
        chosen.append(j)
    return np.concatenate([[lo], np.sort(cand[chosen]), [hi]]).astype(int)
