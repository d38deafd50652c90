"""A studio session: one scene, its buildings, and the library calls the studio's API makes (no HTTP here).

Everything goes through the library the command line uses (scene loading, footprint import, masses, the
:class:`~citygen.builder.Builder`, ruleset kinds, the glTF writer); nothing is implemented a second time. Paths the
browser names are resolved by :class:`Confinement`: inside the scene's folder, or one of the rulesets the scene
names, nothing else.
"""
from __future__ import annotations

import base64
import math
import os
import tempfile
import threading
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from shapely.geometry import MultiPolygon

from citygen.builder import Builder, assign_attributes
from citygen.cliargs import MAX_SIDE
from citygen.errors import CitygenError
from citygen.gltf.meshes import Y_UP
from citygen.layout import LABELS, FacadeLayout, check_partition
from citygen.mass import build_mass, neighbour_cover
from citygen.pipeline import import_footprints
from citygen.registry import Registry
from citygen.request import MIN_STOREY, FacadeRequest, check_request
from citygen.scene import Scene, load_scene
from citygen.usd.materials import BUILTIN
from citygen.usd.names import prim_name
from citygen_studio.confinement import Confinement, StudioError, error_data
from citygen_studio.edited import edited_registry
from citygen_studio.faces import FaceRequests, city_problems, face_layout, face_requests, request_data
from citygen_studio.generation import OUTPUT_FOLDER, OUTPUT_SUFFIXES, Generation
from citygen_studio.memo import Memo

#: The largest ruleset text the studio parses or saves (bytes).
MAX_TEXT = 256 * 1024
#: The most seeds one variations request tries.
MAX_VARIATIONS = 16


@dataclass(frozen=True)
class FaceRequestSize:
    """A preview's size and floors, checked against the limits of ``citygen facade``."""

    width: float
    height: float
    floor_height: float = 3.0
    ground_height: float | None = None
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not 0 < value <= MAX_SIDE:
                raise StudioError(f"{name} must be more than 0 and at most {MAX_SIDE:g} m, got {value!r}")
        for name in ("floor_height", "ground_height"):
            value = getattr(self, name)
            if value is not None and (not isinstance(value, (int, float)) or not MIN_STOREY <= value <= 100):
                raise StudioError(f"{name} must be {MIN_STOREY:g} to 100 m, got {value!r}")
        if not isinstance(self.seed, int) or not 0 <= self.seed < 2**32:
            raise StudioError(f"seed must be an integer from 0 to 2**32 - 1, got {self.seed!r}")


def layout_data(layout: FacadeLayout, floor_lines: Iterable[float] = ()) -> dict[str, Any]:
    """What the browser draws: the size, floor lines and every terminal region."""
    leaves = [{"x": r.x, "y": r.y, "w": r.w, "h": r.h, "label": r.label, "symbol": r.symbol, "layer": r.layer,
               "material": r.material} for r in layout.leaves]
    return {"width": layout.width, "height": layout.height, "floor_lines": list(floor_lines), "leaves": leaves}


