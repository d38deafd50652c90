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
* ``mansard``, ``gambrel``, ``dome``, ``round``: the hipped (gambrel, round: gabled) roof with a piecewise-linear
  :func:`profile`;
  every skeleton face is cut into planar bands where the profile breaks.

Every mesh's open boundary is exactly the outline at the wall top, so it closes the facade walls; faces are
triangles wound outward. A failure raises :class:`RoofError`; the pipeline then builds a flat roof and warns.
"""
from __future__ import annotations

import math
from dataclasses import replace

import mapbox_earcut
import numpy as np
from shapely.geometry import MultiPolygon, Polygon
from shapely.geometry.polygon import orient

from citygen.geometry.building import MeshData
from citygen.registry import RoofBuilder
from citygen.roof import ORIENTATIONS, RoofSpec, inscribed_radius, note, rectangle_like
from citygen_roofs.skeleton import SkeletonError, straight_skeleton


#: Pitch (degrees) of the steep lower slopes of mansard and gambrel roofs, unless the roof's pitch is steeper.
MANSARD_LOWER = 60.0
#: Bands (planar rings of faces) approximating a dome's profile.
DOME_BANDS = 6
#: half-hipped: the gable wall rises to this share of the ridge's height, a small hip above it
HALF_HIP = 0.6


class RoofError(ValueError):
    """A pitched roof cannot be built for this outline."""


def _parts(outline: Polygon | MultiPolygon, party: tuple[int, ...] = ()) -> list[tuple[Polygon, frozenset[int]]]:
    """The outline's parts (oriented) with the indices, within each part, of its party-wall edges."""
    out, first = [], 0
    for part in (outline.geoms if isinstance(outline, MultiPolygon) else [outline]):
        n = sum(len(r.coords) - 1 for r in (part.exterior, *part.interiors))
        out.append((orient(part, sign=1.0), frozenset(k - first for k in party if first <= k < first + n)))
        first += n
    return out


def ridge_orientation(part: Polygon, spec: RoofSpec) -> str | None:
    """``roof:orientation``, else the one ``roof:direction`` gives a rectangle-like (counter-clockwise) part: the
    main face slopes down towards that compass direction, so the ridge runs parallel to the side facing it --
    ``along`` when that is a long side, ``across`` when a short one (OSM's alternative tags; a square building can
    only be told by the direction)."""
    if spec.orientation is not None or spec.direction is None or not rectangle_like(part):
        return spec.orientation
    d = np.diff(np.asarray(part.exterior.coords)[:, :2], axis=0)
    length, angle = np.hypot(*d.T), math.radians(spec.direction)
    facing = int(np.argmax((d[:, 1] * math.sin(angle) - d[:, 0] * math.cos(angle)) / length))  # outward . compass
    short = 0 if length[0] + length[2] <= length[1] + length[3] else 1
    return "across" if facing % 2 == short else "along"


def edge_weights(part: Polygon, party: frozenset[int], orientation: str | None, gables: bool) -> np.ndarray:
    """Per outline edge its speed in the weighted straight skeleton; 0 makes it a vertical gable wall.

    A rectangle-like part has *ends*, the two sides the ridge runs towards: the short ones for ``roof:orientation``
    ``along``, the long ones ``across``; untagged, the pair holding the party walls (the ridge runs perpendicular
    to them, as in a terrace). Ends are gables (0) for a gabled roof or where they are party walls, else hips: at
    the pitch when they are the short sides, steeper when the long ones (weight ``(short / long)^2``: the ridge is
    as long, relative to the side it runs along, as on the short sides). The other two sides slope even where they
    are party walls (a tag wins). Anywhere else party walls get 0, the rest 1."""
    n = sum(len(r.coords) - 1 for r in (part.exterior, *part.interiors))
    weights = np.ones(n)
    if orientation is None and party and rectangle_like(part) and len({k % 2 for k in party}) == 1:
        ends = min(party) % 2
    elif orientation in ORIENTATIONS and rectangle_like(part):
        ends = None
    else:
        weights[list(party)] = 0.0
        return weights
    xy = np.asarray(part.exterior.coords)[:, :2]
    length = np.hypot(*np.diff(xy, axis=0).T)
    pair = np.array([length[0] + length[2], length[1] + length[3]])
    short = 0 if pair[0] <= pair[1] else 1
    if ends is None:
        ends = short if orientation == "along" else 1 - short
    hip = 1.0 if ends == short else float(pair[short] / pair[1 - short]) ** 2
    for k in (ends, ends + 2):
        weights[k] = 0.0 if gables or k in party else hip
    return weights


