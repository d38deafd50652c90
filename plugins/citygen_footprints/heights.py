"""Building heights from the tags real data carries (OSM, CityJSON attributes): pure functions, no I/O.

OSM values are free text: ``"12.13 m"``, ``"12,5"``, ``"40 ft"``, ``"~10"``, ``"4;5"``, ``"3-4"``, ``"IV"``.
:func:`parse_length` and :func:`parse_levels` turn one value into a number or raise :class:`ValueError` saying
why; :func:`resolve_height` picks the first usable source in a fixed order and records which one it used.
Multi-values (``;``) and ranges (``3-4``) take their largest member: the mass must reach the highest part.
"""
from __future__ import annotations

import math
import re
import reprlib
import sys
from collections.abc import Mapping
from dataclasses import dataclass, replace

HEIGHT_TAGS = ("height", "building:height", "measuredHeight")
LEVEL_TAGS = ("building:levels", "storeysAboveGround")
MAX_LEVELS = 300

_NUMBER = r"(\d+(?:[.,]\d+)?|[.,]\d+)"
_UNITS = {"": 1.0, "m": 1.0, "meter": 1.0, "meters": 1.0, "metre": 1.0, "metres": 1.0, "cm": 0.01, "mm": 0.001,
          "ft": 0.3048, "feet": 0.3048, "foot": 0.3048, "'": 0.3048,
          "in": 0.0254, "inch": 0.0254, "inches": 0.0254, '"': 0.0254}
_LENGTH = re.compile(rf"{_NUMBER}\s*([a-z]+|'|\")?")
_FEET_INCHES = re.compile(rf"{_NUMBER}\s*'\s*{_NUMBER}\s*\"?")
_RANGE = re.compile(r"\s*(?:-|–|\bto\b)\s*")
_APPROX = re.compile(r"^(?:~|≈|ca\.?|c\.|approx\.?|about|circa)\s*")
_ROMAN = re.compile(r"m{0,3}(cm|cd|d?c{0,3})(xc|xl|l?x{0,3})(ix|iv|v?i{0,3})")
_ROMAN_VALUES = {"i": 1, "v": 5, "x": 10, "l": 50, "c": 100, "d": 500, "m": 1000}


def _number(text: str) -> float:
    return float(text.replace(",", "."))


def _members(text: str) -> list[str]:
    """Split a multi-value (``a;b``) or range (``a-b``) into its members."""
    parts = [p.strip() for p in text.split(";")]
    return [m.strip() for p in parts if p for m in _RANGE.split(p) if m.strip()]


def _plain(value: object, what: str) -> float | str:
    if isinstance(value, bool) or value is None:
        raise ValueError(f"expected a {what}, got {value!r}")
    if isinstance(value, int) and abs(value) > sys.float_info.max:
        raise ValueError(f"{what} {str(value)[:12]}... is too large")
    if isinstance(value, int | float):
        if not math.isfinite(value) or value < 0:
            raise ValueError(f"{what} {value!r} is {'negative' if value < 0 else 'not finite'}")
        return float(value)
    if not isinstance(value, str):
        raise ValueError(f"expected a {what}, got {type(value).__name__}")
    text = _APPROX.sub("", value.strip().lower()).rstrip("+").strip()
    if not text:
        raise ValueError(f"empty {what}")
    if text.startswith("-"):
        raise ValueError(f"negative {what}")
    return text


def _one_length(text: str) -> float:
    if m := _FEET_INCHES.fullmatch(text):
        return _number(m[1]) * 0.3048 + _number(m[2]) * 0.0254
    m = _LENGTH.fullmatch(text)
    if m is None or (m[2] or "") not in _UNITS:
        raise ValueError("not a length (expected e.g. '12.5', '12.5 m', '40 ft')")
    return _number(m[1]) * _UNITS[m[2] or ""]


def parse_length(value: object) -> float:
    """Metres from a height-like value; the largest member of ``a;b`` and ``a-b``. Raises ValueError."""
    text = _plain(value, "length")
    if isinstance(text, float):
        return text
    members = _members(text)
    if not members:
        raise ValueError("not a length (expected e.g. '12.5', '12.5 m', '40 ft')")
    return max(_one_length(m) for m in members)