class Session:
    """The scene the studio was opened on (or just a folder of rulesets when there is none). With ``background``
    the scene loads in a thread: ``scene_ready`` is set once the scene file and its rulesets are known (what the
    editor and previews need), ``loaded`` once its footprints and masses are built too (what the map and builds
    need); the app waits for the one a request needs. ``events``: those two events, made by the caller (a server
    that answered before this session existed waits on them)."""

    def __init__(self, registry: Registry, scene_path: Path | None = None, root: Path | None = None,
                 background: bool = False, events: tuple[threading.Event, threading.Event] | None = None) -> None:
        self.registry = registry
        self.scene: Scene | None = None
        self.load_error: dict[str, Any] | None = None
        self.footprints, self.masses, self.cover, self.names = [], [], [], []
        self.generation: Generation | None = None
        # parsed texts by (kind, path, text); previews by text and size; builds by building and ruleset texts
        self.parsed: Memo[Any] = Memo(64)
        self.previews: Memo[dict[str, Any]] = Memo(256)
        self.built: Memo[dict[str, Any]] = Memo(16)
        self.requests: Memo[FaceRequests] = Memo(64)
        folder = scene_path.resolve().parent if scene_path is not None else (root or Path.cwd()).resolve()
        self.confinement = Confinement(folder)
        self.scene_ready, self.loaded = events or (threading.Event(), threading.Event())
        if background:  # the page paints while the footprints and masses are built; requests wait for them
            threading.Thread(target=self._load, args=(scene_path,), daemon=True).start()
        else:
            self._load(scene_path)

    def _load(self, scene_path: Path | None) -> None:
        """The scene, the rulesets it names (into the confinement), its footprints, masses and neighbour cover."""
        try:
            if scene_path is None:
                return
            registry = self.registry
            self.scene = load_scene(scene_path, registry.roof_builders, registry.ruleset_kinds)
            named = [p for a in self.scene.assignments for p in (*a.rulesets, *([a.fallback] if a.fallback else []))]
            self.confinement = Confinement(self.confinement.root, named)
            self.scene_ready.set()
            imported = import_footprints(self.scene, registry)
            for fp in imported.footprints:
                try:
                    self.masses.append(build_mass(fp))
                    self.footprints.append(fp)
                except CitygenError:
                    continue  # (generate reports it; the studio shows the buildings it can build)
            self.cover = neighbour_cover(self.masses)
            taken: set[str] = set()
            self.names = [prim_name(fp.id, taken) for fp in self.footprints]
        except CitygenError as exc:
            self.scene, self.load_error = None, error_data(exc, self.confinement)
        except Exception as exc:  # a library bug: the page says so instead of a studio that never loads
            self.scene, self.load_error = None, {"message": f"internal error {type(exc).__name__}: {exc}"}
        finally:
            self.scene_ready.set()
            self.loaded.set()

    def info(self) -> dict[str, Any]:
        """The scene, its rulesets, the ruleset kinds and what an editor completes (materials, labels)."""
        scene = self.scene
        return {"scene": scene.name if scene else None, "file": scene.path.name if scene else None,
                "error": self.load_error, "rulesets": self.rulesets(),
                "buildings": len(self.footprints) if self.loaded.is_set() else None,
                "kinds": [{"id": k.id, "suffixes": list(k.suffixes), "description": k.description}
                          for k in self.registry.ruleset_kinds.values()],
                "materials": sorted({*BUILTIN, *(self.scene.materials if self.scene else {})}), "labels": list(LABELS),
                "floor_height": scene.defaults.floor_height if scene else 3.0}

    def rulesets(self) -> list[str]:
        """The rulesets the scene names, then the other ruleset files in its folder and its subfolders, as the
        browser names them."""
        suffixes = tuple(s for k in self.registry.ruleset_kinds.values() for s in k.suffixes)
        named = sorted(self.confinement.show(str(p)) for p in self.confinement.named)
        root = self.confinement.root  # (two levels deep: a studio opened in a big folder stays quick)
        local = sorted(os.path.relpath(p, root) for p in (*root.glob("*"), *root.glob("*/*"))
                       if p.is_file() and p.name.endswith(suffixes) and not p.name.startswith("."))
        return list(dict.fromkeys(named + local))

    def buildings(self) -> list[dict[str, Any]]:
        """Every building: id, outline rings (local metres), attributes, and the rulesets its faces get."""
        if self.scene is None:
            raise StudioError("no scene is loaded", 409, hint="start the studio with a scene: citygen studio SCENE")
        out = []
        builder = Builder(self.scene, self.scene.seed, self.registry)  # (to choose rulesets, not to load them)
        for k, (fp, mass) in enumerate(zip(self.footprints, self.masses)):
            parts = mass.outline.geoms if isinstance(mass.outline, MultiPolygon) else [mass.outline]
            rings = [[[round(x, 2), round(y, 2)] for x, y in ring.coords] for part in parts
                     for ring in (part.exterior, *part.interiors)]
            chosen = {scope: builder.choose(fp, mass, scope) for scope in ("street", "courtyard")}
            attributes = {key: _plain(v) for key, v in assign_attributes(fp, mass).items()}
            out.append({"index": k, "id": fp.id, "name": self.names[k], "rings": rings, "attributes": attributes,
                        "rulesets": {scope: self.confinement.show(str(c[1])) if c else None
                                     for scope, c in chosen.items()}})
        return out

    def _builder(self, overrides: Mapping[str, str] | None = None) -> Builder:
        if self.scene is None:
            raise StudioError("no scene is loaded", 409, hint="start the studio with a scene: citygen studio SCENE")
        edited = {self.confinement.resolve(name) for name in overrides or {}}
        rulesets = {}
        for (kind_id, path), text in self._ruleset_texts(overrides).items():
            try:
                rulesets[kind_id, path] = self._parse(self.registry.ruleset_kind(kind_id), path, text)
            except CitygenError:
                if path in edited:  # (an edit that does not parse: its error, as data)
                    raise
                continue  # (a saved ruleset that does not load: the builder reports it, as generate would)
        return Builder(self.scene, self.scene.seed, self.registry, rulesets, keep_layouts=True)

    def _ruleset_texts(self, overrides: Mapping[str, str] | None = None) -> dict[tuple[str, Path], str]:
        """The text of every ruleset the scene names, by (kind id, path): its file's, or its edit in ``overrides``
        (by ruleset name; an edited ruleset the scene does not name is parsed too, so its errors show)."""
        assert self.scene is not None
        edited = {}
        for name, text in (overrides or {}).items():
            path = self.confinement.resolve(name)
            edited[path] = (self.registry.kind_for_path(path).id, _text(text))
        texts: dict[tuple[str, Path], str] = {}
        for a in self.scene.assignments:
            for path in (*a.rulesets, *([a.fallback] if a.fallback else [])):
                kind_id = a.kind if a.kind and path in a.rulesets else self.registry.kind_for_path(path).id
                if path in edited:
                    texts[kind_id, path] = edited[path][1]
                elif (kind_id, path) not in texts:
                    try:
                        texts[kind_id, path] = path.read_text(encoding="utf-8")
                    except (OSError, UnicodeDecodeError):
                        continue  # (the builder's own load reports it)
        for path, (kind_id, text) in edited.items():
            texts.setdefault((kind_id, path), text)
        return texts

    def _parse(self, kind: Any, path: Path, text: str) -> Any:
        """``text`` parsed by ``kind`` as the file ``path`` (kept: a ruleset object is immutable, and kinds that
        reuse solves per ruleset object, such as layer stacks, keep reusing them while the text is unchanged)."""
        return self.parsed.get((kind.id, path, text), lambda: kind.loads(text, path))

    def build(self, index: int, overrides: Mapping[str, str] | None = None) -> dict[str, Any]:
        """One building with the scene's rulesets (``overrides``: edited texts by ruleset name): every face's
        frame in the GLB's coordinates (Y-up, origin at the building's pivot) and layout (when dressed), and the
        building as GLB (base64)."""
        if self.scene is None:
            raise StudioError("no scene is loaded", 409, hint="start the studio with a scene: citygen studio SCENE")
        if not isinstance(index, int) or not 0 <= index < len(self.footprints):
            raise StudioError(f"no building {index!r} (the scene has {len(self.footprints)})", 404)
        key = (index, tuple(sorted(self._ruleset_texts(overrides).items())))
        return self.built.get(key, lambda: self._build(index, overrides))

    def _build(self, index: int, overrides: Mapping[str, str] | None) -> dict[str, Any]:
        from citygen.gltf.writer import building_glb

        builder = self._builder(overrides)
        fp, mass = self.footprints[index], self.masses[index]
        outcome = builder.build(fp, mass, self.cover[index], self.names[index], (0, 0))
        if outcome.record is None:
            return {"id": fp.id, "skipped": outcome.skipped.reason, "warnings": list(outcome.warnings)}
        requests = self._requests(index)
        origin = np.asarray(outcome.record.pivot, dtype=float)
        turn = Y_UP[:3, :3]  # the GLB's frame: Y-up, origin at the pivot
        faces = [{"index": f.index, "width": f.width, "height": f.height, "courtyard": f.is_courtyard,
                  "origin": (turn @ (np.asarray(f.origin) - origin)).round(4).tolist(),
                  "u": (turn @ np.asarray(f.u)).round(6).tolist(),
                  "normal": (turn @ np.asarray(f.normal)).round(6).tolist(),
                  "layout": layout_data(outcome.layouts[f.index]) if f.index in outcome.layouts else None,
                  "request": request_data(requests[f.index]) if f.index in requests else None}
                 for f in mass.faces]
        glb = building_glb(outcome.record, self.scene.materials if self.scene else None)
        return {"id": fp.id, "skipped": None, "warnings": list(outcome.warnings), "faces": faces,
                "attributes": {k: _plain(v) for k, v in outcome.record.attributes.items()},
                "glb": base64.b64encode(glb).decode("ascii")}

    def check(self, name: str, text: str) -> dict[str, Any]:
        """Parse a ruleset text: ``{"ok": true}`` or its error (file:line:column) as data."""
        path, text = self.confinement.resolve(name), _text(text)
        kind = self.registry.kind_for_path(path)
        try:
            self._parse(kind, path, text)
        except CitygenError as exc:
            return {"ok": False, "error": error_data(exc, self.confinement)}
        return {"ok": True, "error": None}

    def preview(self, name: str, text: str, size: FaceRequestSize) -> dict[str, Any]:
        """One facade of a ruleset text at a size: its layout, the kind's account of it, and any problem; a text
        that does not parse (or a ruleset that cannot dress the size) gives its error as data."""
        path, text = self.confinement.resolve(name), _text(text)
        kind = self.registry.kind_for_path(path)
        return self.previews.get((kind.id, path, text, size), lambda: self._preview(kind, path, text, size))

    def _preview(self, kind: Any, path: Path, text: str, size: FaceRequestSize) -> dict[str, Any]:
        request = FacadeRequest.preview(size.width, size.height, floor_height=size.floor_height,
                                        ground_height=size.ground_height, seed=size.seed)
        try:
            ruleset = self._parse(kind, path, text)
            layout = kind.generate(ruleset, request)
            explain = kind.explain(ruleset, request)
        except CitygenError as exc:
            return {"ok": False, "error": error_data(exc, self.confinement), "kind": kind.id}
        problems = check_partition(layout) + check_request(layout, request)
        return {"ok": True, "error": None, "kind": kind.id, "layout": layout_data(layout, request.floor_lines),
                "explain": explain, "problems": [str(p) for p in problems]}

    def preview_face(self, name: str, text: str, index: int, face: int) -> dict[str, Any]:
        """Face ``face`` of building ``index`` dressed by a ruleset text under the building's own request (its floor
        lines, entrance, corner strips and seed; coupled with its other faces where the kind couples them), and
        what the city would do with it (``problems``): the preview shows what the city gets."""
        path, text = self.confinement.resolve(name), _text(text)
        kind = self.registry.kind_for_path(path)
        if self.scene is None:
            raise StudioError("no scene is loaded", 409, hint="start the studio with a scene: citygen studio SCENE")
        if not isinstance(index, int) or not 0 <= index < len(self.footprints):
            raise StudioError(f"no building {index!r} (the scene has {len(self.footprints)})", 404)
        requests = self._requests(index)
        if face not in requests:
            raise StudioError(f"building {self.footprints[index].id} has no dressed face {face!r}", 404,
                              hint=f"its dressed faces: {', '.join(map(str, sorted(requests))) or 'none'}")
        return self.previews.get(("face", kind.id, path, text, index, face),
                                 lambda: self._preview_face(kind, path, text, requests, face))

    def _requests(self, index: int) -> FaceRequests:
        """The coordinator's request of every dressed face of building ``index``, and its runs."""
        assert self.scene is not None
        return self.requests.get(index, lambda: face_requests(self.scene, self.footprints[index], self.masses[index],
                                                              self.cover[index]))

    def _preview_face(self, kind: Any, path: Path, text: str, requests: FaceRequests, face: int) -> dict[str, Any]:
        request = requests[face]
        try:
            ruleset = self._parse(kind, path, text)
            layout, judged, asked = face_layout(kind, ruleset, requests, face)
            explain = kind.explain(ruleset, asked)
        except CitygenError as exc:
            return {"ok": False, "error": error_data(exc, self.confinement), "kind": kind.id}
        problems = [str(p) for p in check_partition(layout) + check_request(layout, request)]
        return {"ok": True, "error": None, "kind": kind.id, "layout": layout_data(layout, request.floor_lines),
                "explain": explain, "problems": problems + city_problems(judged, asked),
                "request": request_data(request)}

    def variations(self, name: str, text: str, size: FaceRequestSize, count: int) -> dict[str, Any]:
        """The distinct layouts of a ruleset text at a size over the seeds ``size.seed ... + count - 1`` (a relayout
        model's or SAFE ruleset's variations, a grammar's random choices), each with its seed."""
        if not isinstance(count, int) or not 1 <= count <= MAX_VARIATIONS:
            raise StudioError(f"count must be 1 to {MAX_VARIATIONS}, got {count!r}")
        path, text = self.confinement.resolve(name), _text(text)
        kind = self.registry.kind_for_path(path)
        return self.previews.get(("variations", kind.id, path, text, size, count),
                                 lambda: self._variations(kind, path, text, size, count))

    def _variations(self, kind: Any, path: Path, text: str, size: FaceRequestSize, count: int) -> dict[str, Any]:
        try:
            ruleset = self._parse(kind, path, text)
        except CitygenError as exc:
            return {"ok": False, "error": error_data(exc, self.confinement), "variations": []}
        found, seen = [], set()
        for seed in range(size.seed, size.seed + count):
            request = FacadeRequest.preview(size.width, size.height, floor_height=size.floor_height,
                                            ground_height=size.ground_height, seed=seed)
            try:
                layout = layout_data(kind.generate(ruleset, request), request.floor_lines)
            except CitygenError as exc:
                found.append({"seed": seed, "error": error_data(exc, self.confinement)})
                continue
            key = repr(layout["leaves"])
            if key not in seen:
                seen.add(key)
                found.append({"seed": seed, "layout": layout})
        return {"ok": True, "error": None, "variations": found}

    def generate(self, suffix: str, jobs: int = 1, overrides: Mapping[str, str] | None = None) -> dict[str, Any]:
        """Start generating the whole scene into ``studio-out/<scene><suffix>`` under the scene's folder, one run at a
        time, from its rulesets as the editor has them: ``overrides`` (edited texts by ruleset name) are read in
        place of their files, which are not written. Its progress and report: :meth:`generation_state`."""
        if self.scene is None:
            raise StudioError("no scene is loaded", 409, hint="start the studio with a scene: citygen studio SCENE")
        if suffix not in OUTPUT_SUFFIXES:
            raise StudioError(f"format must be one of {', '.join(OUTPUT_SUFFIXES)}, got {suffix!r}")
        if not isinstance(jobs, int) or not 1 <= jobs <= (os.cpu_count() or 1):
            raise StudioError(f"jobs must be 1 to {os.cpu_count() or 1}, got {jobs!r}")
        edits: dict[Path, str] = {}
        for name, text in (overrides or {}).items():
            path = self.confinement.resolve(name)
            self._parse(self.registry.kind_for_path(path), path, _text(text))  # (an edit that does not parse: 400)
            edits[path] = text
        if edits and jobs != 1:
            raise StudioError("generating from unsaved edits runs in the studio's process: jobs must be 1",
                              hint="save the rulesets to generate with more jobs")
        if self.generation is not None and self.generation.thread.is_alive():
            raise StudioError("the scene is already being generated", 409, hint="wait for it to finish")
        out = self.confinement.root / OUTPUT_FOLDER / f"{self.scene.path.stem}{suffix}"
        registry = edited_registry(self.registry, edits, self._parse) if edits else self.registry
        self.generation = Generation(self.scene, registry, out, jobs,
                                     tuple(sorted(self.confinement.show(str(p)) for p in edits)))
        return self.generation_state()

    def generation_state(self) -> dict[str, Any]:
        if self.generation is None:
            return {"running": False, "done": 0, "total": 0, "error": None, "report": None, "output": None,
                    "edited": []}
        return self.generation.state(self.confinement.root)

    def output(self, name: str) -> Path:
        """A file the studio generated (under ``studio-out``), to download."""
        path = self.confinement.resolve(name)
        if path.parent != self.confinement.root / OUTPUT_FOLDER or not path.is_file():
            raise StudioError(f"{name} is not a generated file", 404)
        return path

    def read(self, name: str) -> dict[str, Any]:
        path = self.confinement.resolve(name)
        if not path.is_file():
            raise StudioError(f"{name}: no such file", 404)
        if path.stat().st_size > MAX_TEXT:
            raise StudioError(f"{name} is larger than {MAX_TEXT // 1024} KiB", 413)
        return {"name": name, "text": path.read_text(encoding="utf-8"), "kind": self.registry.kind_for_path(path).id}

    def save(self, name: str, text: str) -> dict[str, Any]:
        """Write a ruleset text (atomically) to a ruleset file inside the confinement; the kind must read it."""
        path = self.confinement.resolve(name)
        self.registry.kind_for_path(path)  # refuses suffixes no kind reads
        if not path.parent.is_dir():
            raise StudioError(f"{name}: its folder does not exist", 404)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
        try:
            with os.fdopen(fd, "w", encoding="utf-8") as handle:
                handle.write(_text(text))
            os.replace(tmp, path)
        finally:
            Path(tmp).unlink(missing_ok=True)
        self.parsed.clear()  # (a saved file may be one another ruleset refers to)
        self.previews.clear()
        return {"name": name, "saved": True}


def _text(text: Any) -> str:
    if not isinstance(text, str):
        raise StudioError("a ruleset text must be a string")
    if len(text.encode("utf-8")) > MAX_TEXT:
        raise StudioError(f"a ruleset text must be at most {MAX_TEXT // 1024} KiB", 413)
    return text


def _plain(value: Any) -> Any:
    """A JSON-safe attribute value (NaN and infinities as None, numpy scalars as Python ones)."""
    if hasattr(value, "item"):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value if isinstance(value, (str, int, float, bool)) or value is None else str(value)
