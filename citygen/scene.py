"""Scene files (TOML): where footprints come from, defaults, ruleset assignment, seed and output.

See ``docs/scene.md`` for the format. Paths inside a scene are relative to the scene file. Parsing is strict:
unknown keys and wrong types are errors naming ``file:line`` and the valid choices.
"""
from __future__ import annotations

import math
import operator
import re
import tomllib
from collections.abc import Collection, Mapping
from dataclasses import dataclass, field
from dataclasses import fields as dataclass_fields
from pathlib import Path
from typing import Any

from citygen.errors import SceneError, SourceLocation, read_user_text
from citygen.nesting import MAX_NESTING, depth_of
from citygen.plausible import PlausibilityRules
from citygen.request import MIN_STOREY
from citygen.rng import MAX_SEED
from citygen.usd.materials import Material, parse_materials, read_materials, sidecar

UP_AXES = ("Z", "Y")
#: ``[output] lod``: ``variants`` (a variant set ``LOD``: ``LOD0`` facades, ``LOD1`` mass and roof), ``purpose``
#: (both at once, as a render/proxy pair) or ``none``; ``true``/``false`` (the old switch) mean variants/none.
LOD_MODES = ("variants", "purpose", "none")
INSTANCING = ("modules", "elements")
#: ``[output] tile_layers`` unset: a city of more buildings than this is written as payloaded tile layers, each tile
#: built and written by one task, so memory stays bounded by a tile (one layer holds ~0.33 MB per building until
#: it is exported, and exporting doubles it); smaller cities are one file.
AUTO_TILE_LAYERS = 1000
FACE_SCOPES = ("all", "street", "courtyard")


@dataclass(frozen=True)
class Defaults:
    """Building defaults applied where the data says nothing."""

    floor_height: float = 3.2
    ground_floor_height: float = 4.0
    default_height: float = 10.0
    corner_width: float = 0.4
    min_face_width: float = 0.8
    roof_shape: str = "flat"
    roof_pitch: float = 30.0


@dataclass(frozen=True)
class Condition:
    """One test of an assignment rule: an attribute compared to a value (or one of several values)."""

    key: str
    op: str
    values: tuple[Any, ...]

    def holds(self, attrs: Mapping[str, Any]) -> bool:
        value = attrs.get(self.key)
        if value is None:
            return False
        if self.op == "in":
            return str(value) in {str(v) for v in self.values}
        try:
            return bool(_OPS[self.op](float(value), float(self.values[0])))
        except (TypeError, ValueError):
            return False


_OPS = {">=": operator.ge, "<=": operator.le, ">": operator.gt, "<": operator.lt, "==": operator.eq,
        "!=": operator.ne}
_COMPARISON = re.compile(r"^\s*(>=|<=|==|!=|>|<)\s*(-?\d+(?:\.\d*)?)\s*$")
_OPERATOR = re.compile(r"^\s*(>=|<=|==|!=|>|<)")


@dataclass(frozen=True)
class Assignment:
    """``[[assign]]``: buildings matching every condition get one of ``rulesets`` (chosen per building); faces that
    ruleset cannot dress (it gives up or falls back to a plain wall) get the ``fallback`` ruleset when there is
    one (its kind from its suffix)."""

    rulesets: tuple[Path, ...]
    conditions: tuple[Condition, ...] = ()
    faces: str = "all"
    kind: str | None = None
    line: int | None = None
    roof_shape: str | None = None
    roof_pitch: float | None = None
    fallback: Path | None = None

    def matches(self, attrs: Mapping[str, Any]) -> bool:
        return all(c.holds(attrs) for c in self.conditions)


@dataclass(frozen=True)
class Output:
    path: Path
    up_axis: str = "Z"
    tile_size: float = 250.0
    instancing: str = "modules"
    tile_layers: bool | None = None  # None: tile layers for a city of more than AUTO_TILE_LAYERS buildings
    uvs: bool = False
    lod: str = "variants"
    ground: bool = False
    masses: bool = False
    keep_tags: tuple[str, ...] = ()


