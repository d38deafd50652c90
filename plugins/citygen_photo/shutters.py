"""Closed shutters for training the U-Net: a training photo's open shutters stretched over some of its windows.

CMP's training photos show blinds mostly as open shutters beside a window (71 % of the blind pixels of
cmp_b0061-0260) and rarely closed over the opening (25 %, on 25 photos); a closed shutter is a window-shaped blind
the parser then calls a window. :func:`closed_shutters` makes more of them from the photo itself: the pixels of a
window are replaced by one of the photo's own blind patches resized to the window's box, and labelled blind.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from citygen_photo.labels import CMP_LABELS

WINDOW = CMP_LABELS.index("window") + 1
BLIND = CMP_LABELS.index("blind") + 1
#: Parts smaller than this many pixels on either side are ignored (label noise, slivers at the crop's edge).
LEAST_SIDE = 3


@dataclass(frozen=True)
class ShutterParts:
    """The boxes (row slice, column slice) of a label map's blind and window components."""

    blinds: tuple[tuple[slice, slice], ...]
    windows: tuple[tuple[slice, slice], ...]


def _boxes(mask: np.ndarray) -> tuple[tuple[slice, slice], ...]:
    found = ndimage.find_objects(ndimage.label(mask)[0])
    return tuple(box for box in found if box is not None
                 and min(box[0].stop - box[0].start, box[1].stop - box[1].start) >= LEAST_SIDE)


def shutter_parts(labels: np.ndarray) -> ShutterParts:
    """The blind and window components of the label map ``labels`` (ids 1..12)."""
    return ShutterParts(_boxes(labels == BLIND), _boxes(labels == WINDOW))


def closed_shutters(work: np.ndarray, labels: np.ndarray, parts: ShutterParts, rng: np.random.Generator,
                    share: float) -> tuple[np.ndarray, np.ndarray]:
    """``work`` (H, W, 3) and ``labels`` with each window of ``parts`` closed with probability ``share``: its
    window pixels take a random blind patch of the same photo, resized (nearest) to the window's box, and the
    blind label. A photo without blinds or windows comes back unchanged (not copied)."""
    if not parts.blinds or not parts.windows:
        return work, labels
    work, labels = work.copy(), labels.copy()
    for rows, cols in parts.windows:
        if rng.random() >= share:
            continue
        src = work[parts.blinds[rng.integers(len(parts.blinds))]]
        h, w = rows.stop - rows.start, cols.stop - cols.start
        patch = src[np.arange(h) * src.shape[0] // h][:, np.arange(w) * src.shape[1] // w]
        region, lab = work[rows, cols], labels[rows, cols]
        glass = lab == WINDOW
        region[glass] = patch[glass]
        lab[glass] = BLIND
    return work, labels
