"""The floors at a facade's edges: an attic above the top row of windows, a basement row and a ground floor below
the bottom row.

The rows of windows in between repeat one another, so the parser's window probability and the floor period find
them whatever the parser's small errors; the two edge floors do not repeat, and until round 8 they were decided by
one probability threshold each at the photo's top and bottom -- the decisions that flipped when the parser was
retrained. Here each is decided by evidence integrated over its band:

* **Attic** (dormers, a gable's windows: too few for the row mean): the row's highest window probability (an
  ``ATTIC_BOX`` px box) above ``ATTIC_BASE``, summed over the rows of a run and divided by the rows' median height
  -- how much of a window row the run holds, strength and height together -- reaches ``ATTIC_MASS``. A row the
  crop's top cuts to a sliver holds less of it: where the floor band one pitch above the top row leaves the photo,
  a run holding ``SLIVER_MASS`` is a row when the band's visible part repeats the same part of the floor below at
  least ``SLIVER_MI`` times as strongly as that part repeats between the rows found (Eq. 1 on the part alone).
  The run needs wall between it and the top row (``ATTIC_WALL`` of a row's height: a transom on the row's windows
  is their glass) and its centre ``ATTIC_GAP`` pitches above the row's.
* **Basement** (cellar windows under the ground floor's, too few for the row mean): the attic's test on the
  facade turned upside down, where no band of shops stands on the ground.
* **Ground floor** (shops, an entrance, a plinth): the band below the bottom row is a floor when it is at least
  a pitch tall, or its shop + door probability summed over its rows reaches ``GROUND_SHOPS`` pitches (from
  ``GROUND_TALL`` pitches on, ``TALL_SHOPS``), or -- at least ``GROUND_LEAST`` pitches tall -- it repeats the same
  band one floor up less than
  ``GROUND_MI`` times as strongly as the floors repeat one another (mueller2007 §2.1, Eq. 1's mutual information
  of the intensity bands; the wall below a lowest row of windows repeats the wall below the row above it, a
  ground floor does not).
"""
from __future__ import annotations

from itertools import pairwise

import numpy as np
from scipy.ndimage import uniform_filter

from citygen_photo.labels import CMP_LABELS
from citygen_photo.lattice import Similarity, floor_similarity, part_similarity

DOOR, SHOP = (CMP_LABELS.index(n) for n in ("door", "shop"))
#: An attic run's centre lies at least ``ATTIC_GAP`` pitches above the top row's centre, the run at least
#: ``ATTIC_WALL`` row heights above the row (until round 14: the run cut off 0.6 pitches above the row's centre);
#: its rows' highest window probability, smoothed over ``ATTIC_BOX`` pixels, above ``ATTIC_BASE``, sums to
#: ``ATTIC_MASS`` row heights.
ATTIC_GAP = 0.5
ATTIC_WALL = 0.3
ATTIC_BOX = 5
ATTIC_BASE = 0.3
ATTIC_MASS = 0.08
#: The attic row spans the rows of that run where the peak reaches this (all of the run if none does).
ATTIC_ROW = 0.4
#: A run holding ``SLIVER_MASS`` row heights is the row the crop's top cuts when the visible part of that row's
#: floor band repeats the floor below at least ``SLIVER_MI`` times the same part's median MI between the rows.
SLIVER_MASS = 0.02
SLIVER_MI = 0.6
#: The band below the bottom row is a ground floor from a floor pitch on, whatever it holds; or when its rows'
#: mean shop + door probability sums to ``GROUND_SHOPS`` pitches (``TALL_SHOPS`` from ``GROUND_TALL`` pitches on) ...
GROUND_SHOPS = 0.12
GROUND_TALL = 0.7
TALL_SHOPS = 0.06
#: ... or, from ``GROUND_LEAST`` pitches on, when its MI with the band one pitch above is under this share of
#: the median MI between the rows' floor bands.
GROUND_LEAST = 0.3
GROUND_MI = 0.2

Span = tuple[float, float]


