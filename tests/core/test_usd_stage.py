import json
import time
import zipfile

import numpy as np
import pytest
from pxr import Kind, Sdf, Usd, UsdGeom, UsdSemantics, UsdShade

from citygen.cli import main
from citygen.pipeline import generate_city
from citygen.scene import load_scene
from citygen.errors import SceneError
from citygen.usd.validate import validate_stage
from tests.usd_util import assert_resolves, buildings, element_labels, world_points


def generate(scene_path, registry, out, **kw):
    return generate_city(load_scene(scene_path), registry=registry, out=out, **kw)


def copy_city(scene_path, copies):
    """Add ``copies`` shifted copies of the small city's footprints (enough buildings for worker processes)."""
    city = scene_path.parent / "city.local.json"
    features = json.loads(city.read_text())
    city.write_text(json.dumps(features + [
        {**f, "id": f"{f['id']}-copy{k}",
         "coordinates": [[[x + 100 * k, y + 0.37 * k] for x, y in ring] for ring in f["coordinates"]]}
        for k in range(1, copies + 1) for f in features]))


def with_output(scene_path, option):
    """The small scene with one more ``[output]`` option line (e.g. ``uvs = true``)."""
    text = scene_path.read_text()
    scene_path.write_text(text.replace('path = "out/small.usda"', f'path = "out/small.usda"\n{option}'))


def errors(path):
    return [f for f in validate_stage(path) if f.severity == "error"]


@pytest.mark.parametrize("suffix", [".usda", ".usdc", ".usdz"])
def test_every_format_validates(small_scene, test_registry, tmp_path, suffix):
    out = tmp_path / f"city{suffix}"
    generate(small_scene, test_registry, out)
    assert errors(out) == []
    assert not [p for p in out.parent.iterdir() if p.name.startswith(".city")], "temporary file left behind"
    assert out.stat().st_mode & 0o044, "the stage must be readable by others (not mkstemp's 0600)"


def test_same_seed_same_bytes_and_jobs_do_not_matter(small_scene, test_registry, tmp_path):
    a, b, c = tmp_path / "a.usda", tmp_path / "b.usda", tmp_path / "c.usda"
    generate(small_scene, test_registry, a)
    generate(small_scene, test_registry, b)
    generate(small_scene, test_registry, c, seed=99)
    assert a.read_bytes() == b.read_bytes()
    assert a.read_bytes() != c.read_bytes()


def test_worker_processes_and_module_cache_do_not_change_bytes(small_scene, test_registry, tmp_path):
    """Enough buildings for the process pool; module prototypes are cached per process and cleared per city."""
    copy_city(small_scene, 2)
    a, b, c = tmp_path / "a.usdc", tmp_path / "b.usdc", tmp_path / "c.usdc"
    generate(small_scene, test_registry, a, jobs=1)
    generate(small_scene, test_registry, tmp_path / "other.usdc", seed=5, jobs=1)  # fills the cache differently
    generate(small_scene, test_registry, b, jobs=1)
    generate(small_scene, test_registry, c, jobs=2)
    assert a.read_bytes() == b.read_bytes() == c.read_bytes()


