"""Colour and the material library: the one place colours are defined and converted.

Materials are authored as sRGB display colours (what a colour picker or an OSM ``building:colour`` tag gives) in
``materials.toml`` beside this module, in a scene's ``[materials]`` table and in a ruleset's sidecar file
``<ruleset>.materials.toml``. :func:`srgb_to_linear` converts them to the linear values ``UsdPreviewSurface`` (and
glTF's PBR) expect -- once, in :meth:`Material.linear`, which every writer reads.

``colour_rrggbb`` names a colour from the data (:func:`colour_material`); any other name must be defined: the
builder reports an undefined name with the ruleset that used it and falls back to the label's default material.
"""
from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from citygen.errors import SceneError

#: The built-in library (sRGB display colours).
LIBRARY_FILE = Path(__file__).with_name("materials.toml")
#: Sidecar of a ruleset file defining its materials: ``apartment.grammar`` -> ``apartment.materials.toml``.
SIDECAR_SUFFIX = ".materials.toml"
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
_KEYS = {"colour", "roughness", "metallic", "opacity", "texture", "texture_size"}


def srgb_to_linear(rgb: tuple[float, float, float]) -> tuple[float, float, float]:
    """Linear RGB of an sRGB display colour (IEC 61966-2-1 transfer function), each channel in 0..1."""
    r, g, b = (c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4 for c in rgb)
    return r, g, b


@dataclass(frozen=True)
class Material:
    """A material: sRGB display ``colour``, ``roughness``, ``metallic``, ``opacity`` and an optional tiling
    ``texture`` (an image file) one repeat of which covers ``texture_size`` metres (u along, v up the face)."""

    name: str
    colour: tuple[float, float, float]
    roughness: float = 0.9
    metallic: float = 0.0
    opacity: float = 1.0
    texture: Path | None = None
    texture_size: tuple[float, float] = (1.0, 1.0)

    @property
    def linear(self) -> tuple[float, float, float]:
        """The colour as linear RGB: what ``UsdPreviewSurface`` ``diffuseColor`` and glTF ``baseColorFactor`` take."""
        return srgb_to_linear(self.colour)


def hex_colour(text: str) -> tuple[float, float, float] | None:
    """``(r, g, b)`` in 0..1 of ``#rrggbb`` / ``#rgb`` (sRGB), None if it is not one."""
    match = _HEX.fullmatch(text.strip().lower())
    if not match:
        return None
    digits = match.group(1)
    digits = digits if len(digits) == 6 else "".join(c * 2 for c in digits)
    r, g, b = (int(digits[k:k + 2], 16) / 255 for k in (0, 2, 4))
    return r, g, b


def parse_materials(table: Mapping[str, Any], where: str, base: Path) -> dict[str, Material]:
    """Materials of a ``[materials]``-style table (name -> {colour, roughness, ...}); ``texture`` paths are relative
    to ``base``. A bad entry raises a :class:`SceneError` naming ``where`` and the material."""
    out: dict[str, Material] = {}
    for name, spec in table.items():
        def fail(problem: str) -> SceneError:
            return SceneError(f"material {name!r} {problem}", where=where,
                              hint='e.g. [materials.brick_red] colour = "#8c4533", roughness = 0.9 '
                                   '(keys: ' + ", ".join(sorted(_KEYS)) + ")")
        if not isinstance(spec, Mapping):
            raise fail("must be a table")
        if unknown := set(spec) - _KEYS:
            raise fail(f"has unknown keys {', '.join(sorted(unknown))}")
        colour = hex_colour(str(spec["colour"])) if "colour" in spec else None
        if colour is None:
            raise fail(f"needs colour = \"#rrggbb\" (an sRGB display colour), got {spec.get('colour')!r}")
        numbers = {}
        for key, default in (("roughness", 0.9), ("metallic", 0.0), ("opacity", 1.0)):
            value = spec.get(key, default)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 <= value <= 1.0:
                raise fail(f"has {key} = {value!r}; it must be a number from 0 to 1")
            numbers[key] = float(value)
        texture, size = None, (1.0, 1.0)
        if "texture" in spec:
            texture = (base / str(spec["texture"])).resolve()
            if not texture.is_file():
                raise fail(f"has texture {spec['texture']!r}, which is not a file (relative to {base})")
            raw = spec.get("texture_size", 1.0)
            raw = [raw, raw] if isinstance(raw, (int, float)) and not isinstance(raw, bool) else raw
            if (not isinstance(raw, list) or len(raw) != 2
                    or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0
                               for v in raw)):
                raise fail(f"has texture_size = {spec.get('texture_size')!r}; give metres as a number or [u, v]")
            size = (float(raw[0]), float(raw[1]))
        out[str(name)] = Material(str(name), colour, **numbers, texture=texture, texture_size=size)
    return out


def read_materials(path: Path) -> dict[str, Material]:
    """The materials of a TOML file of material tables (the built-in library or a ruleset's sidecar)."""
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise SceneError(f"cannot read materials: {exc}", where=str(path),
                         hint="a TOML file of [name] tables with colour = \"#rrggbb\"") from exc
    return parse_materials(data, str(path), path.parent)


def sidecar(ruleset: Path) -> Path:
    """The materials file beside a ruleset: ``<stem>.materials.toml``."""
    return ruleset.with_name(ruleset.name.split(".")[0] + SIDECAR_SUFFIX)


BUILTIN: Mapping[str, Material] = read_materials(LIBRARY_FILE)
#: Stand-in where a writer meets a name no library defines (the builder has already warned about it).
FALLBACK = BUILTIN["plaster_grey"]


def colour_material(value: object) -> str | None:
    """``colour_rrggbb`` for an OSM colour tag (``#rrggbb``, ``#rgb`` or a colour name), None if it is none."""
    text = str(value).strip().lower().replace(" ", "") if value is not None else ""
    rgb = hex_colour(COLOUR_NAMES.get(text, text)) if text else None
    if rgb is None:
        return None
    return COLOUR_PREFIX + "".join(f"{round(c * 255):02x}" for c in rgb)


def resolve(name: str, library: Mapping[str, Material] | None = None) -> Material | None:
    """The material a name stands for: the scene's and rulesets' ``library`` first, then the built-ins, then a
    ``colour_rrggbb`` colour; None if it is undefined."""
    found = (library or {}).get(name) or BUILTIN.get(name)
    if found is not None:
        return found
    if name.startswith(COLOUR_PREFIX) and (rgb := hex_colour(name[len(COLOUR_PREFIX):])) is not None:
        return Material(name, rgb)
    return None


def material(name: str, library: Mapping[str, Material] | None = None) -> Material:
    """:func:`resolve`, with :data:`FALLBACK`'s look (under the name asked for) for an undefined name."""
    found = resolve(name, library)
    return found if found is not None else Material(name, FALLBACK.colour, FALLBACK.roughness)
