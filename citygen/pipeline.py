"""The city pipeline: scene -> footprints -> masses -> faces -> coordinator -> facades -> geometry -> USD.

One bad building never aborts the city: any error while building it is caught, reported with the building id and
reason, and the rest is written. ``jobs > 1`` generates buildings in worker processes; results are collected in
input order, so the stage is byte-identical whatever the job count. ``executor="dask"`` hands whole tiles to a Dask
cluster instead (:mod:`citygen.distributed`).
"""
from __future__ import annotations

import contextlib
import functools
import importlib
import itertools
from collections import Counter
import os
import pickle
import re
import sys
import tempfile
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import shapely

from citygen.attributes import AttributeKinds
from citygen.distributed import EXECUTORS, run_tiles
from citygen.errors import CitygenError, ExportError, SceneError, SourceLocation
from citygen.footprints import Footprint, FootprintStream, ImportResult, Skipped
from citygen.geometry.building import MeshData
from citygen.gltf import GLTF_SUFFIXES
from citygen.ground import ground_mesh
from citygen.lifeline import apart, stop_workers, tie_to_parent
from citygen.outpaths import check_writable
from citygen.registry import Registry, default_registry, load_registry
from citygen.rng import MAX_SEED
from citygen.roofplan import mass_plan
from citygen.scene import AUTO_TILE_LAYERS, Scene, key_line
from citygen.temporaries import remove_stale_temporaries, temp_prefix
from citygen.tilework import Spill, Strips, TileWork, Work, failed, tile_of, work_items
from citygen.usd.names import SUFFIXES, prim_name

if TYPE_CHECKING:  # (the facade machinery is imported where a run needs it: a mass-only run never does; the
    # stage writer once the footprints' planning is forked off: see _generate)
    from citygen.builder import Builder, BuildingOutcome
    from citygen.tiles import TileResult
    from citygen.usd.writer import StageStats

#: Metres the ground quad (``[output] ground = true``) reaches beyond the buildings.
GROUND_MARGIN = 20.0


@dataclass
class Report:
    """What a run did: counts, skipped buildings with reasons, warnings, timings and the stage's figures.

    ``timings`` are wall seconds per phase; ``cpu`` the main process's CPU seconds per phase (``usd``: the stage
    writer's, its ``add`` calls while buildings stream in and its close) plus ``builds``, the CPU the buildings'
    builds took summed wherever they ran, and ``workers``, the part of it spent in worker processes. With worker
    processes, the wall time of the ``buildings`` phase holds the writer's work too: the two overlap."""

    written: int = 0
    skipped: list[Skipped] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)
    cpu: dict[str, float] = field(default_factory=dict)
    stats: StageStats | None = None
    faces: Counter[str] = field(default_factory=Counter)  # (:func:`citygen.builder.face_tally`, summed)

    @property
    def buildings_per_s(self) -> float:
        """Buildings written per wall second of the whole run (0 before it has a total)."""
        total = self.timings.get("total", 0.0)
        return self.written / total if total > 0 else 0.0

    def summary(self) -> str:
        lines = [f"written {self.written} buildings, skipped {len(self.skipped)}, warnings {len(self.warnings)}"]
        lines += [f"  skipped {s.id}: {s.reason}" + (f" ({s.where})" if s.where else "") for s in self.skipped]
        shown = self.warnings[:20]
        lines += [f"  warning: {w}" for w in shown]
        if len(self.warnings) > len(shown):
            lines.append(f"  ... and {len(self.warnings) - len(shown)} more warnings (all of them: citygen generate "
                         f"--report FILE.json)")
        if self.faces:
            lines.append(_faces_line(self.faces))
        if self.stats:
            s = self.stats
            lines.append(f"stage {s.path.name}: {s.bytes / 1e6:.1f} MB, {s.prims} prims, {s.meshes} meshes, "
                         f"{s.polygons} polygons, {s.instances} instances of {s.prototypes} prototypes")
        lines.append("time " + ", ".join(f"{k} {v:.2f}s" for k, v in self.timings.items())
                     + f"; {self.buildings_per_s:.1f} buildings/s")
        if self.cpu:
            lines.append("cpu " + ", ".join(f"{k} {v:.2f}s" for k, v in self.cpu.items())
                         + (f"; {1000 * self.cpu['builds'] / self.written:.0f} ms per building"
                            if self.written and "builds" in self.cpu else ""))
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """The whole report as JSON-ready data (every skipped building and warning, the stage's figures)."""
        stats = None if self.stats is None else {**asdict(self.stats), "path": str(self.stats.path)}
        return {"written": self.written, "skipped": [asdict(s) for s in self.skipped], "warnings": self.warnings,
                "faces": dict(sorted(self.faces.items())), "stage": stats, "timings": self.timings, "cpu": self.cpu,
                "buildings_per_s": self.buildings_per_s}