def _roman(text: str) -> int:
    if not text or not _ROMAN.fullmatch(text):
        raise ValueError("not a level count (expected e.g. '4', '3.5', '4;5', 'IV')")
    total = 0
    for here, after in zip(text, text[1:] + " ", strict=True):
        v = _ROMAN_VALUES[here]
        total += -v if _ROMAN_VALUES.get(after, 0) > v else v
    return total


def _one_level(text: str) -> float:
    if re.fullmatch(_NUMBER, text):
        return _number(text)
    return float(_roman(text))


def parse_levels(value: object) -> float:
    """A (possibly fractional) level count; the largest member of ``4;5`` and ``3-4``. Raises ValueError."""
    text = _plain(value, "level count")
    levels = text if isinstance(text, float) else max((_one_level(m) for m in _members(text)), default=None)
    if levels is None:
        raise ValueError("not a level count (expected e.g. '4', '3.5', '4;5', 'IV')")
    if levels < 0 or levels > MAX_LEVELS:
        raise ValueError(f"{levels:g} levels is outside 0..{MAX_LEVELS}")
    return levels


#: levels of building types that are low by nature (OSM ``building=*``), used when a feature has no height data
TYPE_LEVELS: tuple[tuple[str, float], ...] = tuple(sorted({
    **dict.fromkeys(("kiosk", "shed", "garage", "garages", "carport", "hut", "cabin", "toilets", "pavilion",
                     "service", "utility", "roof", "bunker", "greenhouse", "glasshouse", "entrance",
                     "underpass_entrance", "container", "bandstand", "gazebo", "static_caravan", "bungalow",
                     "barn", "stable", "sty", "cowshed", "boathouse", "houseboat", "guardhouse", "parking_entrance",
                     "ruins"), 1),
    **dict.fromkeys(("house", "detached", "semidetached_house", "farm", "farm_auxiliary", "transformer_tower"), 2),
    **dict.fromkeys(("terrace",), 3),
}.items()))
#: building types that are slender by nature: never capped by their footprint's width
SLENDER_TYPES = frozenset(("tower", "church", "cathedral", "chapel", "bell_tower", "minaret", "water_tower",
                           "lighthouse", "chimney", "silo", "campanile"))


@dataclass(frozen=True)
class HeightSettings:
    """Scene defaults for height resolution.

    A feature with no usable height or level data gets ``type_levels[building]`` levels when its type is listed,
    else ``default_height`` capped at ``slenderness`` times the footprint's least width (whole levels, at least
    one; ``slenderness = 0`` turns the cap off): an untagged 2 m kiosk does not become an 18 m pillar.
    """

    default_height: float = 10.0
    floor_height: float = 3.0
    max_height: float = 1000.0
    base_offsets: bool = True
    type_levels: tuple[tuple[str, float], ...] = TYPE_LEVELS  # (building type, levels) pairs
    slenderness: float = 3.0


@dataclass(frozen=True)
class Height:
    """A resolved height (metres above ``base_offset``), where it came from, and the problems met.

    ``total``: the height includes the roof (height tags, the scene default, levels with ``roof:levels``), else it
    is the walls' (level counts alone: the roof goes on top, :mod:`citygen.roofplan`). ``levels`` counts the storeys
    below the roof (``building:levels`` less ``building:min_level``).
    ``rejected`` lists the tags whose values were present but unusable (unparsable or implausible);
    ``warnings`` holds one message per problem, naming the feature, tag and value.
    """

    height: float
    source: str
    levels: int | None = None
    base_offset: float = 0.0
    warnings: tuple[str, ...] = ()
    rejected: tuple[str, ...] = ()
    total: bool = True


def _present(tags: Mapping[str, object], key: str) -> bool:
    value = tags.get(key)
    return value is not None and value != ""


def _round_levels(levels: float) -> int:
    return max(1, math.floor(levels + 0.5))


