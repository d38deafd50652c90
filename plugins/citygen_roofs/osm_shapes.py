"""More OSM Simple 3D Buildings roof shapes (https://wiki.openstreetmap.org/wiki/Key:roof:shape), built from
planar pieces (:func:`citygen_roofs.planes.piecewise_roof`):

* ``saltbox``: an asymmetric gable: both eaves at the wall top, the ridge ``SALTBOX_RIDGE`` (2/3) of the depth in
  from the long slope's eave; the long slope at the pitch, the short one twice as steep (in rise per metre). The
  long slope faces ``roof:direction``, else the side facing closest to north.
* ``side_hipped``: the gabled roof with a hip at one end, the end facing ``roof:direction`` (else the one facing
  closest to north); a party wall at an end is the gable.
* ``crosspitched``: two gabled roofs crossing, both ridges at one height (the one across the short span at the
  pitch): a gable on every side, valleys to the corners.
* ``butterfly``: an inverted gable: a valley at the wall top along the middle of the minimum rotated rectangle
  (``roof:orientation=across``: across it), both planes rising at the pitch to high eaves, vertical walls below;
  turned when a party wall lies on the valley line.
* ``sawtooth``: parallel teeth across the building, each a slope at the pitch facing ``roof:direction`` (default:
  out over the longest wall that is no party wall) from its gutter at the wall top up to a vertical glazed wall
  as high as the tooth; ``SAWTOOTH_TOOTH`` (6 m) nominal tooth width, as many teeth as fit.

Saltbox, side_hipped and crosspitched need a rectangle-like part (:func:`citygen.roof.rectangle_like`; its ends
follow ``roof:orientation`` and party walls as for the gabled roof): other parts get the gabled roof, with a
:func:`~citygen.roof.note`. Butterfly and sawtooth roof any outline (courtyards, concave, several parts).
"""
from __future__ import annotations

import math

import numpy as np
from shapely.geometry import MultiPolygon, Polygon

from citygen.geometry.building import MeshData
from citygen.registry import RoofBuilder
from citygen.roof import RoofSpec, note, rectangle_like
from citygen_roofs.pitched import RoofError, _merge, _parts, skeleton_roof
from citygen_roofs.planes import Plane, edge_plane, envelope, piecewise_roof

#: saltbox: the ridge lies this share of the depth in from the long slope's eave
SALTBOX_RIDGE = 2.0 / 3.0
#: sawtooth: nominal width of a tooth (metres across the teeth); the part's run is split into as many as fit
SAWTOOTH_TOOTH = 6.0
#: compass direction (degrees) a saltbox's long slope and a side_hipped roof's hip face when untagged: north
DEFAULT_FACING = 0.0


def _compass(degrees: float) -> np.ndarray:
    angle = math.radians(degrees)
    return np.array([math.sin(angle), math.cos(angle)])  # 0 north (+y), 90 east (+x)


def _outward(xy: np.ndarray, k: int) -> np.ndarray:
    """Outward unit normal of edge ``k`` of a counter-clockwise ring."""
    d = xy[(k + 1) % len(xy)] - xy[k]
    return np.array([d[1], -d[0]]) / math.hypot(*d)


def _facing(xy: np.ndarray, sides: tuple[int, ...], direction: float | None) -> int:
    """Of ``sides``, the one whose outward normal is nearest the compass ``direction`` (default north)."""
    towards = _compass(DEFAULT_FACING if direction is None else direction)
    return max(sides, key=lambda k: float(_outward(xy, k) @ towards))


def _depth(xy: np.ndarray, k: int) -> float:
    """Distance from edge ``k`` of a quadrilateral to the opposite edge (mean over its two ends)."""
    inward = -_outward(xy, k)
    return float(np.mean([(xy[(k + j) % 4] - xy[k]) @ inward for j in (2, 3)]))


