"""Pitched roofs over arbitrary outlines, after CityEngine's roofHip, roofGable, roofPyramid and roofShed.

* ``hipped``: the straight skeleton's faces lifted by ``time x rise`` (every roof plane has the same pitch, every
  eave is at the wall top); courtyards and concave outlines follow from the skeleton.
* ``gabled``: the hipped roof whose *hip ends* -- triangular skeleton faces whose apex continues in exactly one
  ridge -- become vertical gable walls: the ridge is extended along its own line to the wall plane, so both roof
  planes next to it stay planar. Hip ends where the ridge would leave the edge (or a pyramid apex) stay hipped.
* ``pyramidal``: one apex over the centroid; outlines that are not star-shaped around it (or have courtyards) get
  the hipped roof instead, the same roof for a square.
* ``skillion``: one plane falling towards ``roof:direction`` (default: out over the longest edge), closed by
  vertical walls between the wall top and the plane.

Every mesh's open boundary is exactly the outline at the wall top, so it closes the facade walls; faces are
triangles wound outward. A failure raises :class:`RoofError`; the pipeline then builds a flat roof and warns.
"""
from __future__ import annotations

import math

import mapbox_earcut
import numpy as np
from shapely.geometry import MultiPolygon, Polygon
from shapely.geometry.polygon import orient

from citygen.geometry.building import MeshData
from citygen.registry import RoofBuilder
from citygen.roof import RoofSpec
from citygen_roofs.skeleton import SkeletonError, straight_skeleton


class RoofError(ValueError):
    """A pitched roof cannot be built for this outline."""


def _parts(outline: Polygon | MultiPolygon) -> list[Polygon]:
    parts = outline.geoms if isinstance(outline, MultiPolygon) else [outline]
    return [orient(p, sign=1.0) for p in parts]


def _triangulate(xy: np.ndarray, face: list[int]) -> list[tuple[int, int, int]]:
    """Ear-clipped triangles of one simple polygon (indices into ``xy``), counter-clockwise."""
    if len(face) == 3:
        return [tuple(face)]
    ring = xy[face]
    tris = mapbox_earcut.triangulate_float64(ring, np.array([len(face)], np.uint32)).reshape(-1, 3)
    return [(face[a], face[b], face[c]) for a, b, c in tris]


def _mesh(points: np.ndarray, roof_faces: list[list[int]], walls: list[list[int]]) -> MeshData:
    """Triangles of the (non-vertical) roof faces and the vertical walls, with unused points dropped."""
    tris = [t for f in roof_faces for t in _triangulate(points[:, :2], f)]
    for w in walls:
        tris += [(w[0], w[k], w[k + 1]) for k in range(1, len(w) - 1)]
    idx = np.asarray(tris, dtype=np.int64).reshape(-1, 3)
    used, inverse = np.unique(idx, return_inverse=True)
    return MeshData(points[used].astype(np.float32), np.full(len(idx), 3, np.int32),
                    inverse.reshape(-1).astype(np.int32))


def _merge(meshes: list[MeshData]) -> MeshData:
    offsets = np.cumsum([0] + [len(m.points) for m in meshes[:-1]])
    return MeshData(np.concatenate([m.points for m in meshes]), np.concatenate([m.counts for m in meshes]),
                    np.concatenate([m.indices + o for m, o in zip(meshes, offsets)]).astype(np.int32))


def _area(xy: np.ndarray) -> float:
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * float(x[:-1] @ y[1:] - x[1:] @ y[:-1] + x[-1] * y[0] - x[0] * y[-1])


def _rise(spec: RoofSpec, run: float) -> float:
    """Rise per metre for a roof whose highest point is ``run`` metres (horizontally) in from its eave."""
    if run <= 0:
        raise RoofError("outline too thin for a pitched roof")
    rise = spec.height / run if spec.height else spec.slope
    return min(rise, spec.cap / run)


