"""Masses and faces: a footprint extruded to its wall height and split into planar wall faces.

Every ring edge (exterior and courtyard holes) becomes a :class:`Face` with a frame: ``origin`` at its bottom-left
corner seen from outside, ``u`` along the wall left to right, ``v`` up, ``normal`` outward. Rings are cleaned
first so the faces are the walls a person would name: nearly collinear edges merge into one face, and edges
shorter than the tolerance are absorbed into their neighbours instead of becoming 2 cm facades.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon
from shapely.geometry.polygon import orient

from citygen.footprints import Footprint
from citygen.roof import RoofSpec


@dataclass(frozen=True)
class Face:
    """One planar wall rectangle of a mass, in the scene's local frame (z up)."""

    index: int
    ring: int
    origin: tuple[float, float, float]
    u: tuple[float, float, float]
    normal: tuple[float, float, float]
    width: float
    height: float
    corner_angles: tuple[float, float]
    neighbours: tuple[int, int]
    is_courtyard: bool

    @property
    def v(self) -> tuple[float, float, float]:
        return (0.0, 0.0, 1.0)

    def matrix(self) -> np.ndarray:
        """4x4 row-vector transform from face-local ``(x, y, depth)`` to the scene frame."""
        m = np.eye(4)
        m[0, :3], m[1, :3], m[2, :3], m[3, :3] = self.u, self.v, self.normal, self.origin
        return m

    def midpoint(self, offset: float = 0.0) -> np.ndarray:
        o, u, n = np.asarray(self.origin), np.asarray(self.u), np.asarray(self.normal)
        return (o + u * self.width / 2 + n * offset)[:2]


@dataclass(frozen=True)
class Mass:
    """A building's volume: the cleaned outline extruded from ``base`` by ``height`` (its walls), its wall faces,
    and the ``roof`` it carries (shape, pitch and height above the walls, decided with the wall height by
    :mod:`citygen.roofplan`; ``roof_source``: which rule set the roof's height)."""

    outline: Polygon | MultiPolygon
    base: float
    height: float
    faces: tuple[Face, ...]
    roof: RoofSpec = RoofSpec()
    roof_source: str = "flat"

    @property
    def top(self) -> float:
        """The highest point: base, walls and roof."""
        return self.base + self.height + (self.roof.height or 0.0)


def clean_ring(coords: np.ndarray, collinear_tol: float, min_edge: float) -> np.ndarray:
    """Remove near-collinear vertices (deviation < ``collinear_tol``) and collapse edges < ``min_edge``.

    ``coords`` is an ``(n, 2)`` open ring. Returns the cleaned open ring (may have < 3 points if the ring
    degenerates; callers keep the original ring then).
    """
    pts = np.asarray(coords, dtype=float)
    keep = np.r_[True, np.any(np.abs(np.diff(pts, axis=0)) > 1e-9, axis=1)]
    pts = pts[keep]
    if len(pts) > 1 and _close(pts[0], pts[-1]):
        pts = pts[:-1]
    while len(pts) > 3:
        prev, nxt = np.concatenate((pts[-1:], pts[:-1])), np.concatenate((pts[1:], pts[:1]))
        chord = nxt - prev
        length = np.hypot(chord[:, 0], chord[:, 1])
        cross = np.abs(chord[:, 0] * (pts[:, 1] - prev[:, 1]) - chord[:, 1] * (pts[:, 0] - prev[:, 0]))
        deviation = np.where(length > 1e-12, cross / np.maximum(length, 1e-12), 0.0)
        i = int(np.argmin(deviation))
        if deviation[i] < collinear_tol:
            pts = np.delete(pts, i, axis=0)
            continue
        edges = nxt - pts
        elen = np.hypot(edges[:, 0], edges[:, 1])
        j = int(np.argmin(elen))
        if elen[j] >= min_edge:
            break
        k = (j + 1) % len(pts)
        pts[j] = (pts[j] + pts[k]) / 2
        pts = np.delete(pts, k, axis=0)
    return pts


def _close(a: np.ndarray, b: np.ndarray) -> bool:
    """``np.allclose(a, b)`` of two points (its tolerances and arithmetic, without its cost on tiny arrays)."""
    return all(abs(x - y) <= 1e-08 + 1e-05 * abs(y) for x, y in zip(a.tolist(), b.tolist()))


