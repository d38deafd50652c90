"""One face of a building as the city gets it: the building coordinator's requests (floor lines, entrance face,
corner strips, seeds; :func:`citygen.coordinator.plan_building`, as the builder makes them) and a ruleset's layout
for one of them, coupled with the building's other faces where the ruleset kind couples faces, and cut from its
curved wall's facade where it is one face of such a run."""
from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from citygen.coordinator import face_bins, plan_building
from citygen.entrance import enforce_entrance
from citygen.footprints import Footprint
from citygen.layout import FacadeLayout
from citygen.mass import Mass
from citygen.plausible import check_plausible, summary
from citygen.registry import RulesetKind
from citygen.request import FacadeRequest
from citygen.runs import facet_layouts, grouped
from citygen.scene import Scene


class FaceRequests(dict):
    """The coordinator's request of every dressed face of a building by face index (``dict[int, FacadeRequest]``),
    and its curved walls' ``runs`` (:mod:`citygen.runs`)."""

    def __init__(self, requests: dict[int, FacadeRequest], runs: tuple[tuple[int, ...], ...]) -> None:
        super().__init__(requests)
        self.runs = runs


def face_requests(scene: Scene, footprint: Footprint, mass: Mass, cover: np.ndarray) -> FaceRequests:
    """The request of every dressed face of the building by face index, with the scene's plausibility rules (what
    :class:`citygen.builder.Builder` hands the ruleset kinds), and its runs."""
    plan = plan_building(footprint, mass, face_bins(cover), scene.defaults, scene.seed)
    return FaceRequests({r.context.face_index: replace(r, plausibility=scene.plausibility) for r in plan.requests},
                        plan.runs)


def face_layout(kind: RulesetKind, ruleset: Any, requests: FaceRequests, face: int
                ) -> tuple[FacadeLayout, FacadeLayout, FacadeRequest]:
    """The layout ``kind`` gives face ``face`` as the builder asks for it: alone, or, for a kind that couples a
    building's faces (its own ``generate_building``), with the faces on the same side (street or courtyard) of the
    building; a face of a curved wall's run gets its stretch of the run's facade. Also the layout and request the
    city judges for plausibility: the run's, or the face's own."""
    request = requests[face]
    side = [r for r in requests.values() if r.context.is_courtyard == request.context.is_courtyard]
    asked, parts = grouped(side, requests.runs)
    k = next(i for i, members in enumerate(parts) if any(m.context.face_index == face for m in members))
    if type(kind).generate_building is RulesetKind.generate_building:
        judged = kind.generate(ruleset, asked[k])
    else:
        judged = kind.generate_building(ruleset, asked)[k]
    members = parts[k]
    if len(members) == 1:
        return judged, judged, asked[k]
    cut = facet_layouts(judged, [m.width for m in members])
    return cut[[m.context.face_index for m in members].index(face)], judged, asked[k]


def city_problems(layout: FacadeLayout, request: FacadeRequest) -> list[str]:
    """What the builder will do to this layout: a ruleset that fell back, or findings that make the face a plain wall
    (or the scene's fallback ruleset's)."""
    if layout.meta.get("fallback"):
        return [f"the ruleset falls back on this face: {layout.meta['fallback']}"]
    findings = check_plausible(enforce_entrance(layout, request)[0], request, request.plausibility)
    return [f"the city gives this face a plain wall (or the fallback ruleset): {summary(findings)}"] if findings else []


def request_data(request: FacadeRequest) -> dict[str, Any]:
    """What the browser shows of a face's request."""
    return {"width": request.width, "height": request.height, "floor_lines": list(request.floor_lines),
            "entrance": request.entrance, "corner_widths": list(request.corner_widths),
            "courtyard": request.context.is_courtyard, "street_facing": request.context.street_facing}
