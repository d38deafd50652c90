"""Blender's USD importer opens a city stage (optional: needs ``pip install bpy``, marker ``blender``)."""
from __future__ import annotations

import importlib.util
import subprocess
from dataclasses import replace
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
      sum(1 for o in bpy.data.objects if o.type == "POINTCLOUD"),
      "UVMAPPED", sum(1 for o in meshes if "st" in o.data.uv_layers),
      "NORMALS", sum(1 for o in meshes if o.data.has_custom_normals))
"""


@pytest.mark.parametrize("tile_layers, uvs, lod", [(False, False, "none"), (True, False, "none"), (False, True, "none"),
                                                   (True, False, "variants")],
                         ids=["one-layer", "tile-layers", "uvs", "lod"])
def test_blender_imports_the_delft_city(tmp_path, tile_layers, uvs, lod):
    out = tmp_path / "delft.usdc"
    scene = load_scene(REPO / "scenes" / "delft.toml")
    scene = replace(scene, output=replace(scene.output, tile_layers=tile_layers, tile_size=100.0, uvs=uvs,
                                                         lod=lod))
    report = generate_city(scene, out=out)
    assert len(list(tmp_path.glob("delft_tiles/Tile_*.usdc"))) == (5 if tile_layers else 0)
    # bpy bundles its own USD; run it in a separate interpreter so it never meets usd-core in one process
    result = subprocess.run([sys.executable, "-c", IMPORT, str(out)], capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-2000:]
    line = next(l for l in result.stdout.splitlines() if l.startswith("BUILDINGS"))
    fields = line.split()
    assert int(fields[1]) == report.written == 160
    assert int(fields[3]) > 0 and int(fields[5]) > 0
    assert int(fields[7]) == (int(fields[3]) if uvs else 0)  # Blender reads primvars:st as the UV map "st"
    assert int(fields[9]) == int(fields[3])  # and our face normals (without them it shades every crease smooth)


PROPERTIES = """
import sys, bpy
bpy.ops.wm.read_factory_settings(use_empty=True)
assert bpy.ops.wm.usd_import(filepath=sys.argv[1]) == {"FINISHED"}
objects = bpy.data.objects
print("HEIGHTS", sum(1 for o in objects if "citygen:height" in o.keys()),
      "WALLS", sum(1 for o in objects if o.name.startswith("Walls")),
      "FACADES", sum(1 for o in objects if o.name.startswith("Facade")))
"""


def test_blender_keeps_citygen_attributes_as_properties_and_switches_lod(tmp_path):
    """Was: citygen:* were not authored custom, so Blender dropped them all; the LOD variant an importer reads is
    the selected one, so a layer over the city selecting LOD1 imports the mass walls instead of the facades."""
    from pxr import Sdf, Usd

    out = tmp_path / "delft.usdc"
    report = generate_city(load_scene(REPO / "scenes" / "delft.toml"), out=out)
    stage = Usd.Stage.Open(str(out))
    shot = Sdf.Layer.CreateNew(str(tmp_path / "mass.usda"))
    shot.subLayerPaths.append("./delft.usdc")
    for prim in stage.Traverse():
        if prim.GetVariantSets().HasVariantSet("LOD"):
            Sdf.CreatePrimInLayer(shot, prim.GetPath()).variantSelections["LOD"] = "LOD1"
    shot.Save()

    def imported(path: Path) -> list[int]:
        result = subprocess.run([sys.executable, "-c", PROPERTIES, str(path)], capture_output=True, text=True,
                                timeout=600)
        assert result.returncode == 0, result.stderr[-2000:]
        return [int(v) for v in next(l for l in result.stdout.splitlines() if l.startswith("HEIGHTS")).split()[1::2]]

    assert imported(out) == [report.written, 0, report.written]
    assert imported(tmp_path / "mass.usda") == [report.written, report.written, 0]