def resolve_height(tags: Mapping[str, object], feature_id: str, settings: HeightSettings) -> Height:
    """The height of one feature from ``tags``, in the order height tags (a total, roof included), level tags
    (``building:levels``: the walls' storeys, plus ``roof:levels`` in the roof), scene default (a total).

    Heights outside ``(0, max_height]`` and level totals of zero are rejected like unparsable values (with a
    warning) and the next source is tried. ``min_height`` / ``building:min_level`` lift the base when
    ``settings.base_offsets`` is on; the wall then runs from the offset to the top. A lifted part with no height or
    levels but a ``roof:height`` is all roof: its top is the offset plus the roof's height (Helsinki Cathedral's
    corner domes).
    """
    warnings: list[str] = []
    rejected: list[str] = []

    def reject(tag: str, why: str) -> None:
        rejected.append(tag)
        warnings.append(f"{feature_id}: cannot use {tag}={reprlib.repr(tags[tag])} ({why}); "
                        "trying the next height source")

    def read(tag: str, parse) -> float | None:
        if not _present(tags, tag):
            return None
        try:
            return parse(tags[tag])
        except ValueError as exc:
            reject(tag, str(exc))
            return None

    levels = None
    roof_levels = 0.0
    level_tag = ""
    for tag in LEVEL_TAGS:
        if (levels := read(tag, parse_levels)) is not None:
            level_tag = tag
            break
    if levels is not None:
        roof_levels = read("roof:levels", parse_levels) or 0.0
        if levels + roof_levels <= 0:
            reject(level_tag, "no levels above ground")
            levels = None

    offset = offset_levels = 0.0
    if settings.base_offsets:
        min_level = read("building:min_level", parse_levels)
        min_height = read("min_height", parse_length)
        if min_height is not None:
            offset = min_height
            offset_levels = min_level if min_level is not None else min_height / settings.floor_height
        elif min_level is not None:
            offset, offset_levels = min_level * settings.floor_height, min_level

    offsets = (offset, offset_levels, feature_id)
    for tag in HEIGHT_TAGS:
        top = read(tag, parse_length)
        if top is None:
            continue
        if not 0 < top <= settings.max_height:
            reject(tag, f"{top:g} m is not a plausible building height, must be in (0, {settings.max_height:g}]")
            continue
        return _with_offset(top, tag, levels, offsets, warnings, rejected, total=True)
    if levels is not None:  # with roof levels a total (a part may be all roof), else the walls' height
        top = (levels + roof_levels) * settings.floor_height
        if top <= settings.max_height:
            source = level_tag + ("+roof:levels" if roof_levels else "")
            return _with_offset(top, source, levels, offsets, warnings, rejected, total=roof_levels > 0)
        reject(level_tag, f"{levels + roof_levels:g} levels of {settings.floor_height:g} m exceed "
                          f"{settings.max_height:g} m")
    roof = read("roof:height", parse_length) if offset > 0 else None
    if roof and offset + roof <= settings.max_height:  # a lifted part with only its roof's height: all roof
        source = ("min_height" if _present(tags, "min_height") else "building:min_level") + "+roof:height"
        return _with_offset(offset + roof, source, None, offsets, warnings, rejected, total=True)
    return Height(settings.default_height, "default", None, offset, tuple(warnings), tuple(rejected))


def _with_offset(top: float, source: str, wall_levels: float | None, offsets: tuple[float, float, str],
                 warnings: list[str], rejected: list[str], total: bool) -> Height:
    offset, offset_levels, feature_id = offsets
    if offset and offset >= top:
        warnings.append(f"{feature_id}: base offset {offset:g} m is not below the top {top:g} m; ignoring it")
        offset = offset_levels = 0.0
    levels = None if wall_levels is None else _round_levels(max(wall_levels - offset_levels, 1.0))
    return Height(top - offset, source, levels, offset, tuple(warnings), tuple(rejected), total)


def infer_height(height: Height, tags: Mapping[str, object], least_width: float, settings: HeightSettings) -> Height:
    """``height`` itself unless it is the scene default (no usable data): then the height the building type implies
    (``settings.type_levels``, source ``"building=TYPE"``) or the default capped by the footprint's least width
    (source ``"default, capped by width"``); see :class:`HeightSettings`."""
    if height.source != "default":
        return height
    kind = tags.get("building") if isinstance(tags.get("building"), str) else None
    levels = dict(settings.type_levels).get(kind)
    if levels is not None:
        source = f"building={kind}"
    elif settings.slenderness > 0 and settings.slenderness * least_width < height.height and \
            kind not in SLENDER_TYPES:
        levels, source = settings.slenderness * least_width // settings.floor_height, "default, capped by width"
    else:
        return height
    levels = max(1, int(levels))  # (the wall runs from any base offset up, like the default height)
    return replace(height, height=min(levels * settings.floor_height, settings.max_height), source=source,
                   levels=levels, total=False)
