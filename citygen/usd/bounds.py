"""Axis-aligned bounds for ``extent`` (meshes, PointInstancers) and ``extentsHint`` (models), as ``(2, 3)`` float
arrays ``[min, max]``; ``None`` is the empty bound."""
from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np


def points_bound(points: np.ndarray) -> np.ndarray | None:
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    return np.array([pts.min(axis=0), pts.max(axis=0)]) if len(pts) else None


def union(bounds: Iterable[np.ndarray | None]) -> np.ndarray | None:
    found = [b for b in bounds if b is not None]
    if not found:
        return None
    stacked = np.array(found)
    return np.array([stacked[:, 0].min(axis=0), stacked[:, 1].max(axis=0)])


def instances_bounds(proto_bounds: Sequence[np.ndarray | None], proto_indices: np.ndarray, positions: np.ndarray,
                     orientations: np.ndarray, scales: np.ndarray, sizes: Sequence[int]) -> list[np.ndarray | None]:
    """The bounds of PointInstancers' instances as USD composes them (scale, then rotate by the orientation
    quaternion ``(x, y, z, w)``, then translate), each instance's prototype bound given by ``proto_bounds``;
    orientations are taken at half precision, as the stage stores them. A rotated box's bound is its rotated
    centre plus ``|R|`` times its half size. The instancers' rows come one after the other (``sizes``: each one's
    number of rows) in one numpy pass; each bound is what the instancer alone would give."""
    found: list[np.ndarray | None] = [None] * len(sizes)
    known = np.array([b is not None for b in proto_bounds], dtype=bool)
    keep = known[proto_indices] if len(proto_indices) else np.zeros(0, dtype=bool)
    if not keep.any():
        return found
    boxes = np.array([b if b is not None else np.zeros((2, 3)) for b in proto_bounds])[proto_indices[keep]]
    scale = np.asarray(scales, dtype=float)[keep]
    centre, half = (boxes[:, 0] + boxes[:, 1]) * 0.5 * scale, np.abs((boxes[:, 1] - boxes[:, 0]) * 0.5 * scale)
    x, y, z, w = (np.asarray(orientations, dtype=np.float16).astype(float)[keep]).T
    norm = x * x + y * y + z * z + w * w
    s = np.where(norm > 0, 2.0 / np.where(norm > 0, norm, 1.0), 0.0)
    rot = np.empty((len(x), 3, 3))
    rot[:, 0, 0], rot[:, 0, 1], rot[:, 0, 2] = 1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w)
    rot[:, 1, 0], rot[:, 1, 1], rot[:, 1, 2] = s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w)
    rot[:, 2, 0], rot[:, 2, 1], rot[:, 2, 2] = s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y)
    middle = np.einsum("nij,nj->ni", rot, centre) + np.asarray(positions, dtype=float)[keep]
    reach = np.einsum("nij,nj->ni", np.abs(rot), half)
    kept = np.bincount(np.repeat(np.arange(len(sizes)), sizes)[keep], minlength=len(sizes))
    some = np.flatnonzero(kept)
    starts = (np.cumsum(kept) - kept)[some]
    low, high = np.minimum.reduceat(middle - reach, starts), np.maximum.reduceat(middle + reach, starts)
    for k, lo, hi in zip(some.tolist(), low, high):
        found[k] = np.array([lo, hi])
    return found
