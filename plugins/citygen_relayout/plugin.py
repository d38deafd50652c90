"""citygen plugin: the ``relayout`` ruleset kind and the ``citygen relayout`` command."""
from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from citygen.cliargs import add_size_arguments, seconds, seed, whole
from citygen.errors import CitygenError
from citygen.hookspecs import hookimpl
from citygen.lastsolve import LastSolve
from citygen.layout import FacadeLayout
from citygen.preview import add_output_arguments, write_layouts
from citygen.registry import Command, Registry, RulesetKind
from citygen.request import FacadeRequest

if TYPE_CHECKING:  # (the models, their parser and search are imported on first use)
    from citygen_relayout.model import Model
    from citygen_relayout.search import RelayoutResult


def _solve_face(ruleset: Model, request: FacadeRequest) -> RelayoutResult:
    from citygen_relayout.building import solve_face
    return solve_face(ruleset, request)


class RelayoutKind(RulesetKind):
    id = "relayout"
    suffixes = (".relayout",)
    description = "relayout model (bao2013): constrained variations of one facade layout"

    def __init__(self) -> None:
        self._solve = LastSolve(_solve_face)  # (explain after generate: one solve)

    def load(self, path: Path) -> Model:
        from citygen_relayout.parser import load_model
        return load_model(path)

    def loads(self, text: str, path: Path) -> Model:
        from citygen_relayout.parser import parse_model
        return parse_model(text, str(path), base=path.parent)

    def generate(self, ruleset: Model, request: FacadeRequest) -> FacadeLayout:
        from citygen_relayout.building import face_layout
        return face_layout(self._solve(ruleset, request), request)

    def generate_building(self, ruleset: Model, requests: Sequence[FacadeRequest]) -> list[FacadeLayout]:
        from citygen_relayout.building import generate_building
        return generate_building(ruleset, requests)

    def explain(self, ruleset: Model, request: FacadeRequest) -> str:
        result = self._solve(ruleset, request)
        head = (f"relayout model {ruleset.name}: {len(ruleset.symbols)} symbols, {ruleset.terminal_count()} input "
                f"terminals, {sum(len(r.sequences) for r in ruleset.rules.values())} sequences, "
                f"{len(ruleset.alignments)} alignments, {len(ruleset.samesizes)} same-size constraints")
        if result.success:
            tail = (f"solved {request.width:g} x {request.height:g} in {result.seconds * 1000:.1f} ms: "
                    f"{len(result.layout.terminals())} terminals, {result.restarts} restarts, "
                    f"{result.backtracks} backtracks, {result.qp_calls} QPs")
        else:
            tail = f"failed: {result.message} (a fallback layout is used)"
        return f"{head}\n{tail}"


class RelayoutCommand(Command):
    name = "relayout"
    help = "print or draw variations of a relayout model for one size"

    def configure(self, parser: argparse.ArgumentParser) -> None:
        parser.add_argument("model", type=Path, help="a .relayout model file")
        add_size_arguments(parser)
        next(a for a in parser._actions if a.dest == "size").required = False  # not with --symbols
        parser.add_argument("--symbols", action="store_true",
                            help="list the model's symbols (its segmentation) with labels and sizes, then exit")
        parser.add_argument("--count", type=whole(1), default=1, help="variations (default 1)")
        parser.add_argument("--seed", type=seed, default=0, help="random seed (0 to 2**31 - 1; default 0)")
        parser.add_argument("--budget", type=seconds, default=10.0,
                            help="CPU-time safety limit per variation (s, default 10)")
        add_output_arguments(parser)

    def run(self, args: argparse.Namespace, registry: Registry) -> int:
        from citygen_relayout.api import variations
        from citygen_relayout.listing import symbol_lines
        from citygen_relayout.parser import load_model
        try:
            model = load_model(args.model)
        except CitygenError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        if args.symbols:
            print("\n".join(symbol_lines(model)))
            return 0
        if args.size is None:
            print("error: give --size W H (or --symbols)", file=sys.stderr)
            return 2
        width, height = args.size
        estimate = estimated_terminals(model, width, height)
        if estimate > PREVIEW_TERMINALS:
            print(f"error: {args.model}: at {width:g} x {height:g} m the model would lay out about {estimate:,.0f} "
                  f"terminals; a preview stops at {PREVIEW_TERMINALS:,} -- give a smaller --size", file=sys.stderr)
            return 2
        results = variations(model, width, height, args.count, seed=args.seed, budget_s=args.budget)
        layouts = [r.layout for r in results if r.success]
        for k, r in enumerate(results):
            if not r.success:
                print(f"variation {k}: {r.message}", file=sys.stderr)
        if not write_layouts(layouts, args.json, args.png):
            for k, r in enumerate(results):
                if r.success:
                    print(f"variation {k}: {len(r.layout.terminals())} terminals, {r.seconds * 1000:.1f} ms, "
                          f"{r.backtracks} backtracks, {r.restarts} restarts")
        return 0 if len(layouts) == len(results) else 1


#: Most terminals a ``citygen relayout`` preview lays out (a 1000 x 1000 m preview of a house-sized model needed
#: 950 MB and 50 s; 60k terminals take a few seconds).
PREVIEW_TERMINALS = 60_000


def estimated_terminals(model, width: float, height: float) -> float:
    """The model's input terminal count scaled by the face's area over the input's: what a variation lays out."""
    def count(name: str) -> int:
        symbol = model.symbols[name]
        return 1 if symbol.is_terminal else sum(count(c) for c in symbol.children)
    w0, h0 = model.symbols[model.root].extent
    return count(model.root) * (width * height) / max(w0 * h0, 1e-9)


@hookimpl
def citygen_ruleset_kinds() -> list[RulesetKind]:
    return [RelayoutKind()]


@hookimpl
def citygen_commands() -> list[Command]:
    return [RelayoutCommand()]
