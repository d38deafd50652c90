"""``onion``: the bulbous dome of OSM's ``roof:shape=onion`` (Orthodox churches, baroque towers).

The outline is scaled about its centroid ring by ring: first out beyond the walls (the bulb overhangs them by
``ONION_PROFILE``'s widest scale), then in to a point, in ``ONION_BANDS`` bands. Every band of an edge is a
trapezoid (its top and bottom sides are parallel to the edge), so each is planar; the mesh's open boundary is the
outline at the wall top. Height: ``roof:height``, else ``ONION_HEIGHT`` times the centroid's distance to the
nearest wall (a bulb about 1.5 times as high as it is wide), capped like every roof.

Outlines with courtyards or not star-shaped around their centroid, and parts with party walls, get the ``dome``
instead (no scaled ring could stay inside itself, or the bulb would lean over the neighbour)."""
from __future__ import annotations

import numpy as np
from shapely.geometry import MultiPolygon, Polygon

from citygen.geometry.building import MeshData
from citygen.registry import RoofBuilder
from citygen.roof import RoofSpec, inscribed_radius
from citygen_roofs.pitched import _merge, _parts, skeleton_roof, star_around_centroid, welded_mesh

#: (height share, scale of the outline about its centroid): widest at a fifth of the height, then a concave neck
#: to the tip.
ONION_PROFILE = ((0.0, 1.0), (0.2, 1.2), (0.4, 1.05), (0.6, 0.55), (0.78, 0.18), (0.9, 0.05), (1.0, 0.0))
#: Rings of the bulb (planar bands between them).
ONION_BANDS = 12
#: Height over the centroid's distance to the nearest wall.
ONION_HEIGHT = 3.0


def onion_profile() -> tuple[np.ndarray, np.ndarray]:
    """Height shares and outline scales of the ``ONION_BANDS + 1`` rings, from the wall top to the tip."""
    from scipy.interpolate import PchipInterpolator  # (scipy.interpolate takes ~0.3 s to import: only when used)
    z, s = np.array(ONION_PROFILE).T
    levels = np.linspace(0.0, 1.0, ONION_BANDS + 1)
    scales = PchipInterpolator(z, s)(levels)
    scales[0], scales[-1] = 1.0, 0.0
    return levels, scales


def onion(part: Polygon, top: float, spec: RoofSpec) -> MeshData | None:
    """The bulb over one part, or None where it cannot stand (see the module)."""
    star = star_around_centroid(part)
    if star is None:
        return None
    ring, c, run = star
    height = min(spec.height or ONION_HEIGHT * run, spec.cap)
    levels, scales = onion_profile()
    n, bands = len(ring), len(levels) - 1
    xy = c + scales[:-1, None, None] * (ring - c)[None, :, :]  # (rings below the tip, vertices, 2)
    z = np.repeat(top + height * levels[:-1], n)
    points = np.vstack([np.column_stack([xy.reshape(-1, 2), z]), [*c, top + height]])
    i = np.arange(n)
    j = (i + 1) % n
    tris = []
    for k in range(bands - 1):
        lo, hi = k * n, (k + 1) * n
        tris += [np.column_stack([lo + i, lo + j, hi + j]), np.column_stack([lo + i, hi + j, hi + i])]
    apex, last = bands * n, (bands - 1) * n
    tris.append(np.column_stack([last + i, last + j, np.full(n, apex)]))
    return welded_mesh(points, np.concatenate(tris))


class OnionRoof(RoofBuilder):
    id = "onion"
    description = "onion dome: the outline scaled about its centroid, bulging past the walls and drawn to a point"

    def build(self, outline: Polygon | MultiPolygon, top: float, spec: RoofSpec | None = None) -> MeshData:
        spec = spec or RoofSpec(self.id)
        return _merge([(None if party else onion(part, top, spec))
                       or skeleton_roof(part, top, spec, "dome", False, party)
                       for part, party in _parts(outline, spec.party)])

    def rise(self, outline: Polygon | MultiPolygon, spec: RoofSpec) -> float:
        return ONION_HEIGHT * inscribed_radius(outline)
