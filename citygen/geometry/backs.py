"""What stands behind a facade's attachments: the wall, except where an opening stands on a balcony.

A window or door whose bottom edge lies on a balcony's top edge, within the balcony's span, is the balcony's door:
it reaches down behind the railing to the slab, and the balcony's back wall is cut around it. This is how
CMP-style layouts (and the shipped rulesets) draw a balcony: the railing's region, the French window above it.
Everything here is numpy over all of a building's terminals at once.
"""
from __future__ import annotations

import numpy as np

from citygen.geometry.prototypes import balcony_heights

#: How far apart (metres) an opening's bottom and a balcony's top may be and still touch.
TOUCH = 1e-3
#: Faces are narrower than this (metres): it separates the units' ranges in one sort key.
_SPAN = 1e5


def balcony_doors(rects: np.ndarray, units: np.ndarray, balcony: np.ndarray, opening: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Which ``opening`` terminal stands on which ``balcony`` terminal of its unit: ``(openings, balconies)``,
    index pairs into ``rects`` (``(n, 4)`` x0 y0 x1 y1), sorted by balcony, then left to right."""
    b, o = np.flatnonzero(balcony), np.flatnonzero(opening)
    if not len(b) or not len(o):
        return np.zeros(0, np.intp), np.zeros(0, np.intp)
    # Balconies sorted by one float key: the rank of their (unit, top edge), then their left edge.
    q_b = np.rint(rects[b, 3] / TOUCH).astype(np.int64)
    group_b = units[b].astype(np.int64) << 32 | q_b
    groups, rank = np.unique(group_b, return_inverse=True)
    key_b = rank.ravel() * _SPAN + rects[b, 0]
    order = np.argsort(key_b, kind="stable")
    key_b, b = key_b[order], b[order]
    pair = np.full(len(o), -1, np.intp)
    q_o = np.rint(rects[o, 1] / TOUCH).astype(np.int64)
    for dq in (0, -1, 1):  # (an edge within TOUCH may round to the next step)
        group_o = units[o].astype(np.int64) << 32 | (q_o + dq)
        at = np.minimum(np.searchsorted(groups, group_o), len(groups) - 1)
        k = np.searchsorted(key_b, at * _SPAN + rects[o, 0] + TOUCH, side="right") - 1
        k = np.maximum(k, 0)
        cand = b[k]
        hit = ((pair < 0) & (units[cand] == units[o]) & (np.abs(rects[cand, 3] - rects[o, 1]) <= TOUCH)
               & (rects[cand, 0] <= rects[o, 0] + TOUCH) & (rects[cand, 2] >= rects[o, 2] - TOUCH))
        pair[hit] = cand[hit]
    found = pair >= 0
    o, pair = o[found], pair[found]
    order = np.lexsort((rects[o, 0], pair))
    return o[order], pair[order]


def balcony_backs(rects: np.ndarray, units: np.ndarray, attachment: np.ndarray, doors: np.ndarray,
                  under: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(rects, back_rects, back_units)``: the terminals with each door (``doors[k]`` standing on balcony
    ``under[k]``, from :func:`balcony_doors`) reaching down to its balcony's slab, and the wall behind every
    ``attachment``: its whole rect, or a balcony's around its doors (the strip behind the slab, the stretches
    between the doors)."""
    plain = attachment.copy()
    plain[under] = False
    backs, back_units = [rects[plain]], [units[plain]]
    if len(doors):
        rects = rects.copy()
        slab = rects[under, 1] + balcony_heights(rects[under, 3] - rects[under, 1])[0]
        rects[doors, 1] = slab
        first = np.r_[True, under[1:] != under[:-1]]
        last = np.r_[under[1:] != under[:-1], True]
        left = np.where(first, rects[under, 0], np.roll(rects[doors, 2], 1))
        gaps = np.concatenate([np.column_stack([left, slab, rects[doors, 0], rects[under, 3]]),
                               np.column_stack([rects[doors, 2], slab, rects[under, 2], rects[under, 3]])[last]])
        balconies = under[first]
        strips = np.column_stack([rects[balconies, :3], slab[first]])
        pieces = np.concatenate([strips, gaps])
        keep = pieces[:, 2] - pieces[:, 0] > 1e-6
        backs.append(pieces[keep])
        back_units.append(np.concatenate([units[balconies], units[under], units[under][last]])[keep])
    return rects, np.concatenate(backs), np.concatenate(back_units)
