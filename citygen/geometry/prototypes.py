"""Prototype geometry of instanced facade elements (windows, doors, shop fronts, balconies, sills, blinds).

A prototype is built once per :class:`ProtoKey` -- label, material and size quantised to ``QUANTUM`` metres -- in
its own frame: x along the wall, y up, z along the outward normal, origin at the region's bottom-left corner on the
wall plane. Instances scale it by the (small) residual between the region's exact size and the quantised size, so
frames keep their real thickness.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from citygen.geometry.quads import box_quads
from citygen.usd.materials import Material, material

QUANTUM = 0.1
FRAME = 0.07
#: Default depth per label when a region says 0 (recess for openings, protrusion for attachments).
DEFAULT_DEPTH = {"window": -0.22, "door": -0.28, "shop": -0.18, "glass": -0.15, "balcony": 1.1, "sill": 0.09,
                 "blind": 0.04}
INSTANCED = frozenset(DEFAULT_DEPTH)
OPENINGS = frozenset({"window", "door", "shop", "glass"})


@dataclass(frozen=True)
class ProtoKey:
    """Identity of a prototype: what it is and its quantised size in units of ``QUANTUM`` (depth: 0.01 m)."""

    label: str
    material: str
    w: int
    h: int
    d: int

    @property
    def name(self) -> str:
        return f"{self.label}_{self.material}_{self.w}x{self.h}x{self.d}".replace("-", "m")

    @property
    def size(self) -> tuple[float, float, float]:
        return self.w * QUANTUM, self.h * QUANTUM, self.d * 0.01



@dataclass(frozen=True)
class Part:
    """One mesh of a prototype: quads in the prototype frame and the material name."""

    name: str
    material: str
    quads: np.ndarray


def _bars(w: float, h: float, t: float, mullion: bool, transom: bool) -> np.ndarray:
    bars = [(0, 0, w, t), (0, h - t, w, h), (0, t, t, h - t), (w - t, t, w, h - t)]
    if mullion:
        bars.append((w / 2 - t / 2, t, w / 2 + t / 2, h - t))
    if transom:
        bars.append((t, 0.7 * h, w - t, 0.7 * h + t))
    return np.asarray(bars, dtype=float)


def opening_frame(key: ProtoKey) -> tuple[np.ndarray, tuple[float, float, float, float]]:
    """An opening's frame bars (``x0, y0, x1, y1`` rows: the frame, a window's mullion, a window's or shop's
    transom) and the pane inside them (a door's reaches the ground)."""
    w, h, _ = key.size
    t = min(FRAME, 0.2 * w, 0.2 * h)
    bars = _bars(w, h, t, mullion=key.label == "window" and w > 1.3,
                 transom=key.label in ("window", "shop") and h > 1.9)
    return bars, ((t, t, w - t, h - t) if key.label != "door" else (t, 0.0, w - t, h - t))


def balcony_heights(h: float) -> tuple[float, float]:
    """A balcony's slab thickness and railing height in an element ``h`` tall (or in each of an array's)."""
    return np.minimum(0.18, 0.3 * h), np.minimum(1.05, h)


def _shift(quads: np.ndarray, dz: float) -> np.ndarray:
    out = quads.copy()
    out[..., 2] += dz
    return out


def build_prototype(key: ProtoKey, library: Mapping[str, Material] | None = None) -> list[Part]:
    """Mesh parts of the prototype ``key`` (quads in the prototype frame). An opening's material is its frame's (a
    door's: its leaf's), or its panes' when it is see-through (``glass``), the frame then keeping ``frame``."""
    w, h, d = key.size
    full = np.array([[0.0, 0.0, w, h]])
    if key.label in OPENINGS:
        frame_rects, inner = opening_frame(key)
        reveal = Part("reveal", "reveal", box_quads(full, np.array([d]), front=False))
        glazed = material(key.material, library).opacity < 1.0
        frame_material = "frame" if glazed or key.label == "door" else key.material
        pane_material = key.material if glazed or key.label == "door" else "glass"
        frame = Part("frame", frame_material, _shift(box_quads(frame_rects, np.full(len(frame_rects), 0.06)), d))
        pane = Part("door_leaf" if key.label == "door" else "glass", pane_material,
                    _shift(box_quads(np.array([inner]), np.array([0.03]), sides=False), d))
        return [reveal, frame, pane]
    if key.label == "balcony":
        slab_t, rail_h = balcony_heights(h)
        slab = box_quads(np.array([[0.0, 0.0, w, slab_t]]), np.array([d]))
        rail = _shift(box_quads(np.array([[0.0, slab_t, w, rail_h]]), np.array([0.04])), d - 0.04)
        sides = np.concatenate([_side_rail(0.0, slab_t, rail_h, d), _side_rail(w - 0.04, slab_t, rail_h, d)])
        return [Part("slab", "concrete", slab), Part("railing", key.material, np.concatenate([rail, sides]))]
    return [Part("body", key.material, box_quads(full, np.array([d])))]


def _side_rail(x: float, y0: float, y1: float, d: float) -> np.ndarray:
    """A side panel of a balcony railing, running from the wall to the front edge."""
    quads = np.array([[[x, y0, 0.0], [x, y0, d], [x, y1, d], [x, y1, 0.0]],
                      [[x + 0.04, y0, d], [x + 0.04, y0, 0.0], [x + 0.04, y1, 0.0], [x + 0.04, y1, d]]])
    return quads
