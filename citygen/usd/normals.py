"""Face normals of polygon meshes: every citygen mesh is hard-surface (planar walls, roof planes, frames), so each
polygon gets one normal (``uniform`` interpolation), indexed into the mesh's distinct normals.

Without authored normals importers pick their own: Blender's USD importer shades such meshes smooth, which blurs
every ridge, valley and window reveal into a gradient, and Omniverse's asset rules ask for normals on every mesh
that is not subdivided.
"""
from __future__ import annotations

import numpy as np

#: Normals are told apart on a grid of this step (about 0.014 degrees): the faces of one plane share one normal.
STEP = 2.0 ** -12
_NEXT, _LAST = [1, 2, 0], [2, 0, 1]


def polygon_normals(points: np.ndarray, counts: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """``(len(counts), 3)`` unit normals following the polygons' winding (Newell's method; for a mesh of quads
    only, as the welded walls are, the cross product of the diagonals, its equal for a planar quad; ``(0, 0, 1)``
    for a polygon of no area)."""
    n = len(counts)
    if not n:
        return np.zeros((0, 3))
    pts = np.asarray(points, dtype=float)
    if len(indices) == 4 * n and counts[0] == 4 and counts[-1] == 4 and not np.any(np.asarray(counts) - 4):
        p = pts[np.asarray(indices).reshape(n, 4)]
        a, b = p[:, 2] - p[:, 0], p[:, 3] - p[:, 1]
        normal = a[:, _NEXT] * b[:, _LAST] - a[:, _LAST] * b[:, _NEXT]  # a x b (np.cross is slow on small arrays)
    else:
        counts = np.asarray(counts, dtype=np.int64)
        p = pts[indices]
        start = np.cumsum(counts) - counts
        poly = np.repeat(np.arange(n), counts)
        q = p[start[poly] + (np.arange(len(indices)) - start[poly] + 1) % counts[poly]]
        normal = np.add.reduceat(np.column_stack([(p[:, 1] - q[:, 1]) * (p[:, 2] + q[:, 2]),
                                                  (p[:, 2] - q[:, 2]) * (p[:, 0] + q[:, 0]),
                                                  (p[:, 0] - q[:, 0]) * (p[:, 1] + q[:, 1])]), start, axis=0)
    length = np.sqrt(np.einsum("ij,ij->i", normal, normal))
    flat = length <= 1e-12
    normal[flat] = (0.0, 0.0, 1.0)
    length[flat] = 1.0
    return normal / length[:, None]


def indexed_face_normals(points: np.ndarray, counts: np.ndarray, indices: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray]:
    """The distinct face normals ``(k, 3) float32`` (on the ``STEP`` grid, renormalised) and per polygon its index
    ``(len(counts),) int32`` into them."""
    side = int(2 / STEP) + 1  # grid values -1/STEP .. 1/STEP, shifted to 0 .. side - 1
    grid = np.rint(polygon_normals(points, counts, indices) * (1 / STEP)).astype(np.int64) + side // 2
    keys, index = np.unique((grid[:, 0] * side + grid[:, 1]) * side + grid[:, 2], return_inverse=True)
    values = np.column_stack([keys // (side * side), keys // side % side, keys % side]) - side // 2.0
    values /= np.sqrt(np.einsum("ij,ij->i", values, values))[:, None]
    return values.astype(np.float32), index.astype(np.int32)