def _faces_line(faces: Counter[str]) -> str:
    """``facades: 3120 dressed, 40 by fallback rulesets, 12 plain walls (implausible: small-opening 9, ...)``."""
    parts = [f"{faces['dressed']} dressed"]
    parts += [f"{faces[key]} {text}" for key, text in (("fallback", "by fallback rulesets"), ("plain", "plain walls"),
                                                        ("outside-range", "outside their ruleset's size range"))
              if faces[key]]
    codes = sorted(((k.split(":", 1)[1], v) for k, v in faces.items() if k.startswith("finding:")),
                   key=lambda kv: (-kv[1], kv[0]))
    found = f" (implausible: {', '.join(f'{code} {n}' for code, n in codes)})" if codes else ""
    return "facades: " + ", ".join(parts) + found


_WORKER: Builder | None = None


def _init_worker(scene: Scene, seed: int, plugins: tuple[tuple[object, ...], bool] | None, parent: int) -> None:
    global _WORKER
    from citygen.builder import Builder
    tie_to_parent(parent)
    _WORKER = Builder(scene, seed, None if plugins is None else load_registry(*plugins))


def _worker_plugins(registry: Registry) -> tuple[tuple[object, ...], bool] | None | str:
    """How a worker loads ``registry``: ``None`` for the default one, the plugins to register, or why it cannot
    be rebuilt in another process."""
    if registry is default_registry():
        return None
    try:
        pickle.dumps(registry.extra_plugins)
    except Exception as exc:
        return f"its in-process plugins cannot be pickled ({type(exc).__name__}: {exc})"
    return registry.extra_plugins, registry.entry_points


def _work(chunk: Sequence[Work]) -> list[BuildingOutcome]:
    from citygen.tiles import build_building
    assert _WORKER is not None
    return [build_building(_WORKER, item) for item in chunk]


def generate_city(scene: Scene, *, seed: int | None = None, out: Path | None = None, jobs: int = 1,
                  registry: Registry | None = None, progress: Callable[[int, int], None] | None = None,
                  executor: str = "local", scheduler: str | None = None) -> Report:
    """Generate the scene's city and write its stage; never raises for one bad building.

    ``executor`` is ``"local"`` (``jobs`` worker processes) or ``"dask"``: one task per tile on the cluster at
    ``scheduler`` (default: a local cluster of ``jobs`` workers), each tile its own layer whatever the scene's
    ``tile_layers`` (see :mod:`citygen.distributed`). With tile layers (``[output] tile_layers``, by default for a
    city of more than :data:`~citygen.scene.AUTO_TILE_LAYERS` buildings) the local executor runs the same tile tasks
    (:mod:`citygen.tiles`) -- unless the city has fewer tiles than ``jobs``: then buildings are built in the workers
    and their tiles written here.
    """
    if executor not in EXECUTORS:
        raise CitygenError(f"executor must be one of {', '.join(EXECUTORS)}, got {executor!r}")
    registry = registry or default_registry()
    seed = scene.seed if seed is None else seed
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= MAX_SEED:
        raise CitygenError(f"seed must be an integer from 0 to {MAX_SEED} (2**31 - 1), got {seed!r}")
    out = out or scene.output.path
    gltf = Path(out).suffix.lower() in GLTF_SUFFIXES
    if gltf and executor == "dask":
        raise CitygenError(f"the dask executor writes USD tile layers, not glTF ({Path(out).name})",
                           hint="use the local executor for .glb/.gltf, or write .usdc")
    check_stage_path(Path(out))
    with _spill() as spill:
        return _generate(scene, seed, Path(out), gltf, jobs, registry, progress, executor, scheduler, spill)


