"""One building from its footprint, mass and neighbour cover to a stage record: the coordinator's plan, a facade
layout per face from the assigned ruleset kinds, the roof and the geometry.

A :class:`Builder` holds the registry and a ruleset cache; the local executor keeps one per worker process, the
dask executor one per worker thread. Any error while building one building becomes its :class:`BuildingOutcome`'s
``skipped`` reason, never an exception.
"""
from __future__ import annotations

import operator
import time
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from citygen.attributes import assign_attributes, building_attributes, building_materials, building_pivot
from citygen.coordinator import face_bins, plan_building
from citygen.entrance import enforce_entrance
from citygen.errors import CitygenError, SceneError, SourceLocation
from citygen.footprints import Footprint, Skipped
from citygen.gcpause import cyclic_gc_paused
from citygen.geometry.building import build_geometry, clear_module_cache
from citygen.layout import FacadeLayout, Region, check_partition, hidden_behind
from citygen.mass import Mass
from citygen.plausible import check_plausible, plain_wall, summary
from citygen.registry import Registry, RulesetKind, default_registry
from citygen.request import FacadeRequest, check_request
from citygen.rng import derive_rng
from citygen.roofmesh import build_roof
from citygen.runs import grouped, per_face
from citygen.scene import Assignment, Scene
from citygen.geometry.building import BUILDING_RENDER, LABEL_MATERIAL
from citygen.usd.materials import resolve
from citygen.usd.writer import BuildingRecord


@dataclass(frozen=True)
class BuildingOutcome:
    """A built building's stage record, or why it was skipped; the warnings met on the way; from a builder
    that keeps them, the facade layout of each dressed face (by face index); and the CPU seconds its build took,
    measured in the thread that built it (a worker process's or the main one's)."""

    record: BuildingRecord | None
    skipped: Skipped | None
    warnings: tuple[str, ...]
    faces: tuple[tuple[str, int], ...] = ()  # (:func:`face_tally`)
    layouts: Mapping[int, FacadeLayout] | None = None
    cpu: float = 0.0


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


def load_rulesets(scene: Scene, registry: Registry | None = None) -> dict[tuple[str, Path], Any]:
    """Every ruleset the scene's ``[[assign]]`` rules name, and their fallbacks, loaded by its kind (keyed by kind
    id and path), so a ruleset that does not load stops the run before any building is generated: a
    :class:`SceneError` at the rule's line whose message carries the ruleset's own error (file:line:column)."""
    registry = registry or default_registry()
    loaded: dict[tuple[str, Path], Any] = {}
    for number, assignment in enumerate(scene.assignments, 1):
        named = [(p, assignment.kind) for p in assignment.rulesets]
        named += [(assignment.fallback, None)] if assignment.fallback is not None else []
        for path, kind_id in named:
            where = SourceLocation(str(scene.path), assignment.line)
            try:
                kind = registry.ruleset_kind(kind_id) if kind_id else registry.kind_for_path(path)
                if (kind.id, path) not in loaded:
                    loaded[kind.id, path] = kind.load(path)
            except CitygenError as exc:
                raise SceneError(f"[[assign]] #{number}: ruleset {path.name} does not load: {exc}",
                                 where=where) from exc
            except Exception as exc:  # a ruleset kind's bug: the run cannot use this ruleset either
                raise SceneError(f"[[assign]] #{number}: ruleset {path.name} does not load: internal error "
                                 f"{type(exc).__name__}: {exc}", where=where, plugin=kind.id,
                                 hint="this is a bug in the ruleset kind; please report it with the ruleset") from exc
    return loaded


