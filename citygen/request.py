"""FacadeRequest: what a facade generator is asked to produce, with the building's cross-face constraints.

The building coordinator (``citygen.coordinator``) decides floor lines, the entrance face and corner strips once
per building; each face's generator receives them here and must honour them:

* ``floor_lines`` -- every horizontal floor boundary ``0 = y0 < y1 < ... < yn = height``; no region with a label
  in :data:`citygen.layout.FLOOR_BOUND_LABELS` may straddle one (windows of adjacent faces share heights);
* ``entrance`` -- this face must carry exactly one ``door`` region, in its ground floor; all other faces none;
* ``corner_widths`` -- ``(left, right)`` strips at the face ends that stay wall so elements of the two faces at
  a corner never collide and corners meet with equal margins.

:func:`check_request` is the validator every kind and test uses.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from citygen.layout import FLOOR_BOUND_LABELS, FacadeLayout, remembered
from citygen.rng import derive_rng

#: The least storey height (metres) a scene or a preview command may ask for.
MIN_STOREY = 2.0


@dataclass(frozen=True)
class FaceContext:
    """Where a face sits: its building and neighbours, for ruleset conditions and coordination."""

    building_id: str
    face_index: int
    levels: int
    street_facing: bool | None = None
    corner_angles: tuple[float, float] = (90.0, 90.0)
    neighbours: tuple[int, int] = (-1, -1)
    is_courtyard: bool = False
    attributes: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class FacadeRequest:
    """Ask a generator for one facade of ``width x height`` metres under the building's constraints."""

    width: float
    height: float
    floor_lines: tuple[float, ...]
    entrance: bool = False
    corner_widths: tuple[float, float] = (0.0, 0.0)
    context: FaceContext = field(default_factory=lambda: FaceContext(building_id="preview", face_index=0, levels=1))
    seed: tuple[int, ...] = (0,)
    #: Seeds the choices that are the building's, not the face's (a split grammar's stochastic rules: shutters or
    #: none, which floors have balconies): the same on every face of a building, so its faces agree; empty: the
    #: face's own ``seed`` (a preview).
    style_seed: tuple[int | str, ...] = ()
    #: The scene's :class:`citygen.plausible.PlausibilityRules` a generator holds its candidates to (None: the
    #: defaults); set by the builder from the scene's ``[plausibility]`` table.
    plausibility: Any = field(default=None, compare=False)

    @property
    def floor_count(self) -> int:
        return len(self.floor_lines) - 1

    def floor_heights(self) -> np.ndarray:
        return np.diff(np.asarray(self.floor_lines, dtype=float))

    def rng(self, *salt: str | int) -> np.random.Generator:
        """A generator derived from this request's seed and optional salt (e.g. the plugin id)."""
        return derive_rng(*self.seed, *salt)

    def style_rng(self, *salt: str | int) -> np.random.Generator:
        """A generator of the building's choices (:attr:`style_seed`, else this face's seed) and optional salt."""
        return derive_rng(*(self.style_seed or self.seed), *salt)

    @classmethod
    def preview(cls, width: float, height: float, floor_height: float = 3.0, ground_height: float | None = None,
                entrance: bool = True, seed: int = 0) -> FacadeRequest:
        """A stand-alone request (used by ``citygen facade``): evenly spaced floors, optional taller ground."""
        return cls(width=width, height=height,
                   floor_lines=split_floors(height, floor_height, ground_height),
                   entrance=entrance,
                   context=FaceContext(building_id="preview", face_index=0,
                                       levels=len(split_floors(height, floor_height, ground_height)) - 1,
                                       street_facing=True),
                   seed=(seed,))


def split_floors(height: float, floor_height: float, ground_height: float | None = None) -> tuple[float, ...]:
    """Floor lines for a wall of ``height``: a ground floor, then floors close to ``floor_height``.

    The floor count is the nearest whole number; floors above the ground share the remaining height equally, so
    lines always end exactly at ``height``. A wall lower than one floor is one floor.
    """
    ground = floor_height if ground_height is None else ground_height
    for name, value in (("height", height), ("floor_height", floor_height), ("ground_height", ground)):
        if not 0 < value < math.inf:  # (NaN fails too)
            raise ValueError(f"{name} must be a positive finite number of metres, got {value}")
    if height < ground + 0.5 * floor_height:
        return (0.0, float(height))
    upper = max(1, round((height - ground) / floor_height))
    step = (height - ground) / upper
    return (0.0, *(float(ground + i * step) for i in range(upper)), float(height))


def check_request(layout: FacadeLayout, request: FacadeRequest, tol: float = 1e-6) -> list[str]:
    """Problems with ``layout`` as an answer to ``request``; empty when every constraint holds."""
    return remembered(layout, "request", (request, tol), lambda: _problems(layout, request, tol))


def _problems(layout: FacadeLayout, request: FacadeRequest, tol: float) -> list[str]:
    problems: list[str] = []
    eps = tol * max(request.width, request.height, 1.0)
    if abs(layout.width - request.width) > eps or abs(layout.height - request.height) > eps:
        problems.append(f"layout is {layout.width} x {layout.height}, request {request.width} x {request.height}")
    x, y, w, h = layout.leaf_rects.T
    door = layout.label_mask(lambda label: label == "door")
    bound = layout.label_mask(lambda label: label in FLOOR_BOUND_LABELS)
    lines = np.asarray(request.floor_lines[1:-1], dtype=float)
    high_door = door & (y > request.floor_lines[1] - eps) if request.floor_count > 1 else np.zeros_like(door)
    straddles = (lines > (y + eps)[:, None]) & (lines < (y + h - eps)[:, None])
    straddling = bound & straddles.any(axis=1)
    left, right = request.corner_widths
    cornered = bound & ((x < left - eps) | (x + w > request.width - right + eps))
    for i in np.flatnonzero(high_door | straddling | cornered).tolist():
        r = layout.leaves[i]
        if high_door[i]:
            problems.append(f"door {r.symbol} at y={r.y:.3f} is not in the ground floor")
        if straddling[i]:
            cut = lines[straddles[i]][0]
            problems.append(f"{r.label} {r.symbol} at y={r.y:.3f}..{r.y + r.h:.3f} straddles floor line {cut:.3f}")
        if cornered[i]:
            problems.append(f"{r.label} {r.symbol} at x={r.x:.3f}..{r.x + r.w:.3f} enters a corner strip")
    doors = int(door.sum())
    expected = 1 if request.entrance else 0
    if doors != expected:
        problems.append(f"face has {doors} doors, the building coordinator asked for {expected}")
    return problems
