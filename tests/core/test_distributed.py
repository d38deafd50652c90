"""The dask executor: one task per tile, each tile a self-contained layer written by its worker."""
from __future__ import annotations

import hashlib
import json
import re
import socket
import sys
import threading
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from pxr import Sdf, Usd, UsdGeom

from citygen import distributed as distributed_executor
from citygen import tiles as tile_tasks
from citygen.cli import main
from citygen.errors import CitygenError
from citygen.geometry import building
from citygen.pipeline import generate_city
from citygen.scene import load_scene
from citygen.usd.validate import validate_stage
from tests.core.fakes import GridKind
from tests.mini_scene import rect
from tests.usd_util import buildings

REPO = Path(__file__).resolve().parents[2]
TILED = '[output]\npath = "{path}"\ntile_size = 20\ntile_layers = true\n'

distributed = pytest.importorskip("dask.distributed")


@pytest.fixture(scope="module")
def cluster():
    """Two in-process workers of one thread each (cheap: no process spawn)."""
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address="127.0.0.1:0") as c:
        yield c


@pytest.fixture(scope="module")
def one_worker():
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address="127.0.0.1:0") as c:
        yield c


def _scene(small_scene: Path, path: str):
    small_scene.write_text(small_scene.read_text().split("[output]")[0] + TILED.format(path=path))
    return load_scene(small_scene)


def _composed(path: Path) -> dict[str, object]:
    """What a user sees: every prim path (instance proxies included) with its type, points or instance count."""
    stage = Usd.Stage.Open(str(path))
    seen = {}
    for prim in stage.Traverse(Usd.TraverseInstanceProxies(Usd.PrimAllPrimsPredicate)):  # /Prototypes too
        value: object = prim.GetTypeName()
        if prim.IsA(UsdGeom.Mesh):
            points = np.asarray(UsdGeom.Mesh(prim).GetPointsAttr().Get())
            value = (len(points), hashlib.sha256(points.tobytes()).hexdigest())
        elif prim.IsA(UsdGeom.PointInstancer):
            value = len(UsdGeom.PointInstancer(prim).GetProtoIndicesAttr().Get())
        seen[str(prim.GetPath())] = value
    return seen


def _errors(path: Path) -> list:
    return [f for f in validate_stage(path) if f.severity == "error"]


def _payloads(root: Path) -> list[str]:
    """The tile layers a root stage payloads, in order."""
    layer = Sdf.Layer.FindOrOpen(str(root))
    return [str(a.assetPath) for p in layer.GetPrimAtPath("/World").nameChildren for a in p.payloadList.prependedItems]


def test_dask_stage_composes_like_the_local_tile_layers(small_scene, test_registry, cluster):
    local = generate_city(_scene(small_scene, "local/small.usda"), registry=test_registry)
    dask = generate_city(_scene(small_scene, "dask/small.usda"), registry=test_registry, executor="dask",
                         scheduler=cluster.scheduler_address)
    root = dask.stats.path
    tiles = sorted(p.name for p in (root.parent / "small_tiles").glob("Tile_*"))
    assert [re.sub(r"\.[0-9a-f]{12}\.", ".", t) for t in tiles] == ["Tile_0_0.usda", "Tile_0_2.usda", "Tile_1_0.usda"]
    assert _payloads(root) == [f"./small_tiles/{t}" for t in tiles]
    for t in [*tiles, "elements.usda"]:  # one tile-layer contract: the same bytes (so the same content name)
        # whichever executor wrote it
        assert (root.parent / "small_tiles" / t).read_bytes() == \
            (local.stats.path.parent / "small_tiles" / t).read_bytes(), t
    composed = _composed(root)
    assert composed == _composed(local.stats.path)
    assert len(buildings(Usd.Stage.Open(str(root)))) == 3
    assert (dask.written, [s.id for s in dask.skipped], dask.warnings) == \
        (local.written, [s.id for s in local.skipped], local.warnings)
    assert (dask.stats.buildings, dask.stats.instances, dask.stats.polygons, dask.stats.meshes,
            dask.stats.prototypes) == (local.stats.buildings, local.stats.instances, local.stats.polygons,
                                       local.stats.meshes, local.stats.prototypes)
    assert _errors(root) == []
    assert not [p for p in root.parent.iterdir() if p.name.startswith(".")]  # staging published


