"""Walls and roof from a building's height: which roof it gets, how tall, and what is left for the walls.

Heights follow the data's meaning (OSM Simple 3D Buildings). A *total* height -- OSM ``height``, CityJSON
``measuredHeight`` or solid extent, the scene's default height -- includes the roof: walls = total - roof. A height
from level counts (``building:levels``, the levels a building type implies) is the walls' own: the roof goes on top.
The roof's height above the walls, first that applies:

1. a flat roof (``roof:shape = flat``, or a shape no roof builder makes): none;
2. ``roof:height`` (metres);
3. ``roof:angle``: what the roof builder rises at that pitch over the outline (``RoofBuilder.rise``);
4. ``roof:levels`` times the scene's storey height (``[defaults] floor_height``);
5. a tagged ``roof:shape`` without any of these: its rise at the scene's pitch (``roof_pitch``: ``[[assign]]``
   rule or ``[defaults]``), at most ``TAGGED_SHARE`` of the total;
6. an untagged roof (shape from the scene): its rise at the scene's pitch, at most ``ROOF_STOREYS`` storeys and
   ``ROOF_SHARE`` of the total.

A roof of rule 5 or 6 on a total height also leaves each storey at least ``MIN_STOREY`` -- the storeys the data
count (``building:levels``), else one --, down to a flat roof: the data's storeys stay storeys (6 levels in 18 m
under a one-storey roof were 2.45 m each, too low for a door and its transom; Delft's 2.5 m sheds got 1.9 m walls
under a gable, too low for a door).

"Of the total" is of walls + roof where only the walls are known (level counts).

Where only the walls are known, a roof from the data is at most ``MAX_ROOF`` tall (a warning names the building).
Where the total is given, the roof leaves at least ``MIN_WALL_SHARE`` of it to the walls (a warning when tagged
roof data exceed the total; a part that is all roof keeps a low wall). The roof is then built to exactly that
height, so a tagged building's highest point is its base plus its ``height``.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace

from shapely.geometry import MultiPolygon, Polygon

from citygen.errors import FootprintError
from citygen.footprints import Footprint
from citygen.mass import Mass, MassPlan, clean_outline, on_grid
from citygen.registry import RoofBuilder
from citygen.roof import RoofSpec, roof_angle, roof_levels, roof_spec
from citygen.scene import Scene

#: An untagged roof is at most this many storeys tall ...
ROOF_STOREYS = 1.0
#: ... and at most this share of the building's total height.
ROOF_SHARE = 0.25
#: A roof whose shape the data tag (but not its height) is at most this share of the total.
TAGGED_SHARE = 0.5
#: A roof from the data leaves at least this share of a given total height to the walls.
MIN_WALL_SHARE = 0.1
#: A roof at the scene's pitch leaves each storey under it at least this tall (metres).
MIN_STOREY = 2.8
#: A roof from the data on walls of known height (no total) is at most this tall (metres; the tallest spires are
#: ~150 m): more is a tagging error, capped with a warning.
MAX_ROOF = 300.0


@dataclass(frozen=True)
class HeightSplit:
    """A building's wall height, its roof (``roof.height``: the roof's height above the walls, None when flat),
    which rule set the roof's height (``source``: ``flat``, ``roof:height``, ``roof:levels``, ``roof:angle``,
    ``pitch`` or ``pitch, capped``) and the warnings met."""

    walls: float
    roof: RoofSpec
    source: str
    warnings: tuple[str, ...] = ()

    @property
    def total(self) -> float:
        """Walls plus roof: the building's highest point above its base."""
        return self.walls + (self.roof.height or 0.0)


def roof_choice(scene: Scene, attributes: Mapping[str, object]) -> tuple[str, float]:
    """The roof shape and pitch of an untagged roof: the first ``[[assign]]`` rule matching ``attributes`` that
    sets one, else ``[defaults]``."""
    rule = next((a for a in scene.assignments if (a.roof_shape or a.roof_pitch) and a.matches(attributes)), None)
    defaults = scene.defaults
    return (rule and rule.roof_shape) or defaults.roof_shape, (rule and rule.roof_pitch) or defaults.roof_pitch


