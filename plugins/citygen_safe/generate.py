"""A facade for a FacadeRequest: floors by row jumps, width by column jumps, both sized by the QP.

Door budget: jumps never copy or remove the door. A face that must carry no entrance shows its doors as closed
wall panels (label ``wall``, depth 0); an entrance face keeps the input's door. Floor-bound elements are kept out
of the request's corner strips by inequality rows of the width QP.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from citygen.layout import FLOOR_BOUND_LABELS, FacadeLayout
from citygen.request import FacadeRequest, check_request
from citygen_safe.compose import to_layout
from citygen_safe.edit import Settings, Variation, pick, width_variations
from citygen_safe.floors import fit_floors
from citygen_safe.leaves import Facade
from citygen_safe.ruleset import SafeRuleset

PLUGIN_ID = "safe"


@dataclass(frozen=True)
class Edit:
    """The result of editing a ruleset's facade for one request: the chosen variation and what else was on offer."""

    layout: FacadeLayout
    chosen: Variation
    variations: tuple[Variation, ...]
    floor_jumps: tuple[str, ...]
    problems: tuple[str, ...]


def settings_for(ruleset: SafeRuleset, request: FacadeRequest | None = None) -> Settings:
    corners = request.corner_widths if request is not None else (0.0, 0.0)
    return Settings(ruleset.active, ruleset.alignment, ruleset.symmetry, corners=corners,
                    corner_labels=FLOOR_BOUND_LABELS if any(corners) else frozenset())


def edit(ruleset: SafeRuleset, request: FacadeRequest, limit: int = 8) -> Edit:
    settings = settings_for(ruleset, request)
    state, heights = fit_floors(ruleset.facade, settings, tuple(request.floor_lines))
    facade = heights.facade if heights.success else ruleset.facade
    variations = width_variations(facade, settings, request.width, limit)
    if not variations:
        variations = width_variations(facade, replace(settings, alignment=False, symmetry=False), request.width,
                                      limit)
    chosen = pick(variations, request.rng(PLUGIN_ID, ruleset.name)) if variations else Variation((), facade, 0.0)
    layout = _finish(chosen.facade, request, ruleset, chosen, [str(j) for j in state.jumps])
    return Edit(layout, chosen, tuple(variations), tuple(str(j) for j in state.jumps),
                tuple(check_request(layout, request)))


def _finish(facade: Facade, request: FacadeRequest, ruleset: SafeRuleset, chosen: Variation,
            floor_jumps: list[str]) -> FacadeLayout:
    if not request.entrance:
        leaves = tuple(replace(f, region=replace(f.region, label="wall", symbol="Wall", depth=0.0, asset=None))
                       if f.label == "door" else f for f in facade.leaves)
        facade = replace(facade, leaves=leaves)
    meta = {"kind": PLUGIN_ID, "ruleset": ruleset.name, "jumps": floor_jumps + [str(j) for j in chosen.jumps],
            "distortion": round(chosen.objective, 6)}
    if chosen.dropped:
        meta["dropped_constraints"] = list(chosen.dropped)
    return to_layout(facade, meta)
