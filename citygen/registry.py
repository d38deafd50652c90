"""Interfaces of the objects plugins register, and the typed plugin manager core code talks to.

Core code never calls raw pluggy hooks: it asks :class:`Registry` for a ruleset kind by id or file suffix, an
importer for a path, and so on. Loading is forgiving: a plugin that fails to import is recorded as broken (and
shown by ``citygen plugins``) instead of breaking the CLI; duplicate ids are an error naming both owners.
"""
from __future__ import annotations

import argparse
import importlib.metadata
from abc import ABC, abstractmethod
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pluggy

from citygen import hookspecs
from citygen.errors import PluginError, RulesetError
from citygen.roof import inscribed_radius

if TYPE_CHECKING:
    from shapely.geometry import MultiPolygon, Polygon

    from citygen.footprints import ImportResult
    from citygen.geometry.building import MeshData
    from citygen.layout import FacadeLayout
    from citygen.request import FacadeRequest
    from citygen.roof import RoofSpec


class RulesetKind(ABC):
    """A kind of facade ruleset: parses its files and generates layouts for requests.

    ``id`` names the kind in scenes (``kind = "split"``); ``suffixes`` are the file suffixes it reads.
    """

    id: str
    suffixes: tuple[str, ...] = ()
    description: str = ""

    @abstractmethod
    def load(self, path: Path) -> Any:
        """Parse a ruleset file into an immutable ruleset object; errors name file:line:column."""

    def loads(self, text: str, path: Path) -> Any:
        """Parse ruleset ``text`` as if it were the file at ``path`` (errors name ``path``, references resolve
        beside it): what an editor previews before the file is saved. Kinds that cannot say so."""
        raise RulesetError(f"the {self.id} ruleset kind parses files only, not edited text", where=str(path),
                           hint="save the file, then preview it")

    @abstractmethod
    def generate(self, ruleset: Any, request: FacadeRequest) -> FacadeLayout:
        """One facade layout for ``request``; must partition the face and honour the request's constraints."""

    def generate_building(self, ruleset: Any, requests: Sequence[FacadeRequest]) -> list[FacadeLayout]:
        """Layouts for all faces of one building that use this ruleset (override to couple faces)."""
        return [self.generate(ruleset, request) for request in requests]

    def explain(self, ruleset: Any, request: FacadeRequest) -> str:
        """Human-readable account of how the layout for ``request`` was derived (``citygen facade --explain``)."""
        return f"{self.id}: no explanation available"

    def render_png(self, layout: FacadeLayout, path: Path, floor_lines: Sequence[float] = ()) -> None:
        """Draw a layout for ``citygen facade --png`` (override to show kind-specific structure)."""
        from citygen.preview import save_png
        save_png(layout, path, lines=[("y", y) for y in floor_lines])


class FootprintImporter(ABC):
    """Reads building footprints from a file format."""

    id: str
    suffixes: tuple[str, ...] = ()
    description: str = ""

    @abstractmethod
    def read(self, path: Path, options: dict[str, Any]) -> ImportResult:
        """Footprints in a local metric frame plus per-feature problems; never raises for one bad feature."""


class RoofBuilder(ABC):
    """Builds the roof of a mass from its cleaned outline."""

    id: str
    description: str = ""
    #: Reads ``spec.orientation`` on rectangle-like outlines (the pipeline warns where it cannot apply).
    oriented: bool = False

    @abstractmethod
    def build(self, outline: Polygon | MultiPolygon, top: float, spec: RoofSpec | None = None) -> MeshData:
        """Roof mesh for ``outline`` (local frame) whose walls end at height ``top``, shaped by ``spec`` (pitch,
        height, direction, orientation, party-wall edges; None: the builder's defaults). Its open boundary must be
        the outline at ``top`` so it closes the walls; raise on an outline it cannot roof (the pipeline then builds
        a flat roof and warns)."""

    def rise(self, outline: Polygon | MultiPolygon, spec: RoofSpec) -> float:
        """About how tall (metres above the walls) :meth:`build` makes the roof at ``spec.pitch`` when no height
        is given: what the pipeline splits a building's height by (it then builds the roof to that height exactly).
        Default: the pitch's slope times the outline's inscribed radius (the run of a hipped or gabled roof)."""
        return spec.slope * inscribed_radius(outline)


class Command(ABC):
    """A CLI sub-command contributed by a plugin."""

    name: str
    help: str = ""

    @abstractmethod
    def configure(self, parser: argparse.ArgumentParser) -> None:
        """Add the command's arguments."""

    @abstractmethod
    def run(self, args: argparse.Namespace, registry: Registry) -> int:
        """Execute; return the process exit status."""


class LayoutSource(ABC):
    """A ``citygen layout NAME`` sub-command contributed by a plugin: something that becomes a FacadeLayout."""

    name: str
    help: str = ""

    @abstractmethod
    def configure(self, parser: argparse.ArgumentParser) -> None:
        """Add the sub-command's arguments."""

    @abstractmethod
    def run(self, args: argparse.Namespace) -> int:
        """Execute; return the process exit status."""


