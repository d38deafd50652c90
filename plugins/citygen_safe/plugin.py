"""citygen plugin: the ``safe`` ruleset kind (dang2014) and the ``citygen edit`` command. The editing itself (and
SciPy and DAQP it needs) is imported on first use, so loading the plugin costs a city without SAFE rulesets
nothing."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from citygen.cliargs import add_size_arguments, seed, whole
from citygen.errors import CitygenError
from citygen.hookspecs import hookimpl
from citygen.lastsolve import LastSolve
from citygen.layout import FacadeLayout
from citygen.preview import add_output_arguments, write_layouts
from citygen.registry import Command, Registry, RulesetKind
from citygen.request import FacadeRequest
from citygen_safe.ruleset import SafeRuleset, load_ruleset, parse_ruleset

if TYPE_CHECKING:
    from citygen_safe.edit import Variation
    from citygen_safe.generate import Edit


def _edit(ruleset: SafeRuleset, request: FacadeRequest) -> Edit:
    from citygen_safe.generate import edit
    return edit(ruleset, request)


class SafeKind(RulesetKind):
    id = "safe"
    suffixes = (".safe",)
    description = "structure-aware facade editing (dang2014): grid row/column jumps + QP on one input layout"

    def __init__(self) -> None:
        self._edit = LastSolve(_edit)  # (explain after generate: one edit)

    def load(self, path: Path) -> SafeRuleset:
        return load_ruleset(path)

    def loads(self, text: str, path: Path) -> SafeRuleset:
        return parse_ruleset(text, str(path), base=path.parent)

    def generate(self, ruleset: SafeRuleset, request: FacadeRequest) -> FacadeLayout:
        return self._edit(ruleset, request).layout

    def explain(self, ruleset: SafeRuleset, request: FacadeRequest) -> str:
        result = self._edit(ruleset, request)
        lines = [f"safe ruleset {ruleset.name}: {len(ruleset.facade.leaves)} input leaves, grids "
                 f"{', '.join(g.name for g in ruleset.grids)}; active {', '.join(g.name for g in ruleset.active)}",
                 f"floors: {'; '.join(result.floor_jumps) or 'no jumps'}"]
        rejected = {id(v): f for v, f in result.rejected}
        checked = rejected.keys() | {id(v) for v, _ in result.plausible}
        for k, v in enumerate(result.variations):
            mark = "*" if v is result.chosen and not result.layout.meta.get("fallback") else " "
            lines.append(f"{mark} variation {k}: {_describe(v)}" + ("" if id(v) in checked else " (not checked)"))
            lines += [f"      implausible: {f}" for f in rejected.get(id(v), ())[:3]]
        lines += [f"note: {d}" for d in result.diagnostics] + [f"problem: {p}" for p in result.problems]
        return "\n".join(lines)


def _describe(v: Variation) -> str:
    """A variation on one line: its cost, E(x), first defects, leaf count and jumps."""
    defects = f", {len(v.defects)} defect(s): {'; '.join(v.defects[:2])}" if v.defects else ""
    return (f"cost {v.cost:.4g} (E={v.objective:.4g}{defects}), {len(v.facade.leaves)} leaves: "
            f"{'; '.join(map(str, v.jumps)) or 'resize only'}")


class EditCommand(Command):
    name = "edit"
    help = "list or write the K structure-aware variations (dang2014) of a .safe ruleset for one size"

    def configure(self, parser: argparse.ArgumentParser) -> None:
        parser.add_argument("ruleset", type=Path, help="a .safe ruleset file")
        add_size_arguments(parser, floor_height=3.0)
        parser.add_argument("--count", type=whole(1), default=4, help="K, the number of variations (default 4)")
        parser.add_argument("--seed", type=seed, default=0, help="random seed (0 to 2**31 - 1; default 0)")
        parser.add_argument("--no-entrance", action="store_true", help="the face carries no door")
        add_output_arguments(parser)

    def run(self, args: argparse.Namespace, registry: Registry) -> int:
        from citygen_safe.generate import edit
        try:
            ruleset = load_ruleset(args.ruleset)
        except CitygenError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        width, height = args.size
        request = FacadeRequest.preview(width, height, args.floor_height, entrance=not args.no_entrance,
                                        seed=args.seed)
        result = edit(ruleset, request, limit=args.count, wanted=args.count)
        shown = result.plausible[:args.count]
        if not write_layouts([layout for _, layout in shown], args.json, args.png):
            print(f"floors: {'; '.join(result.floor_jumps) or 'no jumps'}")
            for k, (v, _) in enumerate(shown):
                print(f"{'*' if v is result.chosen else ' '} variation {k}: {_describe(v)}")
        if len(shown) < args.count:
            print(shortfall(result, args.count), file=sys.stderr)
        return 0 if shown else 1


def shortfall(result: Edit, count: int) -> str:
    """Why fewer than ``count`` variations were listed: how many distinct ones the edit found, how many of them
    were implausible (with the first finding) and the fallback reason when none was plausible."""
    text = (f"{len(result.plausible)} of {count} variations: the edit found {len(result.variations)} distinct "
            f"layout(s) at this size")
    if result.rejected:
        text += f", {len(result.rejected)} implausible (first: {result.rejected[0][1][0]})"
    if not result.plausible:
        text += f"; the face falls back: {result.layout.meta.get('fallback', '')}"
    return text


@hookimpl
def citygen_ruleset_kinds() -> list[RulesetKind]:
    return [SafeKind()]


@hookimpl
def citygen_commands() -> list[Command]:
    return [EditCommand()]
