"""Names on a stage -- stage file suffixes, prim names of buildings and tiles -- without importing USD: the footprint
planning names every building's prim in a process that never loads ``pxr`` (:func:`citygen.pipeline.generate_city`
forks it before the writer is imported)."""
from __future__ import annotations

import re

SUFFIXES = (".usda", ".usdc", ".usdz")
_OTHER = re.compile(rb"[^A-Za-z0-9_]")


def valid_identifier(text: str) -> str:
    """``Tf.MakeValidIdentifier(text)``, byte for byte: every UTF-8 byte outside ``[A-Za-z0-9_]`` becomes ``_`` (a
    leading digit too), the text ends at its first NUL after the first character, and ``""`` becomes ``_``.
    A lone surrogate raises :class:`UnicodeEncodeError`, as it does passed to USD."""
    data = text.encode("utf-8")
    if not data:
        return "_"
    head, rest = data[:1], data[1:].split(b"\0", 1)[0]
    head = head if head.isalpha() or head == b"_" else b"_"  # (bytes: ASCII letters only)
    return (head + _OTHER.sub(b"_", rest)).decode("ascii")


def prim_name(raw: str, taken: set[str]) -> str:
    """A valid, unique prim name for a stable id (``way/123`` -> ``way_123``; collisions get ``_2``, ``_3``)."""
    base = valid_identifier(raw)
    name, k = base, 2
    while name in taken:
        name, k = f"{base}_{k}", k + 1
    taken.add(name)
    return name


def tile_name(tile: tuple[int, int]) -> str:
    """The prim (and layer file) name of a tile: ``Tile_<i>_<j>``, ``m`` for a minus sign."""
    return f"Tile_{tile[0]}_{tile[1]}".replace("-", "m")