@dataclass(frozen=True)
class Origin:
    """Where a registered object came from."""

    plugin: str
    distribution: str


@dataclass
class Registry:
    """Everything the loaded plugins registered, indexed by id, with load problems kept for reporting."""

    ruleset_kinds: dict[str, RulesetKind] = field(default_factory=dict)
    importers: dict[str, FootprintImporter] = field(default_factory=dict)
    roof_builders: dict[str, RoofBuilder] = field(default_factory=dict)
    commands: dict[str, Command] = field(default_factory=dict)
    layout_sources: dict[str, LayoutSource] = field(default_factory=dict)
    origins: dict[tuple[str, str], Origin] = field(default_factory=dict)
    broken: list[tuple[str, str]] = field(default_factory=list)
    #: how it was loaded, so worker processes can load the same registry
    extra_plugins: tuple[object, ...] = ()
    entry_points: bool = True

    def ruleset_kind(self, kind_id: str) -> RulesetKind:
        try:
            return self.ruleset_kinds[kind_id]
        except KeyError:
            raise PluginError(f"no ruleset kind {kind_id!r}",
                              hint=f"loaded kinds: {', '.join(sorted(self.ruleset_kinds)) or 'none'}") from None

    def kind_for_path(self, path: Path) -> RulesetKind:
        suffix = path.suffix.lower()
        for kind in self.ruleset_kinds.values():
            if suffix in kind.suffixes:
                return kind
        known = sorted(s for k in self.ruleset_kinds.values() for s in k.suffixes)
        raise PluginError(f"no ruleset kind reads {suffix or 'files without suffix'}", where=str(path),
                          hint=f"known ruleset suffixes: {', '.join(known)}; or give kind explicitly")

    def importer_for(self, path: Path, fmt: str | None = None) -> FootprintImporter:
        if fmt is not None:
            if fmt not in self.importers:
                raise PluginError(f"no footprint importer {fmt!r}", where=str(path),
                                  hint=f"known formats: {', '.join(sorted(self.importers))}")
            return self.importers[fmt]
        name = path.name.lower()
        matches = [(len(s), importer.id) for importer in self.importers.values() for s in importer.suffixes
                   if name.endswith(s)]
        if matches:  # the most specific suffix wins: ".city.json" before ".json"
            return self.importers[max(matches)[1]]
        raise PluginError("no footprint importer for this file type", where=str(path),
                          hint=f"set format = one of {', '.join(sorted(self.importers))} in the scene")


_GROUPS = (("citygen_ruleset_kinds", "ruleset_kinds"), ("citygen_footprint_importers", "importers"),
           ("citygen_roof_builders", "roof_builders"), ("citygen_commands", "commands"),
           ("citygen_layout_sources", "layout_sources"))


def load_registry(extra_plugins: Iterable[object] = (), entry_points: bool = True) -> Registry:
    """Load plugins from the ``citygen`` entry-point group (plus ``extra_plugins``) into a :class:`Registry`."""
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs)
    extra_plugins = tuple(extra_plugins)
    registry = Registry(extra_plugins=extra_plugins, entry_points=entry_points)
    dists: dict[str, str] = {}
    if entry_points:
        for ep in sorted(importlib.metadata.entry_points(group=hookspecs.PROJECT), key=lambda e: e.name):
            dist = f"{ep.dist.name} {ep.dist.version}" if ep.dist else "?"
            try:
                pm.register(ep.load(), name=ep.name)
            except Exception as exc:  # a third-party plugin may fail in any way; report it, keep going
                registry.broken.append((ep.name, f"{type(exc).__name__}: {exc}"))
                continue
            dists[ep.name] = dist
    for plugin in extra_plugins:
        name = getattr(plugin, "__name__", type(plugin).__name__)
        pm.register(plugin, name=name)
        dists[name] = "(registered in-process)"
    for hook_name, attr in _GROUPS:
        table = getattr(registry, attr)
        hook = getattr(pm.hook, hook_name)
        for impl in hook.get_hookimpls():
            try:
                items = impl.function() or []
            except Exception as exc:
                registry.broken.append((impl.plugin_name, f"{hook_name} failed: {type(exc).__name__}: {exc}"))
                continue
            for item in items:
                item_id = getattr(item, "id", None) or getattr(item, "name")
                if item_id in table:
                    other = registry.origins[(attr, item_id)].plugin
                    raise PluginError(f"duplicate {attr[:-1].replace('_', ' ')} id {item_id!r}",
                                      plugin=impl.plugin_name, hint=f"also registered by plugin {other}")
                table[item_id] = item
                registry.origins[(attr, item_id)] = Origin(impl.plugin_name, dists.get(impl.plugin_name, "?"))
    return registry


_DEFAULT: Registry | None = None


def default_registry() -> Registry:
    """The process-wide registry from installed entry points (loaded once)."""
    global _DEFAULT
    if _DEFAULT is None:
        _DEFAULT = load_registry()
    return _DEFAULT
