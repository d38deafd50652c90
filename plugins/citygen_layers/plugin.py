"""The ``layers`` ruleset kind: registers the layer-stack generator with citygen."""
from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable
from pathlib import Path

from citygen.entrance import enforce_entrance
from citygen.gcpause import cyclic_gc_paused
from citygen.hookspecs import hookimpl
from citygen.layout import FLOOR_BOUND_LABELS, FacadeLayout
from citygen.registry import RulesetKind
from citygen.request import FacadeRequest
from citygen_layers.candidates import Candidate
from citygen_layers.compose import compose, conform, look
from citygen_layers.explain import explain_text
from citygen_layers.model import Pattern, Ruleset
from citygen_layers.parser import _symbols_of, load, parse
from citygen_layers.solver import DirectionSolution, solve_axis
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


#: Solved directions kept per process, most recently used last: the faces of a building share their height and
#: floor lines (so their vertical solve), opposite faces often their width. A solve is deterministic, so a kept
#: solution is exactly what solving again would return; solves cut by the CPU-time limit are not kept.
_SOLVED: OrderedDict[tuple, tuple[Ruleset, DirectionSolution]] = OrderedDict()
KEEP_SOLVED = 256


def clear_solved() -> None:
    """Forget the kept direction solutions (benchmarks of cold solves, tests of the solver itself)."""
    _SOLVED.clear()


def _reused(ruleset: Ruleset, key: tuple, solve: Callable[[], DirectionSolution]) -> DirectionSolution:
    key = (id(ruleset), *key)
    kept = _SOLVED.get(key)
    if kept is not None and kept[0] is ruleset:
        _SOLVED.move_to_end(key)
        return kept[1]
    solution = solve()
    if not solution.timed_out:
        _SOLVED[key] = (ruleset, solution)
        if len(_SOLVED) > KEEP_SOLVED:
            _SOLVED.popitem(last=False)
    return solution


def _axis_counters(ruleset: Ruleset, axis: str) -> set[str]:
    return set().union(*(pattern_counters(ruleset.patterns[layer.x if axis == "x" else layer.y])
                         for layer in ruleset.layers))


def solve_request(ruleset: Ruleset, request: FacadeRequest, reuse: bool = True
                  ) -> tuple[DirectionSolution, DirectionSolution]:
    """Both directions of the request; with ``reuse`` a direction solved before in this process for the same
    ruleset, extent, floor lines, entrance (if the direction's patterns use it) and bands is taken again."""
    left, right = request.corner_widths
    x_bands = _opening_bands(ruleset, "x", (left, request.width - right)) if left or right else None
    y_bands = _opening_bands(ruleset, "y", (0.0, request.height)) if len(request.floor_lines) > 2 else None

    def x() -> DirectionSolution:
        return solve_axis(ruleset, "x", request.width, (), request.entrance, x_bands)

    def y() -> DirectionSolution:
        return solve_axis(ruleset, "y", request.height, request.floor_lines, request.entrance, y_bands)

    if not reuse:
        return x(), y()
    door = {axis: request.entrance if "entrance" in _axis_counters(ruleset, axis) else None for axis in "xy"}
    return (_reused(ruleset, ("x", request.width, door["x"], (left, right) if x_bands else None), x),
            _reused(ruleset, ("y", request.height, request.floor_lines, door["y"], y_bands is not None), y))


@cyclic_gc_paused()
def generate(ruleset: Ruleset, request: FacadeRequest) -> FacadeLayout:
    """The layout of ``ruleset`` for ``request`` (see docs/layers.md for how requests bind the stack)."""
    sx, sy = solve_request(ruleset, request)
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


class LayersKind(RulesetKind):
    id = "layers"
    suffixes = (".layers",)
    description = "layer stacks of horizontal x vertical patterns, aligned and sized automatically (ilcik2015)"

    def render_png(self, layout, path, floor_lines=()):
        """Layers back to front with the alignment columns of the solve."""
        from citygen_layers.preview import render
        render(layout, path)

    def load(self, path: Path) -> Ruleset:
        return load(path)

    def loads(self, text: str, path: Path) -> Ruleset:
        return parse(text, str(path))

    def generate(self, ruleset: Ruleset, request: FacadeRequest) -> FacadeLayout:
        return generate(ruleset, request)

    def explain(self, ruleset: Ruleset, request: FacadeRequest) -> str:
        sx, sy = solve_request(ruleset, request)
        return explain_text(ruleset, sx, sy)


@hookimpl
def citygen_ruleset_kinds() -> list[RulesetKind]:
    return [LayersKind()]
