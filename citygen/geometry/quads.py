"""Vectorised quad generation for boxes of face-local rectangles.

A *box* is a rectangle ``x0, y0, x1, y1`` pushed from the wall plane (z = 0) to ``z = d`` along the face normal.
Winding is chosen so normals point out of a protrusion (``d > 0``) and into the opening of a recess (``d < 0``);
the same vertex order serves both, which keeps the code branch-free.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

# Quad corners as indices into a rect's x0, y0, x1, y1 columns plus a flag for z (0 = wall plane, 1 = depth).
_FRONT = np.array([[(0, 1, 1), (2, 1, 1), (2, 3, 1), (0, 3, 1)]])
_SIDES = np.array([
    [(0, 1, 0), (2, 1, 0), (2, 1, 1), (0, 1, 1)],  # bottom, y = y0
    [(2, 1, 0), (2, 3, 0), (2, 3, 1), (2, 1, 1)],  # right, x = x1
    [(2, 3, 0), (0, 3, 0), (0, 3, 1), (2, 3, 1)],  # top, y = y1
    [(0, 3, 0), (0, 1, 0), (0, 1, 1), (0, 3, 1)],  # left, x = x0
])


def _corners(rects: np.ndarray, depth: np.ndarray, spec: np.ndarray) -> np.ndarray:
    """``(n * k, 4, 3)`` quad corners of ``n`` rectangles for a ``(k, 4, 3)`` corner spec."""
    out = np.empty((len(rects), len(spec), 4, 3))
    out[..., :2] = rects[:, spec[..., :2]]
    out[..., 2] = depth[:, None, None] * spec[..., 2]
    return out.reshape(-1, 4, 3)


def box_quads(rects: np.ndarray, depth: np.ndarray, front: bool = True, sides: bool = True,
              eps: float = 1e-6) -> np.ndarray:
    """Quads of boxes as an ``(m, 4, 3)`` array in face-local coordinates.

    ``rects`` is ``(n, 4)`` of ``x0, y0, x1, y1``; ``depth`` is ``(n,)``. Sides are emitted only where
    ``|depth| > eps``; the front quad sits at ``z = depth``.
    """
    rects = np.asarray(rects, dtype=float).reshape(-1, 4)
    depth = np.asarray(depth, dtype=float)
    if depth.shape != (len(rects),):  # (a scalar depth; broadcast_to costs more than the quads of a few boxes)
        depth = np.broadcast_to(depth, (len(rects),))
    parts = [_corners(rects, depth, _FRONT)] if front else []
    if sides:
        deep = np.abs(depth) > eps
        if deep.any():
            parts.append(_corners(rects[deep], depth[deep], _SIDES))
    return np.concatenate(parts) if len(parts) > 1 else (parts[0] if parts else np.zeros((0, 4, 3)))


def box_quads_grouped(rects: np.ndarray, depth: np.ndarray, groups: np.ndarray,
                      eps: float = 1e-6) -> tuple[np.ndarray, np.ndarray]:
    """:func:`box_quads` of many groups of boxes in one batch: ``(quads (m, 4, 3), group of every quad)``.

    ``rects`` are sorted by ``groups`` (``(n,)`` ints); the quads come out grouped the same way, and a group's
    quads are those ``box_quads`` gives for the group's boxes alone, in the same order (fronts, then sides).
    """
    front = _corners(rects, depth, _FRONT)
    deep = np.abs(depth) > eps
    sides = _corners(rects[deep], depth[deep], _SIDES)
    rank = np.concatenate([2 * groups, np.repeat(2 * groups[deep] + 1, len(_SIDES))])
    order = np.argsort(rank, kind="stable")
    return np.concatenate([front, sides])[order], rank[order] >> 1


def merge_rects(rects: np.ndarray, eps: float = 1e-6) -> np.ndarray:
    """Fewer rectangles covering the same area: runs touching along x merge, then runs touching along y.

    ``rects`` is ``(n, 4)`` of ``x0, y0, x1, y1`` (a set of disjoint rectangles of one material and depth).
    Wall pieces between the windows of a floor collapse into strips, which is most of a facade mesh's polygons.
    """
    rects = np.asarray(rects, dtype=float).reshape(-1, 4)
    return merge_rects_grouped(rects, np.zeros(len(rects), np.int64), eps)[0]


def merge_rects_grouped(rects: np.ndarray, groups: np.ndarray, eps: float = 1e-6) -> tuple[np.ndarray, np.ndarray]:
    """:func:`merge_rects` of many groups in one batch (rectangles merge only within their group): the merged
    ``(rects, groups)``, sorted by group; a group's rectangles are those ``merge_rects`` gives for it alone."""
    for lo, hi, a, b in ((0, 2, 1, 3), (1, 3, 0, 2)):  # merge along x within rows, then along y within columns
        if len(rects) < 2:
            break
        order = np.lexsort((rects[:, lo], rects[:, b], rects[:, a], groups))
        r, g = rects[order], groups[order]
        joined = ((g[1:] == g[:-1]) & (np.abs(r[1:, a] - r[:-1, a]) < eps) & (np.abs(r[1:, b] - r[:-1, b]) < eps)
                  & (np.abs(r[1:, lo] - r[:-1, hi]) < eps))
        starts = np.flatnonzero(np.concatenate([[True], ~joined]))
        rects = r[starts]
        rects[:, hi] = np.maximum.reduceat(r[:, hi], starts)
        groups = g[starts]
    return rects, groups