@dataclass(frozen=True)
class Scene:
    """A parsed scene file."""

    path: Path
    name: str
    seed: int
    footprints: Path
    footprint_options: Mapping[str, Any]
    defaults: Defaults
    assignments: tuple[Assignment, ...]
    output: Output
    metadata: Mapping[str, Any] = field(default_factory=dict)
    plausibility: PlausibilityRules = field(default_factory=PlausibilityRules)
    materials: Mapping[str, Material] = field(default_factory=dict)


def _line_of(text: str, key: str, start: int = 0) -> int | None:
    match = re.compile(rf"^\s*\"?{re.escape(key)}\"?\s*=", re.M).search(text, start)
    return text.count("\n", 0, match.start()) + 1 if match else None


def key_line(scene: Scene, table: str, key: str) -> int | None:
    """The line of ``key`` in ``[table]`` of the scene's file (None when it cannot be found)."""
    try:
        text = scene.path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None
    header = re.search(rf"^[ \t]*\[[ \t]*{re.escape(table)}[ \t]*\]", text, re.M)
    return _line_of(text, key, header.end()) if header else None


class _Reader:
    """Checks one table of the scene, reporting problems with file:line."""

    def __init__(self, path: Path, text: str, roof_shapes: Collection[str] | None = None,
                 kinds: Mapping[str, Any] | None = None) -> None:
        self.path, self.text, self.roof_shapes, self.kinds = path, text, roof_shapes, kinds

    def fail(self, message: str, key: str | None = None, hint: str | None = None, line: int | None = None,
             table: str | None = None) -> None:
        """Raise a SceneError at ``line``, else at ``key``'s line (within ``[table]`` when given: the same key may
        be in several tables)."""
        if line is None and key is not None:
            header = re.search(rf"^[ \t]*\[[ \t]*{re.escape(table)}[ \t]*\]", self.text, re.M) if table else None
            line = _line_of(self.text, key, header.end() if header else 0) or _line_of(self.text, key)
        raise SceneError(message, where=SourceLocation(str(self.path), line), hint=hint)

    def table(self, data: Mapping[str, Any], name: str, allowed: set[str]) -> Mapping[str, Any]:
        value = data.get(name, {})
        if not isinstance(value, Mapping):
            self.fail(f"[{name}] must be a table", name)
        unknown = sorted(set(value) - allowed)
        if unknown:
            self.fail(f"unknown key {unknown[0]!r} in [{name}]", unknown[0], hint=f"valid keys: {', '.join(sorted(allowed))}",
                      table=name)
        return value

    def number(self, table: Mapping[str, Any], key: str, default: float, least: float = 0.0,
               section: str | None = None) -> float:
        """A finite number above 0 (at least ``least`` when that is more)."""
        value = table.get(key, default)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                or value <= 0 or value < least:
            what = f"a finite number of at least {least:g}" if least > 0 else "a finite positive number"
            self.fail(f"{key} must be {what}, got {value!r}", key, table=section)
        return float(value)

    def roof_shape(self, value: Any, line: int | None) -> str:
        """A roof builder id (checked against the loaded roof builders)."""
        from citygen.registry import default_registry
        shapes = sorted(self.roof_shapes if self.roof_shapes is not None else default_registry().roof_builders)
        if not isinstance(value, str) or value not in shapes:
            self.fail(f"unknown roof shape {value!r}", line=line, hint=f"valid shapes: {', '.join(shapes)}")
        return value

    def ruleset_kind(self, value: Any, paths: Collection[Path], line: int | None) -> str | None:
        """The ``kind`` of an assignment, checked (with the rulesets' suffixes when it is not given) against the
        ruleset kinds the reader was given; without them, the builder checks when it loads the ruleset."""
        if self.kinds is None:
            return value
        if value is not None:
            if not isinstance(value, str) or value not in self.kinds:
                self.fail(f"unknown ruleset kind {value!r}", line=line,
                          hint=f"loaded kinds: {', '.join(sorted(self.kinds))}")
            return value
        suffixes = sorted({s for kind in self.kinds.values() for s in kind.suffixes})
        for p in paths:
            if not p.name.lower().endswith(tuple(suffixes)):
                self.fail(f"no ruleset kind reads {p.suffix or 'files without suffix'} ({p.name})", line=line,
                          hint=f"known ruleset suffixes: {', '.join(suffixes)}; or give kind explicitly")
        return None

    def pitch(self, value: Any, line: int | None) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value < 90:
            self.fail(f"roof_pitch must be a number of degrees between 0 and 90, got {value!r}", line=line)
        return float(value)

    def path_of(self, value: Any, key: str, section: str | None = None) -> Path:
        if not isinstance(value, str) or not value:
            self.fail(f"{key} must be a path string, got {value!r}", key, table=section)
        return (self.path.parent / value).resolve()


