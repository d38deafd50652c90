"""The writer's PointInstancers and meshes: each instancer references its own prototypes, and nothing is authored with
``Sdf.CopySpec`` (named fixture of the tiles whose .usdc bytes differed from run to run with the same text: the copy
orders a spec's fields by the addresses of their names' tokens, which depend on the process's history)."""
from __future__ import annotations

import numpy as np
from pxr import Sdf, Usd

from citygen.geometry.building import Instances
from citygen.pipeline import generate_city
from citygen.scene import load_scene
from citygen.usd.author import Author
from citygen.usd.writer import _instancer


def _instances(n: int) -> Instances:
    rows = np.arange(2 * n) % n
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (2 * n, 1))
    return Instances(tuple(f"k{i}" for i in range(n)), rows.astype(np.int32), np.arange(6 * n, dtype=float)
                     .reshape(-1, 3), quat, np.ones((2 * n, 3), np.float32))


def test_tile_bytes_do_not_depend_on_token_addresses(small_scene, test_registry, monkeypatch):
    """A city written in this process (one job) with ``Sdf.CopySpec`` forbidden: no spec of a written layer gets
    its field order from token addresses."""
    def forbidden(*args):
        raise AssertionError("Sdf.CopySpec orders fields by token address: the .usdc bytes would vary by process")

    monkeypatch.setattr(Sdf, "CopySpec", forbidden)
    text = small_scene.read_text().split("[output]")[0]
    small_scene.write_text(text + '[output]\npath = "out/small.usdc"\ntile_size = 20\ntile_layers = true\n')
    report = generate_city(load_scene(small_scene), registry=test_registry, jobs=1)
    assert report.written == 3 and report.stats.instances > 0 and report.stats.meshes > 0


def test_instancers_keep_their_own_references():
    """Two buildings' instancers of the same size: each references its own prototypes, and the composed
    instancer's prototypes are its own instanceable prims."""
    layer = Sdf.Layer.CreateAnonymous(".usda")
    author = Author(layer)
    for name, target in (("A", "/Prototypes/window"), ("B", "/Prototypes/door")):
        parent = Sdf.PrimSpec(layer, name, Sdf.SpecifierDef, "Xform")
        _instancer(author, parent, _instances(1), {"k0": ("", Sdf.Path(target))}, None)
    protos = Sdf.PrimSpec(layer, "Prototypes", Sdf.SpecifierClass)
    for target in ("window", "door"):
        Sdf.PrimSpec(protos, target, Sdf.SpecifierDef, "Xform")
    stage = Usd.Stage.Open(layer)
    for name, target in (("A", "window"), ("B", "door")):
        proto = stage.GetPrimAtPath(f"/{name}/Elements/Prototypes/p0")
        assert proto.IsInstance()
        refs = layer.GetPrimAtPath(f"/{name}/Elements/Prototypes/p0").referenceList.prependedItems
        assert [r.primPath for r in refs] == [Sdf.Path(f"/Prototypes/{target}")]
        rel = stage.GetPrimAtPath(f"/{name}/Elements").GetRelationship("prototypes")
        assert rel.GetTargets() == [Sdf.Path(f"/{name}/Elements/Prototypes/p0")]
