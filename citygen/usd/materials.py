"""Material looks: a UsdPreviewSurface per material name.

Known names have hand-picked colours; ``colour_rrggbb`` is that colour (from OSM ``building:colour`` /
``roof:colour``, :func:`colour_material`); any other name (a grammar may say ``material: brick_red``) gets a
stable colour from its name's hash, so the same name always looks the same.
"""
from __future__ import annotations

import hashlib
import re

#: name -> (diffuse RGB, roughness, metallic, opacity)
LOOKS: dict[str, tuple[tuple[float, float, float], float, float, float]] = {
    "plaster_ochre": ((0.80, 0.62, 0.36), 0.9, 0.0, 1.0),
    "plaster_cream": ((0.90, 0.85, 0.72), 0.9, 0.0, 1.0),
    "plaster_white": ((0.88, 0.88, 0.85), 0.9, 0.0, 1.0),
    "plaster_pink": ((0.84, 0.64, 0.60), 0.9, 0.0, 1.0),
    "plaster_blue": ((0.62, 0.70, 0.78), 0.9, 0.0, 1.0),
    "plaster_grey": ((0.62, 0.62, 0.60), 0.9, 0.0, 1.0),
    "brick": ((0.55, 0.27, 0.20), 0.95, 0.0, 1.0),
    "stone": ((0.70, 0.68, 0.64), 0.85, 0.0, 1.0),
    "concrete": ((0.60, 0.60, 0.58), 0.9, 0.0, 1.0),
    "trim_white": ((0.93, 0.92, 0.88), 0.7, 0.0, 1.0),
    "reveal": ((0.75, 0.73, 0.70), 0.9, 0.0, 1.0),
    "frame_white": ((0.95, 0.95, 0.95), 0.5, 0.0, 1.0),
    "frame_dark": ((0.15, 0.16, 0.17), 0.5, 0.3, 1.0),
    "frame": ((0.92, 0.92, 0.92), 0.5, 0.0, 1.0),
    "glass": ((0.35, 0.45, 0.52), 0.05, 0.0, 0.45),
    "door_wood": ((0.36, 0.22, 0.13), 0.7, 0.0, 1.0),
    "door_leaf": ((0.36, 0.22, 0.13), 0.7, 0.0, 1.0),
    "railing_metal": ((0.20, 0.21, 0.22), 0.4, 0.8, 1.0),
    "shutter_green": ((0.22, 0.36, 0.25), 0.8, 0.0, 1.0),
    "roof_dark": ((0.25, 0.25, 0.27), 0.9, 0.0, 1.0),
    "ground": ((0.40, 0.40, 0.38), 1.0, 0.0, 1.0),
}

#: Wall materials a building's palette is drawn from.
WALL_PALETTE = ("plaster_ochre", "plaster_cream", "plaster_white", "plaster_pink", "plaster_blue", "plaster_grey",
                "brick")


#: Material names of colours from the data (``colour_rrggbb``).
COLOUR_PREFIX = "colour_"
#: OSM colour names in use (https://wiki.openstreetmap.org/wiki/Key:building:colour) as sRGB hex.
COLOUR_NAMES = {"white": "ffffff", "black": "000000", "grey": "808080", "gray": "808080", "silver": "c0c0c0",
                "lightgrey": "d3d3d3", "lightgray": "d3d3d3", "darkgrey": "a9a9a9", "darkgray": "a9a9a9",
                "red": "ff0000", "darkred": "8b0000", "maroon": "800000", "brown": "a52a2a", "orange": "ffa500",
                "yellow": "ffff00", "beige": "f5f5dc", "tan": "d2b48c", "wheat": "f5deb3", "pink": "ffc0cb",
                "green": "008000", "darkgreen": "006400", "olive": "808000", "blue": "0000ff", "navy": "000080",
                "cream": "fffdd0", "ivory": "fffff0", "gold": "ffd700", "teal": "008080", "purple": "800080"}
_HEX = re.compile(r"#?([0-9a-f]{6}|[0-9a-f]{3})")


def colour_material(value: object) -> str | None:
    """``colour_rrggbb`` for an OSM colour tag (``#rrggbb``, ``#rgb`` or a colour name), None if it is none."""
    text = str(value).strip().lower().replace(" ", "") if value is not None else ""
    text = COLOUR_NAMES.get(text, text)
    match = _HEX.fullmatch(text)
    if not match:
        return None
    digits = match.group(1)
    return COLOUR_PREFIX + (digits if len(digits) == 6 else "".join(c * 2 for c in digits))


def look(name: str) -> tuple[tuple[float, float, float], float, float, float]:
    """The look of a material name (stable colour for unknown names)."""
    if name in LOOKS:
        return LOOKS[name]
    if re.fullmatch(r"colour_[0-9a-f]{6}", name):
        srgb = [int(name[7 + 2 * k:9 + 2 * k], 16) / 255 for k in range(3)]
        r, g, b = (c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4 for c in srgb)  # linear, as USD
        return (r, g, b), 0.9, 0.0, 1.0
    digest = hashlib.blake2b(name.encode("utf-8"), digest_size=3).digest()
    rgb = tuple(0.25 + 0.6 * b / 255 for b in digest)
    return (rgb[0], rgb[1], rgb[2]), 0.8, 0.0, 1.0