@contextlib.contextmanager
def _spill() -> Iterator[Spill]:
    """A :class:`~citygen.tilework.Spill` file for the run's packed tiles in the system's temporary folder, removed
    when the run ends (a killed run's is removed by the next run: :func:`~citygen.temporaries.temp_prefix`)."""
    folder = Path(tempfile.gettempdir())
    remove_stale_temporaries(folder)
    try:
        fd, name = tempfile.mkstemp(prefix=temp_prefix("citygen-tiles"), dir=folder)
    except OSError as exc:
        raise ExportError(f"cannot make the temporary file of the city's tile work: {exc.strerror or exc}",
                          where=str(folder), hint="check free disk space in the temporary folder (TMPDIR)") from None
    os.close(fd)
    try:
        yield Spill(Path(name))
    finally:
        Path(name).unlink(missing_ok=True)


def _generate(scene: Scene, seed: int, out: Path, gltf: bool, jobs: int, registry: Registry,
              progress: Callable[[int, int], None] | None, executor: str, scheduler: str | None, spill: Spill
              ) -> Report:
    """:func:`generate_city` once its arguments are checked, the packed tiles spilled to ``spill``."""
    report = Report()
    t0, c0 = time.perf_counter(), time.process_time()
    roofs = registry.roof_builders
    plan = functools.partial(_plan, scene, registry, roofs, spill)
    tr, cr = time.perf_counter(), time.process_time()
    # the footprints are planned in a child process (their memory stays there: see _Planned) forked before this
    # process loads the rulesets and imports USD, which it does meanwhile
    with apart(plan) as planning:
        # a ruleset that does not load stops the run before any building (masses only: none is used)
        if scene.output.masses:
            rulesets = {}
        else:
            from citygen.builder import load_rulesets
            rulesets = load_rulesets(scene, registry)
        importlib.import_module("citygen.usd.writer")  # (USD, while the child plans)
        loading = time.process_time() - cr  # (in the total, not in the masses phase: the child's alone)
        planned = planning()
    planned_apart = planned is not None
    if planned is None:
        planned = plan()
    report.skipped += planned.skipped
    report.warnings += planned.warnings
    works, ground, georef = planned.works, planned.ground, planned.georef
    t1 = tr + planned.timings["import"]
    c1 = cr + planned.cpu["import"]
    borrowed = planned.cpu["import"] + planned.cpu["masses"] if planned_apart else 0.0  # (the child's CPU)

    def clock() -> float:
        """This process's CPU seconds, and the planning child's."""
        return time.process_time() + borrowed

    plugins = _worker_plugins(registry) if jobs > 1 or executor == "dask" else None
    if isinstance(plugins, str) and executor == "dask":
        raise CitygenError(f"the registry given to generate_city cannot be rebuilt on dask workers: {plugins}",
                           hint="register the plugins through the `citygen` entry-point group")
    if isinstance(plugins, str):
        report.warnings.append(f"running with 1 job: the registry given to generate_city cannot be rebuilt in "
                               f"worker processes: {plugins}")
        jobs, plugins = 1, None
    count = sum(map(len, works))
    tiled = not gltf and (count > AUTO_TILE_LAYERS if scene.output.tile_layers is None else scene.output.tile_layers)
    masses_only = scene.output.masses and not gltf and executor == "local"
    by_tasks = not masses_only and (executor == "dask" or (tiled and (jobs == 1 or len(works) >= jobs)))
    work, lost = ([], []) if by_tasks or masses_only else work_items(works)  # (made per tile where built)
    report.skipped += lost
    t2, c2 = time.perf_counter(), clock()
    layer_data = {"scene": scene.name, "seed": seed, "source": scene.footprints.name, "georeference": georef}
    if gltf:
        ignored = [key for key in ("tile_layers", "uvs", "lod") if getattr(scene.output, key)]
        if ignored:
            report.warnings.append(f"{Path(out).name}: glTF output ignores [output] {', '.join(ignored)}")
    if masses_only:
        timings, cpu = _generate_masses(works, scene, seed, roofs, jobs, plugins, Path(out), layer_data, tiled, report,
                                        progress, ground)
        report.timings = {"import": t1 - t0, "masses": t2 - t1, **timings, "total": time.perf_counter() - t0}
        report.cpu = {"import": c1 - c0, "masses": c2 - c1 - loading, **cpu, "total": clock() - c0}
        return report
    if by_tasks:
        if executor == "dask":
            runner = functools.partial(run_tiles, scheduler=scheduler)
        else:
            from citygen.builder import Builder
            from citygen.tiles import run_local
            runner = functools.partial(run_local, builder=Builder(scene, seed, registry, rulesets))
        timings, cpu, tasks = _generate_tiles(works, scene, seed, plugins, Path(out).absolute(), layer_data, jobs,
                                              runner, report, progress, ground)
        report.timings = {"import": t1 - t0, "masses": t2 - t1, **timings, "total": time.perf_counter() - t0}
        report.cpu = {"import": c1 - c0, "masses": c2 - c1 - loading, **cpu, "total": clock() - c0, **tasks}
        return report
    usd = builds = 0.0  # CPU seconds: the writer's add calls (this thread), the builds (wherever they ran)
    with contextlib.ExitStack() as stack:  # (closing the outcomes stops their workers on any way out)
        writer = stack.enter_context(_writer(out, scene, layer_data, tiled))
        if ground:
            writer.ground(ground)
        outcomes = stack.enter_context(contextlib.closing(_run(work, scene, seed, jobs, registry, plugins, progress,
                                                                rulesets)))
        for outcome in outcomes:
            report.warnings += outcome.warnings
            report.faces.update(dict(outcome.faces))
            builds += outcome.cpu
            if outcome.record is None:
                report.skipped.append(outcome.skipped)
                continue
            tw = time.thread_time()
            writer.add(outcome.record)
            usd += time.thread_time() - tw
            report.written += 1 - _left_out(writer, work, report)
        t3, c3 = time.perf_counter(), clock()
        report.stats = writer.close()
        report.written -= _left_out(writer, work, report)
    t4, c4 = time.perf_counter(), clock()
    report.timings = {"import": t1 - t0, "masses": t2 - t1, "buildings": t3 - t2, "usd": t4 - t3, "total": t4 - t0}
    report.cpu = {"import": c1 - c0, "masses": c2 - c1 - loading, "buildings": c3 - c2 - usd, "usd": usd + c4 - c3,
                  "total": c4 - c0, "builds": builds, "workers": builds if _in_workers(jobs, len(work)) else 0.0}
    return report


