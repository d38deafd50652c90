"""Axis-aligned bounds for ``extent`` (meshes, PointInstancers) and ``extentsHint`` (models), as ``(2, 3)`` float
arrays ``[min, max]``; ``None`` is the empty bound."""
from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

#: The 8 corners of a unit box, as (0 | 1) weights of its max corner.
_CORNERS = np.array([[i >> 2 & 1, i >> 1 & 1, i & 1] for i in range(8)], dtype=float)


def points_bound(points: np.ndarray) -> np.ndarray | None:
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    return np.array([pts.min(axis=0), pts.max(axis=0)]) if len(pts) else None


def union(bounds: Iterable[np.ndarray | None]) -> np.ndarray | None:
    found = [b for b in bounds if b is not None]
    if not found:
        return None
    stacked = np.array(found)
    return np.array([stacked[:, 0].min(axis=0), stacked[:, 1].max(axis=0)])


def instances_bound(proto_bounds: Sequence[np.ndarray | None], proto_indices: np.ndarray, positions: np.ndarray,
                    orientations: np.ndarray, scales: np.ndarray) -> np.ndarray | None:
    """The bound of a PointInstancer's instances as USD composes them (scale, then rotate by the orientation
    quaternion ``(x, y, z, w)``, then translate), each instance's prototype bound given by ``proto_bounds``;
    orientations are taken at half precision, as the stage stores them."""
    if not len(proto_indices):
        return None
    known = np.array([b is not None for b in proto_bounds])
    keep = known[proto_indices]
    if not keep.any():
        return None
    boxes = np.array([b if b is not None else np.zeros((2, 3)) for b in proto_bounds])[proto_indices[keep]]
    corners = boxes[:, 0, None, :] + _CORNERS[None] * (boxes[:, 1] - boxes[:, 0])[:, None, :]  # (n, 8, 3)
    corners = corners * np.asarray(scales, dtype=float)[keep][:, None, :]
    quat = np.asarray(orientations, dtype=np.float16).astype(float)[keep]
    quat = quat / np.linalg.norm(quat, axis=1, keepdims=True)
    q, w = quat[:, None, :3], quat[:, None, 3:]
    t = 2.0 * np.cross(q, corners)
    rotated = corners + w * t + np.cross(q, t)
    placed = rotated + np.asarray(positions, dtype=float)[keep][:, None, :]
    flat = placed.reshape(-1, 3)
    return np.array([flat.min(axis=0), flat.max(axis=0)])
