"""A building's roof mesh from the roof its mass carries, by the registered roof builders; an unknown shape or a
failing builder gives a flat roof, with a warning. Shared by the detailed and the mass-only builds."""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import TYPE_CHECKING

from shapely.geometry import MultiPolygon

from citygen.footprints import Footprint
from citygen.mass import Mass
from citygen.roof import ROOF_BUDGET, rectangle_like, roof_budget, roof_notes

if TYPE_CHECKING:
    from citygen.geometry.building import MeshData
    from citygen.registry import RoofBuilder


def build_roof(footprint: Footprint, mass: Mass, party: tuple[int, ...], roofs: Mapping[str, RoofBuilder],
               warnings: list[str]) -> tuple[MeshData | None, str]:
    """The roof the mass carries (``mass.roof``: shape and height decided with the walls, :mod:`citygen.roofplan`)
    and the shape built; an unknown shape or a failing builder gives a flat roof (with a warning in ``warnings``).
    The faces the coordinator found to be party walls (``party``) are passed on in the spec."""
    spec = replace(mass.roof, party=party)
    flat = roofs.get("flat")
    builder = roofs.get(spec.shape, flat)
    if spec.shape not in roofs:
        warnings.append(f"{footprint.id}: flat roof instead of roof:shape={spec.shape!r}, which no roof builder "
                        f"makes (known: {', '.join(sorted(roofs))})")
    parts = mass.outline.geoms if isinstance(mass.outline, MultiPolygon) else [mass.outline]
    if spec.orientation and getattr(builder, "oriented", False) and not all(map(rectangle_like, parts)):
        warnings.append(f"{footprint.id}: roof:orientation={spec.orientation} ignored where the outline is not "
                        f"rectangle-like; the ridge follows the straight skeleton")
    top = mass.base + mass.height
    if builder is None or builder is flat:
        return (flat.build(mass.outline, top, spec) if flat else None), "flat"
    try:
        with roof_notes() as notes, roof_budget(ROOF_BUDGET):  # what the builder reports: the building's warning
            roof = builder.build(mass.outline, top, spec)
        warnings.extend(f"{footprint.id}: {spec.shape} roof: {n}" for n in notes)
        return roof, spec.shape
    except (Exception, SystemExit) as exc:  # degenerate outline or a builder bug: a flat roof
        warnings.append(f"{footprint.id}: flat roof instead of {spec.shape}: {type(exc).__name__}: {exc}")
        return (flat.build(mass.outline, top, spec) if flat else None), "flat"