def hip_faces(part: Polygon, top: float, spec: RoofSpec) -> tuple[np.ndarray, list[list[int]]]:
    """Lifted skeleton of one part: points ``(k, 3)`` and one face (node indices, CCW) per outline edge."""
    try:
        skeleton = straight_skeleton(part)
    except SkeletonError as exc:
        raise RoofError(f"no straight skeleton: {exc}") from exc
    rise = _rise(spec, float(skeleton.times.max()))
    points = np.column_stack([skeleton.nodes, top + skeleton.times * rise])
    faces = [list(f) for f in skeleton.faces]
    areas = np.array([_area(skeleton.nodes[f]) for f in faces])
    if np.any(areas < -1e-6 * part.area) or not math.isclose(areas.sum(), part.area, rel_tol=1e-6):
        raise RoofError(f"skeleton faces cover {areas.sum():.3f} m² of a {part.area:.3f} m² outline")
    return points, faces


def gable(points: np.ndarray, faces: list[list[int]], outline_nodes: int) -> tuple[np.ndarray, list[list[int]],
                                                                                 list[list[int]]]:
    """Turn hip ends into gable walls: returns points, roof faces and walls (``[a, b, apex]``, outward)."""
    neighbours: dict[int, set[int]] = {}
    owners: dict[int, int] = {}
    for f in faces:
        for k, n in enumerate(f):
            owners[n] = owners.get(n, 0) + 1
            neighbours.setdefault(n, set()).update((f[k - 1], f[(k + 1) % len(f)]))
    points = points.copy()
    roof, walls = [], []
    moved: dict[int, int] = {}
    for f in faces:
        apex = f[2] if len(f) == 3 else None
        ridge = [n for n in neighbours.get(apex, ()) if n >= outline_nodes] if apex is not None else []
        if apex is None or len(ridge) != 1 or owners[apex] != 3 or apex in moved:
            roof.append(f)
            continue
        a, b, p, q = points[f[0]], points[f[1]], points[apex], points[ridge[0]]
        d, e = p[:2] - q[:2], b[:2] - a[:2]
        det = d[0] * -e[1] + e[0] * d[1]
        if abs(det) < 1e-12:
            roof.append(f)
            continue
        rhs = a[:2] - q[:2]
        s = (rhs[0] * -e[1] + e[0] * rhs[1]) / det  # position along the ridge q -> p (1 at the apex)
        u = (d[0] * rhs[1] - d[1] * rhs[0]) / det  # position along the edge a -> b
        if s < 1 - 1e-9 or not 1e-6 < u < 1 - 1e-6:
            roof.append(f)
            continue
        points = np.vstack([points, q + s * (p - q)])
        moved[apex] = len(points) - 1
        walls.append([f[0], f[1], moved[apex]])
    roof = [[moved.get(n, n) for n in f] for f in roof]
    return points, roof, walls


def pyramid(part: Polygon, top: float, spec: RoofSpec) -> MeshData | None:
    """One apex over the centroid, or None when the outline has courtyards or is not star-shaped around it."""
    if part.interiors:
        return None
    ring = np.asarray(part.exterior.coords)[:-1, :2]
    c = np.asarray(part.centroid.coords[0])
    a, b = ring - c, np.roll(ring, -1, axis=0) - c
    cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    edge = np.hypot(*(b - a).T)
    run = float(np.min(cross / edge))  # distance from the centroid to the nearest edge line
    if run <= 1e-6 * math.sqrt(part.area):
        return None
    points = np.vstack([np.column_stack([ring, np.full(len(ring), top)]), [*c, top + run * _rise(spec, run)]])
    apex = len(ring)
    return _mesh(points, [[k, (k + 1) % apex, apex] for k in range(apex)], [])


