"""Material looks: a UsdPreviewSurface per material name.

Known names have hand-picked colours; any other name (a grammar may say ``material: brick_red``) gets a stable
colour from its name's hash, so the same name always looks the same.
"""
from __future__ import annotations

import hashlib

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


def look(name: str) -> tuple[tuple[float, float, float], float, float, float]:
    """The look of a material name (stable colour for unknown names)."""
    if name in LOOKS:
        return LOOKS[name]
    digest = hashlib.blake2b(name.encode("utf-8"), digest_size=3).digest()
    rgb = tuple(0.25 + 0.6 * b / 255 for b in digest)
    return (rgb[0], rgb[1], rgb[2]), 0.8, 0.0, 1.0