def load_scene(path: str | Path, roof_shapes: Collection[str] | None = None,
               kinds: Mapping[str, Any] | None = None) -> Scene:
    """Parse and check a scene file; raise :class:`SceneError` with file:line on any problem.

    Roof shapes are checked against ``roof_shapes`` (default: the roof builders of the installed plugins), and
    when ``kinds`` (id -> ruleset kind) is given, each assignment's ``kind`` or else its rulesets' suffixes."""
    path = Path(path)
    text = read_user_text(path, SceneError, "scene")
    try:
        data = tomllib.loads(text)
    except RecursionError:
        raise SceneError(f"arrays or tables nested more than {MAX_NESTING} levels deep", where=str(path),
                         hint="a scene needs a few levels at most") from None
    except tomllib.TOMLDecodeError as exc:
        match = re.search(r"line (\d+), column (\d+)", str(exc))
        loc = SourceLocation(str(path), int(match[1]), int(match[2])) if match else SourceLocation(str(path))
        raise SceneError(f"not valid TOML: {str(exc).split(' (at')[0]}", where=loc) from exc
    r = _Reader(path, text, roof_shapes, kinds)
    for key, value in data.items():
        if depth_of(value) > MAX_NESTING:
            header = re.search(rf"^[ \t]*\[+[ \t]*\"?{re.escape(key)}\b", text, re.M)
            r.fail(f"[{key}] nests arrays or tables more than {MAX_NESTING} levels deep",
                   hint="a scene needs a few levels at most",
                   line=text.count("\n", 0, header.start()) + 1 if header else _line_of(text, key))
    unknown = sorted(set(data) - {"scene", "footprints", "defaults", "assign", "output", "materials",
                                  "plausibility"})
    if unknown:
        r.fail(f"unknown table [{unknown[0]}]",
               hint="valid tables: scene, footprints, defaults, assign, output, materials, plausibility",
               line=_line_of(text, unknown[0]) or 1)
    meta = r.table(data, "scene", {"name", "seed", "description"})
    seed = meta.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= MAX_SEED:
        r.fail(f"seed must be an integer from 0 to {MAX_SEED} (2**31 - 1), got {seed!r}", "seed", table="scene")
    fp = data.get("footprints")
    if not isinstance(fp, Mapping) or "path" not in fp:
        r.fail("[footprints] with a path is required", hint='e.g. [footprints] path = "data/city.geojson"', line=1)
    fp_options = {k: v for k, v in fp.items() if k != "path"}
    d = r.table(data, "defaults", {f for f in Defaults.__dataclass_fields__})
    numbers = {k: r.number(d, k, getattr(Defaults, k), least=MIN_STOREY if k.endswith("floor_height") else 0.0,
                           section="defaults")
               for k in Defaults.__dataclass_fields__ if k != "roof_shape"}
    at = max(text.find("[defaults]"), 0)
    shape = r.roof_shape(d["roof_shape"], _line_of(text, "roof_shape", at)) if "roof_shape" in d else "flat"
    defaults = Defaults(**numbers, roof_shape=shape)
    r.pitch(defaults.roof_pitch, _line_of(text, "roof_pitch", at))
    out = r.table(data, "output", {"path", "up_axis", "tile_size", "instancing", "tile_layers", "uvs", "lod",
                                     "ground", "keep_tags", "masses"})
    up_axis = str(out.get("up_axis", "Z")).upper()
    if up_axis not in UP_AXES:
        r.fail(f"up_axis must be one of {', '.join(UP_AXES)}, got {out.get('up_axis')!r}", "up_axis", table="output")
    instancing = out.get("instancing", "modules")
    if instancing not in INSTANCING:
        r.fail(f"instancing must be one of {', '.join(INSTANCING)}, got {instancing!r}", "instancing", table="output")
    flags = {key: out.get(key, None if key == "tile_layers" else False)
             for key in ("tile_layers", "uvs", "ground", "masses")}
    for key, value in flags.items():
        if not isinstance(value, bool) and not (key == "tile_layers" and value is None):
            r.fail(f"{key} must be true or false, got {value!r}", key, table="output")
    lod = out.get("lod", "variants")
    lod = {True: "variants", False: "none"}.get(lod, lod) if isinstance(lod, bool) else lod
    if lod not in LOD_MODES:
        r.fail(f"lod must be one of {', '.join(LOD_MODES)}, got {out.get('lod')!r}", "lod", table="output",
               hint="variants: a variant set LOD (LOD0 facades, LOD1 mass); purpose: a render/proxy pair")
    keep = out.get("keep_tags", [])
    if not isinstance(keep, list) or not all(isinstance(k, str) and k for k in keep):
        r.fail(f"keep_tags must be a list of tag names or patterns, got {keep!r}", "keep_tags", table="output",
               hint='e.g. keep_tags = ["name", "addr:*"]')
    output = Output(path=r.path_of(out.get("path", f"{path.stem}.usdc"), "path", "output"), up_axis=up_axis,
                    tile_size=r.number(out, "tile_size", 250.0, section="output"), instancing=instancing, lod=lod,
                    keep_tags=tuple(keep), **flags)
    assignments = _assignments(r, data.get("assign", []))
    return Scene(path=path.resolve(), name=str(meta.get("name", path.stem)), seed=seed,
                 footprints=r.path_of(fp["path"], "path", "footprints"), footprint_options=fp_options,
                 defaults=defaults,
                 assignments=assignments, output=output, metadata={"description": meta.get("description", "")},
                 materials=_materials(r, data.get("materials", {}), assignments), plausibility=_plausibility(r, data))


