"""The dask executor: generation on a Dask cluster, one task per tile, each tile written by its worker.

A task builds its tile's buildings (the same per-building seeds and error handling as the local path: a bad
building skips itself) and writes the tile's layer itself, into the root stage's staging folder on a filesystem the
workers share, with the same writer the local executor's tile layers use: a complete stage of its own, ``/World``
with the tile and the ``/Materials`` and ``/Prototypes`` its buildings use, so it opens alone. Only small results
travel back (a :class:`TileResult`); the main process payloads the layers, in tile order, from the root. Every tile is
built from a fresh module cache, so its bytes depend on the seed and its buildings only, never on which worker
built it or when.

``dask.distributed`` is optional (``pip install 'citygen[distributed]'``) and imported only when used.
"""
from __future__ import annotations

import hashlib
import pickle
import threading
from collections import Counter
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from itertools import groupby
from pathlib import Path
from typing import Any

from citygen.builder import Builder
from citygen.errors import CitygenError
from citygen.footprints import Skipped
from citygen.geometry.building import clear_module_cache
from citygen.geometry.modules import ModuleKey
from citygen.geometry.prototypes import ProtoKey
from citygen.registry import load_registry
from citygen.scene import Scene
from citygen.usd.writer import StageStats, StageWriter, tile_name

EXECUTORS = ("local", "dask")
INSTALL_HINT = "pip install 'citygen[distributed]'"
#: How long ``--scheduler ADDRESS`` is tried before the run stops with an error (the old output is kept)
CONNECT_TIMEOUT = "30s"
#: Dask settings of the local cluster: no statistical profiler in the workers (~7 % of their CPU on citygen's
#: Python-bound tasks), and slower event-loop ticks and system monitor (an idle cluster's main process: 0.7 s of
#: CPU in 40 s instead of 1.8 s)
LOCAL_CLUSTER_CONFIG = {"distributed.worker.profile.enabled": False, "distributed.admin.tick.interval": "1s",
                        "distributed.admin.system-monitor.interval": "2s"}


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
    """What a tile task sends back: its layer file (``None`` when no building was written) and its report items."""

    layer: str | None
    stats: StageStats | None
    prototypes: tuple[ProtoKey | ModuleKey, ...]
    skipped: tuple[Skipped, ...]
    warnings: tuple[str, ...]
    faces: tuple[tuple[str, int], ...] = ()  # (summed :attr:`BuildingOutcome.faces`)


_BUILDERS = threading.local()


def _builder(job: TileJob) -> Builder:
    """The calling worker thread's building builder for this run (registry and rulesets loaded once)."""
    token = job.token
    if getattr(_BUILDERS, "token", None) != token:
        registry = None if job.plugins is None else load_registry(*job.plugins)
        _BUILDERS.builder, _BUILDERS.token = Builder(job.scene, job.seed, registry), token
    return _BUILDERS.builder


def build_tile(job: TileJob, items: Sequence[tuple]) -> TileResult:
    """The task: build one tile's buildings (``items`` are the pipeline's work items) and write its layer."""
    builder = _builder(job)
    clear_module_cache()
    tile = items[0][4]
    layer = f"{tile_name(tile)}{job.suffix}"
    skipped: list[Skipped] = []
    warnings: list[str] = []
    faces: Counter[str] = Counter()
    writer: StageWriter | None = None
    stats = None
    try:
        for item in items:
            outcome = builder.build(*item)
            warnings += outcome.warnings
            faces.update(dict(outcome.faces))
            if outcome.record is None:
                skipped.append(outcome.skipped)
                continue
            if writer is None:
                writer = StageWriter(job.staging / layer, up_axis=job.scene.output.up_axis,
                                     layer_data={**job.layer_data, "tile": tile_name(tile)}, uvs=job.scene.output.uvs,
                                     lod=job.scene.output.lod, materials=job.scene.materials)
            writer.add(outcome.record)
        if writer is not None:
            stats = writer.close()
    finally:
        clear_module_cache()
    return TileResult(layer if writer else None, stats, tuple(writer.prototypes) if writer else (),
                      tuple(skipped), tuple(warnings), tuple(sorted(faces.items())))


@contextmanager
def dask_client(scheduler: str | None, workers: int) -> Iterator[Any]:
    """A client of the cluster at ``scheduler``, or of a local cluster of ``workers`` worker processes."""
    try:
        import dask
        from dask.distributed import Client, LocalCluster
    except ImportError as exc:
        raise CitygenError(f"the dask executor needs dask.distributed, which is not installed ({exc})",
                           hint=INSTALL_HINT) from exc
    if scheduler:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT)
        except ValueError as exc:  # not an address dask can parse
            raise CitygenError(f"--scheduler {scheduler!r} is not a dask scheduler address: {exc}",
                               hint="give it as tcp://HOST:PORT (the address `dask scheduler` prints)") from exc
        except OSError as exc:  # nothing answers there within CONNECT_TIMEOUT
            raise CitygenError(f"cannot reach the dask scheduler at {scheduler}: {exc}",
                               hint="start one with `dask scheduler` and workers with `dask worker ADDRESS`") from exc
        with client:
            yield client
        return
    with dask.config.set(LOCAL_CLUSTER_CONFIG), \
            LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                         dashboard_address="127.0.0.1:0") as cluster, Client(cluster) as client:
        yield client


def run_tiles(work: Sequence[tuple], job: TileJob, scheduler: str | None, workers: int,
              progress: Callable[[int, int], None] | None = None) -> list[TileResult]:
    """Submit one task per tile (``work`` sorted by tile) and return their results in tile order."""
    tiles = [list(items) for _, items in groupby(work, key=lambda w: w[4])]
    total, done = len(work), 0
    results: dict[tuple[int, int], TileResult] = {}
    with dask_client(scheduler, workers) as client:
        from dask.distributed import as_completed

        futures = {client.submit(build_tile, job, items, pure=False): (items[0][4], len(items)) for items in tiles}
        for future in as_completed(futures):
            tile, size = futures[future]
            try:
                result = future.result()
            except Exception as exc:
                client.cancel(list(futures))
                if isinstance(exc, CitygenError):
                    raise
                raise CitygenError(f"{tile_name(tile)} failed on its dask worker: {type(exc).__name__}: {exc}",
                                  hint="see the worker's log") from exc
            results[tile] = result
            future.release()
            done += size
            if progress:
                progress(done, total)
    return [results[tile] for tile in sorted(results)]
