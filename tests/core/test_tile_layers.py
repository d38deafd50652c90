"""Tile layers: each tile streamed into a stage of its own, payloaded by the root (`[output] tile_layers = true`)."""
from __future__ import annotations

import json
import re
import time
from pathlib import Path

import numpy as np
import pytest
from pxr import Pcp, Sdf, Usd, UsdGeom

from citygen.errors import ExportError
from citygen.geometry.building import BuildingGeometry, Instances
from citygen.pipeline import generate_city
from citygen.scene import load_scene
from citygen.usd.validate import validate_stage
from citygen.usd import writer as writer_module
from citygen.temporaries import current_umask
from citygen.usd.writer import BuildingRecord, StageWriter
from tests.usd_util import assert_resolves, buildings


def _scene(small_scene: Path, output: str) -> Path:
    small_scene.write_text(small_scene.read_text().split("[output]")[0] + output)
    return small_scene


def _composed(path: Path) -> dict[str, tuple[str, ...]]:
    """Building prim path -> names of its children, from the composed stage."""
    stage = Usd.Stage.Open(str(path))
    return {str(p.GetPath()): tuple(c.GetName() for c in p.GetChildren()) for p in buildings(stage)}


def test_tile_layers_compose_to_the_single_file_stage(small_scene, test_registry, tmp_path):
    scene = _scene(small_scene, '[output]\npath = "out/small.usda"\ntile_size = 20\n')
    single = generate_city(load_scene(scene), registry=test_registry)
    tiled_scene = _scene(small_scene, '[output]\npath = "tiled/small.usda"\ntile_size = 20\ntile_layers = true\n')
    tiled = generate_city(load_scene(tiled_scene), registry=test_registry)
    root = tiled.stats.path
    tiles = sorted(p.name for p in (root.parent / "small_tiles").glob("Tile_*"))
    assert [re.sub(r"\.[0-9a-f]{12}\.", ".", t) for t in tiles] == ["Tile_0_0.usda", "Tile_0_2.usda", "Tile_1_0.usda"]
    assert (root.parent / "small_tiles" / "elements.usda").is_file()
    layer = Sdf.Layer.FindOrOpen(str(root))
    world = layer.GetPrimAtPath("/World")
    assert [(p.name, [(str(a.assetPath), str(a.primPath)) for a in p.payloadList.prependedItems])
            for p in world.nameChildren] == [(t.split(".")[0], [(f"./small_tiles/{t}", f"/World/{t.split('.')[0]}")])
                                             for t in tiles]
    assert _composed(root) == _composed(single.stats.path)
    assert (tiled.stats.buildings, tiled.stats.instances, tiled.stats.polygons) == \
        (single.stats.buildings, single.stats.instances, single.stats.polygons)
    assert [f for f in validate_stage(root) if f.severity == "error"] == []
    # a tile layer holds only its own buildings
    layer = Sdf.Layer.FindOrOpen(str(next((root.parent / "small_tiles").glob("Tile_1_0.*.usda"))))
    assert [p.name for p in layer.GetPrimAtPath("/World/Tile_1_0").nameChildren] == ["way_2"]


@pytest.mark.parametrize("executor", ["local", "dask"])
def test_every_tile_layer_opens_alone_whichever_executor_wrote_it(small_scene, test_registry, executor):
    """One contract (was: local tile layers had no defaultPrim and referenced prototypes of other tiles)."""
    scene = load_scene(_scene(small_scene, '[output]\npath = "out/small.usda"\ntile_size = 20\ntile_layers = true\n'))
    generate_city(scene, registry=test_registry, executor=executor, jobs=1)
    tiles = sorted((Path(scene.output.path).parent / "small_tiles").glob("Tile_*"))
    assert len(tiles) == 3
    for tile in tiles:
        stage = Usd.Stage.Open(str(tile))
        assert stage.GetDefaultPrim().GetPath() == "/World" and stage.GetMetadata("metersPerUnit") == 1.0
        assert [f for f in validate_stage(stage) if f.severity == "error"] == [], tile.name
        assert_resolves(stage)