def test_stage_structure(small_scene, test_registry, tmp_path):
    out = tmp_path / "city.usda"
    report = generate(small_scene, test_registry, out)
    stage = Usd.Stage.Open(str(out))
    assert stage.GetDefaultPrim().GetPath() == "/World"
    assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0 and UsdGeom.GetStageUpAxis(stage) == "Z"
    world = stage.GetPrimAtPath("/World")
    assert Usd.ModelAPI(world).GetKind() == Kind.Tokens.assembly
    buildings = [p for p in stage.Traverse() if Usd.ModelAPI(p).GetKind() == Kind.Tokens.component]
    assert sorted(p.GetName() for p in buildings) == ["way_1", "way_2", "way_3"]
    b = stage.GetPrimAtPath(buildings[0].GetPath())
    for attr in ("sourceId", "height", "heightSource", "levels", "ruleset", "seed"):
        assert b.GetAttribute(f"citygen:{attr}").HasAuthoredValue()
    assert Usd.ModelAPI(b.GetParent()).GetKind() == Kind.Tokens.group
    instancers = [b.GetChild("Elements") for b in buildings]
    assert sum(len(UsdGeom.PointInstancer(p).GetProtoIndicesAttr().Get()) for p in instancers) == report.stats.instances
    assert {"window", "door"} <= set(element_labels(stage, instancers[0]))
    labels = {tuple(UsdSemantics.LabelsAPI(p, "class").GetLabelsAttr().Get())
              for p in stage.Traverse(Usd.PrimAllPrimsPredicate) if p.HasAPI(UsdSemantics.LabelsAPI)}
    assert {("window",), ("door",), ("wall",), ("roof",)} <= labels
    assert stage.GetRootLayer().customLayerData["citygen"]["seed"] == 3


def test_one_door_per_building(small_scene, test_registry, tmp_path):
    out = tmp_path / "city.usda"
    generate(small_scene, test_registry, out)
    stage = Usd.Stage.Open(str(out))
    buildings = [p for p in stage.Traverse() if Usd.ModelAPI(p).GetKind() == Kind.Tokens.component]
    for b in buildings:
        assert element_labels(stage, b.GetChild("Elements")).count("door") == 1, b.GetPath()


def test_up_axis_y(small_scene, test_registry, tmp_path):
    with_output(small_scene, 'up_axis = "Y"')
    report = generate(small_scene, test_registry, None)
    stage = Usd.Stage.Open(str(report.stats.path))
    assert UsdGeom.GetStageUpAxis(stage) == "Y"
    assert errors(report.stats.path) == []


def test_validate_cli_exit_codes(small_scene, test_registry, tmp_path, capsys):
    out = tmp_path / "city.usda"
    generate(small_scene, test_registry, out)
    assert main(["validate", str(out)]) == 0
    broken = tmp_path / "broken.usda"
    broken.write_text('#usda 1.0\ndef Mesh "M"\n{\n int[] faceVertexCounts = [4]\n int[] faceVertexIndices = [0, 1, 2, 9]\n'
                      ' point3f[] points = [(0,0,0), (1,0,0), (1,1,0), (0,1,0)]\n}\n')
    assert main(["validate", str(broken)]) == 1
    assert "topology" in capsys.readouterr().out
    (tmp_path / "garbage.usda").write_text("#usda 1.0\ndef {")
    assert main(["validate", str(tmp_path / "garbage.usda")]) == 1
    out = capsys.readouterr().out
    assert "cannot open stage" in out and "Error in '" not in out  # (USD's source location is dropped)
    assert main(["validate", str(tmp_path / "missing.usda")]) == 1
    assert "cannot open stage: Failed to open layer" in capsys.readouterr().out


def test_element_instancing_places_the_same_elements(small_scene, test_registry, tmp_path):
    from collections import Counter
    from tests.usd_util import buildings
    modules_out = tmp_path / "modules.usda"
    generate(small_scene, test_registry, modules_out)
    with_output(small_scene, 'instancing = "elements"')
    elements_out = tmp_path / "elements.usda"
    report = generate(small_scene, test_registry, elements_out)
    assert errors(elements_out) == []
    counts = []
    for out in (modules_out, elements_out):
        stage = Usd.Stage.Open(str(out))
        counts.append(Counter(label for b in buildings(stage) for label in element_labels(stage, b.GetChild("Elements"))))
    assert counts[0] == counts[1] and "module" not in counts[1]
    stage = Usd.Stage.Open(str(elements_out))
    assert not [p for p in stage.GetPrimAtPath("/Prototypes").GetAllChildren() if p.GetName().startswith("module_")]
    assert report.stats.prototypes == 2


