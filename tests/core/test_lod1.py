"""Mass-only cities (``citygen generate --masses``, issue 24): the fast path (:mod:`citygen.lod1`,
:mod:`citygen.lod1stage`) builds the mass level of detail a detailed building carries, bit for bit, writes it as
valid, deterministic stages, and does not import the facade machinery."""
from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from pxr import Usd

from citygen.builder import Builder
from citygen.lod1 import mass_batches
from citygen.mass import neighbour_cover
from citygen.pipeline import generate_city, import_footprints
from citygen.registry import default_registry
from citygen.roofplan import plan_mass
from citygen.scene import load_scene
from citygen.usd.normals import face_normals
from citygen.usd.validate import validate_stage

REPO = Path(__file__).resolve().parents[2]
#: Helsinki buildings with flat, hipped (untagged), gabled, dome and multi-part roofs, and courtyards.
SAMPLE = 160


def _masses_scene(path: Path, roof_shape: str | None = None):
    scene = load_scene(path)
    if roof_shape:
        scene = replace(scene, defaults=replace(scene.defaults, roof_shape=roof_shape))
    return replace(scene, output=replace(scene.output, masses=True))


@pytest.mark.parametrize("roof_shape", ["flat", None])
def test_mass_records_equal_the_mass_level_of_detail_of_the_detailed_builder(roof_shape):
    """Walls, roof, their face normals (as the writer batches them), attributes and pivot equal what the builder
    makes of the same building in masses-only mode (its ``LOD1`` walls and its roof), exactly."""
    scene = _masses_scene(REPO / "scenes" / "helsinki.toml", roof_shape)
    roofs = default_registry().roof_builders
    footprints = import_footprints(scene).footprints[:SAMPLE]
    masses = [plan_mass(fp, scene, roofs)[0] for fp in footprints]
    cover = neighbour_cover(masses)
    work = [(fp, m, c, f"b{k}", (0, 0)) for k, (fp, m, c) in enumerate(zip(footprints, masses, cover))]
    builder = Builder(scene, scene.seed)
    shapes = set()
    for item, fast in zip(work, [o for b, _ in mass_batches(work, scene, scene.seed, roofs) for o in b]):
        old = builder.build(*item).record
        new = fast.record
        assert old is not None and new is not None
        geo = old.geometry
        for a, b in ((geo.walls, new.walls), (geo.roof, new.roof)):
            assert (a is None) == (b is None)
            if a is not None:
                for field in ("points", "counts", "indices"):
                    assert np.array_equal(getattr(a, field), getattr(b, field)), (item[0].id, field)
        batch = [*geo.meshes.values(), *([geo.roof] if geo.roof is not None else []), geo.walls]
        normals = face_normals(batch)
        for (va, ia), (vb, ib) in [(normals[-1], new.walls_normals)] + (
                [(normals[len(geo.meshes)], new.roof_normals)] if geo.roof is not None else []):
            assert np.array_equal(va, vb) and np.array_equal(ia, ib), item[0].id
        assert dict(old.attributes) == dict(new.attributes)
        assert old.pivot == new.pivot
        shapes.add(new.attributes["roofShape"])
    assert len(shapes) >= (2 if roof_shape == "flat" else 3)  # (the data's tagged shapes besides the scene's)


def _meshes(stage_path: Path) -> dict[str, tuple]:
    stage = Usd.Stage.Open(str(stage_path))
    return {str(p.GetPath()): tuple(np.asarray(p.GetAttribute(n).Get()).tobytes()
                                    for n in ("points", "faceVertexIndices", "primvars:normals"))
            for p in stage.Traverse() if p.GetTypeName() == "Mesh"}


def test_a_mass_only_city_validates_is_deterministic_and_holds_walls_and_roofs_only(small_scene, test_registry,
                                                                                       tmp_path):
    scene = _masses_scene(small_scene)
    first = generate_city(scene, registry=test_registry, out=tmp_path / "a" / "city.usda")
    again = generate_city(scene, registry=test_registry, out=tmp_path / "b" / "city.usda")
    assert first.written == again.written == 3 and [s.id for s in first.skipped] == ["way/bad"]
    assert (tmp_path / "a" / "city.usda").read_bytes() == (tmp_path / "b" / "city.usda").read_bytes()
    assert [f for f in validate_stage(first.stats.path) if f.severity == "error"] == []
    stage = Usd.Stage.Open(str(first.stats.path))
    buildings = [p for p in stage.Traverse() if p.HasAttribute("citygen:sourceId")]
    assert len(buildings) == 3
    for prim in buildings:
        assert Usd.ModelAPI(prim).GetKind() == "component" and not prim.GetVariantSets().GetNames()
        assert sorted(c.GetName() for c in prim.GetChildren()) == ["Looks", "Roof", "Walls"]
        assert prim.GetAttribute("citygen:ruleset").Get() == "none"
        assert prim.GetAttribute("extentsHint").Get() is not None
        walls = prim.GetChild("Walls")
        assert walls.GetAttribute("semantics:labels:class").Get() == ["wall"]
        assert walls.GetRelationship("material:binding").GetTargets()[0].GetParentPath() == prim.GetPath().AppendChild(
            "Looks")
    assert first.stats.meshes == 6 and first.stats.instances == 0


