"""Curved walls: a run of narrow faces that turn a little at each corner is laid out as one facade.

A round or curved outline is drawn as many short edges (the Helsinki demo: 32 of 480 buildings with eight or more
faces under 2 m). Face by face, each is too narrow for a bay and stays a blank strip; as one facade of their summed
width, unrolled, the ruleset lays its bays across them, and each face takes its stretch of that layout
(:func:`facet_layouts`): a region that spans a corner is cut there, its two parts meeting at the crease.

:func:`face_runs` finds the runs (the coordinator), :func:`run_request` asks for a run's facade and
:func:`facet_layouts` hands it out to the faces (the builder).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from citygen.layout import FacadeLayout, Region
from citygen.mass import Face
from citygen.request import FacadeRequest

#: The most a run's outline may turn at a corner between two of its faces (degrees).
RUN_TURN = 25.0
#: A run's faces are all narrower than this (metres): wider faces take their own bays.
RUN_FACET = 3.0
#: An element's part narrower than this (metres) where a corner cuts it becomes wall: no sliver of a window.
MIN_PART = 0.05

_EPS = 1e-9


def face_runs(faces: Sequence[Face], joinable: np.ndarray) -> tuple[tuple[int, ...], ...]:
    """The runs of a building: chains, in ring order, of two or more ``joinable`` faces narrower than
    :data:`RUN_FACET` whose shared corners turn by at most :data:`RUN_TURN`. A ring that is one whole chain (a
    round building without an entrance on it) is one run starting at its first face."""
    by_index = {face.index: face for face in faces}

    def member(index: int) -> bool:
        return bool(joinable[index]) and by_index[index].width < RUN_FACET

    def joined(face: Face) -> bool:  # (to its right neighbour)
        return member(face.neighbours[1]) and abs(180.0 - face.corner_angles[1]) <= RUN_TURN

    runs, taken = [], set()
    starts = [f for f in faces
              if member(f.index) and not (member(f.neighbours[0]) and joined(by_index[f.neighbours[0]]))]
    begun = {f.index for f in starts}
    rings = [f for f in faces if member(f.index) and f.index not in begun]
    for face in starts + rings:  # (faces of a closed chain have no start: the ring's first face begins it)
        if face.index in taken:
            continue
        chain = [face.index]
        while joined(face) and face.neighbours[1] not in taken and face.neighbours[1] != chain[0]:
            face = by_index[face.neighbours[1]]
            chain.append(face.index)
        taken.update(chain)
        if len(chain) >= 2:
            runs.append(tuple(chain))
    return tuple(runs)


def run_request(members: Sequence[FacadeRequest]) -> FacadeRequest:
    """One facade for a run's faces (their requests in ring order): their summed width, the outer corners of the
    first and last face, no entrance (the coordinator keeps the entrance face out of runs), the first face's
    seed."""
    first, last = members[0], members[-1]
    context = replace(first.context, corner_angles=(first.context.corner_angles[0], last.context.corner_angles[1]),
                      neighbours=(first.context.neighbours[0], last.context.neighbours[1]))
    return replace(first, width=float(sum(m.width for m in members)), entrance=False, context=context,
                   corner_widths=(first.corner_widths[0], last.corner_widths[1]))


def grouped(requests: Sequence[FacadeRequest], runs: Sequence[tuple[int, ...]]
            ) -> tuple[list[FacadeRequest], list[tuple[FacadeRequest, ...]]]:
    """``requests`` (a building's, per face) with each run's faces asked for as one :func:`run_request`, in the
    place of the run's first face; and per request returned, the face requests it stands for."""
    by_face = {r.context.face_index: r for r in requests}
    first = {run[0]: run for run in runs if all(i in by_face for i in run)}
    inner = {i for run in first.values() for i in run[1:]}
    out, parts = [], []
    for request in requests:
        index = request.context.face_index
        if index in inner:
            continue
        members = tuple(by_face[i] for i in first[index]) if index in first else (request,)
        out.append(run_request(members) if len(members) > 1 else request)
        parts.append(members)
    return out, parts


def per_face(parts: Sequence[tuple[FacadeRequest, ...]], layouts: Sequence[FacadeLayout]
             ) -> list[tuple[FacadeRequest, FacadeLayout]]:
    """The layouts of :func:`grouped`'s requests handed back to the faces: a run's cut by :func:`facet_layouts`."""
    out: list[tuple[FacadeRequest, FacadeLayout]] = []
    for members, layout in zip(parts, layouts):
        if len(members) == 1:
            out.append((members[0], layout))
        else:
            out.extend(zip(members, facet_layouts(layout, [m.width for m in members])))
    return out


def facet_layouts(layout: FacadeLayout, widths: Sequence[float]) -> list[FacadeLayout]:
    """``layout`` (a run's facade) cut at its faces' corners: per face of ``widths`` (in order), its stretch as a
    layout of its own, with the run's meta. A region inside one stretch is moved there whole (its module key
    kept); one across a corner is cut in two, and a terminal part narrower than :data:`MIN_PART` becomes wall."""
    edges = np.concatenate(([0.0], np.cumsum(widths)))
    edges[-1] = layout.width
    out = []
    for a, b in zip(edges[:-1].tolist(), edges[1:].tolist()):
        root = _clipped(layout.root, a, b)
        out.append(FacadeLayout(width=b - a, height=layout.height, root=root, meta=dict(layout.meta)))
    return out


def _clipped(region: Region, a: float, b: float) -> Region | None:
    """``region``'s part in ``[a, b]``, moved so that ``a`` is 0; None if it has none."""
    x0, x1 = region.x, region.x + region.w
    if x1 <= a + _EPS or x0 >= b - _EPS:
        return None
    if x0 >= a - _EPS and x1 <= b + _EPS:
        return region.moved(-a, 0.0)
    lo, hi = max(x0, a), min(x1, b)
    children = tuple(c for c in (_clipped(child, a, b) for child in region.children) if c is not None)
    label, depth, asset = region.label, region.depth, region.asset
    material = region.material
    if not children and hi - lo < MIN_PART and label not in (None, "wall"):
        label, depth, asset, material = "wall", 0.0, None, None
    return Region.fast(lo - a, region.y, hi - lo, region.h, region.symbol, label=label, depth=depth,
                       material=material, asset=asset, layer=region.layer, children=children)