def _ends(part: Polygon, party: frozenset[int], orientation: str | None) -> int | None:
    """The ends (edges ``k`` and ``k + 2``, the sides the ridge runs towards) of a rectangle-like part, as for
    the gabled roof: the pair holding the party walls, else by ``roof:orientation`` (the short sides ``along``,
    the default); None when the part is not rectangle-like or, untagged, has party walls on both pairs."""
    if not rectangle_like(part):
        return None
    if orientation is None and party:
        pairs = {k % 2 for k in party}
        return pairs.pop() if len(pairs) == 1 else None
    xy = np.asarray(part.exterior.coords)[:-1, :2]
    length = np.hypot(*(np.roll(xy, -1, axis=0) - xy).T)
    short = 0 if length[0] + length[2] <= length[1] + length[3] else 1
    return short if orientation in (None, "along") else 1 - short


def _gabled(part: Polygon, top: float, spec: RoofSpec, party: frozenset[int], why: str) -> MeshData:
    note(f"{why}: the gabled roof instead")
    return skeleton_roof(part, top, spec, "gabled", True, party, spec.orientation)


def _ring(part: Polygon) -> np.ndarray:
    if not part.is_valid:
        raise RoofError("the outline is not a valid polygon")
    return np.asarray(part.exterior.coords)[:-1, :2]


def saltbox(part: Polygon, top: float, spec: RoofSpec, party: frozenset[int]) -> MeshData:
    """An asymmetric gable over a rectangle-like part: the long slope (facing ``roof:direction``) at the pitch, the
    ridge ``SALTBOX_RIDGE`` of the depth in from its eave."""
    xy = _ring(part)
    ends = _ends(part, party, spec.orientation)
    if ends is None:
        return _gabled(part, top, spec, party, _why(part))
    long = _facing(xy, ((ends + 1) % 4, (ends + 3) % 4), spec.direction)
    short = (long + 2) % 4
    depth = _depth(xy, long)
    run = SALTBOX_RIDGE * depth
    planes = [edge_plane(xy[long], xy[(long + 1) % 4], spec.slope),
              edge_plane(xy[short], xy[(short + 1) % 4], spec.slope * run / (depth - run))]
    return piecewise_roof(part, top, spec, *envelope(planes))


def side_hipped(part: Polygon, top: float, spec: RoofSpec, party: frozenset[int]) -> MeshData:
    """A gabled roof over a rectangle-like part with a hip at the end facing ``roof:direction``: party walls at
    the ends are gables (two party walls: the gabled roof). The hip is at the pitch on a short side, steeper on a
    long one (weight ``(short/long)^2``, as for the hipped roof)."""
    xy = _ring(part)
    ends = _ends(part, party, spec.orientation)
    if ends is None:
        return _gabled(part, top, spec, party, _why(part))
    length = np.hypot(*(np.roll(xy, -1, axis=0) - xy).T)
    pair = np.array([length[0] + length[2], length[1] + length[3]])
    short = int(np.argmin(pair))
    pair_ends = (ends, ends + 2)
    gables = [k for k in pair_ends if k in party] or [k for k in pair_ends
                                                       if k != _facing(xy, pair_ends, spec.direction)]
    hip = 1.0 if ends == short else float(pair[short] / pair[1 - short]) ** 2
    weights = [0.0 if k in gables else hip if k in pair_ends else 1.0 for k in range(4)]
    planes = [edge_plane(xy[k], xy[(k + 1) % 4], spec.slope * w) for k, w in enumerate(weights) if w > 0]
    return piecewise_roof(part, top, spec, *envelope(planes))


def crosspitched(part: Polygon, top: float, spec: RoofSpec, party: frozenset[int]) -> MeshData:
    """Two gabled roofs crossing over a rectangle-like part, ridges at one height: every wall is a gable, so
    party walls need nothing."""
    xy = _ring(part)
    if not rectangle_like(part):
        return _gabled(part, top, spec, party, _why(part))
    depth = [_depth(xy, k) for k in range(2)]
    ridge = spec.slope * min(depth) / 2
    planes = np.array([edge_plane(xy[k], xy[(k + 1) % 4], ridge / (depth[k % 2] / 2)) for k in range(4)])
    lines, _ = envelope(list(planes))

    def plane_at(p: np.ndarray) -> Plane:
        z = planes @ np.array([p[0], p[1], 1.0])
        gables = [min(pair, key=lambda k: z[k]) for pair in ((0, 2), (1, 3))]
        return planes[max(gables, key=lambda k: z[k])]
    return piecewise_roof(part, top, spec, lines, plane_at)


