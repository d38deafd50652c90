"""CLI: ``citygen layout import-cmp`` (and the layout sources other plugins register, e.g. ``from-photo``) and
``citygen grammar extract|cost``."""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from citygen.cliargs import seed
from citygen.errors import CitygenError, LayoutError, read_user_text
from citygen.outpaths import write_text as write_output
from citygen.registry import Command, Registry, default_registry


def write_text(path: str | None, text: str) -> None:
    """Write ``text`` to ``path`` atomically with ordinary permissions (:func:`citygen.outpaths.write_text`;
    stdout when ``path`` is None or -)."""
    if path in (None, "-"):
        sys.stdout.write(text)
        return
    write_output(path, text, "output")


def report(exc: Exception) -> int:
    """Print ``exc`` as one ``error:`` line naming the file (no traceback); exit status 2."""
    if isinstance(exc, FileNotFoundError):
        print(f"error: {exc.filename}: no such file", file=sys.stderr)
    elif isinstance(exc, IsADirectoryError):
        print(f"error: {exc.filename}: is a directory, expected a file", file=sys.stderr)
    else:
        print(f"error: {exc}", file=sys.stderr)
    return 2


def check_degenerate(xml: str) -> None:
    """Refuse CMP objects of zero width or height (cmp_b0284 has one) naming file and object."""
    from citygen_inverse.cmp import _find_labels, parse_cmp_xml
    path = Path(xml)
    labels = _find_labels(path)
    for x0, x1, y0, y1, label, order in parse_cmp_xml(read_user_text(path, LayoutError, "CMP annotation"), xml,
                                                      labels):
        if x0 == x1 or y0 == y1:
            raise LayoutError(f"object {order} ({labels[label][0]}) is a zero-size box "
                              f"(x {x0:g}..{x1:g}, y {y0:g}..{y1:g})", where=xml,
                              hint="fix the annotation or pass --drop-degenerate to drop such boxes")


class LayoutCommand(Command):
    name = "layout"
    help = "layout tools: import annotated facades (and, through plugins, facade photos) as FacadeLayout JSON"

    def configure(self, parser: argparse.ArgumentParser) -> None:
        sub = parser.add_subparsers(dest="layout_command", required=True)
        cmp = sub.add_parser("import-cmp", help="CMP facade annotation (XML) -> layout JSON")
        cmp.add_argument("xml", help="CMP annotation file (*.xml)")
        cmp.add_argument("--png", help="label map of the photo (default: the .png beside the XML)")
        scale = cmp.add_mutually_exclusive_group()
        scale.add_argument("--width", type=float, help="facade width in metres")
        scale.add_argument("--floor-height", type=float, default=3.0,
                           help="metres per row of windows/doors/shops (default 3.0)")
        cmp.add_argument("--drop-degenerate", action="store_true",
                         help="drop zero-size boxes instead of refusing the annotation")
        for flag, default, what in (("--snap", 0.01, "edges this close are one line"),
                                    ("--align", 0.025, "same-side edges of one label this close are aligned"),
                                    ("--equal-sizes", 0.03, "sizes of one label this close are made equal")):
            cmp.add_argument(flag, type=float, default=default,
                             help=f"regularisation (wu2014 §3.3): {what}; share of the facade size "
                                  f"(default {default:g}), capped by the element scale")
        cmp.add_argument("--no-element-caps", action="store_true",
                         help="do not cap the tolerances at shares of the median window size")
        cmp.add_argument("-o", "--output", help="output JSON file (default stdout)")
        for source in sorted(default_registry().layout_sources.values(), key=lambda source: source.name):
            source.configure(sub.add_parser(source.name, help=source.help))

    def run(self, args: argparse.Namespace, registry: Registry) -> int:
        if args.layout_command != "import-cmp":
            return default_registry().layout_sources[args.layout_command].run(args)
        from citygen_inverse.cmp import ELEMENT_SHARE, import_cmp
        for name in ("snap", "align", "equal_sizes"):
            value = getattr(args, name)
            if not 0 <= value < 0.5:
                return report(LayoutError(f"--{name.replace('_', '-')} must be a share of the facade size in "
                                          f"[0, 0.5), got {value:g}", where=args.xml))
        try:
            if not args.drop_degenerate:
                check_degenerate(args.xml)
            layout = import_cmp(args.xml, png=args.png, width=args.width, floor_height=args.floor_height,
                                snap=args.snap, align=args.align, regularize=args.equal_sizes,
                                element_share=None if args.no_element_caps else ELEMENT_SHARE)
        except (CitygenError, OSError) as exc:
            return report(exc)
        write_text(args.output, layout.dumps() + "\n")
        meta = layout.meta
        print(f"{args.xml}: {len(layout.terminals())} terminals, {layout.width:.2f} x {layout.height:.2f} m "
              f"({meta['scale_from']}), {meta['pinwheel_blocks']} pinwheel blocks, "
              f"{100 * meta['annotation_agreement']['element_pixels']:.0f} % of the annotated element pixels kept",
              file=sys.stderr)
        return 0


def _cost_options(parser: argparse.ArgumentParser) -> None:
    """wu2014 Eq. 2's operator costs (each rule also costs its number of successors)."""
    parser.add_argument("--split-cost", type=float, default=0.1, help="cost of a split rule, >= 0 (default 0.1)")
    parser.add_argument("--repeat-cost", type=float, default=0.5, help="cost of a repeat rule, >= 0 (default 0.5)")


