"""The stage writer alone, as a city's run uses it: every tile layer written by a tile task's writer, then the
element library the main process writes, on a scene's real building records (default: the Helsinki demo).

    python benchmarks/tile_writer.py [SCENE] [--cache FILE] [--repeat 5] [--profile [N]] [--phases]

The scene is generated once (one job, in this process) while every tile task's writer call (its job, tile and
building records) is recorded, with the sha256 of the layer it wrote; ``--cache FILE`` pickles them so later runs
skip the generation. Then the recorded tiles are written again ``--repeat`` times, each time as a fresh worker
would (the process's prepared element prototypes and element bounds forgotten first, USD's work done in this
thread), and the element library of their element kinds as the main process writes it: its elements and their
arrays prepared first (the main process does that while the tiles are built), then written. Printed: the CPU
(process_time) of the tile layers and of the library's two parts, best and median, and whether every file's bytes
are the recorded ones. ``--profile`` writes them once more under cProfile and prints the total function calls
(deterministic: the figure to compare between two versions of the writer whatever the machine's load) and the
``N`` functions of most own time. ``--phases`` writes the tiles once more with the CPU of their phases timed
(placing instances, face normals, Vt arrays, export; the rest is authoring specs).
"""
from __future__ import annotations

import argparse
import cProfile
import dataclasses
import hashlib
import pickle
import pstats
import statistics
import tempfile
import time
from pathlib import Path

from pxr import Sdf, Work

import citygen.tiles
from citygen.geometry.prototypes import ProtoKey
from citygen.pipeline import generate_city
from citygen.scene import load_scene
from citygen.usd import definitions, publish
from citygen.usd import writer as writer_module
from citygen.usd.author import Author
from citygen.usd.element_bounds import element_bound
from citygen.usd.library import write_library
from citygen.usd.writer import StageWriter

REPO = Path(__file__).resolve().parents[1]


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def record_tiles(scene_path: Path) -> dict:
    """Every tile writer call of the scene's one-job run: ``(job, tile, records, sha256 of the layer)``, and the
    sha256 of the element library the run published."""
    calls = []
    original = citygen.tiles._layer

    def recording(job, tile, path, records):
        writer, stats = original(job, tile, path, records)
        if writer is not None:
            calls.append((job, tile, list(records), _digest(path)))
        return writer, stats

    scene = load_scene(scene_path)
    citygen.tiles._layer = recording
    try:
        with tempfile.TemporaryDirectory() as scratch:
            out = Path(scratch) / "city.usdc"
            generate_city(scene, out=out, jobs=1)
            library = next((out.parent / f"{out.stem}_tiles").glob("elements.*"), None)
            return {"scene": str(scene_path), "tiles": calls, "library": library and _digest(library)}
    finally:
        citygen.tiles._layer = original


#: The tile writer's phases timed by ``--phases``: the functions whose calls' CPU is summed (none calls another).
PHASES = {"placing instances (lift, element bounds, instance bounds)": [(StageWriter, "_placed")],
          "face normals": [(writer_module, "face_normals"), (definitions, "face_normals")],
          "mesh arrays (Vt)": [(Author, "arrays")], "export": [(publish, "export_layer")]}


def write_all(recorded: dict, folder: Path) -> tuple[float, float, float, bool]:
    """Write the recorded tiles into ``folder`` as fresh workers would, then their element library as the main
    process does (its elements and their arrays prepared as the tile results come in, then written after the last
    tile); return the CPU seconds of the tiles, of the library's preparation and of its writing, and whether every
    file has the recorded bytes."""
    definitions._ELEMENTS.clear()
    element_bound.cache_clear()
    same = True
    keys: set[ProtoKey] = set()
    Work.SetConcurrencyLimit(1)  # (as in a tile worker: citygen.tiles._init_worker)
    c0 = time.process_time()
    for job, tile, records, digest in recorded["tiles"]:
        job = dataclasses.replace(job, staging=folder)
        writer, _ = citygen.tiles._layer(job, tile, folder / f"tile{job.suffix}", records)
        keys.update(k for k in writer.prototypes if isinstance(k, ProtoKey))
        same &= _digest(writer.path) == digest
    c1 = time.process_time()
    Work.SetMaximumConcurrencyLimit()
    definitions._ELEMENTS.clear()  # (the main process prepares the library's elements itself)
    job = recorded["tiles"][0][0]
    output = job.scene.output
    store = definitions.elements(job.scene.materials, output.uvs)
    definitions.prepare_elements(sorted(keys, key=lambda k: k.name), store, job.scene.materials)
    definitions.prepare_arrays([store[k] for k in keys], Author(Sdf.Layer.CreateAnonymous(), output.uvs,
                                                                job.scene.materials))
    c2 = time.process_time()
    path = folder / f"elements{job.suffix}"
    write_library(path, keys, job.scene.materials, output.uvs, output.up_axis)
    c3 = time.process_time()
    same &= recorded["library"] is None or _digest(path) == recorded["library"]
    return c1 - c0, c2 - c1, c3 - c2, same


