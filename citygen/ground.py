"""The ground under the city: one quad where every building stands at one height, else a terrain that meets
every building's foot.

Data with real elevations (CityJSON's LoD1 blocks, OSM parts with a ``base``) put each building at its own
ground height. A flat quad at the lowest of them left the others floating up to the data's spread above it
(Delft: 0.95 m, a dark slot under every facade). The terrain is instead a triangulation (scipy's Delaunay) of the
buildings' outlines, sampled every ``SPACING`` metres at their own ground heights, and of the quad's rim at the
height of the nearest outline: along a wall it runs at the building's foot, between buildings it slopes from one
to the next. Where outlines of different heights meet (a terrace's party walls) it takes the highest, so a
building sinks a few centimetres rather than floats. Triangles inside a footprint are left out.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import shapely

from citygen.geometry.building import MeshData

#: Metres between the outline samples of the terrain.
SPACING = 1.0
#: Metres between the rim samples of the terrain.
RIM_SPACING = 20.0
#: Most samples of one outline, or of one side of the rim (a huge outline's samples are spaced wider).
MOST_SAMPLES = 4096
#: Ground heights closer than this (metres) are one: a flat city gets the quad.
FLAT = 1e-3
#: Samples closer than this (metres) are one point of the terrain.
WELD = 0.01


def ground_mesh(bounds: Sequence[float], feet: Sequence[tuple[bytes, float]], lowest: float) -> MeshData:
    """The ground over ``bounds`` (``x0, y0, x1, y1``) under buildings standing at ``feet`` (each an outline as
    WKB and its ground height): the flat quad at the lowest height when all are one (at ``lowest`` when there are
    none), else the terrain."""
    x0, y0, x1, y1 = map(float, bounds)
    heights = np.array([z for _, z in feet], dtype=float)
    low = float(heights.min()) if len(heights) else float(lowest)
    if not len(heights) or float(heights.max()) - low <= FLAT:
        return MeshData(np.array([[x0, y0, low], [x1, y0, low], [x1, y1, low], [x0, y1, low]], dtype=np.float32),
                        np.array([4], dtype=np.int32), np.arange(4, dtype=np.int32))
    from scipy.spatial import Delaunay, cKDTree  # (only for a terrain: a flat city's run never imports it)

    outlines = shapely.from_wkb([outline for outline, _ in feet])
    rings = shapely.boundary(outlines)
    spacing = np.maximum(SPACING, shapely.length(rings) / MOST_SAMPLES)
    xy, owner = shapely.get_coordinates(shapely.segmentize(rings, spacing), return_index=True)
    z = heights[owner]
    keys = np.rint(xy / WELD).astype(np.int64)
    keys, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    top = np.full(len(keys), -np.inf)
    np.maximum.at(top, inverse.ravel(), z)  # (where outlines meet, the highest foot)
    xy, owner = xy[first], owner[first]
    rim = _rim(x0, y0, x1, y1)
    _, nearest = cKDTree(xy).query(rim)
    points = np.vstack([np.column_stack([xy, top]), np.column_stack([rim, top[nearest]])])
    owner = np.concatenate([owner, np.full(len(rim), -1)])
    triangles = Delaunay(points[:, :2]).simplices
    triangles = triangles[~_inside(points, owner, triangles, outlines)]
    a, b, c = (points[triangles[:, k], :2] for k in range(3))
    ab, ac = b - a, c - a
    clockwise = ab[:, 0] * ac[:, 1] - ab[:, 1] * ac[:, 0] < 0
    triangles[clockwise] = triangles[clockwise][:, ::-1]
    return MeshData(points.astype(np.float32), np.full(len(triangles), 3, np.int32),
                    triangles.astype(np.int32).ravel())


def _rim(x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    """Points every ``RIM_SPACING`` metres round the rectangle, its corners included."""
    nx, ny = (int(np.clip(np.ceil(d / RIM_SPACING), 1, MOST_SAMPLES)) for d in (x1 - x0, y1 - y0))
    xs, ys = np.linspace(x0, x1, nx + 1), np.linspace(y0, y1, ny + 1)
    inner = ys[1:-1]
    return np.vstack([np.column_stack([xs, np.full_like(xs, y0)]), np.column_stack([xs, np.full_like(xs, y1)]),
                      np.column_stack([np.full_like(inner, x0), inner]),
                      np.column_stack([np.full_like(inner, x1), inner])])


def _inside(points: np.ndarray, owner: np.ndarray, triangles: np.ndarray, outlines: np.ndarray) -> np.ndarray:
    """Which triangles have all corners on one outline and their centroid inside it (hidden by the building)."""
    own = owner[triangles]
    one = (own[:, 0] >= 0) & (own[:, 0] == own[:, 1]) & (own[:, 1] == own[:, 2])
    hidden = np.zeros(len(triangles), dtype=bool)
    picked = np.flatnonzero(one)
    if not len(picked):
        return hidden
    centroid = points[triangles[picked], :2].mean(axis=1)
    hidden[picked] = shapely.contains_xy(outlines[own[picked, 0]], centroid[:, 0], centroid[:, 1])
    return hidden
