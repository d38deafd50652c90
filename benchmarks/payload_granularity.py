"""Payload per tile or per building: how fast a big city opens unloaded, gives its world bound, and loads.

    python benchmarks/payload_granularity.py [--buildings 100000] [--per-tile 250]

Writes a synthetic city (one box mesh per building, tile layers as citygen writes them) once, and two roots over
the same tile layers: one payload per tile (what citygen writes) and one payload per building (each building prim
payloading its own prim in the tile layer). Prints, per root: Open(LoadNone), the world bound from extentsHint,
and Open (everything loaded).
"""
from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
from pxr import Sdf, Usd, UsdGeom, Vt

T = Sdf.ValueTypeNames
CUBE_COUNTS = Vt.IntArray([4] * 6)
CUBE_INDICES = Vt.IntArray([0, 1, 3, 2, 4, 6, 7, 5, 0, 4, 5, 1, 2, 3, 7, 6, 0, 2, 6, 4, 1, 5, 7, 3])


def _attr(prim, name, vtype, value):
    Sdf.AttributeSpec(prim, name, vtype).default = value


def _bound(lo, hi) -> Vt.Vec3fArray:
    return Vt.Vec3fArray.FromNumpy(np.array([lo, hi], dtype=np.float32))


def write_tiles(folder: Path, buildings: int, per_tile: int) -> list[tuple[str, list[str], tuple]]:
    """Tile layers of boxes; per tile its name, building names and bound."""
    tiles = []
    side = int(np.ceil(np.sqrt(per_tile)))
    for t in range(int(np.ceil(buildings / per_tile))):
        layer = Sdf.Layer.CreateAnonymous(".usdc")
        names = []
        with Sdf.ChangeBlock():
            layer.defaultPrim = "World"
            world = Sdf.PrimSpec(layer, "World", Sdf.SpecifierDef, "Xform")
            tile = Sdf.PrimSpec(world, f"Tile_{t}", Sdf.SpecifierDef, "Xform")
            tile.SetInfo("kind", "group")
            ox, oy = (t % 20) * 250.0, (t // 20) * 250.0
            for k in range(min(per_tile, buildings - t * per_tile)):
                name = f"B_{t}_{k}"
                x, y = ox + (k % side) * 15.0, oy + (k // side) * 15.0
                prim = Sdf.PrimSpec(tile, name, Sdf.SpecifierDef, "Xform")
                prim.SetInfo("kind", "component")
                lo, hi = (x, y, 0.0), (x + 10.0, y + 10.0, 20.0)
                _attr(prim, "extentsHint", T.Float3Array, _bound(lo, hi))
                mesh = Sdf.PrimSpec(prim, "Mass", Sdf.SpecifierDef, "Mesh")
                corners = np.array([[a, b, c] for a in (lo[0], hi[0]) for b in (lo[1], hi[1]) for c in (0.0, 20.0)],
                                   dtype=np.float32)
                _attr(mesh, "points", T.Point3fArray, Vt.Vec3fArray.FromNumpy(corners))
                _attr(mesh, "faceVertexCounts", T.IntArray, CUBE_COUNTS)
                _attr(mesh, "faceVertexIndices", T.IntArray, CUBE_INDICES)
                _attr(mesh, "extent", T.Float3Array, _bound(lo, hi))
                names.append(name)
        layer.Export(str(folder / f"Tile_{t}.usdc"))
        tiles.append((f"Tile_{t}", names, (ox, oy, 0.0, ox + side * 15.0, oy + side * 15.0, 20.0)))
    return tiles


def write_root(path: Path, tiles, per_building: bool) -> None:
    layer = Sdf.Layer.CreateAnonymous(".usdc")
    with Sdf.ChangeBlock():
        layer.defaultPrim = "World"
        world = Sdf.PrimSpec(layer, "World", Sdf.SpecifierDef, "Xform")
        for name, buildings, bound in tiles:
            tile = Sdf.PrimSpec(world, name, Sdf.SpecifierDef, "Xform")
            tile.SetInfo("kind", "group")
            _attr(tile, "extentsHint", T.Float3Array, _bound(bound[:3], bound[3:]))
            asset = f"./tiles/{name}.usdc"
            if not per_building:
                tile.payloadList.prependedItems.append(Sdf.Payload(asset, tile.path))
                continue
            for b in buildings:  # (the bound of each building would be authored here too; the tile's stands in)
                prim = Sdf.PrimSpec(tile, b, Sdf.SpecifierDef, "Xform")
                prim.SetInfo("kind", "component")
                prim.payloadList.prependedItems.append(Sdf.Payload(asset, prim.path))
                _attr(prim, "extentsHint", T.Float3Array, _bound(bound[:3], bound[3:]))
    layer.Export(str(path))


def measure(path: Path) -> str:
    t0 = time.perf_counter()
    stage = Usd.Stage.Open(str(path), Usd.Stage.LoadNone)
    t1 = time.perf_counter()
    UsdGeom.BBoxCache(Usd.TimeCode.Default(), [UsdGeom.Tokens.default_], useExtentsHint=True) \
        .ComputeWorldBound(stage.GetPseudoRoot())
    t2 = time.perf_counter()
    del stage
    t3 = time.perf_counter()
    Usd.Stage.Open(str(path))
    t4 = time.perf_counter()
    return (f"open unloaded {t1 - t0:.3f} s, world bound {t2 - t1:.3f} s, open loaded {t4 - t3:.2f} s, "
            f"root {path.stat().st_size / 1e6:.1f} MB")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--buildings", type=int, default=100_000)
    parser.add_argument("--per-tile", type=int, default=250)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp)
        (base / "tiles").mkdir()
        t0 = time.perf_counter()
        tiles = write_tiles(base / "tiles", args.buildings, args.per_tile)
        print(f"{args.buildings} buildings in {len(tiles)} tile layers, written in {time.perf_counter() - t0:.0f} s")
        for per_building in (False, True):
            root = base / ("per_building.usdc" if per_building else "per_tile.usdc")
            write_root(root, tiles, per_building)
            print(f"  payload per {'building' if per_building else 'tile'}: {measure(root)}")


if __name__ == "__main__":
    main()
