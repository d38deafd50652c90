"""The dask executor: generation on a Dask cluster, one tile task per tile (:mod:`citygen.tiles`), each tile's layer
written by its worker into the root stage's staging folder on a filesystem the workers share. Only small results
travel back (a :class:`~citygen.tiles.TileResult`); the main process payloads the layers, in tile order, from the
root.

``dask.distributed`` is optional (``pip install 'citygen[distributed]'``) and imported only when used.
"""
from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

from citygen.errors import CitygenError
from citygen.usd.names import tile_name

if TYPE_CHECKING:
    from citygen.tiles import TileJob, TileResult
    from citygen.tilework import TileWork

EXECUTORS = ("local", "dask")
INSTALL_HINT = "pip install 'citygen[distributed]'"
#: How long ``--scheduler ADDRESS`` is tried before the run stops with an error (the old output is kept)
CONNECT_TIMEOUT = "30s"
#: Dask settings of the local cluster: no statistical profiler in the workers (~7 % of their CPU on citygen's
#: Python-bound tasks), and slower event-loop ticks and system monitor (an idle cluster's main process: 0.7 s of
#: CPU in 40 s instead of 1.8 s)
LOCAL_CLUSTER_CONFIG = {"distributed.worker.profile.enabled": False, "distributed.admin.tick.interval": "1s",
                        "distributed.admin.system-monitor.interval": "2s"}


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


def run_tiles(tiles: Sequence[TileWork], job: TileJob, workers: int,
              progress: Callable[[int, int], None] | None = None, *, scheduler: str | None = None,
              take: Callable[[TileResult], TileResult] = lambda result: result) -> list[TileResult]:
    """Submit one task per tile (``tiles`` in tile order, each with its packed bytes: a worker may be on another
    machine) and return their results in tile order, each as ``take`` makes it when it comes in."""
    from citygen.tiles import build_tile  # (the facade machinery: imported when a run needs it)
    total, done = sum(map(len, tiles)), 0
    results: dict[tuple[int, int], TileResult] = {}
    with dask_client(scheduler, workers) as client:
        from dask.distributed import as_completed

        futures = {client.submit(build_tile, job, work.loaded(), pure=False): (work.tile, len(work)) for work in tiles}
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
            results[tile] = take(result)
            future.release()
            done += size
            if progress:
                progress(done, total)
    return [results[tile] for tile in sorted(results)]
