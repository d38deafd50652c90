"""citygen plugin: the ``safe`` ruleset kind (dang2014) and the ``citygen edit`` command."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from citygen.cliargs import add_size_arguments, seed, whole
from citygen.errors import CitygenError
from citygen.hookspecs import hookimpl
from citygen.layout import FacadeLayout
from citygen.preview import add_output_arguments, write_layouts
from citygen.registry import Command, Registry, RulesetKind
from citygen.request import FacadeRequest
from citygen_safe.generate import edit
from citygen_safe.ruleset import SafeRuleset, load_ruleset


class SafeKind(RulesetKind):
    id = "safe"
    suffixes = (".safe",)
    description = "structure-aware facade editing (dang2014): grid row/column jumps + QP on one input layout"

    def load(self, path: Path) -> SafeRuleset:
        return load_ruleset(path)

    def generate(self, ruleset: SafeRuleset, request: FacadeRequest) -> FacadeLayout:
        return edit(ruleset, request).layout

    def explain(self, ruleset: SafeRuleset, request: FacadeRequest) -> str:
        result = edit(ruleset, request)
        lines = [f"safe ruleset {ruleset.name}: {len(ruleset.facade.leaves)} input leaves, grids "
                 f"{', '.join(g.name for g in ruleset.grids)}; active {', '.join(g.name for g in ruleset.active)}",
                 f"floors: {'; '.join(result.floor_jumps) or 'no jumps'}"]
        for k, v in enumerate(result.variations):
            mark = "*" if v is result.chosen else " "
            lines.append(f"{mark} variation {k}: E={v.objective:.4g} {'; '.join(map(str, v.jumps)) or 'resize only'}")
        lines += [f"note: {d}" for d in result.diagnostics] + [f"problem: {p}" for p in result.problems]
        return "\n".join(lines)


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
        from citygen_safe.generate import _finish
        try:
            ruleset = load_ruleset(args.ruleset)
        except CitygenError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        width, height = args.size
        request = FacadeRequest.preview(width, height, args.floor_height, entrance=not args.no_entrance,
                                        seed=args.seed)
        result = edit(ruleset, request, limit=args.count)
        layouts = [_finish(v.facade, request, ruleset, v, list(result.floor_jumps)) for v in result.variations]
        if not write_layouts(layouts, args.json, args.png):
            print(f"floors: {'; '.join(result.floor_jumps) or 'no jumps'}")
            for k, v in enumerate(result.variations):
                mark = "*" if v is result.chosen else " "
                print(f"{mark} variation {k}: E={v.objective:.4g}, {len(v.facade.leaves)} leaves: "
                      f"{'; '.join(map(str, v.jumps)) or 'resize only'}")
        return 0 if layouts else 1


@hookimpl
def citygen_ruleset_kinds() -> list[RulesetKind]:
    return [SafeKind()]


@hookimpl
def citygen_commands() -> list[Command]:
    return [EditCommand()]
