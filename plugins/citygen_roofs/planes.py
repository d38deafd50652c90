"""Roofs made of planar pieces: the outline cut by straight lines into pieces, each piece lifted onto one plane.

Where two pieces meet at different heights (a sawtooth's glazed step) a vertical wall stands between them; along
the outline vertical walls close the gap between the wall top and the roof. Used by the OSM shapes of
:mod:`citygen_roofs.osm_shapes` (saltbox, side_hipped, crosspitched: lower/upper envelopes of edge planes;
butterfly; sawtooth).

The mesh closes the facade walls like every roof: its open boundary is the outline's edges at the wall top, one
mesh edge per outline edge. Where the roof comes down to the wall top inside an outline edge (a butterfly's valley
or a sawtooth's gutter meeting a wall) the closing wall is pinched there; its pieces are joined along their foot by
zero-area triangles on the wall top, so the foot stays one edge.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from itertools import pairwise

import numpy as np
import shapely
from shapely.geometry import LineString, Polygon
from shapely.geometry.polygon import orient

from citygen.geometry.building import MeshData
from citygen.roof import RoofSpec
from citygen_roofs.pitched import RoofError, _cracks, _triangulate, welded_mesh

#: A plane ``z = gx x + gy y + c`` (metres above the wall top) as ``(gx, gy, c)``.
Plane = np.ndarray
#: A line ``(point, direction)``.
Line = tuple[np.ndarray, np.ndarray]


def edge_plane(a: np.ndarray, b: np.ndarray, slope: float) -> Plane:
    """The plane through the edge ``a -> b`` at the wall top rising at ``slope`` to its left (inward for a
    counter-clockwise ring)."""
    d = (b - a) / math.hypot(*(b - a))
    n = np.array([-d[1], d[0]]) * slope
    return np.array([n[0], n[1], -float(n @ a)])


def crease(p: Plane, q: Plane) -> Line | None:
    """The line over which planes ``p`` and ``q`` are at the same height, or None when they are parallel."""
    g = p[:2] - q[:2]
    norm = float(g @ g)
    if norm < 1e-18:
        return None
    return -(p[2] - q[2]) * g / norm, np.array([-g[1], g[0]])


def envelope(planes: list[Plane], lowest: bool = True) -> tuple[list[Line], Callable[[np.ndarray], Plane]]:
    """The creases of every pair of ``planes`` and the function giving the lowest (``lowest``) or highest of them
    at a point: cut along the creases, each piece lies on one plane."""
    stack = np.array(planes)
    lines = [line for i in range(len(planes)) for j in range(i + 1, len(planes))
             if (line := crease(planes[i], planes[j])) is not None]
    pick = np.argmin if lowest else np.argmax
    return lines, lambda p: stack[int(pick(stack @ np.array([p[0], p[1], 1.0])))]


def piecewise_roof(part: Polygon, top: float, spec: RoofSpec, cuts: list[Line],
                   plane_at: Callable[[np.ndarray], Plane]) -> MeshData:
    """The roof over ``part`` cut along ``cuts`` (and a line through each courtyard, so no piece surrounds one),
    each piece on ``plane_at`` (its point on surface); heights scaled so the highest point is at ``roof:height``
    when given, never above ``spec.cap``; vertical walls where pieces meet at different heights and between the
    wall top and the roof along the outline."""
    if not part.is_valid or part.area <= 0:
        raise RoofError("the outline is not a valid polygon")
    part = orient(part, sign=1.0)
    x0, y0, x1, y1 = part.bounds
    size = max(1.0, x1 - x0, y1 - y0)
    # snap rounding: a cut along an outline edge is that edge, not a sliver beside it, and vertices closer than the
    # mesh's float32 points can tell apart (creases crossing near one point) are one vertex
    grid_size = max(2.5e-8 * size, 8 * float(np.spacing(np.float32(max(map(abs, part.bounds))))))
    tol = 4 * grid_size
    centre, reach = np.array([(x0 + x1) / 2, (y0 + y1) / 2]), 2.0 * math.hypot(x1 - x0, y1 - y0) + 1.0
    lines = [LineString(r.coords) for r in (part.exterior, *part.interiors)]
    along = cuts[0][1] if cuts else np.array([1.0, 0.0])
    cuts = cuts + [(np.asarray(Polygon(r).representative_point().coords[0]), along) for r in part.interiors]
    for point, d in cuts:
        d = d / math.hypot(*d)
        mid = point + ((centre - point) @ d) * d
        lines.append(LineString([mid - reach * d, mid + reach * d]))
    cells = shapely.get_parts(shapely.polygonize(shapely.get_parts(shapely.unary_union(lines, grid_size=grid_size))))
    faces = [orient(f, 1.0) for f in cells if part.contains(f.representative_point())]
    if any(f.interiors for f in faces):
        raise RoofError("a roof piece surrounds a courtyard")
    if abs(sum(f.area for f in faces) - part.area) > grid_size * part.length:
        raise RoofError("the roof's pieces do not cover the outline")
    grid = _Grid(tol, 0.75 * grid_size, part)
    rings = [[grid.vertex(p) for p in np.asarray(f.exterior.coords)[:-1, :2]] for f in faces]
    planes = [plane_at(np.asarray(f.representative_point().coords[0])) for f in faces]
    xy = np.array(grid.xy)
    heights = [xy @ p[:2] + p[2] for p in planes]  # per face, at every vertex
    used = np.concatenate([h[ring] for h, ring in zip(heights, rings)])
    if used.min() < -tol * (1 + max(math.hypot(*p[:2]) for p in planes)):  # off the line by snapping, no more
        raise RoofError("the roof would dip below the wall top")
    high = float(used.max())
    if high <= 0:
        raise RoofError("the roof has no height")
    scale = min((spec.height or high) / high, spec.cap / high)
    heights = [top + np.where(h * scale > tol, h * scale, 0.0) for h in heights]  # within tol of the wall top: on it
    owner = {(r[k], r[(k + 1) % len(r)]): f for f, r in enumerate(rings) for k in range(len(r))}
    walls = _WallBuilder(grid, heights, owner, top)
    roof = [[grid.point(v, heights[f][v]) for v in r] for f, r in enumerate(rings)]
    for (a, b), f in owner.items():
        if (b, a) in owner:
            walls.step(a, b, f, owner[b, a])
    for ring in (part.exterior, *part.interiors):
        xy_ring = np.asarray(ring.coords)[:, :2]
        for u, v in pairwise(xy_ring):
            walls.outline(grid.find(u), grid.find(v))
    if walls.unused():
        raise RoofError("the roof's pieces leave outline edges unwalled")
    points = np.array(grid.points)
    snapped = np.array(grid.snapped)[grid.of]  # pieces triangulated as cut (placing can make a ring touch itself)
    tris = [t for ring in roof for t in _triangulate(snapped, ring)]
    tris += [t for ring in walls.rings for t in _wall_triangles(points, ring)] + walls.bridges
    mesh = welded_mesh(points, tris)
    cracks = _cracks(mesh, top, part, sum(len(r.coords) - 1 for r in (part.exterior, *part.interiors)))
    if cracks:
        raise RoofError(f"the roof's pieces leave {cracks} open edge(s) above the eaves")
    return mesh


class _Grid:
    """Vertices of the cut outline (snapped, put back on the outline) and the mesh points over them, one per vertex
    and height (heights within ``tol`` are one point)."""

    def __init__(self, tol: float, snap: float, part: Polygon) -> None:
        self.tol, self.snap = tol, snap
        rings = [np.asarray(r.coords)[:, :2] for r in (part.exterior, *part.interiors)]
        self.corners = np.concatenate([r[:-1] for r in rings])
        self.starts, self.sides = self.corners, np.concatenate([np.diff(r, axis=0) for r in rings])
        self.xy: list[tuple[float, float]] = []
        self.snapped: list[tuple[float, float]] = []
        self.ids: dict[tuple[float, float], int] = {}
        self.points: list[tuple[float, float, float]] = []
        self.over: dict[int, list[int]] = {}  # vertex -> its points
        self.of: list[int] = []  # point -> its vertex

    def vertex(self, p: np.ndarray) -> int:
        """The vertex at the snapped point ``p``, put back where snapping moved it off the outline: on the outline
        corner or onto the outline edge it lies within ``snap`` of (so the roof covers the outline exactly)."""
        key = (float(p[0]), float(p[1]))
        if key not in self.ids:
            self.ids[key] = len(self.xy)
            self.snapped.append(key)
            self.xy.append(self._placed(p))
        return self.ids[key]

    def _placed(self, p: np.ndarray) -> tuple[float, float]:
        gaps = np.hypot(*(self.corners - p).T)
        if gaps.min() <= self.snap:
            return tuple(map(float, self.corners[gaps.argmin()]))
        s = np.clip(np.einsum("ij,ij->i", p - self.starts, self.sides) / np.einsum("ij,ij->i", self.sides, self.sides),
                    0.0, 1.0)
        foot = self.starts + s[:, None] * self.sides
        gaps = np.hypot(*(foot - p).T)
        return tuple(map(float, foot[gaps.argmin()] if gaps.min() <= self.snap else p))

    def find(self, p: np.ndarray) -> int:
        """The vertex at an outline corner."""
        gaps = np.hypot(*(np.array(self.xy) - p).T)
        if gaps.min() > self.tol:
            raise RoofError("an outline corner is lost where the roof is cut")
        return int(gaps.argmin())

    def point(self, v: int, z: float) -> int:
        for k in self.over.setdefault(v, []):
            if abs(self.points[k][2] - z) <= self.tol:
                return k
        self.points.append((*self.xy[v], float(z)))
        self.of.append(v)
        self.over[v].append(len(self.points) - 1)
        return len(self.points) - 1

    def upright(self, ring: list[int]) -> list[int]:
        """``ring`` without repeated points, every vertical side split at the points over its vertex between its
        ends (so walls meeting at a vertex share their sides)."""
        out: list[int] = []
        for k, p in enumerate(ring):
            q = ring[(k + 1) % len(ring)]
            if out and out[-1] == p:
                continue
            out.append(p)
            if q != p and self.of[p] == self.of[q]:
                zp, zq = self.points[p][2], self.points[q][2]
                between = [m for m in self.over[self.of[p]] if min(zp, zq) < self.points[m][2] < max(zp, zq)]
                out += sorted(between, key=lambda m: self.points[m][2], reverse=zq < zp)
        while len(out) > 1 and out[-1] == out[0]:
            out.pop()
        return out


class _WallBuilder:
    """Vertical walls: between pieces at different heights and between the wall top and the roof."""

    def __init__(self, grid: _Grid, heights: list[np.ndarray], owner: dict[tuple[int, int], int], top: float):
        self.grid, self.heights, self.top = grid, heights, top
        self.free: dict[int, list[tuple[int, int]]] = {}  # outline vertex -> (next vertex, face) along the outline
        for (a, b), f in owner.items():
            if (b, a) not in owner:
                self.free.setdefault(a, []).append((b, f))
        self.rings: list[list[int]] = []
        self.bridges: list[tuple[int, int, int]] = []

    def step(self, a: int, b: int, f: int, g: int) -> None:
        """The wall along ``a -> b`` where face ``f`` (on its left) stands above face ``g``."""
        h, k = self.heights[f], self.heights[g]
        da, db = h[a] - k[a], h[b] - k[b]
        tol = self.grid.tol
        if max(da, db) <= tol:
            return
        if min(da, db) < -tol:
            raise RoofError("two roof pieces cross along the line between them")
        p = self.grid.point
        self.rings.append(self.grid.upright([p(a, k[a]), p(b, k[b]), p(b, h[b]), p(a, h[a])]))

    def outline(self, u: int, v: int) -> None:
        """The wall over the outline edge ``u -> v``: from its foot at the wall top up to the roof, in lobes
        where the roof comes down to the wall top inside the edge, joined along the foot."""
        chain, at, p = [], u, self.grid.point
        while at != v:
            nxt = self.free.get(at)
            if not nxt:
                raise RoofError("the roof's pieces do not follow the outline")
            d = np.subtract(self.grid.xy[v], self.grid.xy[at])
            b, f = max(nxt, key=lambda e: _cosine(np.subtract(self.grid.xy[e[0]], self.grid.xy[at]), d))
            nxt.remove((b, f))
            chain += [p(at, self.heights[f][at]), p(b, self.heights[f][b])]
            at = b
        chain = [q for k, q in enumerate(chain) if k == 0 or q != chain[k - 1]]
        foot_u, foot_v = p(u, self.top), p(v, self.top)
        pinches = [k for k in range(1, len(chain) - 1) if chain[k] == p(self.grid.of[chain[k]], self.top)]
        cuts = [0, *pinches, len(chain) - 1]
        for s, e in pairwise(cuts):
            start = foot_u if s == 0 else chain[s]
            end = foot_v if e == len(chain) - 1 else chain[e]
            ring = self.grid.upright([start, end, *chain[s:e + 1][::-1]])
            if len(ring) >= 3:
                self.rings.append(ring)
        feet = [chain[k] for k in pinches]
        for w, x in zip([foot_v, *feet[::-1]], feet[::-1]):
            self.bridges.append((foot_u, w, x))

    def unused(self) -> bool:
        return any(self.free.values())


def _cosine(a: np.ndarray, b: np.ndarray) -> float:
    return float(a @ b) / max(math.hypot(*a) * math.hypot(*b), 1e-300)


def _wall_triangles(points: np.ndarray, ring: list[int]) -> list[tuple[int, int, int]]:
    """Triangles of a vertical wall ``ring`` whose first side runs along its foot, in the wall's plane."""
    a = points[ring[0], :2]
    d = next(points[n, :2] - a for n in ring[1:] if np.hypot(*(points[n, :2] - a)) > 0)
    u = d / math.hypot(*d)
    local = np.column_stack([(points[ring, :2] - a) @ u, points[ring, 2]])
    return [(ring[i], ring[j], ring[k]) for i, j, k in _triangulate(local, list(range(len(ring))))]