def _plausibility(r: _Reader, data: Mapping[str, Any]) -> PlausibilityRules:
    """The ``[plausibility]`` table's rules (docs/scene.md); its errors name the line of the offending key."""
    table = r.table(data, "plausibility", {f.name for f in dataclass_fields(PlausibilityRules)})
    for key, value in table.items():
        try:
            PlausibilityRules.from_mapping({key: value})
        except SceneError as exc:
            r.fail(exc.message, key, hint=exc.hint)
    return PlausibilityRules.from_mapping(table)


def _materials(r: _Reader, table: Any, assignments: tuple[Assignment, ...]) -> dict[str, Material]:
    """The materials rulesets (their ``<stem>.materials.toml`` sidecars) and the scene's ``[materials]`` define;
    the scene's win over a ruleset's of the same name, both over the built-ins."""
    if not isinstance(table, Mapping):
        r.fail("[materials] must be a table of material tables", "materials")
    found: dict[str, Material] = {}
    for a in assignments:
        for ruleset in a.rulesets + ((a.fallback,) if a.fallback else ()):
            if _is_file(side := sidecar(ruleset)):
                found.update(read_materials(side))
    for name, spec in table.items():
        try:
            found.update(parse_materials({name: spec}, str(r.path), r.path.parent))
        except SceneError as exc:
            header = re.search(rf"^\s*\[materials\.\"?{re.escape(str(name))}\"?\]", r.text, re.M)
            r.fail(exc.message, line=r.text.count("\n", 0, header.start()) + 1 if header else None, hint=exc.hint)
    return found