def _clean_polygon(poly: Polygon, collinear_tol: float, min_edge: float) -> Polygon:
    rings = [clean_ring(np.asarray(r.coords)[:, :2], collinear_tol, min_edge)
             for r in (poly.exterior, *poly.interiors)]
    if len(rings[0]) < 3:
        return poly
    candidate = Polygon(rings[0], [r for r in rings[1:] if len(r) >= 3])
    if not candidate.is_valid or candidate.area < 0.5 * poly.area:
        return poly
    return orient(candidate, sign=1.0)


def clean_outline(polygon: Polygon | MultiPolygon, collinear_tol: float = 0.1,
                  min_edge: float = 0.8) -> Polygon | MultiPolygon:
    """The outline walls are built from: every part cleaned, oriented (exterior CCW, holes CW)."""
    parts = list(polygon.geoms) if isinstance(polygon, MultiPolygon) else [polygon]
    cleaned = [_clean_polygon(orient(p, sign=1.0), collinear_tol, min_edge) for p in parts]
    return MultiPolygon(cleaned) if len(cleaned) > 1 else cleaned[0]


def _ring_faces(coords: np.ndarray, ring: int, first_index: int, base: float, height: float,
                is_courtyard: bool) -> list[Face]:
    pts = np.asarray(coords, dtype=float)[:-1, :2]
    n = len(pts)
    d = np.concatenate((pts[1:], pts[:1])) - pts
    width = np.hypot(d[:, 0], d[:, 1])
    u = d / width[:, None]
    before = np.concatenate((u[-1:], u[:-1]))
    turn = np.degrees(np.arctan2(before[:, 0] * u[:, 1] - before[:, 1] * u[:, 0], np.sum(before * u, axis=1)))
    interior = (180.0 - turn).tolist()  # interior angle of the building at the start vertex of each edge
    base, height = float(base), float(height)
    return [Face(index=first_index + i, ring=ring, origin=(x, y, base), u=(ux, uy, 0.0), normal=(uy, -ux, 0.0),
                 width=w, height=height, corner_angles=(interior[i], interior[(i + 1) % n]),
                 neighbours=(first_index + (i - 1) % n, first_index + (i + 1) % n), is_courtyard=is_courtyard)
            for i, ((x, y), (ux, uy), w) in enumerate(zip(pts.tolist(), u.tolist(), width.tolist()))]


#: The grid of wall and storey heights: 2**-20 m (about a micrometre). Multiples of it below 2**33 m are exact
#: floats, and so are their sums and differences: walls on it get storeys equal to the last bit
#: (:func:`citygen.coordinator.plan_floor_lines`).
GRID = 2.0 ** -20


def on_grid(length: float) -> float:
    """``length`` rounded to a multiple of :data:`GRID` (a non-finite one as it is: its checks come later)."""
    return round(length / GRID) * GRID if math.isfinite(length) else float(length)


@dataclass(frozen=True)
class MassPlan:
    """A mass before its wall faces are made: what the pipeline's main process holds of every building of the city
    (tiling, the ground, the neighbour cover's neighbours), a few objects each; a tile task makes the
    :meth:`mass` of its own buildings only."""

    outline: Polygon | MultiPolygon
    base: float
    height: float
    roof: RoofSpec = RoofSpec()
    roof_source: str = "flat"

    def mass(self) -> Mass:
        """The :class:`Mass`: these walls with their faces, this roof."""
        return Mass(outline=self.outline, base=self.base, height=self.height,
                    faces=wall_faces(self.outline, self.base, self.height), roof=self.roof,
                    roof_source=self.roof_source)


def wall_faces(outline: Polygon | MultiPolygon, base: float, height: float) -> tuple[Face, ...]:
    """A face for every exterior and courtyard edge of the cleaned ``outline``, from ``base`` up ``height``."""
    faces: list[Face] = []
    ring = 0
    for part in (outline.geoms if isinstance(outline, MultiPolygon) else [outline]):
        for k, r in enumerate((part.exterior, *part.interiors)):
            faces += _ring_faces(np.asarray(r.coords), ring, len(faces), base, height, k > 0)
            ring += 1
    return tuple(faces)


