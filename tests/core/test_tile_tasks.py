"""Tile tasks on the local executor (issue 24, streaming): each tile built and written by one task, in worker
processes; tile layers by default for big cities."""
from __future__ import annotations

import time
from pathlib import Path

import pytest
from pxr import Usd, Work

from citygen import pipeline, tiles
from citygen.errors import SceneError
from citygen.pipeline import generate_city
from citygen.scene import load_scene
from tests.usd_util import assert_resolves

PHASES = ["import", "masses", "buildings", "usd", "total"]


def _scene(small_scene: Path, output: str):
    small_scene.write_text(small_scene.read_text().split("[output]")[0] + output)
    return load_scene(small_scene)


def _tiles(scene) -> list[str]:
    folder = Path(scene.output.path).parent / "small_tiles"
    return sorted(p.name for p in folder.glob("Tile_*")) if folder.exists() else []


def test_worker_processes_build_and_write_whole_tiles(small_scene, test_registry):
    """With tile layers, the tiles' layers are written where their buildings were built: the main process only
    writes the root (its CPU no longer holds the writer's work)."""
    scene = _scene(small_scene, '[output]\npath = "out/small.usdc"\ntile_size = 20\ntile_layers = true\n')
    report = generate_city(scene, registry=test_registry, jobs=2)
    assert report.written == 3 and len(_tiles(scene)) == 3
    assert list(report.cpu) == PHASES + ["builds", "tile layers", "workers"]
    assert report.cpu["tile layers"] > 0
    assert report.cpu["workers"] == pytest.approx(report.cpu["builds"] + report.cpu["tile layers"])
    assert [s.id for s in report.skipped] == ["way/bad"]  # a bad building skips itself inside its tile's task
    assert_resolves(Usd.Stage.Open(str(report.stats.path)))


def test_one_job_runs_the_tile_tasks_here(small_scene, test_registry):
    scene = _scene(small_scene, '[output]\npath = "out/small.usdc"\ntile_size = 20\ntile_layers = true\n')
    report = generate_city(scene, registry=test_registry, jobs=1)
    assert report.cpu["workers"] == 0.0 and report.cpu["tile layers"] > 0 and report.written == 3


def test_a_tile_tasks_masses_and_covers_count_as_its_builds_not_its_layer(small_scene, test_registry, monkeypatch):
    """The report's ``tile layers`` is the CPU of writing the layers: making the tile's masses and neighbour covers
    (:meth:`TileWork.items`, in the task) counted there once, 0.25 of the demo's 3.3 s."""
    from citygen.tilework import TileWork
    made = TileWork.items

    def slow_items(work):
        end = time.thread_time() + 0.2
        while time.thread_time() < end:
            pass
        return made(work)

    monkeypatch.setattr(TileWork, "items", slow_items)
    scene = _scene(small_scene, '[output]\npath = "out/small.usdc"\ntile_size = 20\ntile_layers = true\n')
    report = generate_city(scene, registry=test_registry, jobs=1)
    assert report.written == 3 and len(_tiles(scene)) == 3  # (three tiles: 0.6 s of items)
    assert report.cpu["builds"] >= 0.6 and report.cpu["tile layers"] < 0.6


def test_a_city_of_fewer_tiles_than_jobs_is_built_building_by_building(small_scene, test_registry):
    """One tile and two jobs: tile tasks would leave a worker idle, so buildings are built in the workers and the
    tile written by the main process, as without tile layers."""
    scene = _scene(small_scene, '[output]\npath = "out/small.usdc"\ntile_size = 1000\ntile_layers = true\n')
    report = generate_city(scene, registry=test_registry, jobs=2)
    assert list(report.cpu) == PHASES + ["builds", "workers"]
    assert report.written == 3 and len(_tiles(scene)) == 1


def test_tile_layers_are_the_default_for_a_big_city(small_scene, test_registry, monkeypatch):
    """Unset ``tile_layers``: a city of more than AUTO_TILE_LAYERS buildings streams into tile layers (memory bounded
    by a tile), a smaller one is one file; ``tile_layers = false`` keeps one file whatever the size."""
    scene = _scene(small_scene, '[output]\npath = "out/small.usdc"\ntile_size = 20\n')
    assert scene.output.tile_layers is None
    generate_city(scene, registry=test_registry)
    assert _tiles(scene) == []
    monkeypatch.setattr(pipeline, "AUTO_TILE_LAYERS", 2)
    generate_city(scene, registry=test_registry)
    assert len(_tiles(scene)) == 3
    single = _scene(small_scene, '[output]\npath = "one/small.usdc"\ntile_size = 20\ntile_layers = false\n')
    generate_city(single, registry=test_registry)
    assert not (Path(single.output.path).parent / "small_tiles").exists()


def test_tile_layers_must_be_true_or_false(small_scene):
    with pytest.raises(SceneError, match=r"tile_layers must be true or false, got 'auto'"):
        _scene(small_scene, '[output]\ntile_layers = "auto"\n')