class Builder:
    """Builds one building at a time; holds the registry and a ruleset cache (``rulesets``: already loaded ones,
    from :func:`load_rulesets`). With ``keep_layouts`` its outcomes carry the facade layouts too (an authoring tool
    shows them; the pipeline never ships them between processes)."""

    def __init__(self, scene: Scene, seed: int, registry: Registry | None = None,
                 rulesets: dict[tuple[str, Path], Any] | None = None, keep_layouts: bool = False) -> None:
        self.scene, self.seed, self.keep_layouts = scene, seed, keep_layouts
        self.registry = registry or default_registry()
        self.rulesets: dict[tuple[str, Path], Any] = dict(rulesets or {})
        self.roofs = self.registry.roof_builders
        self.undefined: dict[tuple[Path, str], bool] = {}  # (ruleset, material name) -> reported yet
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
        """The building's outcome, with the CPU its build took (this thread's, so it holds beside other workers).
        Module prototypes are shared within the building only: one built from another building's region (whichever
        this process built before, which depends on how chunks fell to workers) differs from it by up to ~1e-4 m, and
        the stage would differ between runs and job counts. The cyclic garbage collector is paused during the build:
        its hundreds of thousands of short-lived regions are freed by reference counting, and the collections they
        triggered cost ~6 % of the build's CPU."""
        start = time.thread_time()
        clear_module_cache()
        with cyclic_gc_paused():
            outcome = self._build(footprint, mass, cover, name, tile)
        return replace(outcome, cpu=time.thread_time() - start)

    def _build(self, footprint: Footprint, mass: Mass, cover: np.ndarray, name: str,
               tile: tuple[int, int]) -> BuildingOutcome:
        warnings: list[str] = []
        try:
            bins = face_bins(cover)
            plan = plan_building(footprint, mass, bins, self.scene.defaults, self.seed)
            layouts: dict[int, FacadeLayout] = {}
            used: list[str] = []
            tally: Counter[str] = Counter()
            for scope, courtyard in () if self.scene.output.masses else (("street", False), ("courtyard", True)):
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
                asked, parts = grouped(requests, plan.runs)  # (a curved wall's faces: one facade)
                generated = self._generate(kind, ruleset, asked, any_error=assignment.fallback is not None)
                dressed = [self._defined(layout, path, warnings) for layout in self._held(kind.id, generated, asked)]
                if assignment.fallback is not None:
                    dressed = [self._defined(layout, assignment.fallback, warnings)
                               for layout in self._fall_back(assignment.fallback, asked, dressed, used, warnings)]
                faced = per_face(parts, dressed)
                tally.update(face_tally([layout for _, layout in faced]))
                outside: list[tuple[FacadeRequest, str]] = []
                for request, layout in faced:
                    face = request.context.face_index
                    if layout.meta.get("outside_range"):
                        outside.append((request, layout.meta["fallback"]))
                    layouts[face] = hidden_behind(self._checked(layout, request, kind.id, warnings), bins[face])
                if outside:
                    warnings.append(_outside_range(footprint.id, kind.id, outside))
            wall, roof_material = building_materials(self.seed, footprint)
            faces = [(f, layouts.get(f.index)) for f in mass.faces]
            roof, roof_shape = build_roof(footprint, mass, plan.party_faces, self.roofs, warnings)
            geometry = build_geometry(mass, faces, wall, roof, modules=self.scene.output.instancing == "modules",
                                      roof_material=roof_material, walls=self.scene.output.lod != "none")
        except CitygenError as exc:
            return BuildingOutcome(None, Skipped(footprint.id, str(exc), footprint.source), tuple(warnings))
        except (Exception, SystemExit) as exc:  # a plugin bug (or exit) must skip one building, not the city
            reason = f"internal error {type(exc).__name__}: {exc}"
            return BuildingOutcome(None, Skipped(footprint.id, reason, footprint.source), tuple(warnings))
        attributes = building_attributes(footprint, mass, levels=plan.levels, entrance=plan.entrance_face,
                                         ruleset=", ".join(dict.fromkeys(used)) or "none", seed=self.seed,
                                         roof_shape=roof_shape, keep_tags=self.scene.output.keep_tags)
        pivot = building_pivot(footprint, mass)
        return BuildingOutcome(BuildingRecord(name, tile, geometry, attributes, pivot), None, tuple(warnings),
                               tuple(sorted(tally.items())), layouts if self.keep_layouts else None)

    def _defined(self, layout: FacadeLayout, ruleset: Path, warnings: list[str]) -> FacadeLayout:
        """``layout`` with every material name no library defines dropped (the region's label default is used),
        each such name reported once per ruleset with its fallback."""
        named = set(map(_MATERIAL, layout.leaf_sources[0])) - {None, BUILDING_RENDER}
        undefined = {m for m in named if resolve(m, self.scene.materials) is None}
        if not undefined:
            return layout
        for region in layout.leaves:
            if region.material in undefined and not self.undefined.get((ruleset, region.material)):
                self.undefined[ruleset, region.material] = True
                fallback = LABEL_MATERIAL.get(region.label or "", "the wall material")
                warnings.append(f"{ruleset.name}: material {region.material!r} is not defined; its {region.label} "
                                f"regions use {fallback} instead (define it in the scene's [materials] or in "
                                f"{ruleset.name.split('.')[0]}.materials.toml)")
        return replace(layout, root=_without(layout.root, undefined))

    @staticmethod
    def _generate(kind: RulesetKind, ruleset: Any, requests: list[FacadeRequest],
                  any_error: bool = False) -> list[FacadeLayout]:
        """Layouts for a building's faces; if the kind fails on the building, face by face, so one face it cannot
        dress becomes a plain wall (``meta["fallback"]``: reported later, or dressed by the rule's fallback)
        instead of costing the building. A CitygenError fails one face; with ``any_error`` (the rule has a
        fallback) so does any other exception, else that is a bug that skips the building."""
        caught = Exception if any_error else CitygenError
        try:
            return kind.generate_building(ruleset, requests)
        except caught:
            pass
        layouts = []
        for request in requests:
            try:
                layouts.append(kind.generate(ruleset, request))
            except caught as exc:
                reason = str(exc) if isinstance(exc, CitygenError) else f"internal error {type(exc).__name__}: {exc}"
                layouts.append(plain_wall(request, f"the ruleset failed: {reason}"))
        return layouts

    def _held(self, kind_id: str, layouts: list[FacadeLayout], requests: list[FacadeRequest]) -> list[FacadeLayout]:
        """``layouts`` held to the scene's plausibility rules: a layout with findings (after the entrance repair
        geometry would make) becomes a plain wall whose ``meta["fallback"]`` names them, so the scene's fallback
        ruleset gets the face and the report says why."""
        out = []
        for layout, request in zip(layouts, requests):
            if not layout.meta.get("fallback"):
                findings = check_plausible(_entrance(layout, request)[0], request, self.scene.plausibility)
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
            except Exception:  # the face stays plain, with the assigned ruleset's warning
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
        layout, note = _entrance(layout, request)
        if note:
            warnings.append(f"{where}: {note}")
        warnings.extend(f"{where}: {p}" for p in check_request(layout, request)[:2])
        return layout