def _left_out(writer: Any, work: Sequence[Work], report: Report) -> int:
    """How many buildings the stage writer has left out since the last call (its ``failed``: their writing raised),
    each skipped in ``report`` with the reason, its id and source found in ``work``."""
    lost = writer.failed
    if not lost:
        return 0
    footprints = {item[3]: item[0] for item in work}
    report.skipped += [failed(footprints[record.name], exc, "writing it to the stage") for record, exc in lost]
    count = len(lost)
    lost.clear()
    return count


@dataclass(frozen=True)
class _Planned:
    """The city planned by :func:`_plan`: its tiles' work, the ground quad, the georeference, the skipped
    footprints and warnings met, and the wall and CPU seconds of the ``import`` and ``masses`` phases.

    It is all the main process keeps of the footprint import: planned in a forked child
    (:func:`~citygen.lifeline.apart`), the importer's objects (~5 kB a building: 20,000 buildings held ~60 MB after
    they were dropped, the allocator's fragments) never enter the main process, nor the tile workers forked from it;
    and the tiles' packed work waits in the run's spill file (``works`` say where), read where each tile is built."""

    works: list[TileWork]
    ground: MeshData | None
    georef: dict[str, Any]
    skipped: list[Skipped]
    warnings: list[str]
    timings: dict[str, float]
    cpu: dict[str, float]


