"""Floors of an edited facade: the request's floor count by row jumps, its floor lines as QP constraints.

A *floor band* is a maximal y range of overlapping openings (windows, doors): a ground floor's tall windows and
the transom over its door are one band. To reach the request's floor count, bands are inserted (a copy of a
band with the content between two bands, as a row insertion of §4; a single band is copied with the content
between it and the top or bottom of the face, the boundary standing in for the missing anchor band) or removed,
greedily as the columns are (the height mismatch ranks the jumps, the QP scores the finalists); the band holding
the door is never copied or removed. Each floor line then pins the lowest-cost full-width cut between two bands
(the cut whose scaled position is nearest the line).
"""
from __future__ import annotations

from dataclasses import replace

from citygen_safe.edit import Candidate, Path, Settings, greedy_step, size
from citygen_safe.jump import Jump, boundary_gaps, insert_slab, merge_leaves, remove_slab
from citygen_safe.leaves import EPS, Facade, transpose
from citygen_safe.optimise import Lines, SpatialResult
from citygen_safe.tree import Node

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


def band_candidates(facade: Facade) -> tuple[list[Candidate], list[Candidate]]:
    """Row jumps of the floor bands of the transposed ``facade``: (insertions, removals)."""
    bands = floor_bands(facade)
    middle = 0.5 * facade.width
    grow, shrink = [], []
    for s, band in enumerate(bands):
        gaps = ([(p, (bands[p - 1][1], max(bands[p - 1][1], bands[p][0]))) for p in range(1, len(bands))]
                if len(bands) > 1 else boundary_gaps(band, facade.width))
        for p, gap in gaps:
            grow.append(Candidate(Jump("insert", "floors", "y", s, p), gap[1] - gap[0] + band[1] - band[0],
                                  abs(gap[0] - middle), (gap, band),
                                  lambda m, gap=gap, band=band: insert_slab(facade, gap, band, m)))
        if len(bands) > 1:
            slab = (band[0], bands[s + 1][0]) if s < len(bands) - 1 else (bands[s - 1][1], band[1])
            shrink.append(Candidate(Jump("remove", "floors", "y", s), slab[0] - slab[1],
                                    abs(0.5 * (slab[0] + slab[1]) - middle), (slab,),
                                    lambda m, slab=slab: remove_slab(facade, slab)))
    return grow, shrink


def fit_floors(facade: Facade, settings: Settings, floor_lines: tuple[float, ...], deadline: float = float("inf"),
               notes: list[str] | None = None) -> tuple[Path, SpatialResult]:
    """Jump ``facade`` (upright) to the request's floor count and size its heights to ``floor_lines``.

    Returns the jumped path (transposed, natural sizes) and the height QP's result (its facade is upright).
    A count that cannot be reached (no band to copy or remove) or a spent work budget (``deadline``, in leaves
    sized) is noted in ``notes``."""
    notes = notes if notes is not None else []
    settings = replace(settings, corners=(0.0, 0.0), corner_labels=frozenset())  # corner strips are widths
    target = floor_lines[-1]
    path = Path(*merge_leaves(transpose(facade), settings.fixed))
    want = len(floor_lines) - 1
    while len(floor_bands(path.facade)) != want and floor_bands(path.facade):
        if settings.work.spent > deadline:
            notes.append(f"budget {settings.budget:g} s spent at {len(floor_bands(path.facade))} of {want} floors")
            break
        grow, shrink = band_candidates(path.facade)
        have = len(floor_bands(path.facade))
        nxt = greedy_step(path, grow if have < want else shrink, settings, target, deadline, max(1, want - have))
        if nxt is None:
            notes.append(f"{len(floor_bands(path.facade))} floor bands, no row jump reaches {want} floors")
            break
        path = nxt[0]
    res = size(path.facade, settings, target, _floor_cuts(path.facade, path.root, floor_lines), path.root)
    if not res.success:
        res = size(path.facade, settings, target, root=path.root)
    return path, replace(res, facade=transpose(res.facade))


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