def _library(path: Path) -> set[str]:
    """The element prototypes an element library holds (read afresh, not from USD's layer registry)."""
    layer = Sdf.Layer.OpenAsAnonymous(str(path))  # (held: its specs die with it)
    return {p.name for p in layer.GetPrimAtPath("/Prototypes").nameChildren}


def _elements_used(tiles: Path) -> set[str]:
    """The element prototypes the tile layers in ``tiles`` reference from the library (their instances do; the
    layers' own ``/Prototypes`` are modules)."""
    used = set()
    for tile in tiles.glob("Tile_*"):
        layer = Sdf.Layer.OpenAsAnonymous(str(tile))
        for spec in _specs(layer.pseudoRoot):
            refs = spec.referenceList.prependedItems
            if refs and refs[0].assetPath:
                assert spec.instanceable and refs[0].assetPath == "./elements.usda" and not spec.nameChildren
                used.add(str(refs[0].primPath.name))
        protos = layer.GetPrimAtPath("/Prototypes")
        assert protos is None or all(p.name.startswith("module_") for p in protos.nameChildren)
    return used


def _specs(spec: Sdf.PrimSpec):
    """``spec`` and every prim spec under it, inside variants too."""
    yield spec
    for child in spec.nameChildren:
        yield from _specs(child)
    for variant_set in spec.variantSets:
        for variant in variant_set.variants:
            yield from _specs(variant.primSpec)


def test_tiles_reference_each_element_from_one_library(small_scene, test_registry):
    scene = load_scene(_scene(small_scene, '[output]\npath = "out/small.usda"\ntile_size = 20\ntile_layers = true\n'))
    generate_city(scene, registry=test_registry)
    tiles = Path(scene.output.path).parent / "small_tiles"
    assert _elements_used(tiles) == _library(tiles / "elements.usda") != set()
    library = tiles / "elements.usda"
    assert [f for f in validate_stage(library) if f.severity == "error"] == []
    stage = Usd.Stage.CreateInMemory()  # each element referenced alone brings its looks and materials along
    for name in sorted(_library(library)):
        stage.DefinePrim(f"/Check/{name}").GetReferences().AddReference(str(library), f"/Prototypes/{name}")
    assert_resolves(stage)


def test_the_instances_of_an_element_share_one_prototype_across_tiles(small_scene, test_registry):
    """Was: each tile's instances referenced a ``/Prototypes/<element>`` prim of their tile (which referenced the
    library), so USD made a prototype of each element per tile, and Blender's default import a material of each
    of its materials per tile (the demo: 9,648 materials, 2.35 GB; docs/performance.md)."""
    scene = load_scene(_scene(small_scene, '[output]\npath = "out/small.usdc"\ntile_size = 20\ntile_layers = true\n'))
    generate_city(scene, registry=test_registry)
    stage = Usd.Stage.Open(str(scene.output.path))
    per_element: dict[str, set[str]] = {}
    tiles_of: dict[str, set[str]] = {}
    for prototype in stage.GetPrototypes():
        for instance in prototype.GetInstances():
            refs = [a for a in Usd.PrimCompositionQuery(instance).GetCompositionArcs()
                    if a.GetArcType() == Pcp.ArcTypeReference]
            name = str(refs[0].GetTargetPrimPath().name)
            per_element.setdefault(name, set()).add(str(prototype.GetPath()))
            tiles_of.setdefault(name, set()).add(str(instance.GetPath()).split("/")[2])
    assert max(len(t) for t in tiles_of.values()) > 1  # an element placed in several tiles
    assert all(len(p) == 1 for p in per_element.values()), per_element


def test_a_building_referenced_from_its_tile_layer_brings_its_elements_along(small_scene, test_registry):
    scene = load_scene(_scene(small_scene, '[output]\npath = "out/small.usdc"\ntile_size = 20\ntile_layers = true\n'))
    generate_city(scene, registry=test_registry)
    tile = next((Path(scene.output.path).parent / "small_tiles").glob("Tile_1_0.*.usdc"))
    stage = Usd.Stage.CreateInMemory()
    house = stage.DefinePrim("/Shot/House", "Xform")
    house.GetReferences().AddReference(str(tile), "/World/Tile_1_0/way_2")
    assert_resolves(stage, "/Shot/House")
    instancers = [p for p in Usd.PrimRange(house) if p.IsA(UsdGeom.PointInstancer)]
    assert instancers and stage.GetCompositionErrors() == []