def phases(recorded: dict, folder: Path) -> tuple[float, dict[str, float]]:
    """The tiles written once more with each of :data:`PHASES` timed: the tiles' CPU and each phase's."""
    spent = dict.fromkeys(PHASES, 0.0)
    saved = [(owner, attr, getattr(owner, attr)) for places in PHASES.values() for owner, attr in places]

    def timed(name, function):
        def call(*args, **kwargs):
            start = time.thread_time()
            try:
                return function(*args, **kwargs)
            finally:
                spent[name] += time.thread_time() - start
        return call

    for name, places in PHASES.items():
        for owner, attr in places:
            setattr(owner, attr, timed(name, getattr(owner, attr)))
    try:
        tiles, *_ = write_all(recorded, folder)
    finally:
        for owner, attr, function in saved:
            setattr(owner, attr, function)
    return tiles, spent


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("scene", nargs="?", default=str(REPO / "scenes" / "helsinki.toml"))
    parser.add_argument("--cache", type=Path, help="pickle of the recorded tiles (made if missing)")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--profile", type=int, nargs="?", const=25, default=None, metavar="N")
    parser.add_argument("--phases", action="store_true", help="time the tile writer's phases once more")
    args = parser.parse_args()
    if args.cache and args.cache.is_file():
        recorded = pickle.loads(args.cache.read_bytes())
    else:
        t0 = time.perf_counter()
        recorded = record_tiles(Path(args.scene))
        print(f"generated in {time.perf_counter() - t0:.1f} s")
        if args.cache:
            args.cache.write_bytes(pickle.dumps(recorded, protocol=pickle.HIGHEST_PROTOCOL))
    buildings = sum(len(records) for _, _, records, _ in recorded["tiles"])
    print(f"{Path(recorded['scene']).name}: {len(recorded['tiles'])} tile layers, {buildings} buildings")
    tiles, prepared, libraries = [], [], []
    with tempfile.TemporaryDirectory() as scratch:
        for _ in range(args.repeat):
            cpu, prepare, library, same = write_all(recorded, Path(scratch))
            tiles.append(cpu)
            prepared.append(prepare)
            libraries.append(library)
            print(f"  tile layers {cpu:.3f} s, element library {prepare:.3f} s prepared + {library:.3f} s written, "
                  f"bytes {'the recorded ones' if same else 'DIFFERENT'}")
        if tiles:
            print(f"tile layers best {min(tiles):.3f} / median {statistics.median(tiles):.3f} s, element library "
                  f"prepared (as the results come in) best {min(prepared):.3f} / median "
                  f"{statistics.median(prepared):.3f} s, written (after the last tile) best {min(libraries):.3f} / "
                  f"median {statistics.median(libraries):.3f} s CPU")
        if args.phases:
            cpu, spent = phases(recorded, Path(scratch))
            print(f"phases of the tile layers ({cpu:.3f} s CPU):")
            for name, seconds in [*spent.items(), ("the rest: authoring specs", cpu - sum(spent.values()))]:
                print(f"  {seconds:6.3f} s {100 * seconds / cpu:5.1f} %  {name}")
        if args.profile is not None:
            profile = cProfile.Profile()
            profile.runcall(write_all, recorded, Path(scratch))
            stats = pstats.Stats(profile)
            print(f"under cProfile: {stats.total_calls:,} function calls ({stats.prim_calls:,} primitive)")
            stats.sort_stats("tottime").print_stats(args.profile)


if __name__ == "__main__":
    main()