def _triangulate(xy: np.ndarray, face: list[int]) -> list[tuple[int, int, int]]:
    """Ear-clipped triangles of one simple polygon (indices into ``xy``), counter-clockwise, with no zero-area
    triangle: a polygon with collinear points (break points on a cut line) gets its slivers flipped away."""
    if len(face) == 3:
        return [tuple(face)]
    ring = xy[face]
    cut = mapbox_earcut.triangulate_float64(ring, np.array([len(face)], np.uint32)).reshape(-1, 3)
    tris = [(face[a], face[b], face[c]) for a, b, c in cut.tolist()]
    small = 1e-12 * float((ring.max(axis=0) - ring.min(axis=0)).max()) ** 2  # (np.ptp's own arithmetic)
    thin = _thin_corners(ring[cut], small)
    for _ in range(len(tris)):
        if not thin.any():
            break
        sliver = int(np.argmax(thin))
        t = tris[sliver]
        longest = max(range(3), key=lambda k: float(np.hypot(*(xy[t[k]] - xy[t[k - 1]]))))
        c, a = t[longest - 1], t[longest]  # the sliver is (a, b, c) with b on the long side c -> a
        b = t[(longest + 1) % 3]
        other = next((k for k, u in enumerate(tris) if k != sliver and any(
            (u[m], u[(m + 1) % 3]) == (a, c) for m in range(3))), None)
        if other is None:
            break
        u = tris[other]
        d = next(n for n in u if n not in (a, c))
        tris[sliver], tris[other] = (a, b, d), (b, c, d)
        thin[[sliver, other]] = _thin(xy, [tris[sliver], tris[other]], small)
    return tris


def _thin(xy: np.ndarray, tris: list[tuple[int, int, int]], small: float) -> np.ndarray:
    """Per triangle whether its area is below ``small``: :func:`_area` of every triangle at once (the same
    differences to the first corner and the same products, so the same verdicts)."""
    return _thin_corners(xy[np.asarray(tris, dtype=np.int64).reshape(-1, 3)], small)


def _thin_corners(p: np.ndarray, small: float) -> np.ndarray:
    """:func:`_thin` of triangles given by their corners ``(n, 3, 2+)``."""
    x1, y1 = p[:, 1, 0] - p[:, 0, 0], p[:, 1, 1] - p[:, 0, 1]
    x2, y2 = p[:, 2, 0] - p[:, 0, 0], p[:, 2, 1] - p[:, 0, 1]
    return np.abs(0.5 * (x1 * y2 - x2 * y1)) < small


def _mesh(points: np.ndarray, roof_faces: list[list[int]], walls: list[list[int]]) -> MeshData:
    """Triangles of the (non-vertical) roof faces and the vertical walls as float32, points that round to the same
    float32 point welded (triangles they collapse dropped: their sides cancel, the mesh stays closed) and unused
    points dropped."""
    tris = [t for f in roof_faces for t in _triangulate(points[:, :2], f)]
    for w in walls:  # in the wall's plane: along its foot a -> b, and up (counter-clockwise there is outward)
        a, b = points[w[0], :2], points[w[1], :2]
        u = (b - a) / math.hypot(*(b - a))
        tris += _triangulate(np.column_stack([(points[:, :2] - a) @ u, points[:, 2]]), w)
    return welded_mesh(points, tris)


def welded_mesh(points: np.ndarray, tris: list[tuple[int, int, int]] | np.ndarray) -> MeshData:
    """Triangles over ``points`` as float32 with points that round to the same float32 point welded (triangles they
    collapse dropped) and unused points dropped."""
    welded, weld = np.unique(points.astype(np.float32), axis=0, return_inverse=True)
    idx = weld.reshape(-1)[np.asarray(tris, dtype=np.int64).reshape(-1, 3)]
    idx = idx[(idx[:, 0] != idx[:, 1]) & (idx[:, 1] != idx[:, 2]) & (idx[:, 2] != idx[:, 0])]
    used, inverse = np.unique(idx, return_inverse=True)
    return MeshData(welded[used], np.full(len(idx), 3, np.int32), inverse.reshape(-1).astype(np.int32))