def _plan(scene: Scene, registry: Registry, roofs: dict[str, Any], spill: Spill) -> _Planned:
    """The scene's footprints imported one by one (:func:`stream_footprints`), every building's mass planned
    (:func:`~citygen.roofplan.mass_plan`; one that cannot be is skipped) and its prim name given, and all of them
    packed in tiles a strip at a time (:class:`~citygen.tilework.Strips`), spilled to ``spill``."""
    t0, c0 = time.perf_counter(), time.process_time()
    spill.reset()
    imported = stream_footprints(scene, registry)  # (a streaming importer's first pass)
    clock = _Clock(time.perf_counter() - t0, time.process_time() - c0)
    report = Report()
    works, ground = _plan_masses(clock.timed(imported.footprints), scene, roofs, report, spill)
    if not clock.count:
        report.warnings.insert(0, f"{scene.footprints.name}: no footprint to build; the stage is empty")
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    return _Planned(works, ground, imported.georef.to_dict() if imported.georef else {},
                    [*imported.skipped, *report.skipped], [*imported.warnings, *report.warnings],
                    {"import": clock.wall, "masses": wall - clock.wall},
                    {"import": clock.cpu, "masses": cpu - clock.cpu})


class _Clock:
    """The wall and CPU seconds spent in an iterator's ``next`` (a streamed import's, between plans; added to those
    it starts with), and how many items it gave."""

    def __init__(self, wall: float = 0.0, cpu: float = 0.0) -> None:
        self.wall, self.cpu = wall, cpu
        self.count = 0

    def timed(self, items: Iterator[Any]) -> Iterator[Any]:
        while True:
            t, c = time.perf_counter(), time.process_time()
            item = next(items, _Clock)
            self.wall += time.perf_counter() - t
            self.cpu += time.process_time() - c
            if item is _Clock:
                return
            self.count += 1
            yield item


def _plan_masses(footprints: Iterable[Footprint], scene: Scene, roofs: dict[str, Any], report: Report,
                 spill: Spill | None = None) -> tuple[list[TileWork], MeshData | None]:
    """Every building's mass planned (:func:`~citygen.roofplan.mass_plan`) and its tile found (one that cannot be
    is skipped), its prim name given, and all of them packed in tiles a tile column at a time (their bytes put in
    ``spill``, given one); and the ground when the scene asks for one. Only ~0.1 kB a building
    stays in memory (:class:`~citygen.tilework.Strips`)."""
    strips = Strips()
    kinds = AttributeKinds()
    notes: list[str] = []
    taken: set[str] = set()
    feet: list[tuple[bytes, float]] = []  # (the outlines as WKB: ~0.2 kB a building, where shapely's take ~2 kB)
    lowest = np.inf
    try:
        for fp in footprints:
            try:
                plan, found = mass_plan(fp, scene, roofs)
                tile = tile_of(plan, scene.output.tile_size)
            except CitygenError as exc:
                report.skipped.append(Skipped(fp.id, f"cannot build its mass: {exc}", fp.source))
                continue
            except Exception as exc:  # a bug skips one building, not the city, and says it is one
                report.skipped.append(Skipped(fp.id, f"internal error {type(exc).__name__} building its mass: {exc}",
                                              fp.source))
                continue
            notes += found
            kinds.add(fp, plan)  # (of a mass, it reads the outline's area)
            strips.add(fp, plan, prim_name(fp.id, taken), tile)
            if scene.output.ground:
                lowest = min(lowest, fp.base - fp.lift)
                if not fp.lift:  # (a part lifted off the ground does not stand on it)
                    feet.append((shapely.to_wkb(plan.outline), plan.base))
        report.warnings += notes + kinds.warnings(scene)
        ground = _ground(strips.bounds, feet, lowest) if scene.output.ground and len(strips) else None
        return list(strips.works(spill)), ground
    finally:
        strips.close()


