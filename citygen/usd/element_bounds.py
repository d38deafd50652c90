"""An element prototype's bound from its key alone, bit for bit the bound of its welded meshes.

A tile layer references its element prototypes in the city's element library (:mod:`citygen.usd.library`) and needs
of each only its bound, for the PointInstancers' ``extent`` and the models' ``extentsHint``. Building and welding
the prototype for it (:func:`~citygen.usd.definitions.prepare_elements`) cost each tile worker ~0.2 s of the
Helsinki demo's ~3 s; the bound follows from the boxes :func:`~citygen.geometry.prototypes.build_prototype` makes,
in a few float operations per part. Welding (:func:`~citygen.geometry.quads.weld_many`) snaps a part's corners to
the millimetre grid from the part's lowest corner, so a part's welded bound is that corner and the grid point
nearest its highest, in float32. ``tests/core/test_element_bounds.py`` compares this with the welded meshes for
every label over a grid of sizes and depths: a change of the prototypes' shapes must change both.
"""
from __future__ import annotations

import functools

import numpy as np

from citygen.geometry.prototypes import OPENINGS, ProtoKey, balcony_heights, opening_frame

#: The welding grid of :func:`~citygen.geometry.quads.weld_many` (``decimals=3``), computed as it computes it.
_STEP = 10.0 ** -3
#: :func:`~citygen.geometry.quads.box_quads`'s depth below which a box has no sides.
_FLAT = 1e-6

_Part = tuple[list[float], list[float], list[float]]  # the corners' x, y and z values


def _box(x0: float, y0: float, x1: float, y1: float, depth: float, front: bool = True, sides: bool = True,
         shift: float | None = None) -> _Part | None:
    """The coordinates of :func:`box_quads` of one box (``shift`` added to its z as ``_shift`` adds it); None when
    it has no quads."""
    deep = sides and abs(depth) > _FLAT
    if not front and not deep:
        return None
    zs = ([depth * 1] if front else []) + ([depth * 0, depth * 1] if deep else [])
    if shift is not None:
        zs = [z + shift for z in zs]
    return [x0, x1], [y0, y1], zs


def _parts(key: ProtoKey) -> list[_Part]:
    """The coordinates of each part of :func:`build_prototype` (``key``; the same frame and balcony dimensions), the
    parts without quads left out."""
    w, h, d = key.size
    if key.label in OPENINGS:
        bars, inner = opening_frame(key)
        frame = (bars[:, [0, 2]].ravel().tolist(), bars[:, [1, 3]].ravel().tolist(), [0.0 + d, 0.06 + d])
        parts = [_box(0.0, 0.0, w, h, d, front=False), frame, _box(*inner, 0.03, sides=False, shift=d)]
    elif key.label == "balcony":
        slab_t, rail_h = balcony_heights(h)
        rail = _box(0.0, slab_t, w, rail_h, 0.04, shift=d - 0.04)
        assert rail is not None
        xs = [0.0, 0.0 + 0.04, w - 0.04, (w - 0.04) + 0.04]
        railing = (rail[0] + xs, rail[1] + [slab_t, rail_h], rail[2] + [0.0, d])
        parts = [_box(0.0, 0.0, w, slab_t, d), railing]
    else:
        parts = [_box(0.0, 0.0, w, h, d)]
    return [p for p in parts if p is not None]


@functools.lru_cache(maxsize=8192)
def element_bound(key: ProtoKey) -> np.ndarray:
    """``(2, 3)`` ``[min, max]`` of the welded meshes of element ``key``: what
    :func:`~citygen.usd.definitions.meshes_bound` gives for its prepared prototype (whatever the material library:
    it names the parts' materials, not their shapes)."""
    low, high = [], []
    for part in _parts(key):
        origin = [min(axis) for axis in part]
        low.append([o + 0.0 for o in origin])  # (grid 0: the corner itself; -0.0 + 0.0 is 0.0, as numpy adds it)
        high.append([o + float(round((max(axis) - o) / _STEP)) * _STEP for o, axis in zip(origin, part)])
    low32, high32 = np.array(low, dtype=np.float32), np.array(high, dtype=np.float32)
    bound = np.array([low32.min(axis=0), high32.max(axis=0)], dtype=float)
    bound.flags.writeable = False  # (shared by every tile of the process)
    return bound