def butterfly(part: Polygon, top: float, spec: RoofSpec, party: frozenset[int] = frozenset()) -> MeshData:
    """An inverted gable: the valley at the wall top along the middle of the part's minimum rotated rectangle
    (across it for ``roof:orientation=across``), both planes rising at the pitch to the eaves. A valley along a
    party wall would drain onto the neighbour: the valley turns across, else the part gets the gabled roof."""
    rings = [np.asarray(r.coords)[:-1, :2] for r in (part.exterior, *part.interiors)]
    _ring(part)
    corners = np.asarray(part.minimum_rotated_rectangle.exterior.coords)[:4, :2]
    sides = [corners[1] - corners[0], corners[2] - corners[1]]
    long = int(math.hypot(*sides[1]) > math.hypot(*sides[0]))
    first = 1 - long if spec.orientation == "across" else long
    centre = corners.mean(axis=0)
    for turned, k in enumerate((first, 1 - first)):
        axis = sides[k] / math.hypot(*sides[k])
        n = np.array([-axis[1], axis[0]])
        if _party_on_line(rings, party, centre, n):
            continue
        if turned:
            note("the butterfly roof's valley would lie along a party wall: "
                 "it runs along the other middle line instead")
        n = n * spec.slope
        plane = np.array([n[0], n[1], -float(n @ centre)])
        return piecewise_roof(part, top, spec, *envelope([plane, -plane], lowest=False))
    return _gabled(part, top, spec, party, "the butterfly roof's valley lies along a party wall either way")


def _party_on_line(rings: list[np.ndarray], party: frozenset[int], point: np.ndarray, normal: np.ndarray) -> bool:
    """Whether a party wall (edge index over ``rings``) lies on the line through ``point`` across ``normal``."""
    tol = 1e-6 * max(1.0, float(np.ptp(np.concatenate(rings), axis=0).max()))
    edges = [(r[k], r[(k + 1) % len(r)]) for r in rings for k in range(len(r))]
    return any(abs((a - point) @ normal) < tol and abs((b - point) @ normal) < tol
               for index, (a, b) in enumerate(edges) if index in party)


def sawtooth(part: Polygon, top: float, spec: RoofSpec, party: frozenset[int]) -> MeshData:
    """Teeth whose slopes face ``roof:direction`` (default: out over the longest outer wall that is no party wall).
    Where a gutter would lie along a party wall the teeth move half a tooth; where they still would, the direction
    gives way to the next longest free wall's."""
    rings = [np.asarray(r.coords)[:-1, :2] for r in (part.exterior, *part.interiors)]
    _ring(part)
    outer = rings[0]
    length = np.hypot(*(np.roll(outer, -1, axis=0) - outer).T)
    order = sorted(range(len(outer)), key=lambda k: (k in party, -length[k], k))
    candidates = [_outward(outer, k) for k in order]
    if spec.direction is not None:
        candidates.insert(0, _compass(spec.direction))
    for k, down in enumerate(candidates):
        teeth = next((t for t in (_Teeth(part, down, 0.0), _Teeth(part, down, 0.5)) if not t.gutter_on(rings, party)),
                     None)
        if teeth is not None:
            if k and spec.direction is not None:
                note(f"roof:direction={spec.direction:g} brings a gutter down onto a party wall: the teeth face "
                     f"{math.degrees(math.atan2(down[0], down[1])) % 360:.0f} degrees instead")
            return piecewise_roof(part, top, spec, teeth.cuts(), teeth.plane_at(spec.slope))
    return _gabled(part, top, spec, party, "every direction brings a gutter down onto a party wall")


