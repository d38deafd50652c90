"""The building coordinator: what the faces of one building share, decided before any facade is generated.

* **Floor lines** -- one set of floor heights per building; every face's request carries it, so windows of
  adjacent faces sit at the same heights.
* **Entrance** -- exactly one door per building, on the widest street-facing face whose foot is free (else the
  widest facade face with a free foot; none when every foot is hidden, e.g. a tower rising from a lower block, or
  when the building is lifted off the ground, ``Footprint.lift``: it has no street faces and no taller ground floor;
  none either when its ground floor is lower than ``DOOR_STOREY``, the plausibility rules' door height: a 1.8 m
  shed had every face fall back to a plain wall for the door it could not hold).
* **Corners** -- a wall strip at each corner, the same width on both faces meeting there, so openings of two faces
  never collide at a corner and corners meet with equal margins.

Party walls (faces a neighbouring building covers to within ``PARTY_RISE`` of their top, but for less than
``MIN_SEEN`` metres of their width) and faces narrower than ``min_face_width`` get no facade. A face partly
against a neighbour -- a lower one, or one covering only part of its width -- gets a facade (the part the
neighbour hides is turned to plain wall, :func:`citygen.layout.hidden_behind`) but is no street face and gets no
entrance: its foot is not free.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from citygen.footprints import Footprint
from citygen.mass import Mass, on_grid
from citygen.request import FacadeRequest, FaceContext
from citygen.runs import face_runs
from citygen.scene import Defaults

#: A face whose neighbours reach this close (m) to its top is a party wall (no facade) ...
PARTY_RISE = 1.0
#: ... unless at least this width (m) of it rises above them.
MIN_SEEN = 2.0
#: The least ground floor (m) an entrance door goes into (``PlausibilityRules.door_min_height``).
DOOR_STOREY = 1.9


@dataclass(frozen=True)
class BuildingPlan:
    """The coordinator's decisions for one building and the facade requests that carry them."""

    building_id: str
    levels: int
    floor_lines: tuple[float, ...]
    entrance_face: int | None
    requests: tuple[FacadeRequest, ...]
    plain_faces: tuple[int, ...]
    party_faces: tuple[int, ...] = ()  # party walls (also plain): a pitched roof must not slope onto them
    runs: tuple[tuple[int, ...], ...] = ()  # faces of a curved wall laid out as one facade (citygen.runs)


