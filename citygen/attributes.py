"""What a building carries besides its geometry, the same for detailed and mass-only buildings: the attributes
``[[assign]]`` tests see, its materials (the OSM colours or a palette pick), its ``citygen:*`` attributes and its
pivot; and the warnings about ``when`` tests the footprints can never satisfy."""
from __future__ import annotations

import difflib
from collections.abc import Mapping, Sequence
from fnmatch import fnmatchcase
from typing import Any

import numpy as np

from citygen.footprints import Footprint
from citygen.mass import Mass, MassPlan
from citygen.rng import derive_rng
from citygen.scene import Scene
from citygen.usd.materials import WALL_PALETTE, colour_material


def assign_attributes(footprint: Footprint, mass: Mass) -> dict[str, Any]:
    """What ``[[assign]] when`` tests see: the footprint's attributes plus levels, height (the data's: a total,
    roof included, or for level counts the walls') and area."""
    return {**footprint.attributes, "levels": footprint.levels, "height": footprint.height, "area": mass.outline.area}


class AttributeKinds:
    """The attributes the city's footprints carry, seen one footprint at a time (:meth:`add`), and per attribute
    whether it is a number on every footprint that has it: what :meth:`warnings` checks the scene's ``when`` tests
    against, without holding the footprints."""

    def __init__(self) -> None:
        self.numeric: dict[str, bool] = {}  # (attribute -> a number on every footprint so far)

    def add(self, footprint: Footprint, mass: Mass | MassPlan) -> None:
        for key, value in assign_attributes(footprint, mass).items():
            if value is not None:
                self.numeric[key] = self.numeric.get(key, True) and _is_number(value)

    def warnings(self, scene: Scene) -> list[str]:
        """What is wrong with the scene's ``when`` tests against the footprints seen: an attribute none has (a
        misspelling, with the nearest names), and text compared with an attribute that is a number on every
        footprint that has it (never equal)."""
        if not self.numeric:
            return []
        found = []
        for number, assignment in enumerate(scene.assignments, 1):
            where = f"{scene.path.name}:{assignment.line}: [[assign]] #{number}"
            for condition in assignment.conditions:
                numeric = self.numeric.get(condition.key)
                if numeric is None:
                    near = difflib.get_close_matches(condition.key, list(self.numeric), n=3)
                    found.append(f"{where}: no footprint has attribute {condition.key!r}, so the rule matches none"
                                 + (f" (did you mean {', '.join(map(repr, near))}?)" if near else ""))
                elif condition.op == "in" and numeric and not any(
                        _is_number(v) or _numeric_text(v) for v in condition.values):
                    found.append(f"{where}: when {condition.key} = {list(condition.values)!r} compares text with "
                                 f"{condition.key}, a number on every footprint: it never matches")
        return found


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


def _numeric_text(value: Any) -> bool:
    try:
        float(value)
    except (TypeError, ValueError):
        return False
    return True


def kept_tags(attributes: Mapping[str, Any], patterns: Sequence[str]) -> dict[str, Any]:
    """The source tags the scene keeps (``[output] keep_tags``: names or ``fnmatch`` patterns such as ``addr:*``)
    as ``tag:<name>`` attributes, in name order."""
    return {f"tag:{key}": value for key, value in sorted(attributes.items())
            if any(fnmatchcase(key, p) for p in patterns) and isinstance(value, (str, int, float))}


def building_materials(seed: int, footprint: Footprint) -> tuple[str, str]:
    """Wall and roof materials: the OSM ``building:colour`` / ``roof:colour`` where given, a brick wall for
    ``building:material = brick``, else a wall drawn from the palette (per building seed) and a dark roof."""
    attrs = footprint.attributes
    wall = colour_material(attrs.get("building:colour"))
    if wall is None:
        palette = derive_rng(seed, footprint.id, "palette").integers(len(WALL_PALETTE))
        wall = "brick" if attrs.get("building:material") == "brick" else WALL_PALETTE[palette]
    return wall, colour_material(attrs.get("roof:colour")) or "roof_dark"


def building_attributes(footprint: Footprint, mass: Mass, *, levels: int, entrance: int | None, ruleset: str,
                        seed: int, roof_shape: str, keep_tags: Sequence[str]) -> dict[str, Any]:
    """The building's ``citygen:*`` attributes (docs/dcc.md): its source, heights, levels, ruleset(s), seed,
    entrance face (-1: none), type, the roof shape built, footprint area and the source tags the scene keeps.
    Lengths are rounded to a micrometre: the walls stand on a grid of 2**-20 m (:data:`~citygen.mass.GRID`), and a
    70 m tower read as 69.99999980926513 m in a DCC's properties is not the data's 70 m."""
    return {"sourceId": footprint.id, "height": _um(mass.top - mass.base), "wallHeight": _um(mass.height),
            "roofHeight": _um(mass.roof.height or 0.0), "roofHeightSource": mass.roof_source,
            "heightSource": footprint.height_source, "levels": levels, "base": _um(footprint.base),
            "ruleset": ruleset, "seed": seed, "entranceFace": -1 if entrance is None else entrance,
            "buildingType": str(footprint.attributes.get("building", "yes")), "roofShape": roof_shape,
            "footprintArea": round(float(mass.outline.area), 3), **kept_tags(footprint.attributes, keep_tags)}


def _um(length: float) -> float:
    """``length`` in metres rounded to a micrometre."""
    return round(float(length), 6)


def building_pivot(footprint: Footprint, mass: Mass) -> tuple[float, float, float]:
    """Where the building's transform puts its local origin: the centroid of its outline, on the ground (its base
    less the lift of a part that starts above the ground)."""
    centroid = mass.outline.centroid
    return float(centroid.x), float(centroid.y), float(footprint.base - footprint.lift)