def _merge(meshes: list[MeshData]) -> MeshData:
    offsets = np.cumsum([0] + [len(m.points) for m in meshes[:-1]])
    return MeshData(np.concatenate([m.points for m in meshes]), np.concatenate([m.counts for m in meshes]),
                    np.concatenate([m.indices + o for m, o in zip(meshes, offsets)]).astype(np.int32))


def _area(xy: np.ndarray) -> float:
    """Signed area (shoelace) of a polygon's points ``(k, 2+)``, taken about its first point: in the scene's
    coordinates a building hundreds of kilometres from the origin lost its area to cancellation (a 10 x 15 m outline
    in EPSG:3067 metres was off by more than the coverage check's 1e-6 of it: a flat roof)."""
    x, y = xy[:, 0] - xy[0, 0], xy[:, 1] - xy[0, 1]
    return 0.5 * float(x[:-1] @ y[1:] - x[1:] @ y[:-1] + x[-1] * y[0] - x[0] * y[-1])


def _rise(spec: RoofSpec, run: float) -> float:
    """Rise per metre for a roof whose highest point is ``run`` metres (horizontally) in from its eave."""
    if run <= 0:
        raise RoofError("outline too thin for a pitched roof")
    rise = spec.height / run if spec.height else spec.slope
    return min(rise, spec.cap / run)


def profile(shape: str, spec: RoofSpec, run: float) -> tuple[np.ndarray, np.ndarray]:
    """Height above the eave as a piecewise-linear function of the distance swept in from the eave: breakpoints
    ``(ts, zs)`` from 0 to ``run`` (the skeleton's greatest time), scaled to ``roof:height`` and the cap.

    ``hipped``/``gabled``: one slope at the pitch. ``mansard``/``gambrel``: the outer third of the run at
    ``MANSARD_LOWER`` degrees, the rest at the pitch (one slope if the pitch is as steep). ``dome``, ``round``: a
    quarter ellipse in ``DOME_BANDS`` bands, as high as the run (a hemisphere over a round outline, a half cylinder
    over a rectangle)."""
    if run <= 0:
        raise RoofError("outline too thin for a pitched roof")
    if shape in ("mansard", "gambrel") and spec.pitch < MANSARD_LOWER:
        lower = math.tan(math.radians(MANSARD_LOWER))
        ts = np.array([0.0, run / 3, run])
        zs = np.array([0.0, lower * run / 3, lower * run / 3 + spec.slope * 2 * run / 3])
    elif shape in ("dome", "round"):
        theta = np.linspace(0.0, math.pi / 2, DOME_BANDS + 1)
        ts, zs = run * (1 - np.cos(theta)), run * np.sin(theta)
    else:
        ts, zs = np.array([0.0, run]), np.array([0.0, spec.slope * run])
    if spec.height:
        zs = zs * spec.height / zs[-1]
    return ts, zs * min(1.0, spec.cap / zs[-1])


def skeleton_faces(part: Polygon, weights: np.ndarray | None = None
                   ) -> tuple[np.ndarray, list[list[int]], list[list[int]], list[list[int]]]:
    """The (weighted) straight skeleton of one part as points ``(k, 3)`` -- x, y and the time (distance swept at
    unit speed) -- one face (point indices, CCW, starting with its outline edge) per outline edge, the plateaus a
    weighted skeleton leaves where party walls (weight 0) wall in what the free edges cannot reach, and the vertical
    walls standing inside (:meth:`~citygen_roofs.skeleton._Wavefront.add_edge`); checked to cover the part once
    (faces of weight-0 edges, vertical walls, have no area)."""
    try:
        skeleton = straight_skeleton(part, weights=weights)
    except SkeletonError as exc:
        raise RoofError(f"no straight skeleton: {exc}") from exc
    faces, flats = [list(f) for f in skeleton.faces], [list(f) for f in skeleton.flats]
    areas = np.array([_area(skeleton.nodes[f]) for f in faces + flats])
    if np.any(areas < -1e-6 * part.area) or not math.isclose(areas.sum(), part.area, rel_tol=1e-6):
        raise RoofError(f"skeleton faces cover {areas.sum():.3f} m² of a {part.area:.3f} m² outline")
    return np.column_stack([skeleton.nodes, skeleton.times]), faces, flats, [list(f) for f in skeleton.walls]


