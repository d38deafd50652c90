"""One building from its footprint, mass and neighbour cover to a stage record: the coordinator's plan, a facade
layout per face from the assigned ruleset kinds, the roof and the geometry.

A :class:`Builder` holds the registry and a ruleset cache; the local executor keeps one per worker process, the
dask executor one per worker thread. Any error while building one building becomes its :class:`BuildingOutcome`'s
``skipped`` reason, never an exception.
"""
from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from shapely.geometry import MultiPolygon

from citygen.coordinator import face_bins, plan_building
from citygen.entrance import enforce_entrance
from citygen.errors import CitygenError
from citygen.footprints import Footprint, Skipped
from citygen.geometry.building import MeshData, build_geometry, clear_module_cache
from citygen.layout import FacadeLayout, check_partition, hidden_behind
from citygen.mass import Mass
from citygen.plausible import check_plausible, plain_wall, summary
from citygen.registry import Registry, RulesetKind, default_registry
from citygen.request import FacadeRequest, check_request
from citygen.rng import derive_rng
from citygen.roof import rectangle_like, roof_notes, roof_spec
from citygen.scene import Assignment, Scene
from citygen.usd.materials import WALL_PALETTE, colour_material
from citygen.usd.writer import BuildingRecord


@dataclass(frozen=True)
class BuildingOutcome:
    """A built building's stage record, or why it was skipped; and the warnings met on the way."""

    record: BuildingRecord | None
    skipped: Skipped | None
    warnings: tuple[str, ...]
    faces: tuple[tuple[str, int], ...] = ()  # (:func:`face_tally`)


def face_tally(layouts: Sequence[FacadeLayout]) -> Counter[str]:
    """How a building's generated faces ended: ``dressed`` by the assigned ruleset, dressed by the ``fallback``
    ruleset, ``plain`` wall (the ruleset failed or was implausible), ``outside-range`` (a plain wall: the face's
    size lies outside every size the ruleset takes); and ``finding:CODE`` once per face a plausibility rule
    rejected (:mod:`citygen.plausible`)."""
    tally: Counter[str] = Counter()
    for layout in layouts:
        meta = layout.meta
        tally["outside-range" if meta.get("outside_range") else "plain" if meta.get("fallback")
              else "fallback" if meta.get("fell_back_from") else "dressed"] += 1
        tally.update(f"finding:{code}" for code in {f.split(":", 1)[0] for f in meta.get("findings", ())})
    return tally


def assign_attributes(footprint: Footprint, mass: Mass) -> dict[str, Any]:
    """What ``[[assign]] when`` tests see: the footprint's attributes plus levels, height and area."""
    return {**footprint.attributes, "levels": footprint.levels, "height": footprint.height, "area": mass.outline.area}


