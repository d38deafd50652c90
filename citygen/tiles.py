"""Tile tasks: one task builds one tile's buildings and writes the tile's layer itself.

This is how a city with tile layers is generated, by either executor: the local one runs the tasks in this process
(one job) or in worker processes (:func:`run_local`), the dask one on a cluster (:mod:`citygen.distributed`). The
stage writer's work is then done where the buildings are built, next to them, and a worker holds one tile at a
time: memory is bounded by the largest tile whatever the city's size, and the main process only payloads the layers
from the root. A task is sent its tile's packed work (:class:`~citygen.tilework.TileWork`: on this machine where its
bytes lie in the run's spill file, which the task reads; to dask, the bytes) and makes the masses and neighbour
covers of its buildings itself. The main process keeps of each result only its figures for the root
(:func:`slimmed`): what it holds does not grow with the city. A task builds its buildings with the same per-building seeds and error
handling as the per-building path (a bad building skips itself: :meth:`~citygen.tilework.TileWork.items`,
:func:`build_building`; one the stage writer fails on is found and left out, :func:`_write_tile`) and writes
``/World`` with the tile and the ``/Materials`` and ``/Prototypes`` its buildings use, so the layer opens alone and
its bytes depend on the seed and its buildings only, never on which process built it or when. Only small results
travel back (a :class:`TileResult`).
"""
from __future__ import annotations

import hashlib
import os
import pickle
import threading
import time
from collections import Counter, deque
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from pxr import Work

from citygen.builder import Builder, BuildingOutcome
from citygen.footprints import Footprint, Skipped
from citygen.geometry.modules import ModuleKey
from citygen.geometry.prototypes import ProtoKey
from citygen.lifeline import stop_workers, tie_to_parent
from citygen.registry import load_registry
from citygen.scene import Scene
from citygen.temporaries import temp_prefix
from citygen.tilework import TileWork, failed
from citygen.tilework import Work as Item  # (pxr's Work is USD's thread pool)
from citygen.usd.library import library_name
from citygen.usd.names import tile_name
from citygen.usd.writer import ENVIRONMENT, BuildingRecord, StageStats, StageWriter


@dataclass(frozen=True)
class TileJob:
    """What every tile task shares: the scene, seed, how to rebuild the registry, and where layers go."""

    scene: Scene
    seed: int
    plugins: tuple[tuple[object, ...], bool] | None
    staging: Path
    suffix: str
    layer_data: Mapping[str, Any]

    @property
    def token(self) -> str:
        """Identifies the run's builder configuration in a worker's cache."""
        return hashlib.sha256(pickle.dumps((self.scene, self.seed, self.plugins))).hexdigest()


@dataclass(frozen=True)
class TileResult:
    """What a tile task sends back: its layer file (``None`` when no building was written), its report items and
    the CPU seconds it took: ``builds`` for the buildings (their masses and neighbour covers, made in the task, and
    their builds), ``layer_cpu`` for writing its layer."""

    layer: str | None
    stats: StageStats | None
    prototypes: tuple[ProtoKey | ModuleKey, ...]
    skipped: tuple[Skipped, ...]
    warnings: tuple[str, ...]
    faces: tuple[tuple[str, int], ...] = ()  # (summed :attr:`BuildingOutcome.faces`)
    builds: float = 0.0
    layer_cpu: float = 0.0


_BUILDERS = threading.local()
#: Buildings a tile worker process builds before a fresh one, forked again from the main process, takes over (once
#: the old one has finished its tiles: never more than ``jobs`` workers alive). USD keeps memory for every distinct
#: prim and property path and relationship target a process ever authored, layers long freed (~25-50 B a path, ~160 B
#: a target: ~4-8 kB a synthetic building), so a worker that wrote a whole city grew with it (100,000 buildings:
#: 202 -> 584 MB from 10,000); replaced, it stays within ~30 MB of its start. A fresh worker costs ~0.1-0.3 s of CPU
#: (its plugins and rulesets loaded again).
BUILDINGS_PER_WORKER = 4000
#: The last tiles, this many a worker, are handed out one at a time (see :func:`run_local`).
TAIL = 4


def _init_worker(parent: int) -> None:
    """In a worker process forked to run tile tasks (under :func:`_serial_work`): tied to its parent
    (:mod:`citygen.lifeline`)."""
    tie_to_parent(parent)