class _Bands:
    """Roof faces cut where the profile breaks, so every piece is one plane; cut points are shared by the faces
    (and gable walls) on either side of a skeleton arc, so the mesh stays closed."""

    def __init__(self, points: np.ndarray, ts: np.ndarray) -> None:
        self.tol = 1e-7 * max(1.0, float(np.ptp(points[:, :2], axis=0).max()))
        t = points[:, 2].copy()
        near = np.abs(t[:, None] - ts[None, :]) < 10 * self.tol  # a node (nearly) on a break line is on it
        t[near.any(axis=1)] = ts[near.argmax(axis=1)][near.any(axis=1)]
        self.xy, self.t = [tuple(p[:2]) for p in points], list(t)
        self.ts = ts
        self.cuts: dict[tuple[int, int, int], int] = {}

    def ring(self, cycle: list[int]) -> list[int]:
        """``cycle`` with the profile's break points inserted on its sides."""
        out = []
        for k, u in enumerate(cycle):
            v = cycle[(k + 1) % len(cycle)]
            out.append(u)
            tu, tv = self.t[u], self.t[v]
            inner = [j for j in range(1, len(self.ts) - 1) if min(tu, tv) + 1e-9 < self.ts[j] < max(tu, tv) - 1e-9]
            for j in (inner if tv > tu else inner[::-1]):
                key = (min(u, v), max(u, v), j)
                if key not in self.cuts:
                    s = (self.ts[j] - tu) / (tv - tu)
                    a, b = self.xy[u], self.xy[v]
                    self.xy.append((a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])))
                    self.t.append(float(self.ts[j]))
                    self.cuts[key] = len(self.xy) - 1
                out.append(self.cuts[key])
        return out

    def pieces(self, face: list[int]) -> list[list[int]]:
        """The planar pieces of a roof face: its ring cut along the chords where the profile breaks."""
        ring = self.ring(face)
        a, b = np.asarray(self.xy[ring[0]]), np.asarray(self.xy[ring[1]])
        along = np.array([self.xy[n] for n in ring]) @ ((b - a) / math.hypot(*(b - a)))  # level lines are parallel
        pieces = [ring]
        for level in self.ts[1:-1]:
            for p, q in self._chords(ring, float(level), along):
                k = next((k for k, piece in enumerate(pieces) if p in piece and q in piece), None)
                if k is None:  # a chord between a face's boundary and a hole in it, which joined them already
                    raise RoofError("a profile break line cuts a roof face round a hole where it cannot split it")
                piece = pieces[k]
                i, j = sorted((piece.index(p), piece.index(q)))
                pieces[k:k + 1] = [piece[i:j + 1], piece[j:] + piece[:i + 1]]
        return pieces

    def _chords(self, ring: list[int], level: float, along: np.ndarray) -> list[tuple[int, int]]:
        """Where the level line runs inside the face, as chords between ring points on the level. Runs of such
        points whose neighbours lie on opposite sides are crossings; in order along the line they switch between
        outside and inside. Inside, a chord joins each run to the next one, a touching run (a ridge lying on the
        line) included, so no chord passes over a ring point."""
        t = np.array([self.t[n] for n in ring]) - level
        on = t == 0
        if not on.any() or on.all():
            return []
        n = len(ring)
        start = int(np.flatnonzero(~on)[0])
        runs, k = [], start
        while k < start + n:
            if not on[k % n]:
                k += 1
                continue
            run = []
            while on[k % n]:
                run.append(k % n)
                k += 1
            crossing = bool(np.sign(t[(run[0] - 1) % n]) != np.sign(t[k % n]))
            runs.append((sorted(run, key=lambda m: along[m]), crossing))
        if sum(crossing for _, crossing in runs) % 2:
            raise RoofError("a profile break line crosses a roof face an odd number of times")
        runs.sort(key=lambda run: along[run[0][0]])
        chords, inside, last = [], False, None
        for run, crossing in runs:
            if inside and (last - run[0]) % n not in (1, n - 1):
                chords.append((ring[last], ring[run[0]]))
            inside ^= crossing
            last = run[-1]
        return chords

    def mesh(self, faces: list[list[int]], walls: list[list[int]], top: float, zs: np.ndarray) -> MeshData:
        roof = [piece for f in faces for piece in self.pieces(f)]
        walls = [self.ring(w) for w in walls]
        points = np.column_stack([np.array(self.xy), top + np.interp(self.t, self.ts, zs)])
        return _mesh(points, roof, walls)


