"""A facade for a FacadeRequest: floors by row jumps, width by column jumps, both sized by the QP.

Door budget: jumps never copy or remove the door. A face that must carry no entrance shows its doors as closed
wall panels (label ``wall``, depth 0); an entrance face keeps the input's door. Floor-bound elements are kept out
of the request's corner strips by inequality rows of the width QP.

Every call has a work budget (``Settings.budget``, nominal CPU seconds counted as leaves sized, so the output does
not depend on the machine): floor jumps stop at 40 % of it, column jumps at 80 %; a spent budget
means fewer jumps (the facade resized without jumps is always available) and a note in ``meta.diagnostics``.
Every variation is dressed (a misplaced door becomes wall and :func:`citygen.entrance.enforce_entrance` carves
one) and held to the request and :func:`citygen.plausible.check_plausible`; the generator picks among the near-best
plausible ones. When none is (a floor count no row jump reaches, an element in a corner strip, no sizing with
every element at its least plausible size), the face falls back like the other kinds: plain wall floors with the
reason in ``meta.fallback`` and the findings in ``meta.findings`` (which the pipeline reports), again with a
carved door on the entrance face.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from citygen.entrance import enforce_entrance
from citygen.layout import FLOOR_BOUND_LABELS, FacadeLayout, Region, check_partition
from citygen.plausible import PlausibilityRules, check_plausible
from citygen.request import FacadeRequest, check_request
from citygen_safe.compose import to_layout
from citygen_safe.edit import NEAR_BEST, Settings, Variation, pick, width_variations
from citygen_safe.floors import fit_floors
from citygen_safe.leaves import Facade
from citygen_safe.memory import Memory
from citygen_safe.rank import is_centred
from citygen_safe.ruleset import SafeRuleset

PLUGIN_ID = "safe"
FLOORS_SHARE, JUMPS_SHARE = 0.4, 0.8  #: budget shares by which floor and column jumps stop (the rest: final QPs)
GENERATE_LIMIT = 4  #: variations wanted by the generator (column counts within 2 of the pitch's, see spread)
CENTRE = frozenset({"door"})  #: labels kept centred when the input has them centred (with ``symmetry on``)
#: floor jumps and height QP results with the work they took, by what they use (32 of them)
FLOORS: Memory[tuple] = Memory(32)


@dataclass(frozen=True)
class Edit:
    """The result of editing a ruleset's facade for one request: the chosen variation and what else was on offer
    (``variations``, least cost first; ``plausible``: those whose dressed layout passed
    :func:`citygen.plausible.check_plausible` and the request, with that layout; ``rejected``: the others with
    their findings), the diagnostics (budget cuts, repairs) and the request's problems left in ``layout`` (empty
    unless even the fallback could not meet it)."""

    layout: FacadeLayout
    chosen: Variation
    variations: tuple[Variation, ...]
    floor_jumps: tuple[str, ...]
    problems: tuple[str, ...]
    diagnostics: tuple[str, ...] = ()
    work: int = 0  # leaves sized by the spatial optimisation (the budget's unit), remembered floors included
    plausible: tuple[tuple[Variation, FacadeLayout], ...] = ()
    rejected: tuple[tuple[Variation, tuple[str, ...]], ...] = ()


def settings_for(ruleset: SafeRuleset, request: FacadeRequest | None = None) -> Settings:
    corners = request.corner_widths if request is not None else (0.0, 0.0)
    return Settings(ruleset.active, ruleset.alignment, ruleset.symmetry, corners=corners,
                    corner_labels=FLOOR_BOUND_LABELS if any(corners) else frozenset(), budget=ruleset.budget,
                    centre=CENTRE if ruleset.symmetry and is_centred(ruleset.facade, CENTRE) else frozenset())


def edit(ruleset: SafeRuleset, request: FacadeRequest, limit: int = GENERATE_LIMIT, wanted: int = 1) -> Edit:
    """Floors, then the width variations for ``limit`` wanted (:func:`width_variations`), least cost first, each
    dressed and held to the plausibility rules and the request until ``wanted`` plausible ones and all within
    ``NEAR_BEST`` of the best are found; the generator's choice among the near-best plausible ones, or the fallback
    (plain wall floors, ``meta["fallback"]`` and ``meta["findings"]``) when none is."""
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
    plausible: list[tuple[Variation, FacadeLayout]] = []
    rejected: list[tuple[Variation, tuple[str, ...]]] = []
    if heights.success:
        for v in variations:  # least cost first: dressed until ``wanted`` plausible ones and the near-best are in
            if len(plausible) >= wanted and v.cost > NEAR_BEST * plausible[0][0].cost + 1e-9:
                break
            layout, repairs = _dressed(v, request, ruleset, floor_jumps)
            findings = _findings(layout, request, settings.rules)
            if findings:
                rejected.append((v, tuple(findings)))
            else:
                plausible.append((v, _noted(layout, notes + repairs)))
    if plausible:
        chosen = pick([v for v, _ in plausible], request.rng(PLUGIN_ID, ruleset.name))
        layout = next(lay for v, lay in plausible if v is chosen)
    else:
        chosen = variations[0] if variations else Variation((), facade, 0.0)
        findings = rejected[0][1] if rejected else ()
        reason = (f"no plausible variation of {len(variations)}: {'; '.join(findings[:3])}" if rejected
                  else "no feasible sizing of the " + ("widths" if heights.success else "floors")
                  + " with every element at its least plausible size" + (f" ({notes[-1]})" if notes else ""))
        meta = {"kind": PLUGIN_ID, "ruleset": ruleset.name, "findings": list(findings)}
        layout, note = enforce_entrance(fallback_layout(request, reason, meta), request)
        layout = _noted(layout, notes + ([note] if note else []))
    return Edit(layout, chosen, tuple(variations), tuple(floor_jumps), tuple(check_request(layout, request)),
                tuple(layout.meta.get("diagnostics", ())), settings.work.spent, tuple(plausible), tuple(rejected))


def _floors(ruleset: SafeRuleset, settings: Settings, floor_lines: tuple[float, ...], deadline: float):
    """:func:`fit_floors`, remembered by what it depends on (the input facade, the settings that reach the height
    problem, the floor lines): the faces of a building share their floor lines (and floors ignore the corner
    strips), so only the first face computes the row jumps, and a ruleset text edited in the studio without
    touching its layout or grids parses to an equal facade and finds them too. A remembered result still charges
    the work it took, so a face's budget for column jumps does not depend on which faces the process (one of
    several workers) saw before."""
    key = (ruleset.facade, settings.active, settings.alignment, settings.symmetry, settings.keep, settings.centre,
           settings.budget, id(settings.rules), floor_lines)  # (the rules: always the module's DEFAULT_RULES)
    hit = FLOORS.lookup(key)
    if hit is not None:
        settings.work.spent += hit[3]
        return hit[:3]
    notes: list[str] = []
    before = settings.work.spent
    path, heights = fit_floors(ruleset.facade, settings, floor_lines, deadline, notes)
    FLOORS.remember(key, (path, heights, tuple(notes), settings.work.spent - before), 1)
    return path, heights, tuple(notes)


def _dressed(variation: Variation, request: FacadeRequest, ruleset: SafeRuleset, floor_jumps: list[str]
             ) -> tuple[FacadeLayout, list[str]]:
    """The layout of ``variation`` as the face shows it: a door the request cannot take becomes wall and
    :func:`enforce_entrance` carves one where it fits; the repairs made."""
    layout = _finish(variation.facade, request, ruleset, variation, floor_jumps)
    repairs = []
    problems = check_request(layout, request)
    if problems and all("door" in p for p in problems):
        layout = replace(layout, root=_doors_to_wall(layout.root))
        repairs.append(f"door turned into wall: {problems[0]}")
    layout, note = enforce_entrance(layout, request)
    return layout, repairs + ([note] if note else [])


def _findings(layout: FacadeLayout, request: FacadeRequest, rules: PlausibilityRules) -> list[str]:
    """What keeps ``layout`` from dressing ``request``: broken partition or request, then plausibility findings."""
    broken = check_partition(layout) + check_request(layout, request)
    return broken or [str(f) for f in check_plausible(layout, request, rules)]


def _noted(layout: FacadeLayout, notes: list[str]) -> FacadeLayout:
    return replace(layout, meta={**layout.meta, "diagnostics": list(notes)}) if notes else layout


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