def test_the_element_library_serves_the_old_root_until_the_new_root_replaces_it(small_scene, test_registry,
                                                                                monkeypatch):
    """A rerun whose tiles use other elements: while the root is replaced, the library holds both runs' elements
    (the old root's tiles still compose whole); then only the new run's, byte for byte a fresh run's."""
    scene = load_scene(_scene(small_scene, '[output]\npath = "out/small.usda"\ntile_size = 20\ntile_layers = true\n'))
    generate_city(scene, registry=test_registry)
    tiles = Path(scene.output.path).parent / "small_tiles"
    old = _library(tiles / "elements.usda")
    (small_scene.parent / "bays.testgrid").write_text(json.dumps({"bay": 3.0, "window": 1.1}))
    during, modes = [], []
    finish = writer_module.write_layer

    def watched(layer, path):
        if path == Path(scene.output.path):  # (not a tile's)
            during.append(_library(tiles / "elements.usda"))
            modes.append((tiles / "elements.usda").stat().st_mode & 0o777)
        return finish(layer, path)

    monkeypatch.setattr(writer_module, "write_layer", watched)
    generate_city(load_scene(small_scene), registry=test_registry)
    new = _library(tiles / "elements.usda")
    assert new != old and during == [old | new]
    assert modes == [0o666 & ~current_umask()]  # (was: the union was published 0600, mkstemp's mode)
    assert _elements_used(tiles) == new
    fresh = load_scene(_scene(small_scene, '[output]\npath = "fresh/small.usda"\ntile_size = 20\ntile_layers = true\n'))
    generate_city(fresh, registry=test_registry)
    assert (tiles / "elements.usda").read_bytes() == (Path(fresh.output.path).parent / "small_tiles" /
                                                     "elements.usda").read_bytes()
    assert not [p for p in tiles.iterdir() if p.name.startswith(".")]


def test_load_none_opens_the_city_with_bounds_only(small_scene, test_registry):
    scene = load_scene(_scene(small_scene, '[output]\npath = "out/small.usdc"\ntile_size = 20\ntile_layers = true\n'))
    report = generate_city(scene, registry=test_registry)
    loaded = Usd.Stage.Open(str(report.stats.path))
    unloaded = Usd.Stage.Open(str(report.stats.path), Usd.Stage.LoadNone)
    assert buildings(unloaded) == [] and len(buildings(loaded)) == 3
    cache = UsdGeom.BBoxCache(Usd.TimeCode.Default(), [UsdGeom.Tokens.default_], useExtentsHint=True)
    full = UsdGeom.BBoxCache(Usd.TimeCode.Default(), [UsdGeom.Tokens.default_])
    hinted = cache.ComputeWorldBound(unloaded.GetPseudoRoot()).ComputeAlignedRange()
    computed = full.ComputeWorldBound(loaded.GetPseudoRoot()).ComputeAlignedRange()
    assert np.allclose(hinted.GetMin(), computed.GetMin(), atol=1e-3)
    assert np.allclose(hinted.GetMax(), computed.GetMax(), atol=1e-3)
    assert np.allclose(np.reshape(report.stats.extent, (2, 3)), [computed.GetMin(), computed.GetMax()], atol=1e-3)


def test_tile_layers_are_byte_identical_across_runs_and_job_counts(small_scene, test_registry):
    scene = load_scene(_scene(small_scene, '[output]\npath = "out/small.usdc"\ntile_size = 20\ntile_layers = true\n'))
    out = Path(scene.output.path)

    def files() -> dict[str, bytes]:
        return {p.name: p.read_bytes() for p in [out, *sorted((out.parent / "small_tiles").iterdir())]}

    generate_city(scene, registry=test_registry, jobs=1)
    first = files()
    generate_city(scene, registry=test_registry, jobs=2)
    assert files() == first