def _assignments(r: _Reader, items: Any) -> tuple[Assignment, ...]:
    if not isinstance(items, list) or not items:
        r.fail("at least one [[assign]] table with a ruleset is required", "assign", line=1)
    result = []
    search_from = 0
    for index, item in enumerate(items):
        header = r.text.find("[[assign]]", search_from)
        line = r.text.count("\n", 0, header) + 1 if header >= 0 else None
        search_from = header + 1 if header >= 0 else search_from
        keys = {"ruleset", "when", "faces", "kind", "roof_shape", "roof_pitch", "fallback"}
        unknown = sorted(set(item) - keys)
        if unknown:
            r.fail(f"unknown key {unknown[0]!r} in [[assign]] #{index + 1}", line=line,
                   hint=f"valid keys: {', '.join(sorted(keys))}")
        rulesets = item.get("ruleset")
        names = [rulesets] if isinstance(rulesets, str) else rulesets
        if not names or not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            r.fail(f"[[assign]] #{index + 1} needs ruleset = \"path\" or a list of paths", line=line)
        fallback = item.get("fallback")
        if fallback is not None and not isinstance(fallback, str):
            r.fail(f"[[assign]] #{index + 1}: fallback must be a ruleset path", line=line)
        paths = tuple((r.path.parent / n).resolve() for n in names)
        fallback = (r.path.parent / fallback).resolve() if fallback else None
        for p in paths + ((fallback,) if fallback else ()):
            if not _is_file(p):
                r.fail(f"ruleset {_short(p.name)} does not exist ({_short(str(p))})", line=line,
                       hint="paths are relative to the scene file")
        kind = r.ruleset_kind(item.get("kind"), paths, line)
        if fallback is not None:
            r.ruleset_kind(None, (fallback,), line)  # (a fallback is read by the kind its suffix names)
        faces = item.get("faces", "all")
        if faces not in FACE_SCOPES:
            r.fail(f"faces must be one of {', '.join(FACE_SCOPES)}, got {faces!r}", line=line)
        shape_line = _line_of(r.text, "roof_shape", header) if header >= 0 else line
        pitch_line = _line_of(r.text, "roof_pitch", header) if header >= 0 else line
        shape = r.roof_shape(item["roof_shape"], shape_line) if "roof_shape" in item else None
        pitch = r.pitch(item["roof_pitch"], pitch_line) if "roof_pitch" in item else None
        when_line = _line_of(r.text, "when", header) if header >= 0 and "when" in item else line
        result.append(Assignment(rulesets=paths, conditions=_conditions(r, item.get("when", {}), when_line),
                                 faces=faces, kind=kind, line=line, roof_shape=shape, roof_pitch=pitch,
                                 fallback=fallback))
    return tuple(result)


def _short(text: str, limit: int = 120) -> str:
    return text if len(text) <= limit else f"{text[:limit // 2]}...{text[-limit // 2:]}"


def _is_file(path: Path) -> bool:
    """``path.exists()``, False also for a name the file system refuses (too long)."""
    try:
        return path.exists()
    except OSError:
        return False


def _conditions(r: _Reader, when: Any, line: int | None) -> tuple[Condition, ...]:
    if not isinstance(when, Mapping):
        r.fail("when must be a table of attribute = value", line=line)
    conditions = []
    for key, value in when.items():
        if isinstance(value, list):
            conditions.append(Condition(key, "in", tuple(value)))
        elif isinstance(value, str) and (m := _COMPARISON.match(value)):
            conditions.append(Condition(key, m[1], (float(m[2]),)))
        elif isinstance(value, str) and _OPERATOR.match(value):
            r.fail(f"when {key} = {value!r}: a comparison needs a number", line=line,
                   hint=f'e.g. {key} = "< 7" or ">= 12.5"')
        elif isinstance(value, (str, int, float)) and not isinstance(value, bool):
            conditions.append(Condition(key, "in", (value,)))
        else:
            r.fail(f"condition {key} = {value!r} is not understood", line=line,
                   hint='use a value, a list of values, or a comparison string like ">= 5"')
    return tuple(conditions)