@contextmanager
def _serial_work() -> Iterator[None]:
    """USD's work done serially in this process while it forks tile workers (restored after), and so in the workers
    from their first instruction. USD's work-thread pool (TBB) does not survive a fork: the tasks it runs detached
    -- the freeing of every released layer's data -- never ran, and a forked worker grew by ~0.2 MB per building it
    built (3,000 synthetic buildings: 455 MB USS). Run serially, they free what each tile's layer held, for a few
    per cent more CPU (the freeing the leak skipped); what USD keeps of the paths it saw is bounded by
    :data:`BUILDINGS_PER_WORKER`. The limit is set here, in the thread that forks, not in the worker: a TBB lock
    that one of this process's threads held at the fork stays held in the child, and a worker setting the limit
    itself once waited on it for ever (4 Dec 2026, under load)."""
    before = Work.GetConcurrencyLimit()
    Work.SetConcurrencyLimit(1)
    try:
        yield
    finally:
        Work.SetConcurrencyLimit(before)


@dataclass
class _Slot:
    """One of :func:`run_local`'s worker processes: its executor (None between two workers), the buildings sent to
    it and its tiles in flight."""

    pool: ProcessPoolExecutor | None = None
    given: int = 0
    busy: int = 0


def _pool(workers: int) -> ProcessPoolExecutor:
    """``workers`` tile worker processes (:func:`_init_worker`), forked from this one (under
    :func:`_serial_work`)."""
    return ProcessPoolExecutor(max_workers=workers, initializer=_init_worker, initargs=(os.getpid(),))


def _builder(job: TileJob) -> Builder:
    """The calling worker thread's building builder for this run (registry and rulesets loaded once)."""
    token = job.token
    if getattr(_BUILDERS, "token", None) != token:
        registry = None if job.plugins is None else load_registry(*job.plugins)
        _BUILDERS.builder, _BUILDERS.token = Builder(job.scene, job.seed, registry), token
    return _BUILDERS.builder


def build_building(builder: Builder, item: Item) -> BuildingOutcome:
    """``builder.build(*item)``; a building whose build raises anyway (past the builder's own guard: its
    attributes, its pivot) is skipped with the reason, as the builder skips one."""
    try:
        return builder.build(*item)
    except Exception as exc:
        return BuildingOutcome(None, failed(item[0], exc, "building it"), ())


def build_tile(job: TileJob, work: TileWork, builder: Builder | None = None) -> TileResult:
    """The task: build one tile's buildings (their masses and neighbour covers made here: :meth:`TileWork.items`)
    and write its layer into ``job.staging``; ``builder``: one to use instead of this thread's own (the main
    process's)."""
    builder = builder or _builder(job)
    start = time.thread_time()
    items, skipped = work.items()
    warnings: list[str] = []
    faces: Counter[str] = Counter()
    built: list[tuple[Footprint, BuildingRecord]] = []
    builds = time.thread_time() - start  # (the masses and neighbour covers: the buildings' work, not the layer's)
    for item in items:
        outcome = build_building(builder, item)
        builds += outcome.cpu
        warnings += outcome.warnings
        faces.update(dict(outcome.faces))
        if outcome.record is None:
            skipped.append(outcome.skipped)
        else:
            built.append((item[0], outcome.record))
    writer, stats, lost = _write_tile(job, work.tile, built)
    return TileResult(writer.path.name if writer else None, stats, tuple(writer.prototypes) if writer else (),
                      tuple(skipped + lost), tuple(warnings), tuple(sorted(faces.items())), builds,
                      time.thread_time() - start - builds)


def _write_tile(job: TileJob, tile: tuple[int, int], built: Sequence[tuple[Footprint, BuildingRecord]]
                ) -> tuple[StageWriter | None, StageStats | None, list[Skipped]]:
    """The tile's layer written from ``built``'s records (no writer, no figures: none to write), and the buildings
    left out: those the stage writer fails on (its :attr:`~citygen.usd.writer.StageWriter.failed`, or found by
    writing each record alone when the layer fails as a whole), the layer written again without them, so its bytes
    are those of a tile without them. An error of the machine's (:data:`~citygen.usd.writer.ENVIRONMENT`: a full
    disk, no memory) is no building's: it stops the task."""
    path = job.staging / f"{tile_name(tile)}{job.suffix}"
    try:
        writer, stats = _layer(job, tile, path, [record for _, record in built])
        bad = {record.name: exc for record, exc in writer.failed} if writer else {}
    except ENVIRONMENT:
        raise
    except Exception:
        bad = {record.name: exc for _, record in built if (exc := _fails(job, tile, record)) is not None}
    if not bad:
        return writer, stats, []
    lost = [failed(footprint, bad[record.name], "writing it to the stage") for footprint, record in built
            if record.name in bad]
    return (*_layer(job, tile, path, [record for _, record in built if record.name not in bad]), lost)


