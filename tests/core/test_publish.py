"""Tile layers published atomically and temporaries that no run leaves behind (issue 23 #4 and #10)."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from pxr import Sdf, Usd

import citygen.usd.writer as writer
from citygen.errors import ExportError
from citygen.pipeline import generate_city
from citygen.scene import load_scene
from tests.core.cli_scene import citygen_process, write_scene
from tests.usd_util import assert_resolves

TILED = 'tile_layers = true\ntile_size = 40\n'
LIBRARY = "city_tiles/elements.usdc"  # (the tiles' element library: not payloaded by the root)


def _layers(root: Path) -> dict[str, bytes]:
    """The root's bytes and those of every tile layer its tile prims payload (a missing one: b"")."""
    layer = Sdf.Layer.FindOrOpen(str(root))
    paths = [item.assetPath.removeprefix("./") for tile in layer.GetPrimAtPath("/World").nameChildren
             for item in tile.payloadList.prependedItems]
    Sdf.Layer.Reload(layer)
    files = {root.name: root.read_bytes()}
    for sub in paths:
        target = root.parent / sub
        files[sub] = target.read_bytes() if target.is_file() else b""
    return files


def test_a_failed_root_write_leaves_the_old_root_composing_its_own_tiles(tmp_path, monkeypatch):
    """Was: the new tiles replaced the old ones before the root was written, so a failed (or killed) root write
    left the old root composing the new run's tiles."""
    scene = load_scene(write_scene(tmp_path, buildings=6, extra_output=TILED))
    generate_city(scene, seed=1)
    root = Path(scene.output.path)
    before = _layers(root)
    assert all(before.values()) and len(before) > 2

    def full_disk(layer, path):
        raise ExportError("USD export failed: No space left on device", where=str(path))

    monkeypatch.setattr(writer, "write_layer", full_disk)
    with pytest.raises(ExportError):
        generate_city(scene, seed=2)  # other seed: other tiles
    assert _layers(root) == before
    assert_resolves(Usd.Stage.Open(str(root)))  # the element library still holds the old tiles' elements
    monkeypatch.undo()
    generate_city(scene, seed=2)  # the next good run removes the tiles the failed one published
    listed = set(_layers(root)) - {root.name} | {LIBRARY}
    assert {f"{p.parent.name}/{p.name}" for p in (root.parent / "city_tiles").iterdir()} == listed


def test_same_seed_same_bytes_and_the_tiles_of_a_finished_root_are_kept(tmp_path):
    scene = load_scene(write_scene(tmp_path, buildings=6, extra_output=TILED))
    generate_city(scene)
    root = Path(scene.output.path)
    first = _layers(root)
    generate_city(scene)
    assert _layers(root) == first
    assert {f"city_tiles/{p.name}" for p in (root.parent / "city_tiles").iterdir()} == set(first) - {root.name} | {LIBRARY}


def _dead_pid() -> int:
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def test_stale_temporaries_of_dead_runs_are_removed_and_live_ones_kept(tmp_path):
    scene = load_scene(write_scene(tmp_path, buildings=6, extra_output=TILED))
    out = Path(scene.output.path)
    out.parent.mkdir()
    dead, alive = _dead_pid(), os.getppid()
    stale = [out.parent / f".city.citygen-{dead}-x1y2.usdc", out.parent / f".city_tiles.citygen-{dead}-q9"]
    stale[0].write_bytes(b"half a stage")
    stale[1].mkdir()
    (stale[1] / "Tile_0_0.usdc").write_bytes(b"a finished tile")
    live = out.parent / f".city.citygen-{alive}-a1b2.usdc"
    live.write_bytes(b"another run still writing")
    generate_city(scene)
    assert not any(p.exists() for p in stale)
    assert live.exists()


def test_a_run_killed_while_writing_tiles_leaves_only_what_the_next_run_removes(tmp_path):
    """Was: kill -9 left a hidden ``.<stem>_tiles.XXXX/`` folder of finished tiles (and temporary stages) that no
    later run removed."""
    scene_path = write_scene(tmp_path, buildings=300, extra_output='tile_layers = true\ntile_size = 30\n')
    out = tmp_path / "out"
    proc = citygen_process("generate", str(scene_path), "-q", "--jobs", "1")
    deadline = time.monotonic() + 120
    while not [f for d in out.glob(".city_tiles.citygen-*") for f in d.iterdir()]:
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.02)
    os.kill(proc.pid, signal.SIGKILL)
    proc.communicate(timeout=30)
    assert [p for p in out.iterdir() if p.name.startswith(".")]  # what the killed run left
    generate_city(load_scene(scene_path), jobs=1)
    assert sorted(p.name for p in out.iterdir()) == ["city.usdc", "city_tiles"]
    listed = set(_layers(out / "city.usdc")) - {"city.usdc"} | {LIBRARY}
    assert {f"city_tiles/{p.name}" for p in (out / "city_tiles").iterdir()} == listed