class Builder:
    """Builds one building at a time; holds the registry and a ruleset cache."""

    def __init__(self, scene: Scene, seed: int, registry: Registry | None = None) -> None:
        self.scene, self.seed = scene, seed
        self.registry = registry or default_registry()
        self.rulesets: dict[tuple[str, Path], Any] = {}
        self.roofs = self.registry.roof_builders
        clear_module_cache()

    def ruleset(self, assignment: Assignment, path: Path):
        kind = (self.registry.ruleset_kind(assignment.kind) if assignment.kind
                else self.registry.kind_for_path(path))
        return kind, self._loaded(kind, path)

    def _loaded(self, kind: RulesetKind, path: Path) -> Any:
        key = (kind.id, path)
        if key not in self.rulesets:
            self.rulesets[key] = kind.load(path)
        return self.rulesets[key]

    def choose(self, footprint: Footprint, mass: Mass, scope: str) -> tuple[Assignment, Path] | None:
        attrs = assign_attributes(footprint, mass)
        for a in self.scene.assignments:
            if a.faces in ("all", scope) and a.matches(attrs):
                pick = derive_rng(self.seed, footprint.id, "ruleset", scope).integers(len(a.rulesets))
                return a, a.rulesets[int(pick)]
        return None

    def build(self, footprint: Footprint, mass: Mass, cover: np.ndarray, name: str,
              tile: tuple[int, int]) -> BuildingOutcome:
        warnings: list[str] = []
        try:
            bins = face_bins(cover)
            plan = plan_building(footprint, mass, bins, self.scene.defaults, self.seed)
            layouts: dict[int, FacadeLayout] = {}
            used: list[str] = []
            tally: Counter[str] = Counter()
            for scope, courtyard in (("street", False), ("courtyard", True)):
                requests = [replace(r, plausibility=self.scene.plausibility) for r in plan.requests
                            if r.context.is_courtyard == courtyard]
                if not requests:
                    continue
                choice = self.choose(footprint, mass, scope)
                if choice is None:
                    warnings.append(f"{footprint.id}: no [[assign]] matches its {scope} faces; plain walls")
                    continue
                assignment, path = choice
                kind, ruleset = self.ruleset(assignment, path)
                used.append(f"{kind.id}:{path.name}")
                dressed = self._held(kind.id, self._generate(kind, ruleset, requests), requests)
                if assignment.fallback is not None:
                    dressed = self._fall_back(assignment.fallback, requests, dressed, used, warnings)
                tally.update(face_tally(dressed))
                outside: list[tuple[FacadeRequest, str]] = []
                for request, layout in zip(requests, dressed):
                    face = request.context.face_index
                    if layout.meta.get("outside_range"):
                        outside.append((request, layout.meta["fallback"]))
                    layouts[face] = hidden_behind(self._checked(layout, request, kind.id, warnings), bins[face])
                if outside:
                    warnings.append(_outside_range(footprint.id, kind.id, outside))
            wall, roof_material = self._materials(footprint)
            faces = [(f, layouts.get(f.index)) for f in mass.faces]
            roof = self._roof(footprint, mass, plan.party_faces, warnings)
            geometry = build_geometry(mass, faces, wall, roof, modules=self.scene.output.instancing == "modules",
                                      roof_material=roof_material, walls=self.scene.output.lod)
        except CitygenError as exc:
            return BuildingOutcome(None, Skipped(footprint.id, str(exc), footprint.source), tuple(warnings))
        except Exception as exc:  # a plugin bug must skip one building, not the city
            reason = f"internal error {type(exc).__name__}: {exc}"
            return BuildingOutcome(None, Skipped(footprint.id, reason, footprint.source), tuple(warnings))
        attributes = {"sourceId": footprint.id, "height": float(footprint.height),
                      "heightSource": footprint.height_source, "levels": plan.levels, "base": float(footprint.base),
                      "ruleset": ", ".join(dict.fromkeys(used)) or "none", "seed": self.seed,
                      "entranceFace": -1 if plan.entrance_face is None else plan.entrance_face}
        return BuildingOutcome(BuildingRecord(name, tile, geometry, attributes), None, tuple(warnings),
                               tuple(sorted(tally.items())))

    def _materials(self, footprint: Footprint) -> tuple[str, str]:
        """Wall and roof materials: the OSM ``building:colour`` / ``roof:colour`` where given, a brick wall for
        ``building:material = brick``, else a wall drawn from the palette (per building seed) and a dark roof."""
        attrs = footprint.attributes
        wall = colour_material(attrs.get("building:colour"))
        if wall is None:
            palette = derive_rng(self.seed, footprint.id, "palette").integers(len(WALL_PALETTE))
            wall = "brick" if attrs.get("building:material") == "brick" else WALL_PALETTE[palette]
        return wall, colour_material(attrs.get("roof:colour")) or "roof_dark"

    def _roof(self, footprint: Footprint, mass: Mass, party: tuple[int, ...], warnings: list[str]
              ) -> MeshData | None:
        """The building's roof: shape from its ``roof:shape`` tag, else the first matching ``[[assign]]`` rule
        that sets one, else ``[defaults]``; an unknown tag or a failing builder gives a flat roof (with a warning).
        The faces the coordinator found to be party walls (``party``) are passed on in the spec."""
        attrs = assign_attributes(footprint, mass)
        rule = next((a for a in self.scene.assignments if (a.roof_shape or a.roof_pitch) and a.matches(attrs)), None)
        defaults = self.scene.defaults
        spec = roof_spec(footprint.attributes, mass.height,
                         shape=(rule and rule.roof_shape) or defaults.roof_shape,
                         pitch=(rule and rule.roof_pitch) or defaults.roof_pitch,
                         party=party)
        flat = self.roofs.get("flat")
        builder = self.roofs.get(spec.shape, flat)
        if spec.shape not in self.roofs:
            warnings.append(f"{footprint.id}: flat roof instead of roof:shape={spec.shape!r}, which no roof builder "
                            f"makes (known: {', '.join(sorted(self.roofs))})")
        parts = mass.outline.geoms if isinstance(mass.outline, MultiPolygon) else [mass.outline]
        if spec.orientation and getattr(builder, "oriented", False) and not all(map(rectangle_like, parts)):
            warnings.append(f"{footprint.id}: roof:orientation={spec.orientation} ignored where the outline is not "
                            f"rectangle-like; the ridge follows the straight skeleton")
        top = mass.base + mass.height
        if builder is None or builder is flat:
            return flat.build(mass.outline, top, spec) if flat else None
        try:
            with roof_notes() as notes:  # what the builder reports is this building's warning
                roof = builder.build(mass.outline, top, spec)
            warnings.extend(f"{footprint.id}: {spec.shape} roof: {n}" for n in notes)
            return roof
        except Exception as exc:  # degenerate outline or a builder bug: keep the building, with a flat roof
            warnings.append(f"{footprint.id}: flat roof instead of {spec.shape}: {type(exc).__name__}: {exc}")
            return flat.build(mass.outline, top, spec) if flat else None

    @staticmethod
    def _generate(kind: RulesetKind, ruleset: Any, requests: list[FacadeRequest]) -> list[FacadeLayout]:
        """Layouts for a building's faces; if the kind fails on the building, face by face, so one face it cannot
        dress becomes a plain wall (``meta["fallback"]``: reported later) instead of costing the building."""
        try:
            return kind.generate_building(ruleset, requests)
        except CitygenError:
            pass
        layouts = []
        for request in requests:
            try:
                layouts.append(kind.generate(ruleset, request))
            except CitygenError as exc:
                layouts.append(plain_wall(request, f"the ruleset failed: {exc}"))
        return layouts

    def _held(self, kind_id: str, layouts: list[FacadeLayout], requests: list[FacadeRequest]) -> list[FacadeLayout]:
        """``layouts`` held to the scene's plausibility rules: a layout with findings (after the entrance repair
        geometry would make) becomes a plain wall whose ``meta["fallback"]`` names them, so the scene's fallback
        ruleset gets the face and the report says why."""
        out = []
        for layout, request in zip(layouts, requests):
            if not layout.meta.get("fallback"):
                findings = check_plausible(enforce_entrance(layout, request)[0], request, self.scene.plausibility)
                if findings:
                    layout = plain_wall(request, f"implausible layout: {summary(findings)}", findings, kind=kind_id)
            out.append(layout)
        return out

    def _fall_back(self, path: Path, requests: list[FacadeRequest], layouts: list[FacadeLayout],
                   used: list[str], warnings: list[str]) -> list[FacadeLayout]:
        """The faces the assigned ruleset left plain (``meta["fallback"]``) dressed by the ``fallback`` ruleset, face
        by face on the same floor lines and entrance, held to the same plausibility rules; where it cannot dress
        one either, the face stays plain. The faces it dressed are named in ``used`` (the building's ruleset
        attribute) and in one warning with the first face's reason."""
        plain = [k for k, layout in enumerate(layouts) if layout.meta.get("fallback")]
        if not plain:
            return layouts
        kind = self.registry.kind_for_path(path)
        ruleset, out, dressed = self._loaded(kind, path), list(layouts), []
        for k in plain:
            try:
                layout = self._held(kind.id, [kind.generate(ruleset, requests[k])], [requests[k]])[0]
            except CitygenError:
                continue
            if not layout.meta.get("fallback"):
                out[k] = replace(layout, meta={**layout.meta, "fell_back_from": layouts[k].meta["fallback"],
                                               "findings": layouts[k].meta.get("findings", [])})
                dressed.append(k)
        if dressed:
            faces = ", ".join(str(requests[k].context.face_index) for k in dressed)
            used.append(f"{kind.id}:{path.name} (fallback on faces {faces})")
            first = requests[dressed[0]].context
            warnings.append(f"{first.building_id}: faces {faces} dressed by the fallback {path.name}; face "
                            f"{first.face_index}: {layouts[dressed[0]].meta['fallback']}")
        return out

    @staticmethod
    def _checked(layout: FacadeLayout, request: FacadeRequest, kind_id: str, warnings: list[str]) -> FacadeLayout:
        where = f"{request.context.building_id} face {request.context.face_index}"
        problems = check_partition(layout)
        if problems:
            raise CitygenError(f"{where}: layout is not a partition: {problems[0]}", plugin=kind_id,
                               hint="this is a bug in the ruleset kind; please report it with the ruleset")
        if layout.meta.get("fallback") and not layout.meta.get("outside_range"):  # a kind that could not dress
            warnings.append(f"{where}: {kind_id} fell back to plain walls: {layout.meta['fallback']}")  # the face
        layout, note = enforce_entrance(layout, request)
        if note:
            warnings.append(f"{where}: {note}")
        warnings.extend(f"{where}: {p}" for p in check_request(layout, request)[:2])
        return layout


def _outside_range(building: str, kind_id: str, faces: list[tuple[FacadeRequest, str]]) -> str:
    """One warning for the faces of a building whose size lies outside every size its ruleset can take (plain
    walls): which faces, their sizes, and the first face's reason."""
    widths = [r.width for r, _ in faces]
    heights = [r.height for r, _ in faces]
    size = lambda v: f"{min(v):.2f}" if max(v) - min(v) < 0.005 else f"{min(v):.2f}-{max(v):.2f}"  # noqa: E731
    which = ", ".join(str(r.context.face_index) for r, _ in faces)
    return (f"{building}: {len(faces)} face(s) outside the ruleset's size range are plain walls ({kind_id}; faces "
            f"{which}: {size(widths)} x {size(heights)} m): {faces[0][1]}")
