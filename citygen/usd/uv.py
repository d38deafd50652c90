"""Texture coordinates in metres: every polygon mapped onto its own plane.

A polygon's ``u`` runs along the horizontal direction of its plane (left to right seen from outside: along a wall,
along a roof's eave) and ``v`` up its slope (up a wall, up a roof; across a flat roof), both in metres, so a
texture of a metre-sized pattern (brick, plaster, tiles) tiles at true scale on every face and lines up across
the faces of one wall. Face-varying: corners shared by faces of different planes get one value per face.
"""
from __future__ import annotations

import numpy as np

from citygen.usd.normals import polygon_normals


def planar_st(points: np.ndarray, counts: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """``(len(indices), 2) float32`` texture coordinates (faceVarying) of a polygon mesh."""
    counts = np.asarray(counts, dtype=np.int64)
    if not counts.size:
        return np.zeros((0, 2), np.float32)
    p = np.asarray(points, dtype=float)[indices]
    poly = np.repeat(np.arange(counts.size), counts)
    normal = polygon_normals(points, counts, indices)
    horizontal = np.hypot(normal[:, 0], normal[:, 1])
    level = horizontal < 1e-9  # a flat face: u along x
    tangent = np.column_stack([np.where(level, 1.0, -normal[:, 1] / np.where(level, 1.0, horizontal)),
                               np.where(level, 0.0, normal[:, 0] / np.where(level, 1.0, horizontal)),
                               np.zeros(counts.size)])
    up = np.cross(normal, tangent)
    return np.column_stack([np.einsum("ij,ij->i", p, tangent[poly]),
                            np.einsum("ij,ij->i", p, up[poly])]).astype(np.float32)