def test_a_mass_only_city_with_tile_layers_writes_the_same_meshes(small_scene, test_registry, tmp_path):
    scene = _masses_scene(small_scene)
    one = generate_city(scene, registry=test_registry, out=tmp_path / "one.usdc")
    tiled = generate_city(replace(scene, output=replace(scene.output, tile_layers=True, tile_size=20.0)),
                          registry=test_registry, out=tmp_path / "tiled.usdc")
    assert len(list((tmp_path / "tiled_tiles").iterdir())) > 1
    for path in [tiled.stats.path, *(tmp_path / "tiled_tiles").iterdir()]:
        assert [f for f in validate_stage(path) if f.severity == "error"] == [], path
    a, b = _meshes(one.stats.path), _meshes(tiled.stats.path)
    strip = lambda meshes: sorted((k.split("/", 3)[-1], v) for k, v in meshes.items())  # noqa: E731 (tile names differ)
    assert strip(a) == strip(b)


def test_a_mass_only_run_imports_no_facade_machinery(tmp_path):
    """``citygen generate --masses`` builds no facade: the builder, the tile tasks and the ruleset kinds'
    generators stay unimported, and so do the USD schemas an Sdf-authored ``.usdc`` does not need."""
    scene = tmp_path / "city.toml"
    ring = [[24.9400, 60.1700], [24.9404, 60.1700], [24.9404, 60.1701], [24.9400, 60.1701], [24.9400, 60.1700]]
    (tmp_path / "city.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "id": "way/1", "properties": {"height": 15.0},
         "geometry": {"type": "Polygon", "coordinates": [ring]}}]}))
    scene.write_text('[scene]\nname = "one"\n\n[footprints]\npath = "city.geojson"\n\n'
                     f'[[assign]]\nruleset = {str(REPO / "rulesets" / "apartment.grammar")!r}\n')
    code = ("import sys, json\nfrom citygen.launch import main\n"
            f"status = main(['generate', {str(scene)!r}, '--masses', '-q', '-o', {str(tmp_path / 'c.usdc')!r}])\n"
            "print(json.dumps([status, sorted(sys.modules)]))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    status, loaded = json.loads(out.stdout.splitlines()[-1])
    assert status == 0
    facade = {"citygen.builder", "citygen.tiles", "citygen_relayout.search", "citygen_relayout.api",
              "citygen_layers.solver", "citygen_safe.generate", "scipy", "PIL", "pxr.UsdShade", "pxr.UsdGeom"}
    assert not facade & set(loaded)


def test_workers_build_a_mass_only_city_only_when_its_roofs_pay_for_them(small_scene, test_registry, tmp_path,
                                                                          monkeypatch):
    """Flat roofs cost too little for worker processes to pay off (the rule: estimated build CPU against
    ``WORKERS_FROM``); where workers build the city, its stage is the same bytes."""
    import citygen.lod1 as lod1
    scene = _masses_scene(small_scene)
    here = generate_city(scene, registry=test_registry, out=tmp_path / "here.usda", jobs=2)
    assert here.cpu["workers"] == 0.0
    monkeypatch.setattr(lod1, "WORKERS_FROM", 0.0)
    there = generate_city(scene, registry=test_registry, out=tmp_path / "there.usda", jobs=2)
    assert there.cpu["workers"] > 0.0 and there.written == here.written == 3
    assert (tmp_path / "here.usda").read_bytes().replace(b"here", b"") == \
        (tmp_path / "there.usda").read_bytes().replace(b"there", b"")


def test_the_demo_scenes_flat_roofs_are_built_in_process_and_its_hipped_roofs_in_workers():
    from citygen.lod1 import build_cost, in_workers
    from citygen.roofplan import mass_plan
    from citygen.tilework import TileWork
    scene = load_scene(REPO / "scenes" / "helsinki.toml")
    roofs = default_registry().roof_builders
    footprints = import_footprints(scene).footprints
    flat_scene = replace(scene, defaults=replace(scene.defaults, roof_shape="flat"))

    def cost(scene) -> float:  # (the demo's buildings packed in one tile)
        return build_cost([TileWork.pack((0, 0), [(fp, mass_plan(fp, scene, roofs)[0], fp.id) for fp in footprints])])
    assert not in_workers(cost(flat_scene), 2) and in_workers(cost(scene), 2) and not in_workers(cost(scene), 1)


def test_a_forked_helper_writes_half_of_the_tile_layers_and_the_stage_is_the_same_bytes(small_scene, test_registry,
                                                                                          tmp_path, monkeypatch):
    import citygen.lod1tiles as lod1tiles
    scene = _masses_scene(small_scene)
    scene = replace(scene, output=replace(scene.output, tile_layers=True, tile_size=20.0))
    alone = generate_city(scene, registry=test_registry, out=tmp_path / "a" / "city.usdc", jobs=2)
    assert alone.cpu["workers"] == 0.0  # (3 buildings: below HELPER_FROM)
    monkeypatch.setattr(lod1tiles, "HELPER_FROM", 0)
    helped = generate_city(scene, registry=test_registry, out=tmp_path / "b" / "city.usdc", jobs=2)
    assert helped.cpu["workers"] > 0.0
    assert (helped.written, [s.id for s in helped.skipped]) == (alone.written, [s.id for s in alone.skipped])
    files = lambda root: {p.relative_to(root): p.read_bytes() for p in root.rglob("*") if p.is_file()}  # noqa: E731
    assert files(tmp_path / "a") == files(tmp_path / "b")
    assert len(list((tmp_path / "b" / "city_tiles").iterdir())) > 1


def test_tiles_are_dealt_to_balance_the_buildings():
    from citygen.lod1tiles import deal
    tiles = [[0] * n for n in (5, 40, 12, 30, 3)]
    taken = deal(tiles)
    assert taken == {2, 3, 4}  # 40 here; 30 there; 12 there; 5 here; 3 there: 45 against 45
    assert sum(len(tiles[k]) for k in taken) == 45


def test_a_mass_only_city_with_uvs_gives_every_mesh_texture_coordinates(small_scene, test_registry, tmp_path):
    scene = _masses_scene(small_scene)
    report = generate_city(replace(scene, output=replace(scene.output, uvs=True)), registry=test_registry,
                           out=tmp_path / "uv.usda")
    stage = Usd.Stage.Open(str(report.stats.path))
    meshes = [p for p in stage.Traverse() if p.GetTypeName() == "Mesh"]
    assert len(meshes) == 6 and all(len(p.GetAttribute("primvars:st").Get()) for p in meshes)
    assert [f for f in validate_stage(report.stats.path) if f.severity == "error"] == []


def test_a_bug_building_one_mass_only_building_skips_it_and_keeps_its_warnings(small_scene, test_registry,
                                                                               monkeypatch):
    """One bad building never aborts a mass-only city: it is skipped as an internal error, with the warnings met
    before the error, and the rest is written."""
    import citygen.lod1 as lod1
    original = lod1.building_attributes

    def broken(footprint, mass, **kw):
        if footprint.id == "way/2":
            raise ZeroDivisionError("float division by zero")
        return original(footprint, mass, **kw)

    monkeypatch.setattr(lod1, "building_attributes", broken)
    monkeypatch.setattr(lod1, "build_roof", lambda fp, mass, party, roofs, warnings: (
        warnings.append(f"{fp.id}: a roof note") or (None, "flat")))
    report = generate_city(_masses_scene(small_scene), registry=test_registry)
    assert report.written == 2
    skipped = {s.id: s.reason for s in report.skipped}
    assert skipped["way/2"] == "internal error ZeroDivisionError: float division by zero"
    assert "way/2: a roof note" in report.warnings


def test_a_mass_only_city_makes_its_masses_one_tile_at_a_time(small_scene, test_registry, tmp_path, monkeypatch):
    """Regression (memory at scale): a mass-only city made every building's mass and neighbour cover in the main
    process before building any (~2.5 kB a building); each tile's are now made when the tiles before it are
    built (here one building a batch: the tiles' masses and writes interleave)."""
    import citygen.lod1 as lod1
    from citygen.lod1stage import MassWriter
    from citygen.tilework import TileWork
    log = []
    items, add = TileWork.items, MassWriter.add
    monkeypatch.setattr(TileWork, "items", lambda self: log.append(("items", self.tile)) or items(self))
    monkeypatch.setattr(MassWriter, "add", lambda self, record: log.append(("add", record.tile)) or add(self, record))
    monkeypatch.setattr(lod1, "BATCH", 1)
    scene = _masses_scene(small_scene)
    report = generate_city(replace(scene, output=replace(scene.output, tile_size=20.0)), registry=test_registry,
                           out=tmp_path / "city.usda")
    assert report.written == 3
    assert log == [("items", (0, 0)), ("add", (0, 0)), ("items", (0, 2)), ("add", (0, 2)), ("items", (1, 0)),
                   ("add", (1, 0))]