def _writer(out: Path, scene: Scene, layer_data: dict[str, Any], tiled: bool):
    """The writer ``out``'s suffix asks for: glTF (trimesh imported only then) or a USD stage."""
    if Path(out).suffix.lower() in GLTF_SUFFIXES:
        from citygen.gltf.writer import GltfWriter
        return GltfWriter(out, layer_data=layer_data, materials=scene.materials)
    from citygen.usd.writer import StageWriter
    return StageWriter(out, up_axis=scene.output.up_axis, layer_data=layer_data, tile_layers=tiled,
                       uvs=scene.output.uvs, lod=scene.output.lod, materials=scene.materials)


def check_stage_path(out: Path) -> None:
    """Raise :class:`ExportError` before generating when no stage can be written at ``out`` (its extension, a
    folder in the way, a folder that refuses files)."""
    if out.suffix.lower() not in SUFFIXES + GLTF_SUFFIXES:
        raise ExportError(f"unsupported output extension {out.suffix!r}", where=str(out),
                          hint=f"use one of {', '.join(SUFFIXES + GLTF_SUFFIXES)}")
    check_writable(out, "stage")


def import_footprints(scene: Scene, registry: Registry | None = None) -> ImportResult:
    """The scene's footprint file through its importer (``format`` or the file's suffix), the scene's
    ``[defaults]`` heights and ``[footprints]`` keys as its options: the footprints :func:`generate_city` builds."""
    return _imported(scene, registry, "read")


def stream_footprints(scene: Scene, registry: Registry | None = None) -> FootprintStream:
    """:func:`import_footprints` handed over one by one (the importer's
    :meth:`~citygen.registry.FootprintImporter.stream`): what :func:`generate_city` plans the city from."""
    return _imported(scene, registry, "stream")


def _imported(scene: Scene, registry: Registry | None, how: str) -> Any:
    options = {"default_height": scene.defaults.default_height, "floor_height": scene.defaults.floor_height,
               **scene.footprint_options}
    importer = (registry or default_registry()).importer_for(scene.footprints, options.pop("format", None))
    try:
        return getattr(importer, how)(scene.footprints, options)
    except SceneError as exc:  # an option the importer refuses: at its line in the scene's [footprints]
        key = next((k for k in scene.footprint_options if re.search(rf"\b{re.escape(k)}\b", exc.message)), None)
        line = key_line(scene, "footprints", key) if key else None
        if line is None:
            raise
        raise SceneError(exc.message, where=SourceLocation(str(scene.path), line), plugin=exc.plugin,
                         hint=exc.hint) from None


def _ground(bounds: Sequence[float], feet: Sequence[tuple[bytes, float]], lowest: float) -> MeshData:
    """The ground (:func:`~citygen.ground.ground_mesh`) over the masses' ``bounds`` (``x0, y0, x1, y1`` a mass,
    flat) plus ``GROUND_MARGIN`` on every side, under the buildings standing on it (``feet``: outline as WKB,
    base); at ``lowest`` where none does."""
    box = np.asarray(bounds, dtype=float).reshape(-1, 4)
    x0, y0 = box[:, :2].min(axis=0) - GROUND_MARGIN
    x1, y1 = box[:, 2:].max(axis=0) + GROUND_MARGIN
    return ground_mesh((x0, y0, x1, y1), feet, lowest)