def split_height(footprint: Footprint, outline: Polygon | MultiPolygon, scene: Scene,
                 roofs: Mapping[str, RoofBuilder]) -> HeightSplit:
    """The walls and roof of ``footprint`` (its cleaned ``outline``) by the rules of this module."""
    attrs = footprint.attributes
    shape, pitch = roof_choice(scene, {**attrs, "levels": footprint.levels, "height": footprint.height,
                                       "area": outline.area})
    spec = roof_spec(attrs, math.inf, shape=shape, pitch=pitch)
    storey = scene.defaults.floor_height
    total = footprint.height if footprint.height_is_total else None
    builder = roofs.get(spec.shape)
    levels = roof_levels(attrs)
    if builder is None or builder is roofs.get("flat"):
        rise, source = 0.0, "flat"
    elif spec.height:
        rise, source = spec.height, "roof:height"
    elif roof_angle(attrs) is not None:
        rise, source = builder.rise(outline, spec), "roof:angle"
    elif levels is not None:
        rise, source = levels * storey, "roof:levels"
    else:
        natural = builder.rise(outline, spec)
        tagged = attrs.get("roof:shape") not in (None, "")
        share = TAGGED_SHARE if tagged else ROOF_SHARE
        most = share * total if total is not None else share / (1 - share) * footprint.height
        if total is not None:
            most = min(most, max(0.0, total - (footprint.levels or 1) * MIN_STOREY))
        rise = min(natural, most) if tagged else min(natural, ROOF_STOREYS * storey, most)
        source = "pitch" if rise >= natural else "pitch, capped"
    warnings = []
    walls = footprint.height
    if total is None and rise > MAX_ROOF:
        warnings.append(f"{footprint.id}: a {rise:.4g} m roof ({source}) is no roof; it is {MAX_ROOF:g} m -- check its "
                        "roof tags")
        rise = MAX_ROOF
    if total is not None:
        most = (1 - MIN_WALL_SHARE) * total
        if rise > most:
            if rise > total and source.startswith("roof:"):
                warnings.append(f"{footprint.id}: a {rise:.2f} m roof ({source}) is taller than the building's "
                                f"{total:g} m; the roof is {most:.2f} m, the walls {total - most:.2f} m -- check its "
                                f"height tags")
            rise = most
        walls = total - rise
    if rise <= 0:  # (a shape no builder makes stays named: the builder warns and builds it flat)
        return HeightSplit(walls, replace(spec, shape=spec.shape if builder is None else "flat", height=None),
                           "flat", tuple(warnings))
    return HeightSplit(walls, replace(spec, height=rise, cap=math.inf), source, tuple(warnings))


#: The longest a footprint may span, in metres (the longest buildings are 1-4.5 km). Beyond, its coordinates are
#: not metres in a local frame (millimetres read as metres, an unprojected CRS): its facades would never be derived.
MAX_SPAN = 10_000.0


def mass_plan(footprint: Footprint, scene: Scene, roofs: Mapping[str, RoofBuilder]
              ) -> tuple[MassPlan, tuple[str, ...]]:
    """The building's mass, before its wall faces are made: its cleaned outline, walls to their height and the
    roof it carries (:func:`split_height`); and the warnings met. A :class:`~citygen.errors.FootprintError` when the
    footprint spans more than :data:`MAX_SPAN`."""
    x0, y0, x1, y1 = footprint.polygon.bounds
    span = max(x1 - x0, y1 - y0)
    if not span <= MAX_SPAN:
        raise FootprintError(f"its outline spans {span:,.0f} m (bounds {x0:g}, {y0:g}, {x1:g}, {y1:g}), longer than "
                             f"any building ({MAX_SPAN:,.0f} m at most): its coordinates are not metres in a local "
                             f"frame", hint="check the source's coordinates, their units and CRS")
    outline = clean_outline(footprint.polygon)
    split = split_height(footprint, outline, scene, roofs)
    return MassPlan(outline, footprint.base, on_grid(split.walls), split.roof, split.source), split.warnings


def plan_mass(footprint: Footprint, scene: Scene, roofs: Mapping[str, RoofBuilder]) -> tuple[Mass, tuple[str, ...]]:
    """The building's mass with walls to their height and the roof it carries (:func:`split_height`), and the
    warnings met."""
    plan, warnings = mass_plan(footprint, scene, roofs)
    return plan.mass(), warnings