class _Teeth:
    """Sawtooth teeth over ``part`` falling towards ``down``: as many ``SAWTOOTH_TOOTH`` wide strips across it as
    fit, each rising from its gutter (its ``down`` end) to its glazed wall; ``shift``: the strips moved uphill by
    that share of a tooth (half a tooth: the part's lowest wall is no gutter but meets a tooth half way up)."""

    def __init__(self, part: Polygon, down: np.ndarray, shift: float) -> None:
        s = np.asarray(part.exterior.coords)[:, :2] @ down
        run = float(s.max() - s.min())
        self.count = max(1, round(run / SAWTOOTH_TOOTH))
        self.width = run / self.count
        self.down, self.start = down, float(s.min()) - shift * self.width
        self.count += shift > 0
        self.tol = 1e-7 * max(1.0, run)

    def cuts(self) -> list[tuple[np.ndarray, np.ndarray]]:
        across = np.array([-self.down[1], self.down[0]])
        return [(self.down * (self.start + k * self.width), across) for k in range(1, self.count)]

    def plane_at(self, slope: float):
        def plane(p: np.ndarray) -> Plane:
            k = min(max(int((p @ self.down - self.start) // self.width), 0), self.count - 1)
            gutter = self.start + (k + 1) * self.width
            return np.array([-slope * self.down[0], -slope * self.down[1], slope * gutter])
        return plane

    def gutter_on(self, rings: list[np.ndarray], party: frozenset[int]) -> bool:
        """Whether a party wall lies along a gutter, facing downhill (the slope would drain onto the neighbour)."""
        edges = [(r[k], r[(k + 1) % len(r)], r, k) for r in rings for k in range(len(r))]
        for index, (a, b, ring, k) in enumerate(edges):
            if index not in party or _outward(ring, k) @ self.down < 1 - 1e-9:
                continue
            step = (a @ self.down - self.start) / self.width
            if step > 0.5 and abs(step - round(step)) * self.width < self.tol:
                return True
        return False


def _why(part: Polygon) -> str:
    return ("party walls on both pairs of sides" if rectangle_like(part)
            else "the part is not rectangle-like (four sides, no courtyard)")


class _PlaneRoof(RoofBuilder):
    """A roof of :mod:`citygen_roofs.osm_shapes` over every part of the outline: ``shape(part, top, spec, party)``."""

    shape = staticmethod(sawtooth)

    def build(self, outline: Polygon | MultiPolygon, top: float, spec: RoofSpec | None = None) -> MeshData:
        spec = spec or RoofSpec(self.id)
        return _merge([self.shape(part, top, spec, party) for part, party in _parts(outline, spec.party)])


class SaltboxRoof(_PlaneRoof):
    id = "saltbox"
    description = "saltbox roof: an asymmetric gable, its long slope facing roof:direction (default north)"
    oriented = True
    shape = staticmethod(saltbox)


class SideHippedRoof(_PlaneRoof):
    id = "side_hipped"
    description = "side-hipped roof: gabled, with a hip at the end facing roof:direction (default north)"
    oriented = True
    shape = staticmethod(side_hipped)


class CrosspitchedRoof(_PlaneRoof):
    id = "crosspitched"
    description = "crosspitched roof: two gabled roofs crossing, a gable on every side"
    shape = staticmethod(crosspitched)


class ButterflyRoof(_PlaneRoof):
    id = "butterfly"
    description = "butterfly roof: an inverted gable, a valley along the middle and high eaves"
    shape = staticmethod(butterfly)


class SawtoothRoof(_PlaneRoof):
    id = "sawtooth"
    description = "sawtooth roof: parallel teeth, slopes facing roof:direction, vertical glazed walls"

    def rise(self, outline: Polygon | MultiPolygon, spec: RoofSpec) -> float:
        """The slope over one tooth (the direction's, else the longest outer wall's)."""
        widths = []
        for part in getattr(outline, "geoms", [outline]):
            outer = np.asarray(part.exterior.coords)[:-1, :2]
            k = int(np.argmax(np.hypot(*(np.roll(outer, -1, axis=0) - outer).T)))
            down = _compass(spec.direction) if spec.direction is not None else _outward(outer, k)
            widths.append(_Teeth(part, down, 0.0).width)
        return spec.slope * max(widths)
