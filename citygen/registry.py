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

    from citygen.footprints import FootprintStream, ImportResult
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

    def stream(self, path: Path, options: dict[str, Any]) -> FootprintStream:
        """:meth:`read`'s footprints handed over one by one (:class:`~citygen.footprints.FootprintStream`): what the
        pipeline plans a city from. An importer that can read its format without holding every footprint at once
        overrides it; by default the whole :meth:`read` is handed over."""
        from citygen.footprints import FootprintStream
        return FootprintStream.of(self.read(path, options))


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
    #: file suffix -> the id of the ruleset kind / importer that reads it (see :func:`load_registry`)
    suffix_owners: dict[str, dict[str, str]] = field(default_factory=dict)
    #: problems worth a warning that do not make a plugin broken (a suffix claimed twice)
    warnings: list[str] = field(default_factory=list)
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
        owner = self.suffix_owners.get("ruleset_kinds", {}).get(suffix)
        if owner is not None:
            return self.ruleset_kinds[owner]
        for kind in self.ruleset_kinds.values():  # (a registry built by hand has no suffix table)
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
        owners = self.suffix_owners.get("importers")
        matches = [(len(s), importer.id) for importer in self.importers.values() for s in importer.suffixes
                   if name.endswith(s.lower()) and (owners is None or owners.get(s.lower()) == importer.id)]
        if matches:  # the most specific suffix wins: ".city.json" before ".json"
            return self.importers[max(matches)[1]]
        raise PluginError("no footprint importer for this file type", where=str(path),
                          hint=f"set format = one of {', '.join(sorted(self.importers))} in the scene")


_GROUPS = (("citygen_ruleset_kinds", "ruleset_kinds", RulesetKind), ("citygen_footprint_importers", "importers",
                                                                      FootprintImporter),
           ("citygen_roof_builders", "roof_builders", RoofBuilder), ("citygen_commands", "commands", Command),
           ("citygen_layout_sources", "layout_sources", LayoutSource))
#: The distribution whose plugins keep their file suffixes when another plugin claims one too.
SHIPPED = "citygen"
#: Interfaces whose objects are named by ``name`` (CLI words), not ``id``.
NAMED = (Command, LayoutSource)


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
            except (Exception, SystemExit) as exc:  # a third-party plugin may fail in any way; report it, keep going
                registry.broken.append((ep.name, f"{type(exc).__name__}: {exc}"))
                continue
            dists[ep.name] = dist
    for plugin in extra_plugins:
        name = getattr(plugin, "__name__", type(plugin).__name__)
        pm.register(plugin, name=name)
        dists[name] = "(registered in-process)"
    for hook_name, attr, interface in _GROUPS:
        table = getattr(registry, attr)
        hook = getattr(pm.hook, hook_name)
        for impl in hook.get_hookimpls():
            try:
                items = impl.function()
            except (Exception, SystemExit) as exc:
                registry.broken.append((impl.plugin_name, f"{hook_name} failed: {type(exc).__name__}: {exc}"))
                continue
            problem = _malformed(items, interface)
            if problem:
                registry.broken.append((impl.plugin_name, f"{hook_name} returned {problem}; nothing of it is "
                                                          f"registered"))
                continue
            for item in items or ():
                item_id = getattr(item, "name" if interface in NAMED else "id")
                if item_id in table:
                    other = registry.origins[(attr, item_id)].plugin
                    raise PluginError(f"duplicate {attr[:-1].replace('_', ' ')} id {item_id!r}",
                                      plugin=impl.plugin_name, hint=f"also registered by plugin {other}")
                table[item_id] = item
                registry.origins[(attr, item_id)] = Origin(impl.plugin_name, dists.get(impl.plugin_name, "?"))
    for attr, what in (("ruleset_kinds", "ruleset kind"), ("importers", "footprint importer")):
        registry.suffix_owners[attr] = _suffix_owners(registry, attr, what)
    return registry


def _malformed(items: object, interface: type) -> str | None:
    """What is wrong with a hook's result (None when it is a list of ``interface`` objects, or None): each item
    needs a non-empty string ``id`` (``name`` for commands), string ``suffixes`` where it has them, and every
    abstract method of ``interface``."""
    if items is None:
        return None
    if not isinstance(items, (list, tuple)):
        return f"{type(items).__name__}, not a list"
    key = "name" if interface in NAMED else "id"
    for k, item in enumerate(items):
        ident = getattr(item, key, None)
        missing = sorted(m for m in interface.__abstractmethods__ if not callable(getattr(item, m, None)))
        suffixes = getattr(item, "suffixes", ())
        if not isinstance(ident, str) or not ident:
            return f"item {k} ({type(item).__name__}) without a string {key!r}"
        if missing:
            return f"{ident!r} without method(s) {', '.join(missing)} of a {interface.__name__}"
        if not isinstance(suffixes, (list, tuple)) or not all(isinstance(x, str) and x for x in suffixes):
            return f"{ident!r} whose suffixes are not a list of strings"
    return None


def _suffix_owners(registry: Registry, attr: str, what: str) -> dict[str, str]:
    """Which ``attr`` item reads each file suffix. A suffix claimed twice stays with the shipped plugins' item
    (distribution ``citygen``), else with the first by plugin name and id; the other claim is a warning naming
    both, and its item is still used where a scene names it (``kind = ...`` / ``format = ...``)."""
    table = getattr(registry, attr)

    def rank(item_id: str) -> tuple[bool, str, str]:
        origin = registry.origins[(attr, item_id)]
        return origin.distribution.split(" ")[0] != SHIPPED, origin.plugin, item_id

    owners: dict[str, str] = {}
    for item_id in sorted(table, key=rank):
        for suffix in table[item_id].suffixes:
            suffix = suffix.lower()
            if suffix not in owners:
                owners[suffix] = item_id
                continue
            first = owners[suffix]
            option = "kind" if attr == "ruleset_kinds" else "format"
            registry.warnings.append(
                f"{what} {item_id!r} (plugin {registry.origins[(attr, item_id)].plugin}) also claims {suffix}, "
                f"which stays with {what} {first!r} (plugin {registry.origins[(attr, first)].plugin}); "
                f"set {option} = \"{item_id}\" in a scene to use it")
    return owners


_DEFAULT: Registry | None = None


def default_registry() -> Registry:
    """The process-wide registry from installed entry points (loaded once)."""
    global _DEFAULT
    if _DEFAULT is None:
        _DEFAULT = load_registry()
    return _DEFAULT
