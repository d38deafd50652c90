"""The delivered stage as a DCC user meets it: writer CPU, file size per LOD mode, payload-unloaded open, world
bound from extentsHint, and (optional, needs bpy) Blender's import time and memory.

    python benchmarks/stage_dcc.py [SCENE] [--blender]

Default scene: scenes/helsinki.toml. Targets on a 2-core machine (idle): writer < 3 s CPU, unloaded open
< 0.5 s, world bound from extentsHint < 0.1 s, Blender import < 30 s and < 2 GB (with Blender's default options, and
with Material Name Collision: Reference Existing).
"""
from __future__ import annotations

import argparse
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import shapely
from pxr import Usd, UsdGeom

from citygen.builder import load_rulesets
from citygen.mass import neighbour_cover
from citygen.pipeline import _ground, _run, import_footprints
from citygen.registry import default_registry
from citygen.roofplan import plan_mass
from citygen.scene import load_scene
from citygen.usd.names import prim_name
from citygen.usd.writer import StageWriter

REPO = Path(__file__).resolve().parents[1]
BLENDER = """
import resource, sys, time, bpy
bpy.ops.wm.read_factory_settings(use_empty=True)
t, c = time.perf_counter(), time.process_time()
options = {} if sys.argv[2] == "default" else {"mtl_name_collision_mode": sys.argv[2]}
assert bpy.ops.wm.usd_import(filepath=sys.argv[1], **options) == {"FINISHED"}
print(f"{time.perf_counter() - t:.1f} s ({time.process_time() - c:.1f} s CPU), "
      f"peak {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6:.2f} GB, {len(bpy.data.objects)} objects, "
      f"{len(bpy.data.collections)} collections, {len(bpy.data.materials)} materials")
"""


def records(scene):
    """The scene's building records, built once (2 jobs), in stage order."""
    registry = default_registry()
    imported = import_footprints(scene, registry)
    footprints, masses = [], []
    for fp in imported.footprints:
        try:
            masses.append(plan_mass(fp, scene, registry.roof_builders)[0])
            footprints.append(fp)
        except Exception:  # reported by the pipeline; not this benchmark's business
            continue
    taken: set[str] = set()
    size = scene.output.tile_size
    work = sorted(zip(footprints, masses, neighbour_cover(masses), [prim_name(f.id, taken) for f in footprints],
                      [(math.floor(m.outline.centroid.x / size), math.floor(m.outline.centroid.y / size))
                       for m in masses]), key=lambda w: (w[4], w[3]))
    out = [o.record for o in _run(work, scene, scene.seed, 2, registry, None, None, load_rulesets(scene, registry))
           if o.record]
    feet = [(shapely.to_wkb(m.outline), m.base) for f, m in zip(footprints, masses) if not f.lift]
    return out, _ground([v for m in masses for v in m.outline.bounds], feet, min(f.base - f.lift for f in footprints))


def write(scene, recs, ground, path: Path, **options) -> tuple[float, int]:
    """CPU seconds of writing the stage, and its size in bytes (root and tile layers)."""
    out = scene.output
    c0 = time.process_time()
    with StageWriter(path, up_axis=out.up_axis, layer_data={}, tile_layers=options.get("tile_layers", False),
                     uvs=out.uvs, lod=options.get("lod", out.lod), materials=scene.materials) as writer:
        writer.ground(ground)
        for record in recs:
            writer.add(record)
        stats = writer.close()
    return time.process_time() - c0, stats.bytes


def opening(path: Path) -> str:
    t0 = time.perf_counter()
    stage = Usd.Stage.Open(str(path), Usd.Stage.LoadNone)
    t1 = time.perf_counter()
    cache = UsdGeom.BBoxCache(Usd.TimeCode.Default(), [UsdGeom.Tokens.default_], useExtentsHint=True)
    bound = cache.ComputeWorldBound(stage.GetPseudoRoot()).ComputeAlignedRange()
    t2 = time.perf_counter()
    full = Usd.Stage.Open(str(path))
    t3 = time.perf_counter()
    hinted = UsdGeom.BBoxCache(Usd.TimeCode.Default(), [UsdGeom.Tokens.default_], useExtentsHint=True)
    hinted.ComputeWorldBound(full.GetPseudoRoot())
    t4 = time.perf_counter()
    return (f"open unloaded {t1 - t0:.3f} s, world bound from extentsHint {t2 - t1:.3f} s "
            f"({bound.GetSize()[0]:.0f} x {bound.GetSize()[1]:.0f} x {bound.GetSize()[2]:.0f} m); "
            f"open loaded {t3 - t2:.2f} s, its hinted world bound {t4 - t3:.3f} s")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("scene", nargs="?", default=str(REPO / "scenes" / "helsinki.toml"))
    parser.add_argument("--blender", action="store_true", help="also time Blender's import (needs bpy)")
    args = parser.parse_args()
    scene = load_scene(args.scene)
    t0 = time.perf_counter()
    recs, ground = records(scene)
    print(f"{Path(args.scene).name}: {len(recs)} buildings built in {time.perf_counter() - t0:.1f} s (2 jobs)")
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp)
        for lod in ("none", "variants", "purpose"):
            cpu, size = write(scene, recs, ground, base / f"{lod}.usdc", lod=lod)
            print(f"  lod = {lod!r}: writer {cpu:.2f} s CPU, {size / 1e6:.1f} MB")
        cpu, size = write(scene, recs, ground, base / "tiled.usdc", tile_layers=True)
        tiles = len(list((base / "tiled_tiles").glob("Tile_*")))
        print(f"  tile layers: writer {cpu:.2f} s CPU, {size / 1e6:.1f} MB in {tiles} tile layers and the element "
              f"library")
        print(f"  one file:    {opening(base / 'variants.usdc')}")
        print(f"  tile layers: {opening(base / 'tiled.usdc')}")
        if args.blender:
            for name in ("variants.usdc", "tiled.usdc"):
                for mode in ("default", "REFERENCE_EXISTING"):  # (default: no options, as File > Import)
                    result = subprocess.run([sys.executable, "-c", BLENDER, str(base / name), mode],
                                            capture_output=True, text=True, timeout=1800)
                    lines = [line for line in result.stdout.splitlines() if " GB, " in line]
                    print(f"  Blender import of {name} ({mode}): " + (lines[-1] if lines else result.stderr[-300:]))


if __name__ == "__main__":
    main()