def _layer(job: TileJob, tile: tuple[int, int], path: Path, records: Sequence[BuildingRecord]
           ) -> tuple[StageWriter | None, StageStats | None]:
    """The layer at ``path`` of ``records`` (none: no layer) and its figures."""
    if not records:
        return None, None
    writer = StageWriter(path, up_axis=job.scene.output.up_axis, layer_data={**job.layer_data, "tile": tile_name(tile)},
                         uvs=job.scene.output.uvs, lod=job.scene.output.lod, materials=job.scene.materials,
                         element_library=library_name(job.suffix))
    for record in records:
        writer.add(record)
    return writer, writer.close()


def _fails(job: TileJob, tile: tuple[int, int], record: BuildingRecord) -> Exception | None:
    """The error writing ``record`` alone in a layer raises or leaves out (a scratch file, removed), or None."""
    scratch = job.staging / f"{temp_prefix(tile_name(tile))}check{job.suffix}"
    try:
        writer, _ = _layer(job, tile, scratch, [record])
    except ENVIRONMENT:
        raise
    except Exception as exc:
        return exc
    finally:
        scratch.unlink(missing_ok=True)
    return writer.failed[0][1] if writer and writer.failed else None


def slimmed(result: TileResult, writer: StageWriter) -> TileResult:
    """``result`` as the main process holds it until every tile is done: its prototype keys handed to the root's
    ``writer`` as it comes in (:meth:`~citygen.usd.writer.StageWriter.take_prototypes`) and dropped, so what is
    held does not grow with the keys (~1.8 module prototypes a building, ~250 bytes each)."""
    writer.take_prototypes(result.prototypes)
    return replace(result, prototypes=())


def run_local(tiles: Sequence[TileWork], job: TileJob, jobs: int, progress: Callable[[int, int], None] | None = None,
              *, builder: Builder, take: Callable[[TileResult], TileResult] = lambda result: result
              ) -> list[TileResult]:
    """Every tile's task, here (``jobs`` 1, or a single tile: with ``builder``) or in ``jobs`` worker processes
    (:func:`_init_worker`; each replaced after :data:`BUILDINGS_PER_WORKER` buildings), largest tile first so the
    last ones to finish are small; results in tile order, each as ``take`` makes it when it comes in
    (:func:`slimmed`). The workers read their tiles' packed work from the spill file themselves."""
    total, done = sum(map(len, tiles)), 0
    if jobs <= 1 or len(tiles) < 2:
        results = []
        for items in tiles:
            results.append(take(build_tile(job, items, builder)))
            done += len(items)
            if progress:
                progress(done, total)
        return results
    order = sorted(range(len(tiles)), key=lambda k: (-len(tiles[k]), k))
    found: dict[int, TileResult] = {}
    slots = [_Slot() for _ in range(min(jobs, len(tiles)))]
    pending: dict[Future, tuple[int, _Slot]] = {}
    queue = deque(order)  # (a few tiles in flight: an interrupted run has little queued to drop)

    def feed(slot: _Slot) -> None:
        """Up to two tiles in flight in ``slot``'s worker (one in the last :data:`TAIL` tiles a slot, so those go to
        whichever worker is free first instead of waiting behind a slot's running tile: the demo's last tile waited
        1.3 s), a fresh worker once the last has built its share and is done (no two workers of a slot alive at
        once: the tree's memory stays that of ``jobs`` workers)."""
        while (slot.busy < 1 or slot.busy < 2 and len(queue) > TAIL * len(slots)) and \
                not (slot.pool is not None and slot.given >= BUILDINGS_PER_WORKER):
            if not queue:
                return
            k = queue.popleft()
            if slot.pool is None:
                slot.pool = _pool(1)
            slot.given += len(tiles[k])
            slot.busy += 1
            pending[slot.pool.submit(build_tile, job, tiles[k])] = (k, slot)
        if slot.busy == 0 and slot.pool is not None:  # (its share built: a fresh worker takes over)
            slot.pool.shutdown()
            slot.pool, slot.given = None, 0
            feed(slot)

    with _serial_work():
        try:
            for slot in slots:
                feed(slot)
            while pending:
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                for future in finished:
                    k, slot = pending.pop(future)
                    found[k] = take(future.result())
                    slot.busy -= 1
                    feed(slot)
                    done += len(tiles[k])
                    if progress:
                        progress(done, total)
        except BaseException:  # an error, Ctrl-C, SIGTERM: the workers end now
            for slot in slots:
                if slot.pool is not None:
                    stop_workers(slot.pool)
            raise
        live = [slot.pool for slot in slots if slot.pool is not None]
        for pool in live:  # (the workers end side by side, then are joined)
            pool.shutdown(wait=False)
        for pool in live:
            pool.shutdown()
    return [found[k] for k in range(len(tiles))]