def skeleton_roof(part: Polygon, top: float, spec: RoofSpec, shape: str, gables: bool,
                  party: frozenset[int] = frozenset(), orientation: str | None = None) -> MeshData:
    """A roof over the weighted straight skeleton of ``part`` (:func:`edge_weights`) with ``shape``'s profile;
    faces of weight-0 edges are gable walls; ``gables``: hip ends turned into gables too. A part enclosed by
    party walls on every side (a building inside a block, seen only from above) is roofed as if free; where the
    weighted skeleton fails, so is the part, with a :func:`citygen.roof.note`."""
    weights = edge_weights(part, party, orientation, gables)
    if party and not weights.any():
        return skeleton_roof(part, top, spec, shape, gables, frozenset(), orientation)
    try:
        points, faces, flats, inner = skeleton_faces(part, weights)
        walls = [f for f, w in zip(faces, weights) if w == 0] + inner
        faces = [f for f, w in zip(faces, weights) if w != 0]
        if gables:
            points, faces, walls = gable(points, faces, walls, len(weights),
                                         HALF_HIP if shape == "half-hipped" else 1.0, flats)
        else:
            faces += flats
        ts, zs = profile(shape, spec, float(points[:, 2].max()))
        mesh = _Bands(points, ts).mesh(faces, walls, top, zs)
        cracks = _cracks(mesh, top, part, len(weights))
        if cracks:
            raise RoofError(f"the skeleton's faces leave {cracks} open edge(s) above the eaves")
    except RoofError as exc:
        if not party:
            raise
        note(f"party walls ignored: {exc}")
        return skeleton_roof(part, top, spec, shape, gables, frozenset(), orientation)
    return mesh


def _cracks(mesh: MeshData, top: float, part: Polygon, edges: int) -> int:
    """Mesh edges with no twin (used once, not in the opposite direction) that are no eave: not at the wall top, or
    off the outline (``part``, with ``edges`` edges) there -- a crack just above the eave. Every open edge of a
    closed roof is an eave."""
    tris = mesh.indices.reshape(-1, 3).astype(np.int64)
    a, b = tris.ravel(), np.roll(tris, -1, axis=1).ravel()
    n = len(mesh.points)
    lone = ~np.isin(a * n + b, b * n + a)
    z = mesh.points[:, 2].astype(float)
    high = (np.abs(z[a] - top) > 1e-3) | (np.abs(z[b] - top) > 1e-3)
    eaves = np.flatnonzero(lone & ~high)
    if len(eaves) != edges:  # not one open edge at the wall top per outline edge: each must lie on the outline
        pa, pb = mesh.points[a[eaves], :2].astype(float), mesh.points[b[eaves], :2].astype(float)
        rings = [np.asarray(r.coords)[:, :2] for r in (part.exterior, *part.interiors)]
        starts = np.concatenate([r[:-1] for r in rings])
        d = np.concatenate([np.diff(r, axis=0) for r in rings])
        off = np.zeros(len(eaves))
        for q in (pa, pb, (pa + pb) / 2):
            s = np.clip(np.einsum("ijk,jk->ij", q[:, None, :] - starts[None], d) / np.einsum("ij,ij->i", d, d),
                        0.0, 1.0)
            gap = np.hypot(*(q[:, None, :] - starts[None] - s[..., None] * d[None]).transpose(2, 0, 1)).min(axis=1)
            off = np.maximum(off, gap)
        high[eaves[off > 1e-3]] = True
    return int(np.count_nonzero(lone & high))