def verified(text: str, layouts: list, paths: list[str]) -> str:
    """Check that an exact grammar regenerates its layout (a joint grammar: each layout from its own facade
    symbol); a mismatch is a bug, reported as an error."""
    from citygen_inverse.verify import joint_mismatches, mismatches
    found = [mismatches(text, layouts[0])] if len(layouts) == 1 else joint_mismatches(text, layouts)
    for problems, path in zip(found, paths):
        if problems:
            raise CitygenError("the extracted grammar does not regenerate the layout: " + "; ".join(problems),
                               where=path, hint="this is a bug in citygen: please report it with the layout file")
    return "exact: re-derived" if len(layouts) == 1 else f"exact: all {len(layouts)} facades re-derived"


class GrammarCommand(Command):
    name = "grammar"
    help = "extract a split grammar from a layout (wu2014) or score a grammar file"

    def configure(self, parser: argparse.ArgumentParser) -> None:
        sub = parser.add_subparsers(dest="grammar_command", required=True)
        ext = sub.add_parser("extract", help="layout JSON -> grammar in citygen's DSL")
        ext.add_argument("layouts", nargs="+", help="layout JSON file(s); several give one joint grammar")
        ext.add_argument("--method", choices=("greedy", "is", "adp", "exact"), default="adp",
                         help="search (wu2014 §4): greedy by the splitting heuristic, importance sampling or "
                              "approximate dynamic programming (default adp); exact: adp, then the cheapest grammar "
                              "over the same candidate rules as an integer program (HiGHS), with a lower bound")
        ext.add_argument("--iterations", type=int, default=2000,
                         help="grammars built by is / adp / exact, at least 1 (default 2000; greedy builds one)")
        ext.add_argument("--seed", type=seed, default=0, help="random seed of is / adp / exact (default 0)")
        ext.add_argument("--time-limit", type=float, default=None,
                         help="seconds after which is / adp stop iterating and exact's integer program stops "
                              "(default: none; exact's program stops after 20 s)")
        _cost_options(ext)
        ext.add_argument("--size-independent", action="store_true",
                         help="a grammar for any face: floor slabs on the building's floor lines, a door on entrance "
                              "faces, alignment kept (wu2014 §5, Fig. 12); one layout only")
        ext.add_argument("-o", "--output", help="grammar file (default stdout)")
        cost = sub.add_parser("cost", help="wu2014 Eq. 1-2 cost of a grammar file")
        cost.add_argument("grammar", help="grammar file in citygen's DSL (extracted or hand-written)")
        _cost_options(cost)

    def run(self, args: argparse.Namespace, registry: Registry) -> int:
        where = args.grammar if args.grammar_command == "cost" else args.layouts[0]
        bad = [f"--{name.replace('_', '-')} must be a finite number >= 0, got {getattr(args, name):g}"
               for name in ("split_cost", "repeat_cost") if not 0 <= getattr(args, name) < float("inf")]
        if args.grammar_command == "extract" and args.method != "greedy" and args.iterations < 1:
            bad.append(f"--iterations must be at least 1, got {args.iterations}")
        if args.grammar_command == "extract" and args.time_limit is not None and not 0 < args.time_limit < math.inf:
            bad.append(f"--time-limit must be a number of seconds > 0, got {args.time_limit:g}")
        if bad:
            return report(CitygenError("; ".join(bad), where=where))
        try:
            return self._extract(args) if args.grammar_command == "extract" else self._cost(args)
        except (CitygenError, OSError) as exc:
            return report(exc)

    def _extract(self, args: argparse.Namespace) -> int:
        from citygen.layout import FacadeLayout, check_partition
        from citygen_inverse.actions import CostModel
        from citygen_inverse.extract import extract_grammar
        from citygen_inverse.independent import extract_size_independent
        layouts = [FacadeLayout.loads(read_user_text(Path(p), LayoutError, "layout"), p) for p in args.layouts]
        for path, layout in zip(args.layouts, layouts):
            problems = check_partition(layout)
            if problems:
                raise LayoutError("not a partition: " + "; ".join(problems[:3]), where=path,
                                  hint="grammar extraction needs terminals that tile the facade exactly")
        model = CostModel(split=args.split_cost, repeat=args.repeat_cost)
        if args.size_independent:
            if len(layouts) > 1:
                raise LayoutError("--size-independent takes one layout", where=args.layouts[1],
                                  hint="extract a joint grammar without --size-independent")
            command = " ".join(["citygen grammar extract", Path(args.layouts[0]).name, "--method", args.method,
                                "--iterations", str(args.iterations), "--seed", str(args.seed),
                                "--size-independent"])
            result = extract_size_independent(layouts[0], args.method, args.iterations, args.seed, model,
                                              args.time_limit, header=(f"made by: {command}",))
            check = ""
        else:
            result = extract_grammar(layouts, args.method, args.iterations, args.seed, model, args.time_limit)
            check = "  " + verified(result.text, layouts, args.layouts)
            if result.verdict():
                check += f"  {result.verdict()}"
        write_text(args.output, result.text)
        print(f"cost {result.cost:.2f}  rules {result.rules}  terminals {result.terminals}  "
              f"time {result.seconds:.3f} s  ({result.method}, {result.iterations} iterations){check}",
              file=sys.stderr)
        return 0

    def _cost(self, args: argparse.Namespace) -> int:
        import citygen_split
        grammar = citygen_split.load(Path(args.grammar))
        cost = citygen_split.grammar_cost(grammar, args.split_cost, args.repeat_cost)
        rules = sum(1 for r in grammar.rules if type(r.body).__name__ != "Terminal")
        print(f"cost {cost:.2f}  rules {rules}")
        return 0
