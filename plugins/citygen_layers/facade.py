"""A facade from a layer stack (ilcik2015 §5): the solve per direction, its alternatives, the composed layout."""
from __future__ import annotations

from dataclasses import replace

from citygen.entrance import enforce_entrance
from citygen.gcpause import cyclic_gc_paused
from citygen.layout import FLOOR_BOUND_LABELS, FacadeLayout
from citygen.plausible import Finding, check_plausible, plain_wall, summary
from citygen.request import FacadeRequest
from citygen_layers.alternatives import Alternatives, blamed_axes, clear_solved
from citygen_layers.candidates import Candidate
from citygen_layers.compose import compose, conform, look
from citygen_layers.model import Pattern, Ruleset
from citygen_layers.parser import _symbols_of
from citygen_layers.solver import DirectionSolution, axis_solutions
from citygen_layers.words import Letter, pattern_counters


def _visible_symbols(ruleset: Ruleset, pattern: Pattern) -> list[Letter]:
    """Letters a pattern can produce visibly (substituted content, or any letter of a plain pattern)."""
    if pattern.substituted:
        names = set().union(*(_symbols_of(c) for c in pattern.substitutions.values()))
    else:
        names = _symbols_of(pattern.control)
    out = []
    for name in sorted(names):
        sym = ruleset.symbols.get(name)
        if sym is not None and not sym.transparent:
            out.append(Letter(name, sym.size or 0.0))
    return out


def _opening_bands(ruleset: Ruleset, axis: str, interval: tuple[float, float]):
    """Letters of ``axis`` words that make floor-bound shapes (windows, doors, ...) must stay in ``interval``."""

    def bands(candidate: Candidate) -> dict:
        out: dict = {}
        for layer in ruleset.layers:
            pattern = layer.x if axis == "x" else layer.y
            others = _visible_symbols(ruleset, ruleset.patterns[layer.y if axis == "x" else layer.x])
            key = (layer.groups[0 if axis == "x" else 1], pattern)
            bound: dict[Letter, bool] = {}     # a word repeats its letters
            for i, letter in enumerate(candidate.words[pattern]):
                if letter.transparent:
                    continue
                opening = bound.get(letter)
                if opening is None:
                    opening = bound[letter] = any(
                        lk.visible and lk.label in FLOOR_BOUND_LABELS
                        for lk in (look(ruleset, layer, *((letter, other) if axis == "x" else (other, letter)))
                                   for other in others))
                if opening:
                    out.setdefault(key, {})[i] = interval
        return out

    return bands


def _axis_counters(ruleset: Ruleset, axis: str) -> set[str]:
    return set().union(*(pattern_counters(ruleset.patterns[layer.x if axis == "x" else layer.y])
                         for layer in ruleset.layers))


def alternatives(ruleset: Ruleset, request: FacadeRequest, reuse: bool = True
                 ) -> tuple[Alternatives, Alternatives]:
    """Both directions' solutions for the request; with ``reuse`` a direction solved before in this process for
    the same ruleset, extent, floor lines, entrance (if the direction's patterns use it) and bands is kept."""
    left, right = request.corner_widths
    x_bands = _opening_bands(ruleset, "x", (left, request.width - right)) if left or right else None
    y_bands = _opening_bands(ruleset, "y", (0.0, request.height)) if len(request.floor_lines) > 2 else None
    door = {axis: request.entrance if "entrance" in _axis_counters(ruleset, axis) else None for axis in "xy"}
    x_key = (id(ruleset), "x", request.width, door["x"], (left, right) if x_bands else None)
    y_key = (id(ruleset), "y", request.height, request.floor_lines, door["y"], y_bands is not None)
    return (Alternatives(ruleset, x_key if reuse else None,
                         lambda: axis_solutions(ruleset, "x", request.width, (), request.entrance, x_bands)),
            Alternatives(ruleset, y_key if reuse else None,
                         lambda: axis_solutions(ruleset, "y", request.height, request.floor_lines, request.entrance,
                                                y_bands)))


def solve_request(ruleset: Ruleset, request: FacadeRequest, reuse: bool = True
                  ) -> tuple[DirectionSolution, DirectionSolution]:
    """The first solution of both directions (see :func:`alternatives`)."""
    xs, ys = alternatives(ruleset, request, reuse)
    return xs.get(0), ys.get(0)