_MATERIAL = operator.attrgetter("material")


def _entrance(layout: FacadeLayout, request: FacadeRequest) -> tuple[FacadeLayout, str | None]:
    """:func:`enforce_entrance`, which a layout with its doors already skips without a walk of its terminals."""
    if layout.count("door") == (1 if request.entrance else 0):
        return layout, None
    return enforce_entrance(layout, request)


def _without(region: Region, names: set[str]) -> Region:
    """``region`` with the materials ``names`` cleared throughout its tree."""
    children = tuple(_without(c, names) for c in region.children)
    if region.material in names or children != region.children:
        return replace(region, material=None if region.material in names else region.material, children=children)
    return region


def _outside_range(building: str, kind_id: str, faces: list[tuple[FacadeRequest, str]]) -> str:
    """One warning for the faces of a building whose size lies outside every size its ruleset can take (plain
    walls): which faces, their sizes, and the first face's reason."""
    widths = [r.width for r, _ in faces]
    heights = [r.height for r, _ in faces]
    size = lambda v: f"{min(v):.2f}" if max(v) - min(v) < 0.005 else f"{min(v):.2f}-{max(v):.2f}"  # noqa: E731
    which = ", ".join(str(r.context.face_index) for r, _ in faces)
    return (f"{building}: {len(faces)} face(s) outside the ruleset's size range are plain walls ({kind_id}; faces "
            f"{which}: {size(widths)} x {size(heights)} m): {faces[0][1]}")