def with_attic(window: np.ndarray, rows: list[Span], pitch: float, similar: Similarity | None = None) -> list[Span]:
    """``rows`` (top to bottom) with an attic row put on top: the run of the smoothed window probability's row
    peak above ``ATTIC_BASE``, ``ATTIC_WALL`` row heights above the top row and its centre ``ATTIC_GAP`` pitches
    above the row's, that holds the most of it, when that reaches ``ATTIC_MASS`` of the rows' median height -- or,
    a row the crop's top cuts (``similar``: the MI of two intensity bands, see :func:`cut_row_repeats`),
    ``SLIVER_MASS``."""
    if not rows or pitch <= 0:
        return rows
    height = float(np.median([y1 - y0 for y0, y1 in rows]))
    top = rows[0][0] - ATTIC_WALL * height
    if top <= 2:
        return rows
    peak = uniform_filter(window[:int(top)], ATTIC_BOX, mode="nearest").max(axis=1)
    excess = np.clip(peak - ATTIC_BASE, 0.0, None)
    above = np.concatenate([[0], (excess > 0).astype(np.int8), [0]])
    edges = np.flatnonzero(np.diff(above))
    highest = (rows[0][0] + rows[0][1]) / 2 - ATTIC_GAP * pitch
    runs = [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2]) if (a + b) / 2 <= highest]
    if not runs:
        return rows
    a, b = max(runs, key=lambda s: excess[s[0]:s[1]].sum())
    mass = excess[a:b].sum() / height
    if mass < ATTIC_MASS and not (mass >= SLIVER_MASS and similar is not None
                                  and cut_row_repeats(rows, pitch, similar, a)):
        return rows
    row = a + np.flatnonzero(peak[a:b] >= ATTIC_ROW)
    return [(float(row[0]), float(row[-1] + 1)) if row.size else (float(a), float(b)), *rows]


def with_basement(window: np.ndarray, rows: list[Span], pitch: float) -> list[Span]:
    """``rows`` with a row of basement windows put below the bottom row: the attic's test
    (:func:`with_attic`) on the facade turned upside down."""
    h = window.shape[0]
    found = with_attic(window[::-1], [(h - b, h - a) for a, b in reversed(rows)], pitch)
    return [(h - b, h - a) for a, b in reversed(found)]


def cut_row_repeats(rows: list[Span], pitch: float, similar: Similarity, start: float) -> bool:
    """Whether the row one ``pitch`` above the top row of ``rows`` is one the crop's top cuts (its floor band leaves
    the photo, part of it is inside, and a run starting at ``start`` lies in that part) whose visible part repeats
    the same part of the floor below at least ``SLIVER_MI`` times as strongly as that part repeats between the
    rows (mueller2007 Eq. 1 on the part: a floor band cut by the crop is still a floor band)."""
    centre = (rows[0][0] + rows[0][1]) / 2 - pitch
    half = pitch / 2
    if not centre - half < 0 < centre + half or start >= centre + half:
        return False
    floors = part_similarity(rows, -centre, half, similar)
    band = similar(0.0, centre + half, pitch)
    return bool(floors) and np.isfinite(band) and band >= SLIVER_MI * floors


def ground_floor(prob: np.ndarray, rows: list[Span], pitch: float, shops: float | None,
                 similar: Similarity | None = None) -> float | None:
    """The top (working pixels, y down) of the ground floor below the bottom row of ``rows``, None without one:
    halfway down to ``shops`` (the top of a band of shops standing on the ground), else half the rows' median gap
    below the bottom row; a floor by its height, its shop + door probability or its MI with the band one pitch
    above (``similar``; see the module)."""
    h = prob.shape[0]
    if not rows or pitch <= 0:
        return None
    if shops is not None:
        top = max((rows[-1][1] + shops) / 2, rows[-1][1])
    else:
        gap = float(np.median([a - b for (_, b), (a, _) in pairwise(rows)])) if len(rows) > 1 else 0.1 * h
        top = rows[-1][1] + max(gap, 0.0) / 2
    share = (h - top) / pitch
    if h - top < 2:
        return None
    if share >= 1.0:
        return top
    shop_door = prob[round(top):, :, SHOP] + prob[round(top):, :, DOOR]
    if shop_door.mean(axis=1).sum() >= (TALL_SHOPS if share >= GROUND_TALL else GROUND_SHOPS) * pitch:
        return top
    if share < GROUND_LEAST or similar is None:
        return None
    floors = floor_similarity(rows, pitch, similar)
    band = similar(top, float(h), -pitch)
    return top if floors and np.isfinite(band) and band < GROUND_MI * floors else None
