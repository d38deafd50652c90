"""What a roof builder is asked to build: the shape and its parameters, from OSM roof tags and scene defaults.

Tags read (https://wiki.openstreetmap.org/wiki/Key:roof:shape): ``roof:shape``, ``roof:height`` (metres above the
wall top), ``roof:angle`` (pitch in degrees), ``roof:direction`` (compass degrees or N/NE/..., the direction the
main slope faces, i.e. downhill; where the orientation is untagged the ridge runs parallel to the side facing it),
``roof:orientation`` (``along``: ridge parallel to the longest side, ``across``: perpendicular to it;
rectangle-like outlines only, see :func:`rectangle_like`). A tag that does not parse is ignored, so the scene's
default applies.

*Party walls* -- outline edges a neighbour stands against up to the eave (``citygen.coordinator.party_walls``) --
are passed to the builder in :attr:`RoofSpec.party`: a pitched roof must not slope down onto the neighbour.
"""
from __future__ import annotations

import math
import re
import threading
import time
import warnings
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import shapely
from shapely.geometry import MultiPolygon, Polygon

#: A pitch outside this range (degrees) is clamped: flatter is a flat roof, steeper a tower.
PITCH_RANGE = (5.0, 75.0)
#: A roof is never taller than this many times its walls (with at least ``MIN_ROOF_CAP`` metres allowed).
ROOF_TO_WALL_CAP = 1.0
MIN_ROOF_CAP = 4.0

_CARDINAL = {name: 22.5 * k for k, name in enumerate(
    "N NNE NE ENE E ESE SE SSE S SSW SW WSW W WNW NW NNW".split())}
#: ``roof:orientation`` values (OSM): the ridge along or across the longest side.
ORIENTATIONS = ("along", "across")
#: A part is rectangle-like when it has four sides and fills at least this share of its minimum rotated rectangle.
RECTANGLE_FILL = 0.9
_NUMBER = re.compile(r"^\s*(-?\d+(?:\.\d*)?)\s*(m|deg|°)?\s*$")


class RoofWarning(UserWarning):
    """A roof builder built something other than asked (e.g. ignored party walls), outside :func:`roof_notes`."""


_NOTES = threading.local()


@contextmanager
def roof_notes() -> Iterator[list[str]]:
    """Collect what roof builders :func:`note` in this thread (the pipeline: per building, as its warnings)."""
    outer = getattr(_NOTES, "items", None)
    _NOTES.items = items = []
    try:
        yield items
    finally:
        _NOTES.items = outer


#: Seconds one roof may take; past it the pipeline builds that roof flat, with a warning.
ROOF_BUDGET = 5.0


class RoofBudgetExceeded(Exception):
    """A roof builder ran past the time budget of :func:`roof_budget` (raised by :func:`check_budget`)."""


@contextmanager
def roof_budget(seconds: float) -> Iterator[None]:
    """Builders running in this block (this thread) get ``seconds`` of wall time: :func:`check_budget` raises
    :class:`RoofBudgetExceeded` after that."""
    outer = getattr(_NOTES, "deadline", None)
    _NOTES.deadline = (time.perf_counter() + seconds, seconds)
    try:
        yield
    finally:
        _NOTES.deadline = outer


def check_budget() -> None:
    """Raise :class:`RoofBudgetExceeded` when the enclosing :func:`roof_budget` has run out. Builders call it in
    their long loops (the straight skeleton: once per wavefront event); outside a budget it does nothing."""
    deadline = getattr(_NOTES, "deadline", None)
    if deadline is not None and time.perf_counter() > deadline[0]:
        raise RoofBudgetExceeded(f"over the roof time budget of {deadline[1]:g} s")


def note(message: str) -> None:
    """Report that a roof was built other than asked: to the enclosing :func:`roof_notes` of this thread (so
    concurrent threads never mix their buildings' reports), else as a :class:`RoofWarning`."""
    items = getattr(_NOTES, "items", None)
    if items is None:
        warnings.warn(message, RoofWarning, stacklevel=2)
    else:
        items.append(message)


