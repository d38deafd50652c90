"""Face normals of polygon meshes: every citygen mesh is hard-surface (planar walls, roof planes, frames), so each
polygon gets one normal (``uniform`` interpolation), indexed into the mesh's distinct normals.

Without authored normals importers pick their own: Blender's USD importer shades such meshes smooth, which blurs
every ridge, valley and window reveal into a gradient, and Omniverse's asset rules ask for normals on every mesh
that is not subdivided.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from citygen.geometry.building import MeshData

#: Normals are told apart on a grid of this step (about 0.014 degrees): the faces of one plane share one normal.
STEP = 2.0 ** -12


def polygon_normals(points: np.ndarray, counts: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """``(len(counts), 3)`` unit normals following the polygons' winding, ``(0, 0, 1)`` for a polygon of no area.
    Triangles and quads (all the walls and nearly all roofs) take the cross product of the diagonals (a triangle as a
    quad with its last corner twice), which equals Newell's normal for a planar quad; other polygons Newell's (only
    they: a batch of many meshes with a few such polygons keeps the fast path for the rest)."""
    counts = np.asarray(counts, dtype=np.int64)
    if not counts.size:
        return np.zeros((0, 3))
    pts = np.asarray(points)
    if pts.dtype != np.float32:  # (float32 points are gathered as they are and widened in the subtraction)
        pts = np.asarray(pts, dtype=float)
    indices = np.asarray(indices)
    start = np.cumsum(counts) - counts
    if counts.min() >= 3 and counts.max() <= 4:
        normal = _diagonal_normals(pts, counts, indices, start)
    else:
        normal = np.empty((counts.size, 3))
        small = (counts >= 3) & (counts <= 4)
        normal[small] = _diagonal_normals(pts, counts[small], indices, start[small])
        other = np.flatnonzero(~small)
        corner = np.repeat(start[other] - np.cumsum(counts[other]) + counts[other], counts[other]) + \
            np.arange(counts[other].sum())
        normal[other] = _newell_normals(np.asarray(pts, dtype=float), counts[other], indices[corner])
    length = np.sqrt(np.einsum("ij,ij->i", normal, normal))
    flat = length <= 1e-12
    normal[flat] = (0.0, 0.0, 1.0)
    length[flat] = 1.0
    return normal / length[:, None]


def _diagonal_normals(pts: np.ndarray, counts: np.ndarray, indices: np.ndarray, start: np.ndarray) -> np.ndarray:
    """Unnormalised normals of triangles and quads (``start``: each one's first corner in ``indices``): the cross
    product of the diagonals from corner 0 to 2 and from corner 1 to the last, in float64. The corners are gathered
    from each coordinate column of ``pts`` as stored (float32 points: half the bytes to gather) and widened by the
    subtraction, which gives the bits of a subtraction of float64 copies (gathers of ``(n, 3)`` rows and np.cross
    take twice as long)."""
    columns = [pts[:, axis] for axis in range(3)]
    i0, i1, i2, i3 = indices[start], indices[start + 1], indices[start + 2], indices[start + counts - 1]
    ax, ay, az = (np.subtract(c[i2], c[i0], dtype=np.float64) for c in columns)
    bx, by, bz = (np.subtract(c[i3], c[i1], dtype=np.float64) for c in columns)
    normal = np.empty((len(start), 3))
    normal[:, 0], normal[:, 1], normal[:, 2] = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
    return normal


def _newell_normals(pts: np.ndarray, counts: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """Unnormalised Newell normals of polygons whose corners are ``indices``, one polygon after the other."""
    start = np.cumsum(counts) - counts
    p = pts[indices]
    poly = np.repeat(np.arange(counts.size), counts)
    q = p[start[poly] + (np.arange(len(indices)) - start[poly] + 1) % counts[poly]]
    return np.add.reduceat(np.column_stack([(p[:, 1] - q[:, 1]) * (p[:, 2] + q[:, 2]),
                                            (p[:, 2] - q[:, 2]) * (p[:, 0] + q[:, 0]),
                                            (p[:, 0] - q[:, 0]) * (p[:, 1] + q[:, 1])]), start, axis=0)


def face_normals(meshes: Sequence[MeshData]) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per mesh, its distinct face normals ``(k, 3) float32`` (on the ``STEP`` grid, renormalised, in grid order)
    and per polygon the index ``(len(counts),) int32`` into them. The meshes of one building or prototype are done
    in one batch (a mesh has ~20 polygons, too few for numpy calls of its own)."""
    meshes = list(meshes)
    if not meshes:
        return []
    sizes = np.array([len(m.counts) for m in meshes])
    offsets = np.cumsum([0] + [len(m.points) for m in meshes[:-1]])
    points = np.concatenate([m.points for m in meshes])
    counts = np.concatenate([m.counts for m in meshes])
    indices = np.concatenate([m.indices for m in meshes]).astype(np.int64)
    indices += np.repeat(offsets, [len(m.indices) for m in meshes])
    side = int(2 / STEP) + 1  # grid values -1/STEP .. 1/STEP, shifted to 0 .. side - 1
    grid = np.rint(polygon_normals(points, counts, indices) * (1 / STEP)).astype(np.int64) + side // 2
    key = (grid[:, 0] * side + grid[:, 1]) * side + grid[:, 2]
    # distinct (mesh, normal) pairs: sorted by mesh, so each mesh's normals are one run of them
    pairs, pair = np.unique(np.repeat(np.arange(len(meshes)), sizes) * side ** 3 + key, return_inverse=True)
    key = pairs % side ** 3
    table = np.column_stack([key // (side * side), key // side % side, key % side]) - side // 2.0
    table = (table / np.sqrt(np.einsum("ij,ij->i", table, table))[:, None]).astype(np.float32)
    first = np.searchsorted(pairs, np.arange(len(meshes) + 1) * side ** 3).tolist()
    local = (pair.reshape(-1) - np.repeat(first[:-1], sizes)).astype(np.int32)
    ends = np.cumsum(sizes).tolist()
    return [(table[first[k]:first[k + 1]], local[e - n:e]) for k, (n, e) in enumerate(zip(sizes.tolist(), ends))]