def test_rewriting_replaces_the_old_tiles(small_scene, test_registry):
    scene = load_scene(_scene(small_scene, '[output]\npath = "out/small.usda"\ntile_size = 20\ntile_layers = true\n'))
    generate_city(scene, registry=test_registry)
    tiles = Path(scene.output.path).parent / "small_tiles"
    (tiles / "Tile_9_9.usda").write_text("#usda 1.0\n")  # left over from an older, bigger city
    generate_city(scene, registry=test_registry)
    assert "Tile_9_9.usda" not in {p.name for p in tiles.iterdir()}
    assert not [p for p in tiles.parent.iterdir() if p.name.startswith(".")]  # no staging folders left


def test_usdz_packages_the_tile_layers(small_scene, test_registry):
    scene = load_scene(_scene(small_scene, '[output]\npath = "out/small.usdz"\ntile_size = 20\ntile_layers = true\n'))
    report = generate_city(scene, registry=test_registry)
    assert not (report.stats.path.parent / "small_tiles").exists()
    assert len(buildings(Usd.Stage.Open(str(report.stats.path)))) == 3
    assert [f for f in validate_stage(report.stats.path) if f.severity == "error"] == []


def test_a_failed_run_leaves_the_old_stage_and_no_staging(small_scene, test_registry, monkeypatch):
    scene = load_scene(_scene(small_scene, '[output]\npath = "out/small.usda"\ntile_size = 20\ntile_layers = true\n'))
    generate_city(scene, registry=test_registry)
    out = Path(scene.output.path)
    before = {p.name: p.read_bytes() for p in (out.parent / "small_tiles").iterdir()}

    def broken(self):
        raise ExportError("disk full", where=str(out))

    monkeypatch.setattr(StageWriter, "close", broken)
    with pytest.raises(ExportError):
        generate_city(scene, registry=test_registry)
    assert {p.name: p.read_bytes() for p in (out.parent / "small_tiles").iterdir()} == before
    assert not [p for p in out.parent.iterdir() if p.name.startswith(".")]


def _record(name: str, tile: tuple[int, int]) -> BuildingRecord:
    empty = Instances((), np.zeros(0, np.int32), np.zeros((0, 3)), np.zeros((0, 4)), np.zeros((0, 3), np.float32))
    return BuildingRecord(name, tile, BuildingGeometry({}, empty, {}, None), {})


def test_a_tile_cannot_be_reopened(tmp_path):
    writer = StageWriter(tmp_path / "x.usda", tile_layers=True)
    writer.add(_record("a", (0, 0)))
    writer.add(_record("b", (1, 0)))
    with pytest.raises(ExportError, match="tile \\(0, 0\\) was already written"):
        writer.add(_record("c", (0, 0)))


def test_usdz_with_tile_layers_is_byte_reproducible(small_scene, test_registry):
    """Was: the zip recorded each packed file's modification time, so two runs differed."""
    scene = load_scene(_scene(small_scene, '[output]\npath = "out/small.usdz"\ntile_size = 20\ntile_layers = true\n'))
    first = generate_city(scene, registry=test_registry).stats.path.read_bytes()
    time.sleep(2.1)  # (the zip records file times in 2 s steps)
    assert generate_city(scene, registry=test_registry).stats.path.read_bytes() == first


def _bay_building(name: str, tile: tuple[int, int], wall_x: float) -> BuildingRecord:
    """A building of one module instance (key ``BAY``; its wall quad ends at ``wall_x``) holding one window."""
    from citygen.geometry.building import MeshData, ModuleProto
    from citygen.geometry.modules import ModuleKey
    from citygen.geometry.prototypes import ProtoKey

    window, bay = ProtoKey("window", "glass", 11, 15, -25), ModuleKey(7, 300, 300, "brick")
    wall = MeshData(np.array([[0, 0, 0], [wall_x, 0, 0], [wall_x, 3, 0], [0, 3, 0]], np.float32),
                    np.array([4], np.int32), np.arange(4, dtype=np.int32))
    one = (np.zeros(1, np.int32), np.array([[1.0, 1.0, 0.0]]), np.array([[0.0, 0.0, 0.0, 1.0]]),
           np.ones((1, 3), np.float32))
    geometry = BuildingGeometry({}, Instances((bay,), *one), {bay: ModuleProto({("wall", "brick"): wall},
                                                                               Instances((window,), *one))}, None)
    return BuildingRecord(name, tile, geometry, {"height": 3.0})