@dataclass(frozen=True)
class RoofSpec:
    """A roof to build: ``shape`` (a roof builder id), ``pitch`` in degrees, an explicit ``height`` in metres
    (wins over the pitch), the compass ``direction`` its slope faces (skillion), ``cap``, the greatest
    height allowed above the wall top, the ridge ``orientation`` (``"along"``/``"across"``; None: untagged) and
    ``party``, the indices of the outline edges that are party walls (edge ``k`` of the outline's rings in order,
    part by part, exterior ring first: the mass's face indices)."""

    shape: str = "flat"
    pitch: float = 30.0
    height: float | None = None
    direction: float | None = None
    cap: float = math.inf
    orientation: str | None = None
    party: tuple[int, ...] = ()

    @property
    def slope(self) -> float:
        """Rise per metre of run for the pitch."""
        return math.tan(math.radians(self.pitch))


def _number(value: Any) -> float | None:
    if isinstance(value, bool):
        return None
    if isinstance(value, (int, float)):
        return float(value) if math.isfinite(value) else None
    match = _NUMBER.match(str(value))
    number = float(match[1]) if match else math.nan  # (digits beyond float range read as inf)
    return number if math.isfinite(number) else None


def parse_direction(value: Any) -> float | None:
    """Compass degrees from a number or a cardinal direction (``"NE"``), or None."""
    if value is None:
        return None
    cardinal = _CARDINAL.get(str(value).strip().upper())
    if cardinal is not None:
        return cardinal
    number = _number(value)
    return None if number is None else number % 360.0


def rectangle_like(part: Polygon) -> bool:
    """Four sides, no courtyard and nearly filling its minimum rotated rectangle: ``roof:orientation`` applies."""
    return (not part.interiors and len(part.exterior.coords) == 5
            and part.area >= RECTANGLE_FILL * part.minimum_rotated_rectangle.area)


def inscribed_radius(outline: Polygon | MultiPolygon) -> float:
    """The radius of the largest circle inside ``outline`` (of its largest part, to 0.1 m): a pitched roof's run."""
    parts = getattr(outline, "geoms", [outline])
    return max(shapely.length(shapely.maximum_inscribed_circle(list(parts), 0.1)).tolist(), default=0.0)


def roof_angle(attributes: Mapping[str, Any]) -> float | None:
    """The tagged ``roof:angle`` in degrees when it parses and lies in (0, 90), else None."""
    angle = _number(attributes.get("roof:angle"))
    return angle if angle is not None and 0 < angle < 90 else None


def roof_levels(attributes: Mapping[str, Any]) -> float | None:
    """The tagged ``roof:levels`` (storeys inside the roof) when it parses and is positive, else None."""
    levels = _number(attributes.get("roof:levels"))
    return levels if levels is not None and levels > 0 else None


def roof_spec(attributes: Mapping[str, Any], wall_height: float, shape: str = "flat",
              pitch: float = 30.0, party: tuple[int, ...] = ()) -> RoofSpec:
    """The roof of a building with OSM-style ``attributes``; ``shape`` and ``pitch`` apply where it has no tags;
    ``party``: its party-wall edges."""
    tag = attributes.get("roof:shape")
    shape = str(tag).strip().lower() if tag not in (None, "") else shape
    angle = roof_angle(attributes)
    if angle is not None:
        pitch = angle
    pitch = min(max(pitch, PITCH_RANGE[0]), PITCH_RANGE[1])
    height = _number(attributes.get("roof:height"))
    cap = max(MIN_ROOF_CAP, ROOF_TO_WALL_CAP * wall_height)
    orientation = str(attributes.get("roof:orientation", "")).strip().lower()
    return RoofSpec(shape=shape, pitch=pitch, height=min(height, cap) if height and height > 0 else None,
                    direction=parse_direction(attributes.get("roof:direction")), cap=cap,
                    orientation=orientation if orientation in ORIENTATIONS else None, party=tuple(party))
