"""Faces of one building (bao2013 §9.1): request constraints and cross-face coupling.

A request's floor lines become floor constraints (regions holding openings stay within one floor), its
``entrance`` a door budget (exactly one door region on that face, in the ground floor; none elsewhere, where
door-bearing regions are pruned and door-only frequency minimums relaxed), its corner widths corner strips.
Across faces, ``samesize ... across`` references are shared: the first face solved fixes them for the others
(the entrance face goes first). A face that cannot be relayouted gets a plain fallback layout that still meets
the request, and the failure is recorded in its ``meta``. Every layout is held to
:func:`citygen.plausible.check_plausible` for its request inside the search (an implausible one is not a solution:
the search restarts); when none is found, the fallback's ``meta["findings"]`` lists what the last one had.
"""
from __future__ import annotations

from collections.abc import Sequence

from citygen.layout import FacadeLayout, Region
from citygen.plausible import check_plausible
from citygen.request import FacadeRequest
from citygen_relayout.api import relayout
from citygen_relayout.model import Model
from citygen_relayout.search import Constraints, RelayoutResult

PLUGIN_ID = "relayout"


def solve_face(model: Model, request: FacadeRequest, shared: dict | None = None,
               budget_s: float = 10.0, backtrack_budget: int = 6000) -> RelayoutResult:
    constraints = Constraints(floor_lines=tuple(request.floor_lines), corners=tuple(request.corner_widths),
                              doors=1 if request.entrance else 0, shared=shared, key_salt=tuple(request.seed))
    return relayout(model, request.width, request.height, rng=request.rng(PLUGIN_ID, model.name),
                    constraints=constraints, budget_s=budget_s, backtrack_budget=backtrack_budget,
                    judge=lambda layout: check_plausible(layout, request))


def generate_face(model: Model, request: FacadeRequest, shared: dict | None = None) -> FacadeLayout:
    return face_layout(solve_face(model, request, shared), request)


def face_layout(result: RelayoutResult, request: FacadeRequest) -> FacadeLayout:
    """The layout of a face's solve: the relayout, or the fallback when the search failed."""
    if result.success:
        return result.layout
    return fallback_layout(request, result.message, outside_range=result.status == "infeasible",
                           findings=result.findings)


def generate_building(model: Model, requests: Sequence[FacadeRequest]) -> list[FacadeLayout]:
    shared: dict = {}
    order = sorted(range(len(requests)), key=lambda i: (not requests[i].entrance, i))
    out: dict[int, FacadeLayout] = {}
    for i in order:
        out[i] = generate_face(model, requests[i], shared)
    return [out[i] for i in range(len(requests))]


def fallback_layout(request: FacadeRequest, reason: str, outside_range: bool = False,
                    findings: Sequence = ()) -> FacadeLayout:
    """Wall bands per floor, with a door centred between the corner strips on an entrance face. ``outside_range``:
    the face's size lies outside every size the model can take (``meta["outside_range"]``; the pipeline reports
    such faces once per building); ``findings``: what the last complete layout had (``meta["findings"]``)."""
    w, h = request.width, request.height
    lines = list(request.floor_lines)
    bands = []
    for k, (y0, y1) in enumerate(zip(lines, lines[1:])):
        if k == 0 and request.entrance:
            bands.append(_door_band(request, y0, y1 - y0))
        else:
            bands.append(Region(0.0, y0, w, y1 - y0, "FallbackWall", "wall"))
    root = Region(0.0, 0.0, w, h, "Fallback", None, children=tuple(bands))
    meta = {"kind": PLUGIN_ID, "fallback": reason, "findings": [str(f) for f in findings],
            **({"outside_range": True} if outside_range else {})}
    return FacadeLayout(w, h, root, meta=meta)


def _door_band(request: FacadeRequest, y: float, fh: float) -> Region:
    w = request.width
    left, right = request.corner_widths
    avail = max(w - left - right, 0.0)
    dw = min(1.2, 0.8 * avail)
    dh = min(2.2, 0.9 * fh)
    x0 = left + 0.5 * (avail - dw)
    column = Region(x0, y, dw, fh, "FallbackEntry", None, children=(
        Region(x0, y, dw, dh, "FallbackDoor", "door", -0.2),
        Region(x0, y + dh, dw, fh - dh, "FallbackWall", "wall")))
    return Region(0.0, y, w, fh, "FallbackGround", None, children=(
        Region(0.0, y, x0, fh, "FallbackWall", "wall"), column,
        Region(x0 + dw, y, w - x0 - dw, fh, "FallbackWall", "wall")))