def test_a_tile_layers_bytes_do_not_depend_on_the_tiles_its_process_wrote_before(tmp_path):
    """Prototypes are prepared once per process for elements only: a module's key leaves sub-millimetre details of
    its meshes open, so a process that wrote a tile with another version of the same module before (a worker
    writes many tiles) must still write the module of this tile's own first building."""
    def tile(path: Path, wall_x: float) -> bytes:
        with StageWriter(path) as writer:
            writer.add(_bay_building("b", (0, 0), wall_x))
            writer.close()
        return path.read_bytes()

    def wall_end(path: Path) -> float:
        layer = Sdf.Layer.OpenAsAnonymous(str(path))
        return max(p[0] for p in layer.GetAttributeAtPath(
            "/Prototypes/module_000000000007_300x300_brick/wall_brick.points").default)

    first = tile(tmp_path / "first.usdc", 3.0)
    tile(tmp_path / "other.usdc", 3.0004)
    assert wall_end(tmp_path / "other.usdc") == pytest.approx(3.0004)
    assert tile(tmp_path / "again.usdc", 3.0) == first


def test_layers_authored_in_crate_data_write_the_bytes_of_layers_authored_in_sdf_data(small_scene, test_registry,
                                                                                       monkeypatch):
    """A ``.usdc`` layer is authored in crate data (its export then copies crate data, ~2x cheaper than SdfData):
    fields keep the order they were authored in, so every file (root, tiles, element library) has the bytes the
    same city authored in SdfData (``.usda`` anonymous layers, as before) exports to."""
    def files(folder: Path) -> dict[str, bytes]:
        return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}

    scene = _scene(small_scene, '[output]\npath = "crate/small.usdc"\ntile_size = 20\ntile_layers = true\n')
    generate_city(load_scene(scene), registry=test_registry, jobs=1)
    anonymous, asked = Sdf.Layer.CreateAnonymous, []

    def in_sdf_data(tag: str = "") -> Sdf.Layer:
        asked.append(tag)
        return anonymous(".usda" if tag == ".usdc" else tag)

    monkeypatch.setattr(Sdf.Layer, "CreateAnonymous", in_sdf_data)
    scene = _scene(small_scene, '[output]\npath = "data/small.usdc"\ntile_size = 20\ntile_layers = true\n')
    generate_city(load_scene(scene), registry=test_registry, jobs=1)
    crate, data = files(small_scene.parent / "crate"), files(small_scene.parent / "data")
    assert len(crate) == 5 and sum(name.startswith("small_tiles/Tile_") for name in crate) == 3
    assert asked.count(".usdc") == 5  # (the root, three tiles and the library)
    assert crate == data


def test_the_root_prepares_each_element_kind_of_the_library_as_the_tile_results_come_in(tmp_path):
    """The element library's prototypes are made while the workers still build (the library's writing at the end
    of the run only authors them): each new kind once, with its arrays, the modules only counted; the library holds
    them all."""
    from citygen.geometry.modules import ModuleKey
    from citygen.geometry.prototypes import ProtoKey

    # (kinds no other test prepares: the prepared elements are the process's)
    window, door = ProtoKey("window", "glass", 123, 157, 5), ProtoKey("door", "wood", 101, 213, 5)
    with StageWriter(tmp_path / "city.usdc", tile_layers=True) as writer:
        assert door not in writer.elements
        writer.take_prototypes([window, ModuleKey(7, 300, 300, "brick")])
        prepared = writer.elements[window]
        assert prepared.arrays is not None  # (its normals and USD arrays too: the library's end only authors it)
        arrays = prepared.arrays
        writer.take_prototypes([window, door])
        assert writer.elements[window] is prepared and prepared.arrays is arrays and door in writer.elements
        assert writer.tile_prototypes == {window, door} and len(writer.tile_modules) == 1
        writer.close()
    library = Sdf.Layer.OpenAsAnonymous(str(tmp_path / "city_tiles" / "elements.usdc"))
    assert {p.name for p in library.GetPrimAtPath("/Prototypes").nameChildren} == {window.name, door.name}