#: Pairs of direction solutions a request tries before it gives up (each costs a composition and a check).
TRIES = 12


def _layout(ruleset: Ruleset, request: FacadeRequest, sx: DirectionSolution, sy: DirectionSolution
            ) -> FacadeLayout:
    diagnostics = [*sx.diagnostics, *sy.diagnostics]
    meta = {"kind": "layers", "ruleset": ruleset.source, "status": {"x": sx.status, "y": sy.status},
            "mu": {"x": sx.mu, "y": sy.mu}, "expansions": sx.expansions + sy.expansions,
            "counters": {**sx.candidate.env, **sy.candidate.env},
            "columns": {"x": {g: list(b) for g, b in sx.sizing.borders.items()},
                        "y": {g: list(b) for g, b in sy.sizing.borders.items()}}}
    layout, notes = conform(compose(ruleset, sx, sy, meta), request.floor_lines, request.corner_widths)
    layout, note = enforce_entrance(layout, request)  # e.g. a door the corner strips left no room for
    diagnostics += notes + ([note] if note else [])
    if diagnostics:
        layout = FacadeLayout(layout.width, layout.height, layout.root, {**layout.meta, "diagnostics": diagnostics})
    return layout


def _relaxed(solution: DirectionSolution) -> Finding:
    """A direction whose sizing broke the stack's own rules to fit (letters below a third of their size,
    synchronisation, bands or pins dropped: a best-effort squeeze) makes no plausible layout, whatever its sizes."""
    return Finding("relaxed-sizing", f"{solution.axis}: {solution.sizing.relaxed[-1]}")


@cyclic_gc_paused()
def generate(ruleset: Ruleset, request: FacadeRequest) -> FacadeLayout:
    """The layout of ``ruleset`` for ``request`` (see docs/layers.md for how requests bind the stack): the first
    pair of direction solutions whose layout :func:`citygen.plausible.check_plausible` accepts, advancing the
    direction(s) each layout's findings blame; a plain wall (with the entrance's door) and the findings when none is
    within ``TRIES``. With ``mirror building`` half of the buildings (by their style seed, every face alike) take
    the mirror image: the stack solved with the corner strips swapped, reflected left to right."""
    if takes_mirror_image(ruleset, request):
        layout = _generate(ruleset, swapped_corners(request))
        return layout.mirrored({**layout.meta, "mirrored": True})
    return _generate(ruleset, request)


def takes_mirror_image(ruleset: Ruleset, request: FacadeRequest) -> bool:
    """Whether the request's building takes the stack's mirror image (``mirror building``: half the buildings, by
    their style seed)."""
    return ruleset.mirror and request.style_rng("layers", "mirror").random() < 0.5


def swapped_corners(request: FacadeRequest) -> FacadeRequest:
    """The request a mirror image is solved for: its corner strips swapped."""
    return replace(request, corner_widths=request.corner_widths[::-1])


def _generate(ruleset: Ruleset, request: FacadeRequest) -> FacadeLayout:
    xs, ys = alternatives(ruleset, request)
    i = j = tries = 0
    first: tuple[FacadeLayout, list] | None = None
    while tries < TRIES:
        sx, sy = xs.get(i), ys.get(j)
        if sx is None or sy is None:
            break
        tries += 1
        layout = _layout(ruleset, request, sx, sy)
        squeezed = [s for s in (sx, sy) if s.sizing.relaxed]
        findings = [*map(_relaxed, squeezed), *check_plausible(layout, request)]
        if not findings:
            return layout if tries == 1 else replace(layout, meta={**layout.meta, "tries": tries})
        first = first or (layout, findings)
        axes = blamed_axes(findings[len(squeezed):]) | {s.axis for s in squeezed}
        i, j = i + ("x" in axes), j + ("y" in axes)
    layout, findings = first
    plain = plain_wall(request, f"no plausible layer-stack layout in {tries} tried: {summary(findings)}", findings,
                       kind="layers", ruleset=ruleset.source, status=layout.meta["status"],
                       diagnostics=layout.meta.get("diagnostics", []))
    return enforce_entrance(plain, request)[0]   # the request's contract holds on the plain wall too


__all__ = ["alternatives", "clear_solved", "generate", "solve_request", "swapped_corners", "takes_mirror_image"]
