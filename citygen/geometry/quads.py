"""Vectorised quad generation for boxes of face-local rectangles.

A *box* is a rectangle ``x0, y0, x1, y1`` pushed from the wall plane (z = 0) to ``z = d`` along the face normal.
Winding is chosen so normals point out of a protrusion (``d > 0``) and into the opening of a recess (``d < 0``);
the same vertex order serves both, which keeps the code branch-free.
"""
from __future__ import annotations

import numpy as np

# Corner selectors (index into x0,y0,x1,y1 columns, z side 0 = wall plane, 1 = depth) per side quad.
_SIDES = (
    ((0, 1, 0), (2, 1, 0), (2, 1, 1), (0, 1, 1)),  # bottom, y = y0
    ((2, 1, 0), (2, 3, 0), (2, 3, 1), (2, 1, 1)),  # right, x = x1
    ((2, 3, 0), (0, 3, 0), (0, 3, 1), (2, 3, 1)),  # top, y = y1
    ((0, 3, 0), (0, 1, 0), (0, 1, 1), (0, 3, 1)),  # left, x = x0
)
_FRONT = ((0, 1, 1), (2, 1, 1), (2, 3, 1), (0, 3, 1))


def _corners(rects: np.ndarray, depth: np.ndarray, spec) -> np.ndarray:
    """``(n, 4, 3)`` quad corners for ``n`` rectangles following a corner spec."""
    out = np.empty((len(rects), 4, 3))
    for k, (xi, yi, zi) in enumerate(spec):
        out[:, k, 0] = rects[:, xi]
        out[:, k, 1] = rects[:, yi]
        out[:, k, 2] = depth if zi else 0.0
    return out


def box_quads(rects: np.ndarray, depth: np.ndarray, front: bool = True, sides: bool = True,
              eps: float = 1e-6) -> np.ndarray:
    """Quads of boxes as an ``(m, 4, 3)`` array in face-local coordinates.

    ``rects`` is ``(n, 4)`` of ``x0, y0, x1, y1``; ``depth`` is ``(n,)``. Sides are emitted only where
    ``|depth| > eps``; the front quad sits at ``z = depth``.
    """
    rects = np.asarray(rects, dtype=float).reshape(-1, 4)
    depth = np.broadcast_to(np.asarray(depth, dtype=float), (len(rects),))
    parts = []
    if front:
        parts.append(_corners(rects, depth, _FRONT))
    if sides:
        deep = np.abs(depth) > eps
        if deep.any():
            r, d = rects[deep], depth[deep]
            parts += [_corners(r, d, spec) for spec in _SIDES]
    return np.concatenate(parts) if parts else np.zeros((0, 4, 3))


def to_world(quads: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Apply a 4x4 row-vector transform to ``(..., 3)`` points."""
    return quads @ matrix[:3, :3] + matrix[3, :3]


def weld(quads: np.ndarray, decimals: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Shared vertices for ``(m, 4, 3)`` quads: ``(points (k, 3) float32, indices (m*4,) int32)``.

    Vertices closer than ``10**-decimals`` metres merge, so adjacent wall pieces share their corners.
    """
    flat = quads.reshape(-1, 3)
    key = np.round(flat, decimals)
    points, inverse = np.unique(key, axis=0, return_inverse=True)
    return points.astype(np.float32), inverse.reshape(-1).astype(np.int32)
