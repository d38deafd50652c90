"""Blender's USD importer opens a city stage (optional: needs ``pip install bpy``, marker ``blender``)."""
from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

from citygen.pipeline import generate_city
from citygen.scene import load_scene

REPO = Path(__file__).resolve().parents[2]
pytestmark = [pytest.mark.blender, pytest.mark.slow,
              pytest.mark.skipif(importlib.util.find_spec("bpy") is None, reason="bpy not installed")]

IMPORT = """
import sys, bpy
bpy.ops.wm.read_factory_settings(use_empty=True)
assert bpy.ops.wm.usd_import(filepath=sys.argv[1]) == {"FINISHED"}
tiles = [o for o in bpy.data.objects if o.name.startswith("Tile_")]
buildings = [o for o in bpy.data.objects if o.parent in tiles]
meshes = [o for o in bpy.data.objects if o.type == "MESH"]
print("BUILDINGS", len(buildings), "MESHES", len(meshes), "INSTANCERS",
      sum(1 for o in bpy.data.objects if o.type == "POINTCLOUD"))
"""


def test_blender_imports_the_delft_city(tmp_path):
    out = tmp_path / "delft.usdc"
    report = generate_city(load_scene(REPO / "scenes" / "delft.toml"), out=out)
    # bpy bundles its own USD; run it in a separate interpreter so it never meets usd-core in one process
    result = subprocess.run([sys.executable, "-c", IMPORT, str(out)], capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-2000:]
    line = next(l for l in result.stdout.splitlines() if l.startswith("BUILDINGS"))
    fields = line.split()
    assert int(fields[1]) == report.written == 160
    assert int(fields[3]) > 0 and int(fields[5]) > 0
