"""A mass-only city with tile layers, built and written by two processes: this one and one helper forked from it.

Worker processes do not pay for a city of flat-roofed masses (:func:`citygen.lod1.in_workers`): started fresh, each
would register the plugins again and be sent its work. A forked helper needs neither -- it starts with everything
this process has, the tiles' packed work included -- and costs a fork and a pipe. It builds and writes every
other tile layer (the tiles dealt to balance the buildings) into the root's staging folder and sends back only each
layer's name, figures and report items; this process does the rest and payloads the layers in tile order, so the
stage is the same bytes as with one process.
"""
from __future__ import annotations

import multiprocessing
import os
import time
import traceback
from collections.abc import Iterator, Mapping, Sequence, Sized
from dataclasses import replace
from pathlib import Path
from typing import Any

from citygen.errors import CitygenError
from citygen.lifeline import tie_to_parent
from citygen.lod1 import mass_batches
from citygen.lod1stage import MassWriter, Part, write_outcomes
from citygen.registry import RoofBuilder
from citygen.scene import Scene
from citygen.tilework import TileWork
from citygen.usd.names import tile_name

#: Buildings from which a helper process writes half of the tile layers (below it, the fork and the pipe cost
#: more than half of the work saves: a mass-only building costs ~1.7 ms to build and write).
HELPER_FROM = 200


def with_helper(works: Sequence[TileWork], jobs: int, tiled: bool) -> bool:
    """Whether a helper writes half of the tiles: a tiled city of at least :data:`HELPER_FROM` buildings in two
    tiles or more, with two jobs or more."""
    return tiled and jobs > 1 and sum(map(len, works)) >= HELPER_FROM and len(works) > 1


def deal(tiles: Sequence[Sized]) -> set[int]:
    """The indices of the tiles the helper takes: largest first, each to the side with fewer buildings so far."""
    mine = theirs = 0
    taken: set[int] = set()
    for k in sorted(range(len(tiles)), key=lambda k: (-len(tiles[k]), k)):
        if theirs < mine:
            taken.add(k)
            theirs += len(tiles[k])
        else:
            mine += len(tiles[k])
    return taken


def run_with_helper(works: Sequence[TileWork], scene: Scene, seed: int, roofs: Mapping[str, RoofBuilder],
                    writer: MassWriter) -> Iterator[Part]:
    """Every tile in order, as a :class:`~citygen.lod1stage.Part`: the tiles dealt to this process built and added
    to ``writer``, the helper's payloaded from the layers it wrote. Each process makes its tiles' work items
    (:meth:`~citygen.tilework.TileWork.items`) one tile at a time."""
    taken = deal(works)
    staging = writer.staging_folder()
    context = multiprocessing.get_context("fork")
    receive, send = context.Pipe(duplex=False)
    helper = context.Process(target=_helper, args=([works[k] for k in sorted(taken)], scene, seed, roofs, staging,
                                                   writer, send, os.getpid()), daemon=True)
    helper.start()
    send.close()
    try:
        for k, work in enumerate(works):
            if k not in taken:
                start = time.process_time()
                items, lost = work.items()
                outcomes = [o for batch, _ in mass_batches(items, scene, seed, roofs) for o in batch]
                part = write_outcomes(writer, outcomes, time.process_time() - start)
                yield replace(part, skipped=(*lost, *part.skipped))
                continue
            done = receive.recv()
            if isinstance(done, str):
                raise CitygenError(f"the helper process writing tile layers failed: {done}")
            layer, stats, part = done
            if layer is not None:
                writer.add_layer(layer, stats)
            yield part
        helper.join()
    except EOFError:
        raise CitygenError(f"the helper process writing tile layers ended early (exit status {helper.exitcode})",
                           hint="run with --jobs 1 to write every tile in one process") from None
    finally:
        receive.close()
        if helper.is_alive():
            helper.kill()
            helper.join()


def _helper(works: Sequence[TileWork], scene: Scene, seed: int, roofs: Mapping[str, RoofBuilder], staging: Path,
            root: MassWriter, send: Any, parent: int) -> None:
    """In the forked helper: build and write each tile's layer, in tile order, and send its name (None: no building
    written), figures and :class:`~citygen.lod1stage.Part` (or, on any error, the traceback's text)."""
    tie_to_parent(parent)
    try:
        for work in works:
            start = time.thread_time()
            items, lost = work.items()
            outcomes = [o for batch, _ in mass_batches(items, scene, seed, roofs) for o in batch]
            builds = time.thread_time() - start
            layer = stats = None
            if any(o.record is not None for o in outcomes):
                layer = f"{tile_name(work.tile)}{root.tile_suffix}"
                writer = MassWriter(staging / layer, up_axis=root.up_axis, layer_data={**root.layer_data,
                                                                                       "tile": tile_name(work.tile)},
                                    uvs=root.uvs, lod=root.lod, materials=root.library)
                part = write_outcomes(writer, outcomes, builds)
                stats = writer.close()
            else:
                part = write_outcomes(root, outcomes, builds)  # (nothing to add: skipped buildings only)
            send.send((layer, stats, replace(part, skipped=(*lost, *part.skipped),
                                             usd=time.thread_time() - start - builds, here=False)))
    except BaseException:
        send.send(traceback.format_exc(limit=4))
    finally:
        send.close()
        os._exit(0)  # (no cleanup of the parent's state: the parent owns the staging folder and its files)
