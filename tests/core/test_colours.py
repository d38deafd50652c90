"""Colour management and the material library (citygen.usd.materials): sRGB in, linear on the stage, once."""
import re
from pathlib import Path

import pytest
from pxr import Usd, UsdShade

from citygen.errors import SceneError
from citygen.pipeline import generate_city
from citygen.scene import load_scene
from citygen.usd.materials import BUILTIN, colour_material, material, read_materials, resolve, srgb_to_linear
from tests.usd_util import buildings

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("value, name", [
    ("#cd7f32", "colour_cd7f32"), ("#FFFFFF", "colour_ffffff"), ("99FFFF", "colour_99ffff"), ("#fa2", "colour_ffaa22"),
    ("brown", "colour_a52a2a"), ("Light Grey", "colour_d3d3d3"), ("gray", "colour_808080"),
    ("", None), (None, None), ("sort of red", None), ("#12345", None), ("#gggggg", None),
])
def test_osm_colour_tags_become_colour_materials(value, name):
    assert colour_material(value) == name


def test_srgb_to_linear_is_the_iec_transfer_function():
    assert srgb_to_linear((0.0, 1.0, 0.04045)) == pytest.approx((0.0, 1.0, 0.04045 / 12.92))
    assert srgb_to_linear((0.5, 0.5, 0.5))[0] == pytest.approx(0.21404, abs=1e-5)
    assert material("colour_808080").linear == pytest.approx((0.21586,) * 3, abs=1e-4)  # sRGB 128


def test_every_material_a_shipped_ruleset_names_is_defined():
    names = set()
    for path in (ROOT / "rulesets").iterdir():
        names |= set(re.findall(r"\bmaterial\s*[:=]\s*\"?([A-Za-z_][\w]*)", path.read_text()))
    assert {"metal", "wood", "plaster", "iron", "stone", "glass"} <= names
    assert sorted(n for n in names if n != "render" and resolve(n) is None) == []


def test_palette_colour_reaches_the_stage_as_its_linear_value(small_scene, test_registry, tmp_path):
    """roof_dark is #404045 in materials.toml: the stage's diffuseColor is its linear value (0.0513, 0.0513,
    0.0595), not the display value written as if it were linear (the old 0.25 grey rendered as 54 % grey)."""
    report = generate_city(load_scene(small_scene), registry=test_registry, out=tmp_path / "c.usda")
    stage = Usd.Stage.Open(str(report.stats.path))
    roof = buildings(stage)[0].GetChild("Roof")
    mat, _ = UsdShade.MaterialBindingAPI(roof).ComputeBoundMaterial()
    shader = UsdShade.Shader(mat.GetPrim().GetChild("PreviewSurface"))
    colour = shader.GetInput("diffuseColor").Get()
    assert BUILTIN["roof_dark"].colour == pytest.approx((0x40 / 255, 0x40 / 255, 0x45 / 255))
    assert tuple(colour) == pytest.approx((0.0513, 0.0513, 0.0595), abs=1e-4)


def test_scene_and_ruleset_sidecar_define_materials(small_scene, test_registry, tmp_path):
    (tmp_path / "bays.materials.toml").write_text('[slate]\ncolour = "#2f3540"\nroughness = 0.6\n')
    small_scene.write_text(small_scene.read_text() + '\n[materials.roof_dark]\ncolour = "#ff0000"\nmetallic = 0.5\n')
    scene = load_scene(small_scene)
    assert scene.materials["slate"].colour == pytest.approx((0x2f / 255, 0x35 / 255, 0x40 / 255))
    assert scene.materials["roof_dark"].metallic == 0.5 and material("roof_dark", scene.materials).linear == (1, 0, 0)
    report = generate_city(scene, registry=test_registry, out=tmp_path / "c.usda")
    stage = Usd.Stage.Open(str(report.stats.path))
    mat, _ = UsdShade.MaterialBindingAPI(buildings(stage)[0].GetChild("Roof")).ComputeBoundMaterial()
    assert tuple(UsdShade.Shader(mat.GetPrim().GetChild("PreviewSurface")).GetInput("diffuseColor").Get()) == (1, 0, 0)


@pytest.mark.parametrize("entry, problem", [
    ('colour = "red"', "needs colour"), ('colour = "#ffffff"\nroughness = 2', "roughness"),
    ('colour = "#ffffff"\nshine = 1', "unknown keys shine"),
    ('colour = "#ffffff"\ntexture = "missing.png"', "not a file"),
])
def test_a_bad_material_names_the_file_line_and_material(small_scene, entry, problem):
    small_scene.write_text(small_scene.read_text() + f'\n[materials.tin]\n{entry}\n')
    with pytest.raises(SceneError, match=problem) as info:
        load_scene(small_scene)
    assert "'tin'" in str(info.value) and "scene.toml:" in str(info.value)


def test_a_bad_sidecar_names_its_file(tmp_path):
    (tmp_path / "x.materials.toml").write_text('[tin]\ncolour = 3\n')
    with pytest.raises(SceneError, match="x.materials.toml.*'tin'"):
        read_materials(tmp_path / "x.materials.toml")


def test_a_textured_material_gets_uvs_on_its_meshes_only(small_scene, test_registry, tmp_path):
    from PIL import Image
    from pxr import UsdGeom

    (tmp_path / "tex").mkdir()
    Image.new("RGB", (4, 4), (120, 60, 40)).save(tmp_path / "tex" / "tiles.png")
    small_scene.write_text(small_scene.read_text() + '\n[materials.roof_dark]\ncolour = "#404045"\n'
                           'texture = "tex/tiles.png"\ntexture_size = [0.5, 0.25]\n')
    report = generate_city(load_scene(small_scene), registry=test_registry, out=tmp_path / "out" / "c.usda")
    stage = Usd.Stage.Open(str(report.stats.path))
    from citygen.usd.validate import validate_stage
    assert [f for f in validate_stage(stage) if f.severity == "error"] == []
    for b in buildings(stage):
        assert UsdGeom.PrimvarsAPI(b.GetChild("Roof")).GetPrimvar("st").IsDefined()
        assert not any(UsdGeom.PrimvarsAPI(m).GetPrimvar("st").IsDefined() for m in b.GetChild("Facade").GetChildren())
    mat, _ = UsdShade.MaterialBindingAPI(buildings(stage)[0].GetChild("Roof")).ComputeBoundMaterial()
    texture = UsdShade.Shader(mat.GetPrim().GetChild("Texture"))
    assert texture.GetInput("file").Get().path == "../tex/tiles.png"  # relative to the stage: it moves with it
    assert tuple(UsdShade.Shader(mat.GetPrim().GetChild("Tiling")).GetInput("scale").Get()) == (2.0, 4.0)