def _generate_tiles(works: Sequence[TileWork], scene: Scene, seed: int, plugins: tuple[tuple[object, ...], bool] | None,
                    out: Path, layer_data: dict[str, Any], jobs: int, runner: Callable[..., list[TileResult]],
                    report: Report, progress: Callable[[int, int], None] | None,
                    ground: MeshData | None
                    ) -> tuple[dict[str, float], dict[str, float], dict[str, float]]:
    """Tiles built and written by tile tasks (:mod:`citygen.tiles`: here, in worker processes or on dask); the root
    layer payloading them (and the ground) written here. Returns the wall and main-process CPU seconds of the
    ``buildings`` and ``usd`` phases, and the tasks' CPU: ``builds``, ``tile layers`` (writing them) and the part of
    both spent in ``workers``."""
    from citygen.tiles import TileJob, slimmed
    from citygen.usd.writer import StageWriter
    t0, c0 = time.perf_counter(), time.process_time()
    with StageWriter(out, up_axis=scene.output.up_axis, layer_data=layer_data, tile_layers=True,
                     uvs=scene.output.uvs, lod=scene.output.lod, materials=scene.materials) as writer:
        if ground:
            writer.ground(ground)
        job = TileJob(scene, seed, plugins, writer.staging_folder(), writer.tile_suffix, layer_data)
        results = runner(works, job, jobs, progress, take=functools.partial(slimmed, writer=writer))
        t1, c1 = time.perf_counter(), time.process_time()
        for result in results:
            report.warnings += result.warnings
            report.faces.update(dict(result.faces))
            report.skipped += result.skipped
            if result.stats is not None:
                writer.add_tile_layer(result.layer, result.stats, result.prototypes)
                report.written += result.stats.buildings
        report.stats = writer.close()
    builds, layers = sum(r.builds for r in results), sum(r.layer_cpu for r in results)
    elsewhere = runner.func is run_tiles or (jobs > 1 and len(results) > 1)
    return ({"buildings": t1 - t0, "usd": time.perf_counter() - t1},
            {"buildings": c1 - c0, "usd": time.process_time() - c1},
            {"builds": builds, "tile layers": layers, "workers": builds + layers if elsewhere else 0.0})