def build_mass(footprint: Footprint, collinear_tol: float = 0.1, min_edge: float = 0.8, *,
               outline: Polygon | MultiPolygon | None = None, height: float | None = None) -> Mass:
    """Extrude ``footprint`` to its height (or ``height``); faces for every exterior and courtyard edge of its
    cleaned outline (or ``outline``, already cleaned)."""
    outline = clean_outline(footprint.polygon, collinear_tol, min_edge) if outline is None else outline
    height = footprint.height if height is None else height
    return Mass(outline=outline, base=footprint.base, height=height,
                faces=wall_faces(outline, footprint.base, height))


#: Equal parts of a face's width in which the neighbour cover is measured (one sample each).
COVER_BINS = 10
#: Metres outside a wall at which the neighbour cover's samples lie.
COVER_OFFSET = 0.3


#: Sample points made into geometries at a time (a city's 100,000 buildings have millions: made at once, their
#: GEOS objects took ~130 MB per 20,000 buildings that the allocator kept after they were freed).
COVER_CHUNK = 65536


def neighbour_cover(masses: Sequence[Mass], offset: float = COVER_OFFSET, bins: int = COVER_BINS, *,
                    around: Sequence[Mass | MassPlan] = ()) -> list[np.ndarray]:
    """Per mass, an ``(n_faces, bins)`` array: per face and per bin (equal parts of its width, left to right seen
    from outside) the height (metres above the mass's base, 0..its height) up to which other buildings -- the other
    ``masses`` and those ``around`` them -- stand against it there; 0 where none does.

    A bin's sample lies ``offset`` metres outside the wall at the bin's centre; it is hidden up to the lowest top
    among the neighbours it falls in (the wall is seen above them). Each sample's figure depends only on the
    buildings it falls in, so a tile's masses with their :func:`neighbours` from other tiles ``around`` get the
    figures the whole city's masses get.
    """
    standing = [*masses, *around]
    tree = shapely.STRtree([m.outline for m in standing])
    fractions = (np.arange(bins) + 0.5) / bins
    owner = [mi for mi, mass in enumerate(masses) for _ in mass.faces]
    if not owner:
        return [np.zeros((0, bins)) for _ in masses]
    frames = np.array([(*f.origin[:2], *f.u[:2], *f.normal[:2], f.width) for m in masses for f in m.faces])
    o, u, n, width = frames[:, None, 0:2], frames[:, None, 2:4], frames[:, None, 4:6], frames[:, 6]
    pts = (o + (fractions[None, :] * width[:, None])[:, :, None] * u + n * offset).reshape(-1, 2)
    point_owner = np.repeat(np.asarray(owner), bins)
    hits = [tree.query(shapely.points(pts[k:k + COVER_CHUNK]), predicate="within") + np.array([[k], [0]])
            for k in range(0, len(pts), COVER_CHUNK)]
    hit_pt, hit_poly = np.concatenate(hits, axis=1)
    other = hit_poly != point_owner[hit_pt]
    hit_pt, hit_poly = hit_pt[other], hit_poly[other]
    base, height = np.array([m.base for m in standing]), np.array([m.height for m in standing])
    top = base + height
    covered = np.full(len(pts), np.inf)  # per sample the lowest neighbour top above the face's base
    np.minimum.at(covered, hit_pt, top[hit_poly] - base[point_owner[hit_pt]])
    covered = np.where(np.isfinite(covered), covered, 0.0).reshape(-1, bins)
    per_face = np.clip(covered, 0.0, height[np.asarray(owner)][:, None])
    result, start = [], 0
    for mass in masses:
        result.append(per_face[start:start + len(mass.faces)])
        start += len(mass.faces)
    return result


def neighbours(outlines: Sequence[Polygon | MultiPolygon], offset: float = COVER_OFFSET) -> np.ndarray:
    """``(2, k)`` index pairs ``i, j`` (``i != j``) of the ``outlines`` such that ``j`` may hold a sample of
    :func:`neighbour_cover` for ``i``: their bounds, ``i``'s widened by twice the samples' ``offset``, meet (a
    superset: every sample lies within ``offset`` of its wall, inside those bounds)."""
    if not len(outlines):
        return np.zeros((2, 0), dtype=np.intp)
    bounds = shapely.bounds(outlines)
    reach = 2 * offset
    boxes = shapely.box(bounds[:, 0] - reach, bounds[:, 1] - reach, bounds[:, 2] + reach, bounds[:, 3] + reach)
    pairs = shapely.STRtree(outlines).query(boxes)
    return pairs[:, pairs[0] != pairs[1]]