def gable(points: np.ndarray, faces: list[list[int]], walls: list[list[int]], outline_nodes: int,
          clip: float = 1.0, flats: list[list[int]] = ()) -> tuple[np.ndarray, list[list[int]], list[list[int]]]:
    """Turn hip ends into gable walls: ``points`` are x, y, time; ``walls`` the faces already standing (party
    walls), ``flats`` plateaus (kept as they are). Returns points (new points appended), roof faces (the flats
    last) and walls (the new ones outward).

    A hip end ``[a, b, apex]`` whose apex ends a ridge becomes the wall ``[a, b, A]``, A where the ridge, extended,
    meets the edge. With ``clip`` < 1 (half-hipped) the wall stops at ``clip`` of the ridge's time: the wall is
    ``[a, b, Rb, Ra]`` (Ra = a + clip (A - a), on the rakes), a small hip ``[Ra, Rb, P]`` rises above it to
    P = apex + clip (A - apex) on the ridge, and the side faces run a -> Ra -> P (their planes are unchanged)."""
    neighbours: dict[int, set[int]] = {}
    owners: dict[int, int] = {}
    for f in [*faces, *walls, *flats]:
        for k, n in enumerate(f):
            owners[n] = owners.get(n, 0) + 1
            neighbours.setdefault(n, set()).update((f[k - 1], f[(k + 1) % len(f)]))
    rows = [points]
    count = len(points)
    tiny = 1e-7 * max(1.0, float(np.ptp(points[:, :2], axis=0).max()))
    roof, walls = [], list(walls)
    ends: dict[int, tuple[int, int, int, int, int]] = {}  # apex -> (a, b, Ra, Rb, new apex)

    def add(point: np.ndarray) -> int:
        nonlocal count
        rows.append(point[None, :])
        count += 1
        return count - 1
    for f in faces:
        apex = f[2] if len(f) == 3 else None
        ridge = [n for n in neighbours.get(apex, ()) if n >= outline_nodes] if apex is not None else []
        if apex is None or len(ridge) != 1 or owners[apex] != 3 or apex in ends:
            roof.append(f)
            continue
        a, b, p, q = points[f[0]], points[f[1]], points[apex], points[ridge[0]]
        d, e = p[:2] - q[:2], b[:2] - a[:2]
        det = d[0] * -e[1] + e[0] * d[1]
        if abs(det) < 1e-12 or math.hypot(*d) < tiny:  # parallel, or no ridge: a standing corner's foot and top
            roof.append(f)
            continue
        rhs = a[:2] - q[:2]
        s = (rhs[0] * -e[1] + e[0] * rhs[1]) / det  # position along the ridge q -> p (1 at the apex)
        u = (d[0] * rhs[1] - d[1] * rhs[0]) / det  # position along the edge a -> b
        if s < 1 - 1e-9 or not 1e-6 < u < 1 - 1e-6:
            roof.append(f)
            continue
        end = q + s * (p - q)
        if clip >= 1.0:
            top = add(end)
            ends[apex] = (f[0], f[1], top, top, top)
            walls.append([f[0], f[1], top])
            continue
        ra, rb, top = add(a + clip * (end - a)), add(b + clip * (end - b)), add(p + clip * (end - p))
        ends[apex] = (f[0], f[1], ra, rb, top)
        walls.append([f[0], f[1], rb, ra])
        roof.append([ra, rb, top])

    def remap(ring: list[int]) -> list[int]:
        out = []
        for k, n in enumerate(ring):
            if n not in ends:
                out.append(n)
                continue
            a, b, ra, rb, top = ends[n]
            before, after = ring[k - 1], ring[(k + 1) % len(ring)]
            out += [ra] if before == a and ra != top else []
            out.append(top)
            out += [rb] if after == b and rb != top else []
        return out
    return np.vstack(rows), [remap(f) for f in [*roof, *flats]], [remap(w) for w in walls]


def pyramid(part: Polygon, top: float, spec: RoofSpec) -> MeshData | None:
    """One apex over the centroid, or None when the outline has courtyards or is not star-shaped around it."""
    star = star_around_centroid(part)
    if star is None:
        return None
    ring, c, run = star
    points = np.vstack([np.column_stack([ring, np.full(len(ring), top)]), [*c, top + run * _rise(spec, run)]])
    apex = len(ring)
    return _mesh(points, [[k, (k + 1) % apex, apex] for k in range(apex)], [])


def star_around_centroid(part: Polygon) -> tuple[np.ndarray, np.ndarray, float] | None:
    """The outline ring (counter-clockwise), its centroid and the centroid's distance to the nearest edge line, when
    the part has no courtyard and every edge faces the centroid (star-shaped around it); else None."""
    if part.interiors:
        return None
    ring = np.asarray(part.exterior.coords)[:-1, :2]
    c = np.asarray(part.centroid.coords[0])
    a, b = ring - c, np.roll(ring, -1, axis=0) - c
    cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    run = float(np.min(cross / np.hypot(*(b - a).T)))
    return (ring, c, run) if run > 1e-6 * math.sqrt(part.area) else None