def test_tile_workers_run_usd_work_in_their_own_thread_without_asking_tbb(monkeypatch):
    """Regression (memory at scale): a forked worker's USD work-thread pool never ran the detached freeing of
    released layers, so every tile layer it wrote stayed in memory (~0.2 MB per building); tile workers run USD's
    work serially. Regression (a hang): a worker that set the limit itself waited for ever on a TBB lock held at
    the fork (under load, 4 Dec 2026): the limit is the forking process's, set while it forks, and restored."""
    before = Work.GetConcurrencyLimit()
    with tiles._serial_work():
        monkeypatch.setattr(Work, "SetConcurrencyLimit", _no_tbb_after_the_fork)  # (the workers inherit it)
        with tiles._pool(1) as pool:
            assert pool.submit(_usd_concurrency).result(timeout=120) == 1
        monkeypatch.undo()
    assert Work.GetConcurrencyLimit() == before


def _no_tbb_after_the_fork(limit: int) -> None:
    raise AssertionError("a forked tile worker asked TBB for its concurrency")


def _usd_concurrency() -> int:
    return Work.GetConcurrencyLimit()


def _tiled_stage_files(small_scene: Path, registry):
    """The scene of three one-building tiles, a function reading its stage's files (root and tiles), and those files
    as one job writes them."""
    scene = _scene(small_scene, '[output]\npath = "out/small.usdc"\ntile_size = 20\ntile_layers = true\n')
    out = Path(scene.output.path)

    def files() -> dict[str, bytes]:
        return {p.name: p.read_bytes() for p in [out, *sorted((out.parent / "small_tiles").iterdir())]}

    generate_city(scene, registry=registry, jobs=1)
    return scene, files, files()


def test_tile_workers_write_the_stage_one_job_writes(small_scene, test_registry):
    scene, files, alone = _tiled_stage_files(small_scene, test_registry)
    report = generate_city(scene, registry=test_registry, jobs=2)
    assert files() == alone and report.written == 3 and report.cpu["workers"] > 0


def test_tile_workers_are_replaced_after_their_share_of_buildings_and_write_the_same_stage(small_scene, test_registry,
                                                                                          monkeypatch):
    """Regression (memory at scale): USD keeps memory for every distinct path a process authored, so a worker that
    wrote a whole city grew with it (~7.6 kB a building); each worker is replaced after BUILDINGS_PER_WORKER
    buildings, once its tiles are done, and the stage is the same bytes."""
    scene, files, alone = _tiled_stage_files(small_scene, test_registry)
    pools = []
    pool = tiles._pool
    monkeypatch.setattr(tiles, "_pool", lambda workers: pools.append(workers) or pool(workers))
    monkeypatch.setattr(tiles, "BUILDINGS_PER_WORKER", 1)
    report = generate_city(scene, registry=test_registry, jobs=2)
    assert pools == [1, 1, 1]  # (3 tiles of one building, 2 workers: the third tile goes to a fresh one)
    assert files() == alone and report.written == 3 and report.cpu["workers"] > 0


def test_tile_results_hand_their_prototype_keys_to_the_root_writer(tmp_path):
    """Regression (main-process memory at scale): results held until every tile is done held each tile's prototype
    keys (~1.8 module keys a building); the root's writer now takes them as a result comes in -- the element kinds
    kept for the library, the module prototypes counted -- and the result drops them."""
    from citygen.geometry.modules import ModuleKey
    from citygen.geometry.prototypes import ProtoKey
    from citygen.usd.writer import StageWriter
    window, door = ProtoKey("window", "glass", 120, 150, 5), ProtoKey("door", "wood", 100, 210, 5)
    modules = [ModuleKey(k, 300, 310, "plaster") for k in (7, 8, 9)]
    writer = StageWriter(tmp_path / "city.usdc", tile_layers=True)
    first = tiles.slimmed(tiles.TileResult(None, None, (window, *modules[:2]), (), ()), writer)
    second = tiles.slimmed(tiles.TileResult(None, None, (window, door, *modules[1:]), (), ()), writer)
    assert first.prototypes == second.prototypes == ()
    assert writer.tile_prototypes == {window, door} and len(writer.tile_modules) == 3


def test_the_spill_file_of_the_packed_tiles_goes_with_the_run(small_scene, test_registry, monkeypatch, tmp_path):
    """The tiles' packed work waits in a file of the temporary folder (the workers read their tiles from it), which
    the run removes whether it ends well or not."""
    import tempfile

    from citygen.tilework import Spilled
    folder = tmp_path / "tmp"
    folder.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(folder))
    scene = _scene(small_scene, '[output]\npath = "out/small.usdc"\ntile_size = 20\ntile_layers = true\n')
    build = tiles.build_tile
    seen = []

    def spying(job, work, builder=None):
        seen.append(isinstance(work.packed, Spilled) and Path(work.packed.path).parent == folder)
        return build(job, work, builder)
    monkeypatch.setattr(tiles, "build_tile", spying)
    assert generate_city(scene, registry=test_registry, jobs=1).written == 3
    assert seen == [True] * 3 and list(folder.iterdir()) == []

    def failing(job, work, builder=None):
        raise OSError("disk full")
    monkeypatch.setattr(tiles, "build_tile", failing)
    with pytest.raises(OSError, match="disk full"):
        generate_city(scene, registry=test_registry, jobs=1)
    assert list(folder.iterdir()) == []