def test_each_dask_tile_layer_opens_alone(small_scene, test_registry, cluster):
    report = generate_city(_scene(small_scene, "dask/small.usda"), registry=test_registry, executor="dask",
                           scheduler=cluster.scheduler_address)
    for tile in sorted((report.stats.path.parent / "small_tiles").glob("Tile_*")):
        assert _errors(tile) == [], tile.name
        stage = Usd.Stage.Open(str(tile))
        assert stage.GetDefaultPrim().GetPath() == Sdf.Path("/World")
        (group,) = [p for p in stage.GetPrimAtPath("/World").GetChildren() if p.GetName().startswith("Tile_")]
        assert group.GetName() == tile.name.split(".")[0]  # (Tile_i_j.<digest>.usda)
        assert stage.GetCompositionErrors() == []  # every referenced prototype is in the layer
        targets = [t for prim in stage.Traverse(Usd.TraverseInstanceProxies(Usd.PrimDefaultPredicate))
                   for rel in prim.GetRelationships() for t in rel.GetTargets()]
        assert targets and all(stage.GetPrimAtPath(t.GetPrimPath()) for t in targets)  # materials, prototypes


def test_dask_output_is_byte_identical_whatever_the_workers_and_completion_order(small_scene, test_registry,
                                                                                 cluster, one_worker, monkeypatch):
    scene = _scene(small_scene, "out/small.usdc")
    out = Path(scene.output.path)

    def files() -> dict[str, bytes]:
        return {p.name: p.read_bytes() for p in [out, *sorted((out.parent / "small_tiles").iterdir())]}

    generate_city(scene, registry=test_registry, executor="dask", scheduler=one_worker.scheduler_address)
    first = files()
    assert len(first) == 5  # the root, 3 tiles and their element library
    generate_city(scene, registry=test_registry, executor="dask", scheduler=cluster.scheduler_address)
    assert files() == first

    def reversed_completion(futures):
        distributed.wait(list(futures))
        return reversed(list(futures))

    monkeypatch.setattr(distributed, "as_completed", reversed_completion)
    generate_city(scene, registry=test_registry, executor="dask", scheduler=cluster.scheduler_address)
    assert files() == first


def test_a_bad_building_on_a_dask_worker_skips_itself(small_scene, test_registry, cluster, monkeypatch):
    original = GridKind.generate

    def broken_on_way_2(self, ruleset, request):
        if request.context.building_id == "way/2":
            raise ZeroDivisionError("a plugin bug")
        return original(self, ruleset, request)

    monkeypatch.setattr(GridKind, "generate", broken_on_way_2)  # in-process workers see the patch
    report = generate_city(_scene(small_scene, "dask/small.usda"), registry=test_registry, executor="dask",
                           scheduler=cluster.scheduler_address)
    assert report.written == 2
    assert [(s.id, s.reason) for s in report.skipped] == [
        ("way/bad", "invalid polygon or height"), ("way/2", "internal error ZeroDivisionError: a plugin bug")]
    root = report.stats.path
    # way/2 was alone in Tile_1_0: no layer for it
    assert [re.sub(r"\.[0-9a-f]{12}\.", ".", p) for p in _payloads(root)] == \
        ["./small_tiles/Tile_0_0.usda", "./small_tiles/Tile_0_2.usda"]
    assert sorted(str(p.GetPath()) for p in buildings(Usd.Stage.Open(str(root)))) == \
        ["/World/Tile_0_0/way_1", "/World/Tile_0_2/way_3"]
    assert _errors(root) == []


def test_missing_dask_names_the_extra_to_install(small_scene, test_registry, monkeypatch):
    scene = _scene(small_scene, "out/small.usda")
    monkeypatch.setitem(sys.modules, "dask.distributed", None)  # `import dask.distributed` raises ImportError
    with pytest.raises(CitygenError, match=r"pip install 'citygen\[distributed\]'"):
        generate_city(scene, registry=test_registry, executor="dask")
    out = Path(scene.output.path)
    assert not out.exists() and not [p for p in out.parent.iterdir() if p.name.startswith(".")]