def skillion(part: Polygon, top: float, spec: RoofSpec) -> MeshData:
    """One plane falling towards ``spec.direction`` over the part, with walls up to it."""
    rings = [np.asarray(r.coords)[:-1, :2] for r in (part.exterior, *part.interiors)]
    xy = np.concatenate(rings)
    if spec.direction is None:  # the slope faces out over the longest outer edge
        ext = rings[0]
        d = np.roll(ext, -1, axis=0) - ext
        k = int(np.argmax(np.hypot(d[:, 0], d[:, 1])))
        down = np.array([d[k, 1], -d[k, 0]]) / math.hypot(*d[k])
    else:
        angle = math.radians(spec.direction)
        down = np.array([math.sin(angle), math.cos(angle)])  # compass: 0 north (+y), 90 east (+x)
    along = xy @ down
    run = float(along.max() - along.min())
    rise = _rise(spec, run)
    lift = (along.max() - along) * rise
    n = len(xy)
    high = np.where(lift > 1e-6, np.arange(n) + n, np.arange(n))  # a point on the low eave is its own lift
    points = np.vstack([np.column_stack([xy, np.full(n, top)]), np.column_stack([xy, top + lift])])
    ends = np.cumsum([len(r) for r in rings]).astype(np.uint32)
    tris = mapbox_earcut.triangulate_float64(xy, ends).reshape(-1, 3)
    a, b, c = xy[tris[:, 0]], xy[tris[:, 1]], xy[tris[:, 2]]
    down_wound = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) < 0
    tris[down_wound] = tris[down_wound][:, ::-1]
    walls, first = [], 0
    for r in rings:
        for k in range(len(r)):
            i, j = first + k, first + (k + 1) % len(r)
            wall = [i, j] + [v for v in (high[j], high[i]) if v >= n]
            if len(wall) >= 3:
                walls.append(wall)
        first += len(r)
    return _mesh(points, [list(high[t]) for t in tris], walls)


class HippedRoof(RoofBuilder):
    id = "hipped"
    description = "hipped roof: straight-skeleton faces at one pitch (roof:angle, roof:height)"

    def build(self, outline: Polygon | MultiPolygon, top: float, spec: RoofSpec | None = None) -> MeshData:
        spec = spec or RoofSpec(self.id)
        meshes = []
        for part in _parts(outline):
            points, faces = hip_faces(part, top, spec)
            meshes.append(_mesh(points, faces, []))
        return _merge(meshes)


class GabledRoof(RoofBuilder):
    id = "gabled"
    description = "gabled roof: hipped roof with its hip ends turned into vertical gable walls"

    def build(self, outline: Polygon | MultiPolygon, top: float, spec: RoofSpec | None = None) -> MeshData:
        spec = spec or RoofSpec(self.id)
        meshes = []
        for part in _parts(outline):
            points, faces = hip_faces(part, top, spec)
            outline_nodes = sum(len(r.coords) - 1 for r in (part.exterior, *part.interiors))
            points, roof, walls = gable(points, faces, outline_nodes)
            meshes.append(_mesh(points, roof, walls))
        return _merge(meshes)


class PyramidalRoof(RoofBuilder):
    id = "pyramidal"
    description = "pyramidal roof: one apex over the centroid (hipped where the outline is not star-shaped)"

    def build(self, outline: Polygon | MultiPolygon, top: float, spec: RoofSpec | None = None) -> MeshData:
        spec = spec or RoofSpec(self.id)
        meshes = []
        for part in _parts(outline):
            mesh = pyramid(part, top, spec)
            if mesh is None:
                points, faces = hip_faces(part, top, spec)
                mesh = _mesh(points, faces, [])
            meshes.append(mesh)
        return _merge(meshes)


class SkillionRoof(RoofBuilder):
    id = "skillion"
    description = "skillion (shed) roof: one plane falling towards roof:direction, closed by walls"

    def build(self, outline: Polygon | MultiPolygon, top: float, spec: RoofSpec | None = None) -> MeshData:
        spec = spec or RoofSpec(self.id)
        return _merge([skillion(part, top, spec) for part in _parts(outline)])
