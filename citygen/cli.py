"""The ``citygen`` command line: generate, validate, plugins, facade, plus sub-commands plugins register."""
from __future__ import annotations

import argparse
import contextlib
import json
import os
import signal
import sys
import threading
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

from citygen import __version__
from citygen.cliargs import add_size_arguments, seed, whole
from citygen.distributed import EXECUTORS
from citygen.errors import CitygenError
from citygen.layout import FacadeLayout, check_partition
from citygen.outpaths import check_writable, write_text
from citygen.plausible import DEFAULT_RULES, PlausibilityRules, check_plausible
from citygen.pipeline import generate_city, terminal_progress
from citygen.registry import Registry, default_registry
from citygen.request import FacadeRequest, check_request
from citygen.scene import load_scene


def _cmd_generate(args: argparse.Namespace, registry: Registry) -> int:
    scene = load_scene(args.scene, registry.roof_builders, registry.ruleset_kinds)
    if args.masses:
        scene = replace(scene, output=replace(scene.output, masses=True))
    jobs = args.jobs if args.jobs > 0 else (os.cpu_count() or 1)
    if args.scheduler and args.executor != "dask":
        raise CitygenError("--scheduler needs --executor dask", hint="add --executor dask")
    if args.report:
        check_writable(args.report, "report")
    report = generate_city(scene, seed=args.seed, out=Path(args.output) if args.output else None, jobs=jobs,
                           registry=registry, progress=None if args.quiet else terminal_progress,
                           executor=args.executor, scheduler=args.scheduler)
    print(report.summary())
    if args.report:
        write_text(args.report, json.dumps(report.to_dict(), indent=1) + "\n", "report")
        print(f"report: {args.report}")
    problems = [f"{len(report.skipped)} buildings skipped"] if report.skipped else []
    problems += ["no building written"] if not report.written else []
    if args.strict and problems:
        print(f"citygen: --strict: {' and '.join(problems)} (exit status 1)", file=sys.stderr)
        return 1
    return 0


def _cmd_validate(args: argparse.Namespace, registry: Registry) -> int:
    from citygen.usd.validate import validate_stage  # (UsdValidation and UsdGeom: only validating needs them)
    status = 0
    for stage in args.stages:
        findings = validate_stage(stage)
        errors = [f for f in findings if f.severity == "error"]
        for f in findings:
            if f.severity == "error" or args.verbose:
                print(f"{stage}: {f.severity}: {f.where}: {f.message}")
        print(f"{stage}: {'ok' if not errors else f'{len(errors)} errors'} "
              f"({len(findings) - len(errors)} warnings/infos)")
        status = status or (1 if errors else 0)
    return status


def _cmd_plugins(args: argparse.Namespace, registry: Registry) -> int:
    tables = (("ruleset kinds", registry.ruleset_kinds, "ruleset_kinds"),
              ("footprint importers", registry.importers, "importers"),
              ("roof builders", registry.roof_builders, "roof_builders"),
              ("commands", registry.commands, "commands"),
              ("layout sources", registry.layout_sources, "layout_sources"))
    for title, table, attr in tables:
        print(f"{title}:")
        for key, item in sorted(table.items()):
            origin = registry.origins[(attr, key)]
            extra = f" {' '.join(item.suffixes)}" if getattr(item, "suffixes", None) else ""
            desc = getattr(item, "description", "") or getattr(item, "help", "")
            print(f"  {key:<14}{extra:<22} {desc}  [{origin.plugin} from {origin.distribution}]")
    for name, problem in registry.broken:
        print(f"broken plugin {name}: {problem}")
    for warning in registry.warnings:
        print(f"warning: {warning}")
    return 0


#: ``citygen facade`` exit codes, worst first (README "Command line"): the outcome a caller got.
FACADE_EXIT = {"dressed": 0, "implausible": 3, "constraints-broken": 4, "fell-back": 5}


def facade_outcome(layout: FacadeLayout, request: FacadeRequest, rules: PlausibilityRules = DEFAULT_RULES
                   ) -> tuple[str, list[str]]:
    """What a preview got: ``fell-back`` (the generator could not dress the face: a plain wall), else
    ``constraints-broken`` (not a partition, or the request's floor lines / entrance / corners broken), else
    ``implausible`` (plausibility findings), else ``dressed``; and the lines that say why."""
    if layout.meta.get("fallback"):
        return "fell-back", [str(layout.meta["fallback"]), *layout.meta.get("findings", ())]
    problems = check_partition(layout) + check_request(layout, request)
    if problems:
        return "constraints-broken", problems
    findings = check_plausible(layout, request, rules)
    return ("implausible", [str(f) for f in findings]) if findings else ("dressed", [])


def _cmd_facade(args: argparse.Namespace, registry: Registry) -> int:
    path = Path(args.ruleset)
    kind = registry.ruleset_kind(args.kind) if args.kind else registry.kind_for_path(path)
    ruleset = kind.load(path)
    width, height = args.size
    request = FacadeRequest.preview(width, height, floor_height=args.floor_height, ground_height=args.ground_height,
                                    entrance=not args.no_entrance, seed=args.seed)
    layout = kind.generate(ruleset, request)
    outcome, reasons = facade_outcome(layout, request)
    if args.explain:
        print(kind.explain(ruleset, request))
    if args.json:
        print(layout.dumps())
    if args.png:
        kind.render_png(layout, Path(args.png), request.floor_lines[1:-1])
        print(f"wrote {args.png}", file=sys.stderr)
    if not (args.json or args.png or args.explain):
        counts: dict[str, int] = {}
        for r in layout.leaves:
            counts[r.label or "(transparent)"] = counts.get(r.label or "(transparent)", 0) + 1
        print(f"{path.name} [{kind.id}] {width} x {height} m: " + ", ".join(f"{v} {k}" for k, v in sorted(counts.items())))
    print(f"status: {outcome}", file=sys.stderr)
    for reason in reasons:
        print(f"  {reason}", file=sys.stderr)
    return FACADE_EXIT[outcome]


