"""Floors of an edited facade: the request's floor count by row jumps, its floor lines as QP constraints.

A *floor band* is a maximal y range of overlapping openings (windows, doors): a ground floor's tall windows and
the transom over its door are one band. To reach the request's floor count, bands are inserted (a copy of an
upper band with the content between two bands, as a row insertion of §4) or removed, greedily by least height
distortion; the band holding the door is never copied or removed. Each floor line then pins the lowest-cost
full-width cut between two bands (the cut whose scaled position is nearest the line).
"""
from __future__ import annotations

from dataclasses import replace

from citygen_safe.edit import Settings, Variation, _kept, size
from citygen_safe.jump import Jump, insert_slab, remove_slab
from citygen_safe.leaves import EPS, Facade, transpose
from citygen_safe.optimise import Lines, SpatialResult
from citygen_safe.tree import Node, decompose

OPENINGS = frozenset({"window", "door"})


def floor_bands(facade: Facade) -> list[tuple[float, float]]:
    """Bands (as x ranges of the transposed ``facade``) of overlapping openings, in increasing order."""
    spans = sorted((f.x, f.right) for f in facade.leaves if f.label in OPENINGS and f.w > EPS)
    bands: list[tuple[float, float]] = []
    for lo, hi in spans:
        if bands and lo < bands[-1][1] - EPS:
            bands[-1] = (bands[-1][0], max(bands[-1][1], hi))
        else:
            bands.append((lo, hi))
    return bands


def _band_jumps(facade: Facade, settings: Settings, grow: bool) -> list[tuple[Jump, Facade]]:
    bands = floor_bands(facade)
    kept = _kept(facade, settings.keep)
    out = []
    for s, band in enumerate(bands):
        if grow:
            for p in range(1, len(bands)):
                gap = (bands[p - 1][1], max(bands[p - 1][1], bands[p][0]))
                out.append((Jump("insert", "floors", "y", s, p), insert_slab(facade, gap, band)))
        elif len(bands) > 1:
            slab = (band[0], bands[s + 1][0]) if s < len(bands) - 1 else (bands[s - 1][1], band[1])
            out.append((Jump("remove", "floors", "y", s), remove_slab(facade, slab)))
    return [(j, f) for j, f in out if _kept(f, settings.keep) == kept]


def fit_floors(facade: Facade, settings: Settings, floor_lines: tuple[float, ...]) -> tuple[Variation, SpatialResult]:
    """Jump ``facade`` (upright) to the request's floor count and size its heights to ``floor_lines``.

    Returns the jumped variation (transposed) and the height QP's result (its facade is upright)."""
    t = transpose(facade)
    target = floor_lines[-1]
    state = Variation((), t, 0.0)
    want = len(floor_lines) - 1
    while len(floor_bands(state.facade)) != want and floor_bands(state.facade):
        grow = len(floor_bands(state.facade)) < want
        scored = []
        for jump, new in _band_jumps(state.facade, settings, grow):
            res = size(new, settings, target)
            if res.success:
                scored.append(Variation(state.jumps + (jump,), new, res.objective))
        if not scored:
            break
        state = min(scored, key=lambda v: (v.objective, [str(j) for j in v.jumps]))
    root = decompose(state.facade)
    res = size(state.facade, settings, target, _floor_cuts(state.facade, root, floor_lines), root)
    if not res.success:
        res = size(state.facade, settings, target)
    return state, replace(res, facade=transpose(res.facade))


def _floor_cuts(t: Facade, root: Node, floor_lines: tuple[float, ...]) -> Lines | None:
    """Full-width cuts of the transposed facade ``t`` pinned to the floor lines, one between each two bands."""
    bands = floor_bands(t)
    if len(bands) != len(floor_lines) - 1:
        return None
    if root.split != "x":
        return None
    scale = floor_lines[-1] / t.width
    nodes, at = [], []
    for k in range(1, len(bands)):
        cuts = [c for c in root.children[1:] if bands[k - 1][1] - EPS <= c.x <= bands[k][0] + EPS]
        if cuts:
            nodes.append(min(cuts, key=lambda c: (abs(c.x * scale - floor_lines[k]), c.x)))
            at.append(floor_lines[k])
    return Lines(tuple(nodes), tuple(at)) if nodes else None