def to_world(quads: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Apply a 4x4 row-vector transform to ``(..., 3)`` points (as one ``(n, 3)`` product: a stack of quads would
    be multiplied quad by quad)."""
    return (quads.reshape(-1, 3) @ matrix[:3, :3]).reshape(quads.shape) + matrix[3, :3]


def weld(quads: np.ndarray, decimals: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Shared vertices for ``(m, 4, 3)`` quads: ``(points (k, 3) float32, indices (m*4,) int32)``.

    Vertices within ``10**-decimals`` metres merge, so adjacent wall pieces share their corners. Coordinates are
    snapped to that grid relative to the quads' minimum corner and packed into one int64 key per vertex (21 bits
    per axis: extents up to 2 km at 1 mm), which keeps the unique step a 1-D sort; larger extents (a 10 km tower)
    take the row-wise unique, which orders the vertices the same way (x, then y, then z).
    """
    flat = quads.reshape(-1, 3)
    if not len(flat):
        return np.zeros((0, 3), np.float32), np.zeros(0, np.int32)
    step = 10.0 ** -decimals
    origin = flat.min(axis=0)
    grid = np.rint((flat - origin) / step).astype(np.int64)
    if grid.max() < 1 << 21:
        key = (grid[:, 0] << 42) | (grid[:, 1] << 21) | grid[:, 2]
        _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    else:
        _, first, inverse = np.unique(grid, axis=0, return_index=True, return_inverse=True)
    points = origin + grid[first] * step
    return points.astype(np.float32), inverse.reshape(-1).astype(np.int32)


def weld_many(quads: list[np.ndarray], decimals: int = 3, parts: Sequence[int] | None = None
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`weld` of each ``(m, 4, 3)`` array of ``quads`` (vertices merge only within their array) in one batch:
    ``(points, indices, point bounds, index bounds)``, array ``k``'s points ``points[pb[k]:pb[k + 1]]`` and indices
    (into them) ``indices[ib[k]:ib[k + 1]]`` being exactly those ``weld`` gives for it alone.

    With ``parts``, mesh ``k`` is the next ``parts[k]`` arrays of ``quads`` joined (not concatenated first)."""
    parts = [1] * len(quads) if parts is None else list(parts)
    bounds = np.cumsum([0, *parts]).tolist()
    pieces = [4 * len(q) for q in quads]
    sizes = [sum(pieces[bounds[k]:bounds[k + 1]]) for k in range(len(parts))]
    index_bounds = np.cumsum([0, *sizes])
    step = 10.0 ** -decimals
    flat = np.concatenate(quads).reshape(-1, 3) if quads else np.zeros((0, 3))
    mesh = np.repeat(np.arange(len(parts)), sizes)
    starts = index_bounds[:-1][np.asarray(sizes, dtype=np.int64) > 0]
    origin = np.zeros((len(parts), 3))
    if len(flat):
        origin[mesh[starts]] = np.minimum.reduceat(flat, starts, axis=0)
    grid = np.rint((flat - origin[mesh]) / step).astype(np.int64)
    top = int(np.max(grid, initial=0))
    if top >= 1 << 21:  # (a mesh too large for one int64 key per vertex: each on its own)
        alone = [weld(flat[index_bounds[k]:index_bounds[k + 1]].reshape(-1, 4, 3), decimals)
                 for k in range(len(parts))]
        return (np.concatenate([p for p, _ in alone]), np.concatenate([i for _, i in alone]),
                np.cumsum([0, *(len(p) for p, _ in alone)]), index_bounds)
    # one int64 key per vertex ordered by (mesh, x, y, z): the axes packed in as few bits as the largest grid
    # value needs, the mesh above them (else the axes' 21-bit key, sorted by mesh then key)
    bits = top.bit_length()
    if 3 * bits + max(len(parts) - 1, 0).bit_length() <= 63:
        key = (((mesh << bits) | grid[:, 0]) << bits | grid[:, 1]) << bits | grid[:, 2]
        order = np.argsort(key, kind="stable")
        sorted_key = key[order]
        new = np.ones(len(order), dtype=bool)
        new[1:] = sorted_key[1:] != sorted_key[:-1]
    else:
        key = (grid[:, 0] << 42) | (grid[:, 1] << 21) | grid[:, 2]
        order = np.lexsort((key, mesh))
        sorted_key, sorted_mesh = key[order], mesh[order]
        new = np.ones(len(order), dtype=bool)
        new[1:] = (sorted_key[1:] != sorted_key[:-1]) | (sorted_mesh[1:] != sorted_mesh[:-1])
    first = order[new]
    inverse = np.empty(len(order), np.int64)
    inverse[order] = np.cumsum(new) - 1
    point_bounds = np.searchsorted(mesh[first], np.arange(len(parts) + 1))
    points = (origin[mesh[first]] + grid[first] * step).astype(np.float32)
    return points, (inverse - point_bounds[mesh]).astype(np.int32), point_bounds, index_bounds