def _generate_masses(works: Sequence[TileWork], scene: Scene, seed: int, roofs: dict[str, Any], jobs: int,
                     plugins: tuple[tuple[object, ...], bool] | None, out: Path, layer_data: dict[str, Any],
                     tiled: bool, report: Report,
                     progress: Callable[[int, int], None] | None,
                     ground: MeshData | None
                     ) -> tuple[dict[str, float], dict[str, float]]:
    """A mass-only city (:mod:`citygen.lod1`, :mod:`citygen.lod1stage`): built in ``jobs`` worker processes where
    its estimated build CPU pays for them (:func:`citygen.lod1.in_workers`), else here; a tiled one of that kind
    written half here, half by a forked helper where it is big enough (:func:`citygen.lod1tiles.with_helper`), else
    all here. The work items -- masses and neighbour covers -- are made one tile at a time as they are built, so
    memory does not grow with the city. Returns the wall and CPU seconds of the ``buildings`` and ``usd`` phases
    (this process) and the ``builds`` CPU, with the part of it spent in ``workers`` (or the helper's builds and
    tile layers)."""
    from citygen.lod1 import build_cost, in_workers, mass_batches
    from citygen.lod1stage import MassWriter, write_outcomes
    from citygen.lod1tiles import run_with_helper, with_helper
    t0, c0 = time.perf_counter(), time.process_time()
    usd = builds = helper = 0.0  # CPU seconds: writing here, the builds (wherever), the helper's (builds and layers)
    done, total = 0, sum(map(len, works))
    workers = in_workers(build_cost(works), jobs)
    lost: list[Skipped] = []  # (buildings whose mass or cover cannot be made, met by :func:`_tile_items`)
    with MassWriter(out, up_axis=scene.output.up_axis, layer_data=layer_data, tile_layers=tiled,
                    uvs=scene.output.uvs, lod=scene.output.lod, materials=scene.materials) as writer:
        if ground:
            writer.ground(ground)
        chunk = max(1, min(64, total // (8 * jobs))) if workers else 0
        parts = (run_with_helper(works, scene, seed, roofs, writer) if with_helper(works, jobs, tiled) and not workers
                 else (write_outcomes(writer, outcomes, cpu) for outcomes, cpu in
                       mass_batches(_tile_items(works, lost), scene, seed, roofs, jobs, plugins, chunk)))
        for part in parts:
            report.skipped += part.skipped
            report.warnings += part.warnings
            report.written += part.written
            builds += part.builds
            usd += part.usd if part.here else 0.0
            helper += 0.0 if part.here else part.builds + part.usd
            done += part.written + len(part.skipped)
            if progress:
                progress(done, total)
        report.skipped += lost
        t1, c1 = time.perf_counter(), time.process_time()
        report.stats = writer.close()
    return ({"buildings": t1 - t0, "usd": time.perf_counter() - t1},
            {"buildings": c1 - c0 - usd, "usd": usd + time.process_time() - c1, "builds": builds,
             "workers": builds if workers else helper})


def _tile_items(works: Sequence[TileWork], lost: list[Skipped]) -> Iterator[Work]:
    """The tiles' work items, each tile's made when the one before is used up; the buildings skipped on the way
    go to ``lost``."""
    for work in works:
        items, skipped = work.items()
        lost += skipped
        yield from items


def _in_workers(jobs: int, total: int) -> bool:
    """Whether :func:`_run` builds ``total`` buildings in worker processes (else in this one)."""
    return jobs > 1 and total >= 2 * jobs


def _run(work: Sequence[Work], scene: Scene, seed: int, jobs: int, registry: Registry,
         plugins: tuple[tuple[object, ...], bool] | None, progress: Callable[[int, int], None] | None,
         rulesets: dict[tuple[str, Path], Any]) -> Iterator[BuildingOutcome]:
    """Outcomes in ``work`` order; with worker processes only a few chunks are in flight at a time, so finished
    buildings never pile up in memory faster than the stage writer consumes them. ``rulesets``: the scene's,
    already loaded (worker processes load their own)."""
    from citygen.builder import Builder
    from citygen.tiles import build_building
    total = len(work)
    if not _in_workers(jobs, total):
        builder = Builder(scene, seed, registry, rulesets)
        for k, item in enumerate(work):
            yield build_building(builder, item)
            if progress:
                progress(k + 1, total)
        return
    size = max(1, min(16, total // (8 * jobs)))
    chunks = iter([work[i:i + size] for i in range(0, total, size)])
    done = 0
    pool = ProcessPoolExecutor(max_workers=jobs, initializer=_init_worker, initargs=(scene, seed, plugins, os.getpid()))
    try:
        pending = deque(pool.submit(_work, c) for c in itertools.islice(chunks, 4 * jobs))
        while pending:
            outcomes = pending.popleft().result()
            following = next(chunks, None)
            if following is not None:
                pending.append(pool.submit(_work, following))
            for outcome in outcomes:
                done += 1
                yield outcome
                if progress:
                    progress(done, total)
    except BaseException:  # an error, Ctrl-C, SIGTERM, or the consumer closing early: the workers end now
        stop_workers(pool)
        raise
    pool.shutdown()


def terminal_progress(done: int, total: int) -> None:
    """A one-line progress bar on stderr (only when it is a terminal)."""
    if not sys.stderr.isatty():
        return
    width = 30
    filled = int(width * done / max(total, 1))
    sys.stderr.write(f"\r[{'#' * filled}{'.' * (width - filled)}] {done}/{total} buildings")
    if done == total:
        sys.stderr.write("\n")
    sys.stderr.flush()
