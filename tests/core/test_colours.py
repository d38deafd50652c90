"""OSM colour tags as materials (citygen.usd.materials)."""
import pytest

from citygen.usd.materials import colour_material, look


@pytest.mark.parametrize("value, name", [
    ("#cd7f32", "colour_cd7f32"), ("#FFFFFF", "colour_ffffff"), ("99FFFF", "colour_99ffff"), ("#fa2", "colour_ffaa22"),
    ("brown", "colour_a52a2a"), ("Light Grey", "colour_d3d3d3"), ("gray", "colour_808080"),
    ("", None), (None, None), ("sort of red", None), ("#12345", None), ("#gggggg", None),
])
def test_osm_colour_tags_become_colour_materials(value, name):
    assert colour_material(value) == name


def test_colour_materials_look_like_their_colour_in_linear_rgb():
    assert look("colour_ffffff")[0] == (1.0, 1.0, 1.0)
    assert look("colour_000000")[0] == (0.0, 0.0, 0.0)
    (r, g, b), roughness, metallic, opacity = look("colour_808080")
    assert r == g == b == pytest.approx(0.2158, abs=1e-3) and (metallic, opacity) == (0.0, 1.0)  # sRGB 128 -> linear