def test_an_unreachable_scheduler_is_an_error_that_keeps_the_old_stage(small_scene, test_registry, monkeypatch):
    scene = _scene(small_scene, "out/small.usda")
    out = Path(scene.output.path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("#usda 1.0\n")
    with socket.socket() as s:  # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    monkeypatch.setattr(distributed_executor, "CONNECT_TIMEOUT", "1s")
    with pytest.raises(CitygenError, match=f"cannot reach the dask scheduler at tcp://127.0.0.1:{port}") as err:
        generate_city(scene, registry=test_registry, executor="dask", scheduler=f"tcp://127.0.0.1:{port}")
    assert "dask scheduler" in err.value.hint
    with pytest.raises(CitygenError, match="'tcp://host:port' is not a dask scheduler address") as err:
        generate_city(scene, registry=test_registry, executor="dask", scheduler="tcp://host:port")
    assert "tcp://HOST:PORT" in err.value.hint
    assert out.read_text() == "#usda 1.0\n"
    assert sorted(p.name for p in out.parent.iterdir()) == ["small.usda"]


def test_an_unknown_executor_lists_the_choices(small_scene, test_registry):
    with pytest.raises(CitygenError, match="executor must be one of local, dask, got 'spark'"):
        generate_city(load_scene(small_scene), registry=test_registry, executor="spark")


def test_module_cache_is_per_thread():
    """Regression: tile tasks in threads of one worker process must not share (or clear) each other's modules."""
    building.clear_module_cache()
    building._module_cache()["mine"] = "prototype"
    other: list[dict] = []
    thread = threading.Thread(target=lambda: (building.clear_module_cache(), other.append(building._module_cache())))
    thread.start()
    thread.join()
    assert other == [{}]
    assert building._module_cache() == {"mine": "prototype"}
    building.clear_module_cache()


def test_cli_generates_on_a_local_dask_cluster(tmp_path, capsys):
    features = [{"type": "Feature", "properties": {"id": i, "osm_type": "way", "building:levels": "3"},
                 "geometry": {"type": "Polygon", "coordinates": [rect(x, 0, 12, 10)]}} for i, x in ((1, 0), (2, 300))]
    (tmp_path / "mini.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": features}))
    ruleset = (REPO / "rulesets" / "apartment.grammar").as_posix()
    (tmp_path / "mini.toml").write_text(f'[scene]\nseed = 1\n[footprints]\npath = "mini.geojson"\n'
                                        f'[[assign]]\nruleset = "{ruleset}"\n[output]\npath = "mini.usdc"\n')
    assert main(["generate", str(tmp_path / "mini.toml"), "--executor", "dask", "--jobs", "1", "-q"]) == 0
    assert "written 2 buildings" in capsys.readouterr().out
    assert len(list((tmp_path / "mini_tiles").glob("Tile_*"))) == 2
    assert main(["validate", str(tmp_path / "mini.usdc")]) == 0
    assert main(["generate", str(tmp_path / "mini.toml"), "--scheduler", "tcp://127.0.0.1:1"]) == 2
    assert "--scheduler needs --executor dask" in capsys.readouterr().err


def test_dask_usdz_packages_the_tile_layers(small_scene, test_registry, cluster):
    report = generate_city(_scene(small_scene, "out/small.usdz"), registry=test_registry, executor="dask",
                           scheduler=cluster.scheduler_address)
    assert not (report.stats.path.parent / "small_tiles").exists()
    assert len(buildings(Usd.Stage.Open(str(report.stats.path)))) == 3
    assert _errors(report.stats.path) == []


def test_a_failed_tile_task_stops_the_run_and_keeps_the_old_stage(small_scene, test_registry, cluster, monkeypatch):
    scene = _scene(small_scene, "out/small.usda")
    generate_city(scene, registry=test_registry, executor="dask", scheduler=cluster.scheduler_address)
    out = Path(scene.output.path)
    before = {p.name: p.read_bytes() for p in [out, *(out.parent / "small_tiles").iterdir()]}

    add = tile_tasks.StageWriter.add

    def disk_gone(self, record):
        if record.tile == (1, 0):
            raise OSError("disk gone")
        add(self, record)

    monkeypatch.setattr(tile_tasks.StageWriter, "add", disk_gone)
    with pytest.raises(CitygenError, match=r"Tile_1_0 failed on its dask worker: OSError: disk gone"):
        generate_city(scene, registry=test_registry, executor="dask", scheduler=cluster.scheduler_address)
    assert {p.name: p.read_bytes() for p in [out, *(out.parent / "small_tiles").iterdir()]} == before
    assert not [p for p in out.parent.iterdir() if p.name.startswith(".")]


def test_output_options_compose_the_same_on_dask(small_scene, test_registry, cluster):
    """ground, lod and uvs reach the dask workers' tile layers and the root layer as they reach the local ones."""
    def scene(path):
        s = _scene(small_scene, path)
        return replace(s, output=replace(s.output, ground=True, lod="variants", uvs=True))
    local = generate_city(scene("local/small.usda"), registry=test_registry)
    dask = generate_city(scene("dask/small.usda"), registry=test_registry, executor="dask",
                         scheduler=cluster.scheduler_address)
    composed = _composed(dask.stats.path)
    assert composed == _composed(local.stats.path)
    assert "/World/Ground" in composed
    stage = Usd.Stage.Open(str(dask.stats.path))
    assert all(p.GetVariantSets().HasVariantSet("LOD") for p in buildings(stage))
    assert all(p.HasAttribute("primvars:st") for p in stage.Traverse() if p.IsA(UsdGeom.Mesh))
    assert _errors(dask.stats.path) == []