def skillion(part: Polygon, top: float, spec: RoofSpec, party: frozenset[int] = frozenset()) -> MeshData:
    """One plane falling towards ``spec.direction`` over the part, with walls up to it."""
    rings = [np.asarray(r.coords)[:-1, :2] for r in (part.exterior, *part.interiors)]
    xy = np.concatenate(rings)
    if spec.direction is None:  # the slope faces out over the longest outer edge that is no party wall
        ext = rings[0]
        d = np.roll(ext, -1, axis=0) - ext
        length = np.hypot(d[:, 0], d[:, 1])
        free = np.array([k not in party for k in range(len(ext))])
        k = int(np.argmax(np.where(free, length, -1.0) if free.any() else length))
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


class _SkeletonRoof(RoofBuilder):
    """A roof over the straight skeleton with the profile of its ``id``; ``gables``: hip ends become gables;
    ``oriented``: reads ``roof:orientation`` (or ``roof:direction``). Party walls are gable walls."""

    gables = False

    def build(self, outline: Polygon | MultiPolygon, top: float, spec: RoofSpec | None = None) -> MeshData:
        spec = spec or RoofSpec(self.id)
        parts = _parts(outline, spec.party)
        if self.oriented and spec.orientation is None and spec.direction is not None \
                and not all(rectangle_like(part) for part, _ in parts):
            note(f"roof:direction={spec.direction:g} sets the ridge of rectangle-like parts only; elsewhere the "
                 "ridge follows the straight skeleton")
        return _merge([skeleton_roof(part, top, spec, self.id, self.gables, party,
                                     ridge_orientation(part, spec) if self.oriented else None)
                       for part, party in parts])

    def rise(self, outline: Polygon | MultiPolygon, spec: RoofSpec) -> float:
        """The profile's height over the inscribed radius (the skeleton's run where the outline is convex)."""
        run = inscribed_radius(outline)
        return float(profile(self.id, replace(spec, height=None, cap=math.inf), run)[1][-1]) if run > 0 else 0.0


class HippedRoof(_SkeletonRoof):
    id = "hipped"
    description = "hipped roof: straight-skeleton faces at one pitch (roof:angle, roof:height)"
    oriented = True


class GabledRoof(_SkeletonRoof):
    id = "gabled"
    description = "gabled roof: hipped roof with its hip ends turned into vertical gable walls"
    gables = True
    oriented = True


class HalfHippedRoof(_SkeletonRoof):
    id = "half-hipped"
    description = "half-hipped (jerkinhead) roof: gable walls up to 60 % of the ridge height, a small hip above"
    gables = True
    oriented = True


class MansardRoof(_SkeletonRoof):
    id = "mansard"
    description = "mansard roof: hipped, steep on the outer third of the run, at the pitch above"
    oriented = True


class GambrelRoof(_SkeletonRoof):
    id = "gambrel"
    description = "gambrel roof: gabled with the mansard's two slopes"
    gables = True
    oriented = True


class DomeRoof(_SkeletonRoof):
    id = "dome"
    description = "dome: a quarter-ellipse profile over the straight skeleton, as high as the outline is deep"


class RoundRoof(_SkeletonRoof):
    id = "round"
    description = "round (barrel) roof: gabled with the dome's quarter-ellipse profile, in planar bands"
    gables = True
    oriented = True


class PyramidalRoof(RoofBuilder):
    id = "pyramidal"
    description = ("pyramidal roof: one apex over the centroid (hipped where the outline is not star-shaped or "
                   "has party walls)")

    def build(self, outline: Polygon | MultiPolygon, top: float, spec: RoofSpec | None = None) -> MeshData:
        spec = spec or RoofSpec(self.id)
        return _merge([(None if party else pyramid(part, top, spec))
                       or skeleton_roof(part, top, spec, "hipped", False, party)
                       for part, party in _parts(outline, spec.party)])


class ConeRoof(PyramidalRoof):
    id = "cone"
    description = "cone (OSM roof:shape=cone, round towers): the pyramidal roof, one apex over the centroid"


class SkillionRoof(RoofBuilder):
    id = "skillion"
    description = "skillion (shed) roof: one plane falling towards roof:direction, closed by walls"

    def build(self, outline: Polygon | MultiPolygon, top: float, spec: RoofSpec | None = None) -> MeshData:
        spec = spec or RoofSpec(self.id)
        return _merge([skillion(part, top, spec, party) for part, party in _parts(outline, spec.party)])

    def rise(self, outline: Polygon | MultiPolygon, spec: RoofSpec) -> float:
        """The slope over the whole depth: the plane runs from one side to the other."""
        return 2.0 * super().rise(outline, spec)
