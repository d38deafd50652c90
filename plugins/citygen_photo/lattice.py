"""Rows of windows checked against the floor period (mueller2007 §2.2: floors repeat at the period the mutual
information finds).

The rows come from the window probability alone (:mod:`citygen_photo.regular`); the period is independent
evidence from the photo's intensities. Where the mutual-information period is the rows' pitch or a multiple of it
(two floors repeating as one), the rows are checked against the pitch's lattice: a row closer than a floor to
each neighbour (a shop sign's lettering, a mezzanine strip above the shops) is dropped, and one pitch above the
top row (below the bottom row) a row is put where the parser saw none -- a dormer of closed shutters, a row of
blinds -- if the floor band there repeats its neighbour's band as strongly as the facade's own floors repeat each
other (Eq. 1's mutual information of the two bands).
"""
from __future__ import annotations

from collections.abc import Callable
from itertools import pairwise

import numpy as np

#: The MI period confirms the rows' pitch when it is 1, 2 or 3 pitches within this share.
AGREE = 0.15
#: Two rows are a floor apart when their spacing is at least ``1 - OFF`` pitches.
OFF = 0.3
#: A lattice position beyond the end rows becomes a row when its floor band's MI with its neighbour's band
#: reaches this share of the median MI between the bands of the rows found.
FILL = 0.9

Span = tuple[float, float]
#: ``similar(y0, y1, shift)``: MI of the intensity bands ``[y0, y1)`` and ``[y0 + shift, y1 + shift)`` (working
#: pixels; NaN when a band leaves the photo).
Similarity = Callable[[float, float, float], float]


def confirms(pitch: float, period: float | None) -> bool:
    """Whether the MI ``period`` is one, two or three ``pitch`` es (within ``AGREE``)."""
    return bool(period) and pitch > 0 and any(abs(period - k * pitch) <= AGREE * k * pitch for k in (1, 2, 3))


def on_lattice(rows: list[Span], pitch: float) -> list[Span]:
    """``rows`` without those closer than ``1 - OFF`` pitches to every neighbour, when at least three rows are
    left. (A spacing of 1.4 pitches is kept: a row the shop glass below it pulls down is a row.)"""
    centres = [(a + b) / 2 for a, b in rows]

    def fits(d: float) -> bool:
        return d >= (1 - OFF) * pitch

    kept = [row for i, row in enumerate(rows)
            if any(fits(abs(centres[i] - centres[j])) for j in (i - 1, i + 1) if 0 <= j < len(rows))]
    return kept if len(kept) >= 3 else rows


def floor_similarity(rows: list[Span], pitch: float, similar: Similarity) -> float | None:
    """The median MI between the floor bands (a ``pitch`` tall, centred on the rows) of consecutive ``rows``; None
    when no pair fits in the photo or the floors do not repeat (median <= 0)."""
    return part_similarity(rows, -pitch / 2, pitch / 2, similar)


def part_similarity(rows: list[Span], start: float, stop: float, similar: Similarity) -> float | None:
    """The median MI between the bands ``[c + start, c + stop)`` of consecutive ``rows`` (``c``: a row's centre):
    how strongly that part of a floor repeats in the floor below; None as :func:`floor_similarity`."""
    mi = [similar((a + b) / 2 + start, (a + b) / 2 + stop, (c + d) / 2 - (a + b) / 2)
          for (a, b), (c, d) in pairwise(rows)]
    mi = [s for s in mi if np.isfinite(s)]
    return float(np.median(mi)) if mi and np.median(mi) > 0 else None


def lattice_rows(rows: list[Span], pitch: float, period: float | None, similar: Similarity | None,
                 bottom: float) -> list[Span]:
    """``rows`` (top to bottom, working pixels) checked against the pitch's lattice where the MI ``period``
    confirms it: rows squeezed between floors dropped, rows put back one pitch at a time above the top row (down
    to the photo's top) and below the bottom row (above ``bottom``, the ground floor's band of shops or the photo's
    bottom) while ``similar`` finds the floor band there repeating its neighbour's. Unchanged with fewer than
    three rows."""
    if len(rows) < 3 or similar is None or not confirms(pitch, period):
        return rows
    rows = on_lattice(rows, pitch)
    half = pitch / 2
    floors = floor_similarity(rows, pitch, similar)
    if floors is None:  # (the floors found do not repeat: nothing to compare a band with)
        return rows
    strong = FILL * floors
    height = float(np.median([b - a for a, b in rows]))
    out = list(rows)
    while True:
        centre = (out[0][0] + out[0][1]) / 2 - pitch
        if centre - half < 0 or not similar(centre - half, centre + half, pitch) >= strong:
            break
        out.insert(0, (centre - height / 2, centre + height / 2))
    while True:
        centre = (out[-1][0] + out[-1][1]) / 2 + pitch
        if centre + half > bottom or not similar(centre - half, centre + half, -pitch) >= strong:
            return out
        out.append((centre - height / 2, centre + height / 2))