def plan_floor_lines(height: float, levels: int | None, defaults: Defaults, lifted: bool = False
                     ) -> tuple[float, ...]:
    """Floor boundaries from 0 to ``height``: the data's level count when known, else the default floor height.

    A taller ground floor (``ground_floor_height``) is used when the building has at least three floors, the
    upper floors stay at least 2.4 m high and it is not ``lifted`` off the ground; everything always ends exactly at
    ``height``. The storeys above the lowest are equal to the last bit, so they derive alike (a grammar derives a
    storey's subtree once and places copies): their height and ``height`` are rounded to the grid of
    :data:`citygen.mass.GRID` and the lowest storey takes the rest, within micrometres of its plan (a ``height``
    off the grid leaves the top storey within micrometres of the others).
    """
    if levels is None or levels < 1:
        levels = round(height / defaults.floor_height)
    levels = max(1, min(levels, int(height // 2.4)))
    if levels == 1:
        return (0.0, float(height))
    typical = height / levels
    ground = min(defaults.ground_floor_height, 1.3 * typical)
    if levels >= 3 and ground > typical and (height - ground) / (levels - 1) >= 2.4 and not lifted:
        step = on_grid((height - ground) / (levels - 1))
    else:
        step = on_grid(typical)
    lowest = on_grid(height) - (levels - 1) * step
    return (0.0, *(lowest + i * step for i in range(levels - 1)), float(height))


def party_walls(cover: np.ndarray, widths: np.ndarray, height: float) -> np.ndarray:
    """Per face, whether it is a party wall: ``cover`` (per face, or per face and bin, from
    :func:`citygen.mass.neighbour_cover`) reaches within ``PARTY_RISE`` of ``height`` somewhere, and on all but
    less than ``MIN_SEEN`` metres of its width (a face narrower than that is one only where a neighbour reaches
    its top: a lower one leaves it free above)."""
    cover = face_bins(cover)
    topped = cover >= height - PARTY_RISE
    seen = (~topped).mean(axis=1) * np.asarray(widths, dtype=float)
    return (cover > 0.0).any(axis=1) & topped.any(axis=1) & (seen < MIN_SEEN)


def face_bins(cover: np.ndarray) -> np.ndarray:
    """Neighbour cover as ``(faces, bins)``; one value per face is a cover over the whole width."""
    cover = np.asarray(cover, dtype=float)
    return cover[:, None] if cover.ndim == 1 else cover


@dataclass(frozen=True)
class FaceRoles:
    """What each face of a building is, decided before any request: the building's ``floor_lines``, and per face
    (bool arrays) a ``party`` wall, a ``facade`` face (neither a party wall nor too narrow), a ``street`` face
    (a facade face, not a courtyard's, whose foot is free); the ``entrance`` face (None: no door)."""

    floor_lines: tuple[float, ...]
    party: np.ndarray
    facade: np.ndarray
    street: np.ndarray
    entrance: int | None

    @property
    def levels(self) -> int:
        return len(self.floor_lines) - 1


def face_roles(footprint: Footprint, mass: Mass, cover: np.ndarray, defaults: Defaults) -> FaceRoles:
    """The :class:`FaceRoles` of a building; ``cover`` is per face (and bin across its width) the height up to
    which neighbours stand against it (``citygen.mass.neighbour_cover``)."""
    lifted = footprint.lift > 0.0
    floor_lines = plan_floor_lines(mass.height, footprint.levels, defaults, lifted)
    faces = mass.faces
    widths = np.array([f.width for f in faces])
    cover = face_bins(cover)
    party = party_walls(cover, widths, mass.height)
    facade = ~party & (widths >= defaults.min_face_width)
    free_foot = (cover.max(axis=1) <= 0.0) & (not lifted)
    street = facade & free_foot & np.array([not f.is_courtyard for f in faces])
    door_candidates = np.flatnonzero(street & (widths >= 1.5))
    if door_candidates.size == 0:
        door_candidates = np.flatnonzero(facade & free_foot & (widths >= 1.5))
    if floor_lines[1] - floor_lines[0] < DOOR_STOREY:  # (no face can hold a door: none is asked for)
        door_candidates = door_candidates[:0]
    entrance = int(door_candidates[np.argmax(widths[door_candidates])]) if door_candidates.size else None
    return FaceRoles(floor_lines, party, facade, street, entrance)


def plan_building(footprint: Footprint, mass: Mass, cover: np.ndarray, defaults: Defaults,
                  seed: int, attributes: Mapping[str, Any] | None = None) -> BuildingPlan:
    """Decide floor lines, entrance face and corner strips (:func:`face_roles`), and the runs of a curved wall's
    faces (:func:`citygen.runs.face_runs`, dressed even where narrower than a facade face, with no strips at their
    inner corners); build one request per facade face. ``cover`` is per face (and bin across its width) the height up to which neighbours stand against it
    (``citygen.mass.neighbour_cover``)."""
    roles = face_roles(footprint, mass, cover, defaults)
    floor_lines, facade, street, entrance = roles.floor_lines, roles.facade, roles.street, roles.entrance
    faces = mass.faces
    widths = np.array([f.width for f in faces])
    free = (face_bins(cover).max(axis=1) <= 0.0) & (footprint.lift <= 0.0)
    joinable = ~roles.party & free
    if entrance is not None:
        joinable[entrance] = False
    runs = face_runs(faces, joinable)
    facade = facade.copy()
    facade[[i for run in runs for i in run]] = True
    corner = _corner_strips(mass, widths, facade, defaults.corner_width)
    for run in runs:  # (no strips at a run's inner corners: its bays run across them)
        for left, right in zip(run[:-1], run[1:]):
            corner[left, 1] = corner[right, 0] = 0.0
    attrs = dict(attributes if attributes is not None else footprint.attributes)
    requests = []
    for face in faces:
        if not facade[face.index]:
            continue
        context = FaceContext(building_id=footprint.id, face_index=face.index, levels=len(floor_lines) - 1,
                              street_facing=bool(street[face.index]), corner_angles=face.corner_angles,
                              neighbours=face.neighbours, is_courtyard=face.is_courtyard, attributes=attrs)
        requests.append(FacadeRequest(width=face.width, height=face.height, floor_lines=floor_lines,
                                      entrance=face.index == entrance,
                                      corner_widths=(float(corner[face.index, 0]), float(corner[face.index, 1])),
                                      context=context, seed=(seed, footprint.id, face.index),
                                      style_seed=(seed, footprint.id)))
    return BuildingPlan(building_id=footprint.id, levels=len(floor_lines) - 1, floor_lines=floor_lines,
                        entrance_face=entrance, requests=tuple(requests),
                        plain_faces=tuple(int(i) for i in np.flatnonzero(~facade)),
                        party_faces=tuple(int(i) for i in np.flatnonzero(roles.party)), runs=runs)


def _corner_strips(mass: Mass, widths: np.ndarray, facade: np.ndarray, corner_width: float) -> np.ndarray:
    """``(n, 2)`` strip widths (left, right) per face; both faces at a corner get the same width.

    The strip at a vertex is ``min(corner_width, 15% of each facade face meeting there)``; next to a plain face
    (party wall, sliver) the strip is kept so openings stay clear of the neighbour.
    """
    strips = np.zeros((len(mass.faces), 2))
    limit = np.where(facade, 0.15 * widths, np.inf)
    for face in mass.faces:
        left_nb = face.neighbours[0]
        at_start = min(corner_width, limit[face.index], limit[left_nb])
        strips[face.index, 0] = at_start
        strips[left_nb, 1] = at_start
    return strips
