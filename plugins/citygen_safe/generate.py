"""A facade for a FacadeRequest: floors by row jumps, width by column jumps, both sized by the QP.

Door budget: jumps never copy or remove the door. A face that must carry no entrance shows its doors as closed
wall panels (label ``wall``, depth 0); an entrance face keeps the input's door. Floor-bound elements are kept out
of the request's corner strips by inequality rows of the width QP.

Every call has a work budget (``Settings.budget``, nominal CPU seconds counted as leaves sized, so the output does
not depend on the machine): floor jumps stop at 40 % of it, column jumps at 80 %; a spent budget
means fewer jumps (the facade resized without jumps is always available) and a note in ``meta.diagnostics``.
When the edit cannot meet the request (a floor count no row jump reaches, an element in a corner strip, a door
outside the ground floor), the face falls back like the other kinds: a misplaced door becomes wall and
:func:`citygen.entrance.enforce_entrance` carves one; any other problem gives plain wall floors with the reason in
``meta.fallback`` (which the pipeline reports), again with a carved door on the entrance face.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from citygen.entrance import enforce_entrance
from citygen.layout import FLOOR_BOUND_LABELS, FacadeLayout, Region
from citygen.request import FacadeRequest, check_request
from citygen_safe.compose import to_layout
from citygen_safe.edit import Settings, Variation, pick, width_variations
from citygen_safe.floors import fit_floors
from citygen_safe.leaves import Facade
from citygen_safe.ruleset import SafeRuleset

PLUGIN_ID = "safe"
FLOORS_SHARE, JUMPS_SHARE = 0.4, 0.8  #: budget shares by which floor and column jumps stop (the rest: final QPs)
FLOOR_CACHE_SIZE = 32
_FLOOR_CACHE: dict[tuple, tuple] = {}


@dataclass(frozen=True)
class Edit:
    """The result of editing a ruleset's facade for one request: the chosen variation and what else was on offer,
    the diagnostics (budget cuts, repairs) and the request's problems left in ``layout`` (empty unless even the
    fallback could not meet it)."""

    layout: FacadeLayout
    chosen: Variation
    variations: tuple[Variation, ...]
    floor_jumps: tuple[str, ...]
    problems: tuple[str, ...]
    diagnostics: tuple[str, ...] = ()
    work: int = 0  # leaves sized by the spatial optimisation (the budget's unit), remembered floors included


def settings_for(ruleset: SafeRuleset, request: FacadeRequest | None = None) -> Settings:
    corners = request.corner_widths if request is not None else (0.0, 0.0)
    return Settings(ruleset.active, ruleset.alignment, ruleset.symmetry, corners=corners,
                    corner_labels=FLOOR_BOUND_LABELS if any(corners) else frozenset(), budget=ruleset.budget)


def edit(ruleset: SafeRuleset, request: FacadeRequest, limit: int = 8) -> Edit:
    settings = settings_for(ruleset, request)
    notes: list[str] = []
    path, heights, floor_notes = _floors(ruleset, settings, tuple(request.floor_lines),
                                         FLOORS_SHARE * settings.units)
    notes += floor_notes
    facade = heights.facade if heights.success else ruleset.facade
    deadline = JUMPS_SHARE * settings.units
    variations = width_variations(facade, settings, request.width, limit, deadline, notes)
    if not variations:
        variations = width_variations(facade, replace(settings, alignment=False, symmetry=False), request.width,
                                      limit, deadline, notes)
    floor_jumps = [str(j) for j in path.jumps]
    chosen = pick(variations, request.rng(PLUGIN_ID, ruleset.name)) if variations else Variation((), facade, 0.0)
    layout = _finish(chosen.facade, request, ruleset, chosen, floor_jumps)
    if not heights.success or not variations:
        notes.append("no feasible sizing")
    layout = _checked(layout, request, notes)
    return Edit(layout, chosen, tuple(variations), tuple(floor_jumps), tuple(check_request(layout, request)),
                tuple(notes), settings.work.spent)


def _floors(ruleset: SafeRuleset, settings: Settings, floor_lines: tuple[float, ...], deadline: float):
    """:func:`fit_floors`, remembered per ruleset and floor lines: the faces of a building share their floor lines
    (and floors ignore the corner strips), so only the first face computes the row jumps. A remembered result
    still charges the work it took, so a face's budget for column jumps does not depend on which faces the
    process (one of several workers) saw before."""
    key = (id(ruleset), floor_lines)
    hit = _FLOOR_CACHE.get(key)
    if hit is not None and hit[0] is ruleset:
        settings.work.spent += hit[4]
        return hit[1:4]
    notes: list[str] = []
    before = settings.work.spent
    path, heights = fit_floors(ruleset.facade, settings, floor_lines, deadline, notes)
    if len(_FLOOR_CACHE) >= FLOOR_CACHE_SIZE:
        _FLOOR_CACHE.pop(next(iter(_FLOOR_CACHE)))
    _FLOOR_CACHE[key] = (ruleset, path, heights, tuple(notes), settings.work.spent - before)
    return path, heights, tuple(notes)


def _checked(layout: FacadeLayout, request: FacadeRequest, notes: list[str]) -> FacadeLayout:
    """``layout`` if it meets ``request``, else repaired (door) or replaced by the fallback; notes in meta."""
    problems = check_request(layout, request) if layout.width > 0 else ["empty layout"]
    if any("door" not in p for p in problems) or "no feasible sizing" in notes:
        layout = fallback_layout(request, "; ".join(problems[:2] or notes[-1:]), layout.meta)
    elif problems:  # only the door: a misplaced one becomes wall, enforce_entrance carves one where it fits
        layout = replace(layout, root=_doors_to_wall(layout.root))
        notes.append(f"door turned into wall: {problems[0]}")
    layout, note = enforce_entrance(layout, request)
    if note:
        notes.append(note)
    if notes:
        layout = replace(layout, meta={**layout.meta, "diagnostics": list(notes)})
    return layout


def _doors_to_wall(region: Region) -> Region:
    if region.children:
        return replace(region, children=tuple(_doors_to_wall(c) for c in region.children))
    return replace(region, label="wall", symbol="Wall", depth=0.0, asset=None) if region.label == "door" else region


def fallback_layout(request: FacadeRequest, reason: str, meta: dict | None = None) -> FacadeLayout:
    """Plain wall, one region per floor (``enforce_entrance`` carves the door), with ``reason`` in meta."""
    lines = request.floor_lines
    bands = tuple(Region(0.0, y0, request.width, y1 - y0, "FallbackWall", "wall") for y0, y1 in zip(lines, lines[1:]))
    root = Region(0.0, 0.0, request.width, request.height, "Fallback", None, children=bands)
    return FacadeLayout(request.width, request.height, root,
                        meta={**(meta or {}), "kind": PLUGIN_ID, "fallback": reason})


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
