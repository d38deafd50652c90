"""Choosing topological jumps for a target size (dang2014 §4-5, made non-interactive).

The paper proposes variations and lets the user pick. For a target width we try column counts around the one
the grid's pitch suggests (one fewer, that one, one more); each count is reached by jumps chosen greedily (a
small beam) among every source column at every position of every active grid (insertions) or every column
(removals), each candidate scored by the spatial optimisation's objective at the target width. The variations
are listed best first; a generator picks one of the near-best from the seed. Heights do the same with floors:
the request's floor count fixes how many floor bands (rows of openings) the facade must have.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from citygen_safe.grids import FacadeGrid, GridSpec, detect_grid
from citygen_safe.jump import Jump, insert_column, remove_column, source_columns
from citygen_safe.leaves import EPS, Facade
from citygen_safe.optimise import Lines, optimise_widths
from citygen_safe.tree import Node, decompose

BEAM = 1
NEAR_BEST = 1.05  #: variations within this factor of the least distortion are the generator's choices


@dataclass(frozen=True)
class Settings:
    """How an edit is solved: active grid specs, constraint switches, labels never duplicated or removed (the
    door, whose budget the building coordinator owns), corner strips and the labels kept out of them."""

    active: tuple[GridSpec, ...]
    alignment: bool = True
    symmetry: bool = True
    keep: frozenset[str] = frozenset({"door"})
    corners: tuple[float, float] = (0.0, 0.0)
    corner_labels: frozenset[str] = frozenset()


@dataclass(frozen=True)
class Variation:
    """A facade after ``jumps`` and the spatial optimisation, with its distortion E(x)."""

    jumps: tuple[Jump, ...]
    facade: Facade
    objective: float
    dropped: tuple[str, ...] = ()


def grids_of(facade: Facade, specs: Sequence[GridSpec]) -> list[FacadeGrid]:
    return [g for g in (detect_grid(facade, s) for s in specs) if g is not None]


def size(facade: Facade, settings: Settings, target: float, lines: Lines | None = None, root: Node | None = None):
    """The spatial optimisation of ``facade`` at width ``target`` (``lines`` refer to nodes of ``root``)."""
    return optimise_widths(facade, root or decompose(facade), grids_of(facade, settings.active), target, lines=lines,
                           corners=settings.corners, corner_labels=settings.corner_labels,
                           alignment=settings.alignment, symmetry=settings.symmetry)


def _holds(facade: Facade, slab: tuple[float, float], labels: frozenset[str]) -> bool:
    return any(f.label in labels and f.x < slab[1] - EPS and f.right > slab[0] + EPS for f in facade.leaves)


def _kept(facade: Facade, labels: frozenset[str]) -> int:
    return sum(1 for f in facade.leaves if f.label in labels)


def _column_jumps(facade: Facade, settings: Settings, grow: bool) -> list[tuple[Jump, Facade]]:
    """Every single jump of the active grids; none may duplicate or remove a kept label (the door)."""
    out = []
    kept = _kept(facade, settings.keep)
    for spec in settings.active:
        grid = detect_grid(facade, spec)
        if grid is None or len(grid.columns) < 2:
            continue
        if grow:
            candidates = [(Jump("insert", spec.name, "x", s, p), insert_column(facade, grid, s, p))
                          for s in source_columns(facade, grid) for p in range(1, len(grid.columns))]
        else:
            candidates = [(Jump("remove", spec.name, "x", c), remove_column(facade, grid, c))
                          for c in range(len(grid.columns))]
        out += [(j, new) for j, new in candidates if new is not None and _kept(new, settings.keep) == kept]
    return out


def pitch(facade: Facade, settings: Settings) -> float | None:
    """Mean distance between consecutive columns of the first active grid with two or more columns."""
    for grid in grids_of(facade, settings.active):
        if len(grid.columns) > 1:
            return (grid.columns[-1][0] - grid.columns[0][0]) / (len(grid.columns) - 1)
    return None


def width_variations(facade: Facade, settings: Settings, target: float, limit: int = 8) -> list[Variation]:
    """Variations of ``facade`` at width ``target``, least distortion first (ties by jump description)."""
    step = pitch(facade, settings)
    best_k = 0 if step is None else int(round((target - facade.width) / step))
    counts = sorted({best_k - 1, best_k, best_k + 1} if step is not None else {0})
    found: list[Variation] = []
    for k in counts:
        states = [Variation((), facade, 0.0)]
        for _ in range(abs(k)):
            scored = []
            for state in states:
                for jump, new in _column_jumps(state.facade, settings, grow=k > 0):
                    res = size(new, settings, target)
                    if res.success:
                        scored.append(Variation(state.jumps + (jump,), res.facade, res.objective, res.dropped))
            scored.sort(key=lambda v: (v.objective, [str(j) for j in v.jumps]))
            states = scored[:BEAM]
            if not states:
                break
        for state in states:
            if not state.jumps:
                res = size(facade, settings, target)
                if res.success:
                    found.append(Variation((), res.facade, res.objective, res.dropped))
            else:
                found.append(state)
    found.sort(key=lambda v: (v.objective, [str(j) for j in v.jumps]))
    unique, seen = [], set()
    for v in found:
        key = tuple(sorted((round(f.x, 6), round(f.w, 6), f.origin) for f in v.facade.leaves))
        if key not in seen:
            seen.add(key)
            unique.append(v)
    return unique[:limit]


def pick(variations: Sequence[Variation], rng: np.random.Generator) -> Variation:
    """One of the near-best variations (objective within NEAR_BEST of the least), chosen by ``rng``."""
    best = variations[0].objective
    near = [v for v in variations if v.objective <= best * NEAR_BEST + 1e-9]
    return near[int(rng.integers(len(near)))]