def test_a_registry_workers_cannot_rebuild_runs_in_one_job(small_scene, test_registry, tmp_path):
    from citygen.registry import load_registry
    from tests.core.fakes import FakePlugin

    class LocalPlugin(FakePlugin):  # defined in a function: cannot be pickled for worker processes
        pass

    copy_city(small_scene, 1)
    report = generate(small_scene, load_registry(extra_plugins=[LocalPlugin()]), tmp_path / "a.usda", jobs=2)
    assert report.written == 6
    assert any("running with 1 job" in w and "pickled" in w for w in report.warnings)


def test_uvs_are_metres_on_every_mesh_and_validate(small_scene, test_registry, tmp_path):
    with_output(small_scene, 'uvs = true')
    report = generate(small_scene, test_registry, None)
    assert errors(report.stats.path) == []
    stage = Usd.Stage.Open(str(report.stats.path))
    meshes = [UsdGeom.Mesh(p) for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    assert meshes
    for mesh in meshes:
        st = UsdGeom.PrimvarsAPI(mesh).GetPrimvar("st")
        assert st.GetInterpolation() == UsdGeom.Tokens.faceVarying and st.GetTypeName() == "texCoord2f[]"
        assert len(st.Get()) == len(mesh.GetFaceVertexIndicesAttr().Get())


def test_no_uvs_unless_asked(small_scene, test_registry, tmp_path):
    out = tmp_path / "city.usda"
    generate(small_scene, test_registry, out)
    stage = Usd.Stage.Open(str(out))
    assert not any(p.HasAttribute("primvars:st") for p in stage.Traverse())


def test_lod_variants_switch_each_building_between_facades_and_plain_walls(small_scene, test_registry, tmp_path):
    """On by default, named as importers read them (Unreal: a set ``LOD`` of ``LOD0``, ``LOD1``, ...)."""
    report = generate(small_scene, test_registry, tmp_path / "lod.usda")
    with_output(small_scene, 'lod = "none"')
    plain = generate(small_scene, test_registry, tmp_path / "plain.usda")
    assert errors(report.stats.path) == []
    stage, before = Usd.Stage.Open(str(report.stats.path)), Usd.Stage.Open(str(plain.stats.path))
    detailed = sorted(str(p.GetPath()) for p in stage.Traverse())
    assert detailed == sorted(str(p.GetPath()) for p in before.Traverse())  # LOD0 composes as without variants
    for prim in buildings(stage):
        lods = prim.GetVariantSets().GetVariantSet("LOD")
        assert lods.GetVariantNames() == ["LOD0", "LOD1"] and lods.GetVariantSelection() == "LOD0"
        faces = len(UsdGeom.Mesh(prim.GetChild("Roof")).GetFaceVertexCountsAttr().Get()) > 0
        assert faces and prim.GetChild("Facade") and not prim.GetChild("Walls")
        lods.SetVariantSelection("LOD1")
        walls = UsdGeom.Mesh(prim.GetChild("Walls"))
        assert walls and prim.GetChild("Roof") and not prim.GetChild("Facade") and not prim.GetChild("Elements")
        z = np.array(walls.GetPointsAttr().Get())[:, 2]
        height = prim.GetAttribute("citygen:height").Get()
        assert z.max() - z.min() == pytest.approx(height, abs=1e-3)


@pytest.mark.parametrize("option, mode", [("lod = true", "variants"), ("lod = false", "none")])
def test_the_old_lod_switch_still_reads(small_scene, option, mode):
    with_output(small_scene, option)
    assert load_scene(small_scene).output.lod == mode


def test_lod_as_a_render_proxy_pair(small_scene, test_registry, tmp_path):
    with_output(small_scene, 'lod = "purpose"')
    report = generate(small_scene, test_registry, None)
    assert errors(report.stats.path) == []
    stage = Usd.Stage.Open(str(report.stats.path))
    for prim in buildings(stage):
        assert not prim.GetVariantSets().HasVariantSet("LOD")
        render, proxy = prim.GetChild("Render"), prim.GetChild("Proxy")
        assert UsdGeom.Imageable(render).ComputePurpose() == UsdGeom.Tokens.render and render.GetChild("Facade")
        assert UsdGeom.Imageable(proxy).ComputePurpose() == UsdGeom.Tokens.proxy and proxy.GetChild("Walls")


def test_a_bad_lod_mode_is_a_clear_error(small_scene):
    with_output(small_scene, 'lod = "full"')
    with pytest.raises(SceneError, match="lod must be one of variants, purpose, none, got 'full'"):
        load_scene(small_scene)


def test_ground_quad_under_the_city(small_scene, test_registry, tmp_path):
    with_output(small_scene, 'ground = true')
    report = generate(small_scene, test_registry, None)
    assert errors(report.stats.path) == []
    stage = Usd.Stage.Open(str(report.stats.path))
    ground = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Ground"))
    points = np.array(ground.GetPointsAttr().Get())
    feet = np.array([[p.GetAttribute("citygen:base").Get()] for p in buildings(stage)])
    assert len(points) == 4 and np.all(points[:, 2] == feet.min())
    roofs = np.concatenate([world_points(p.GetChild("Roof")) for p in buildings(stage)])
    assert np.all(points[:, :2].min(axis=0) < roofs[:, :2].min(axis=0) - 19)  # 20 m beyond every building
    assert np.all(points[:, :2].max(axis=0) > roofs[:, :2].max(axis=0) + 19)
    labels = UsdSemantics.LabelsAPI(ground.GetPrim(), "class").GetLabelsAttr().Get()
    assert list(labels) == ["ground"]


def test_a_building_referenced_alone_keeps_its_looks_and_instances_at_its_pivot(small_scene, test_registry, tmp_path):
    """Was: bindings to /World/Looks were lost in a reference, and every building sat at the city origin."""
    report = generate(small_scene, test_registry, tmp_path / "city.usdc")
    city = Usd.Stage.Open(str(report.stats.path))
    source = next(b for b in buildings(city) if b.GetName() == "way_2")
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    placed = stage.DefinePrim("/Shot/House", "Xform")
    stage.SetDefaultPrim(stage.GetPrimAtPath("/Shot"))
    placed.GetReferences().AddReference(str(report.stats.path), source.GetPath())
    assert_resolves(stage, "/Shot/House")
    assert errors(stage) == []
    assert placed.GetAttribute("citygen:sourceId").Get() == "way/2"
    pivot = placed.GetAttribute("xformOp:translate").Get()
    assert tuple(pivot) == pytest.approx((35.0, 15.0, 0.0))  # the footprint's centroid (courtyard: symmetric)
    local = np.array(UsdGeom.Mesh(placed.GetChild("Roof")).GetPointsAttr().Get())
    assert np.allclose(local[:, :2].mean(axis=0), 0.0, atol=8.0) and local[:, 2].min() >= 0.0
    assert np.allclose(world_points(placed.GetChild("Roof")), world_points(source.GetChild("Roof")), atol=1e-4)


def test_buildings_are_components_with_metadata_dccs_keep(small_scene, test_registry, tmp_path):
    with_output(small_scene, 'keep_tags = ["build*"]')
    report = generate(small_scene, test_registry, None)
    stage = Usd.Stage.Open(str(report.stats.path))
    values = set()
    for b in buildings(stage):
        attrs = [a for a in b.GetAttributes() if a.GetName().startswith("citygen:")]
        assert attrs and all(a.IsCustom() for a in attrs)  # Blender's importer drops non-custom attributes
        for name in ("buildingType", "roofShape", "footprintArea"):
            assert b.GetAttribute(f"citygen:{name}").HasAuthoredValue(), name
        assert Usd.ModelAPI(b).GetAssetInfo()["name"] == b.GetName()
        primvar = UsdGeom.PrimvarsAPI(b).GetPrimvar("citygen:variation")
        assert primvar.GetInterpolation() == UsdGeom.Tokens.constant and 0 <= primvar.Get() < 1
        values.add(primvar.Get())
    assert len(values) == 3
    house = stage.GetPrimAtPath("/World/Tile_0_0/way_3")
    assert house.GetAttribute("citygen:tag:building").Get() == "house"
    assert house.GetAttribute("citygen:buildingType").Get() == "house"
    assert house.GetAttribute("citygen:footprintArea").Get() == pytest.approx(160.0, abs=1.0)


def test_every_model_has_extents_hint_and_every_instancer_an_extent(small_scene, test_registry, tmp_path):
    report = generate(small_scene, test_registry, tmp_path / "city.usdc")
    stage = Usd.Stage.Open(str(report.stats.path))
    hinted = UsdGeom.BBoxCache(Usd.TimeCode.Default(), [UsdGeom.Tokens.default_], useExtentsHint=True)
    models = [p for p in stage.Traverse() if Usd.ModelAPI(p).IsModel()]
    assert len(models) == 1 + 1 + 3  # world, tile, buildings
    for prim in models:
        assert UsdGeom.ModelAPI(prim).GetExtentsHintAttr().HasAuthoredValue(), prim.GetPath()
        computed = UsdGeom.BBoxCache(Usd.TimeCode.Default(), [UsdGeom.Tokens.default_])
        a, b = hinted.ComputeWorldBound(prim).ComputeAlignedRange(), computed.ComputeWorldBound(prim).ComputeAlignedRange()
        assert np.allclose(a.GetMin(), b.GetMin(), atol=1e-3) and np.allclose(a.GetMax(), b.GetMax(), atol=1e-3)
    instancers = [p for root in [stage.GetPseudoRoot(), *stage.GetPrototypes()] for p in Usd.PrimRange(root)
                  if p.IsA(UsdGeom.PointInstancer)]  # (not through instance proxies: USD's extent fails there)
    assert len(instancers) == 3  # one per building: module prototypes hold meshes only (citygen.geometry.lift)
    for prim in instancers:
        authored = np.array(UsdGeom.PointInstancer(prim).GetExtentAttr().Get())
        exact = np.array(UsdGeom.PointInstancer(prim).ComputeExtentAtTime(Usd.TimeCode.Default(),
                                                                           Usd.TimeCode.Default()))
        assert np.allclose(authored, exact, atol=2e-3), prim.GetPath()


def test_usdz_is_byte_reproducible_and_its_root_layer_named_after_it(small_scene, test_registry, tmp_path):
    """Was: a random hidden root layer name (.delft.fykqxyis.usdc) inside, different bytes every run."""
    a, b = tmp_path / "a" / "delft.usdz", tmp_path / "b" / "delft.usdz"
    generate(small_scene, test_registry, a)
    time.sleep(2.1)  # (the zip records file times in 2 s steps)
    generate(small_scene, test_registry, b)
    assert a.read_bytes() == b.read_bytes()
    assert zipfile.ZipFile(a).namelist()[0] == "delft.usdc"


def test_an_undefined_material_warns_naming_the_ruleset_and_falls_back(small_scene, test_registry, tmp_path):
    (tmp_path / "bays.testgrid").write_text(json.dumps({"bay": 3.0, "window": 1.3, "material": "unobtainium"}))
    report = generate(small_scene, test_registry, tmp_path / "city.usda")
    found = [w for w in report.warnings if "unobtainium" in w]
    assert len(found) == 1 and "bays.testgrid" in found[0] and "frame_white" in found[0]
    stage = Usd.Stage.Open(str(report.stats.path))
    assert not [p for p in stage.Traverse(Usd.PrimAllPrimsPredicate) if "unobtainium" in p.GetName()]


def test_openings_honour_their_material(small_scene, test_registry, tmp_path):
    """Was: window, door and shop frames always 'frame', whatever the ruleset said."""
    (tmp_path / "bays.testgrid").write_text(json.dumps({"bay": 3.0, "window": 1.3, "material": "metal"}))
    report = generate(small_scene, test_registry, tmp_path / "city.usda")
    stage = Usd.Stage.Open(str(report.stats.path))
    window = next(p for p in stage.GetPrimAtPath("/Prototypes").GetAllChildren()
                  if p.GetName().startswith("window_"))
    mat, _ = UsdShade.MaterialBindingAPI(window.GetChild("frame")).ComputeBoundMaterial()
    assert mat.GetPrim().GetName() == "metal"


def test_validate_names_a_finding_on_a_property_instead_of_crashing():
    """Was: AttributeError on 'NoneType'.identifier when a validator reported a property site."""
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetDefaultPrim(stage.DefinePrim("/M", "Material"))
    reader = UsdShade.Shader.Define(stage, "/M/ST")
    reader.CreateIdAttr("UsdPrimvarReader_float2")
    reader.GetPrim().CreateAttribute("inputs:varname", Sdf.ValueTypeNames.Token).Set("st")
    found = [f for f in validate_stage(stage) if f.where == "/M/ST.inputs:varname"]
    assert found and "Expected 'string'" in found[0].message


def test_kept_tags_with_any_characters_become_valid_attribute_names(small_scene, test_registry, tmp_path):
    city = small_scene.parent / "city.local.json"
    features = json.loads(city.read_text())
    features[2]["tags"] = {**features[2]["tags"], "ref:bag-id": "0363", "addr:street": "Oude Delft", "3dr:type": 1}
    city.write_text(json.dumps(features))
    with_output(small_scene, 'keep_tags = ["ref:*", "addr:*", "3dr:*"]')
    report = generate(small_scene, test_registry, None)
    assert report.written == 3 and errors(report.stats.path) == []
    stage = Usd.Stage.Open(str(report.stats.path))
    house = stage.GetPrimAtPath("/World/Tile_0_0/way_3")
    assert house.GetAttribute("citygen:tag:ref:bag_id").Get() == "0363"
    assert house.GetAttribute("citygen:tag:addr:street").Get() == "Oude Delft"
    assert house.GetAttribute("citygen:tag:_dr:type").Get() == 1


def test_looks_are_one_reference_to_a_look_set_authored_once_per_combination(small_scene, test_registry, tmp_path):
    """Each building's and prototype's ``Looks`` is one spec referencing ``/Looks/<set>``; the sets' Materials
    compose under it, so its bindings resolve (the reference test above) and it lists exactly its materials."""
    report = generate(small_scene, test_registry, tmp_path / "city.usda")
    layer = Sdf.Layer.FindOrOpen(str(report.stats.path))
    sets = layer.GetPrimAtPath("/Looks")
    assert sets.specifier == Sdf.SpecifierClass
    users = [spec for spec in _specs(layer.pseudoRoot) if spec.name == "Looks" and spec.path != sets.path]
    assert users and all(not spec.nameChildren for spec in users)
    targets = [spec.referenceList.prependedItems[0].primPath for spec in users]
    assert len(set(targets)) == len(sets.nameChildren) < len(users)  # shared, and every set is used
    stage = Usd.Stage.Open(str(report.stats.path))
    for spec in users:
        if not spec.path.ContainsPrimVariantSelection() and not str(spec.path).startswith("/Prototypes"):
            composed = [c.GetName() for c in stage.GetPrimAtPath(spec.path).GetChildren()]
            assert composed == str(targets[users.index(spec)].name).split("__")


def _specs(spec):
    yield spec
    for child in spec.nameChildren:
        yield from _specs(child)