def build_parser(registry: Registry) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="citygen", description="Procedural cities from footprints, as USD.")
    parser.add_argument("--version", action="version", version=f"citygen {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    g = sub.add_parser("generate", help="generate a scene's city and write its USD stage")
    g.add_argument("scene", help="scene TOML file")
    g.add_argument("-o", "--output",
                   help="output path: a USD stage (.usda/.usdc/.usdz) or glTF (.glb/.gltf); default from the scene")
    g.add_argument("--seed", type=seed, help="override the scene seed (an integer from 0 to 2**31 - 1)")
    g.add_argument("--strict", action="store_true", help="exit non-zero when any building is skipped")
    g.add_argument("--masses", action="store_true",
                   help="masses only (LOD1: extruded walls and roofs, no facades), as [output] masses = true")
    g.add_argument("--jobs", type=whole(0), default=0,
                   help="worker processes (default 0: one per CPU core); the output does not depend on it")
    g.add_argument("--executor", choices=EXECUTORS, default="local",
                   help="local (default): worker processes on this machine; dask: one task per tile on a Dask "
                        "cluster, each tile its own layer written by its worker")
    g.add_argument("--scheduler", metavar="ADDRESS",
                   help="with --executor dask: the scheduler to use (e.g. tcp://host:8786); default: a local "
                        "cluster of --jobs workers")
    g.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    g.add_argument("--report", metavar="FILE.json",
                   help="also write the whole report as JSON: every skipped building (id, reason, where) and every "
                        "warning (the summary shows the first 20), the stage's figures, timings")
    g.set_defaults(run=_cmd_generate)
    v = sub.add_parser("validate", help="run UsdValidation and mesh topology checks on stages")
    v.add_argument("stages", nargs="+")
    v.add_argument("-v", "--verbose", action="store_true", help="also print warnings")
    v.set_defaults(run=_cmd_validate)
    p = sub.add_parser("plugins", help="list loaded plugins and what they register")
    p.set_defaults(run=_cmd_plugins)
    f = sub.add_parser("facade", help="preview one facade of a ruleset")
    f.add_argument("ruleset")
    add_size_arguments(f, floor_height=3.2, ground=True)
    f.add_argument("--kind", help="ruleset kind (default: from the file suffix)")
    f.add_argument("--json", action="store_true", help="print the FacadeLayout JSON")
    f.add_argument("--png", help="write a PNG drawing of the layout")
    f.add_argument("--explain", action="store_true", help="print how the layout was derived")
    f.add_argument("--seed", type=seed, default=0, help="random seed (0 to 2**31 - 1; default 0)")
    f.add_argument("--no-entrance", action="store_true", help="preview a face without the building's door")
    f.set_defaults(run=_cmd_facade)
    for name, command in sorted(registry.commands.items()):
        c = sub.add_parser(name, help=command.help)
        command.configure(c)
        c.set_defaults(run=lambda a, r, command=command: command.run(a, r))
    return parser


class Terminated(BaseException):
    """SIGTERM arrived: unwinds like Ctrl-C's KeyboardInterrupt, so temporary files and workers are cleaned up."""


def _terminate(signum: int, frame: object) -> None:
    raise Terminated(signum)


@contextlib.contextmanager
def _sigterm_unwinds() -> Iterator[None]:
    """While the command runs, SIGTERM raises :class:`Terminated` (in the main thread only: elsewhere it cannot)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def main(argv: list[str] | None = None) -> int:
    """Run one command. Exit status: 0 done; 1 done, but something is wrong with the result (``generate
    --strict`` with skipped buildings, ``validate`` errors); 2 an error, one ``citygen: error:`` line (bad input,
    an output that cannot be written); 3-5 ``facade``'s outcomes (:data:`FACADE_EXIT`); 130 Ctrl-C; 143 SIGTERM."""
    try:
        registry = default_registry()
    except CitygenError as exc:
        print(f"citygen: {exc}", file=sys.stderr)
        return 2
    args = build_parser(registry).parse_args(argv)
    if args.run is not _cmd_plugins:  # (which lists them on stdout)
        for name, problem in registry.broken:
            print(f"citygen: warning: broken plugin {name} not loaded: {problem}", file=sys.stderr)
        for warning in registry.warnings:
            print(f"citygen: warning: {warning}", file=sys.stderr)
    try:
        with _sigterm_unwinds():
            return int(args.run(args, registry) or 0)
    except CitygenError as exc:
        print(f"citygen: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        return 0
    except KeyboardInterrupt:
        print("citygen: interrupted", file=sys.stderr)
        return 130
    except Terminated:
        print("citygen: terminated (SIGTERM)", file=sys.stderr)
        return 143


if __name__ == "__main__":
    sys.exit(main())
