"""``.safe`` ruleset files: one input layout, its general grids and which of them are active.

    # comment
    safe NAME                       first statement: the ruleset's name
    layout "PATH"                   the input FacadeLayout JSON (relative to the ruleset file)
    relabel LABEL NEW               the input's LABEL terminals read as NEW (an import's mislabelled class)
    grid NAME LABEL...              a general grid of every leaf with one of the labels
    active NAME...                  grids whose columns/rows topological jumps insert or remove
    alignment on|off                alignment constraints C_a (default on)
    symmetry on|off                 same-size constraints C_s (default on)
    budget SECONDS                  work per generated facade in nominal CPU seconds (default 2; counted, not timed)

Without ``grid`` statements the grids are detected from labels (``window``, ``door``, ``window+door``, ...);
without ``active`` the ``window`` grid is active. Errors name file:line:column and what was expected.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, replace
from pathlib import Path

from citygen.errors import CitygenError, ParseError, SourceLocation, read_user_text
from citygen.layout import FacadeLayout, check_partition
from citygen_safe.grids import GridSpec, auto_specs
from citygen_safe.leaves import Facade, facade_from_layout

BUDGET_S = 2.0  #: default budget per generated facade, in nominal CPU seconds

_TOKEN = re.compile(r'\s*(?:(#.*)|"([^"]*)"|([^\s"#]+)|(")|$)')


@dataclass(frozen=True)
class SafeRuleset:
    """A parsed ``.safe`` file: the input facade, its grid specs, the active ones, the constraint switches and the
    work budget per facade (nominal CPU seconds, see ``citygen_safe.edit.LEAVES_PER_SECOND``)."""

    name: str
    source: str
    facade: Facade
    grids: tuple[GridSpec, ...]
    active: tuple[GridSpec, ...]
    alignment: bool = True
    symmetry: bool = True
    budget: float = BUDGET_S


def load_ruleset(path: Path | str) -> SafeRuleset:
    path = Path(path)
    return parse_ruleset(read_user_text(path, ParseError, "ruleset"), str(path), base=path.parent)


def _tokens(line: str, source: str, lineno: int) -> list[tuple[str, int]]:
    out, pos = [], 0
    while pos < len(line):
        m = _TOKEN.match(line, pos)
        if m.group(4):
            raise ParseError("unterminated string", where=SourceLocation(source, lineno, m.start(4) + 1),
                             hint='close it with "')
        if m.group(1) is not None or m.end() == pos:
            break
        text = m.group(2) if m.group(2) is not None else m.group(3)
        if text is not None:
            out.append((text, m.start(2) if m.group(2) is not None else m.start(3) + 1))  # a string: its quote
        pos = m.end()
    return out


def parse_ruleset(text: str, source: str = "<safe>", base: Path | None = None) -> SafeRuleset:
    base = base or Path(".")
    name = layout = None
    grids: dict[str, GridSpec] = {}
    active: list[tuple[str, int, int]] = []
    relabels: dict[str, tuple[str, SourceLocation]] = {}
    switches = {"alignment": True, "symmetry": True}
    budget = BUDGET_S
    last = (1, 1)
    for lineno, line in enumerate(text.splitlines(), 1):
        toks = _tokens(line, source, lineno)
        if not toks:
            continue
        (head, col), args = toks[0], toks[1:]
        last = (lineno, col)
        where = SourceLocation(source, lineno, col)

        def need(count: str, ok: bool) -> None:
            if not ok:
                at = SourceLocation(source, lineno, args[-1][1] if args else len(line) + 1)
                raise ParseError(f"'{head}' expects {count}", where=at)

        if name is None and head != "safe":
            raise ParseError(f"expected 'safe NAME' first, found '{head}'", where=where)
        if head == "safe":
            need("one name", len(args) == 1 and name is None)
            name = args[0][0]
        elif head == "layout":
            need('one quoted path', len(args) == 1)
            layout = (args[0][0], SourceLocation(source, lineno, args[0][1]))
        elif head == "grid":
            need("a name and one or more labels", len(args) >= 2)
            if args[0][0] in grids:
                raise ParseError(f"grid '{args[0][0]}' defined twice", where=SourceLocation(source, lineno, args[0][1]))
            grids[args[0][0]] = GridSpec(args[0][0], tuple(a for a, _ in args[1:]))
        elif head == "relabel":
            need("a label and its new label", len(args) == 2)
            if args[0][0] in relabels:
                raise ParseError(f"label '{args[0][0]}' relabelled twice",
                                 where=SourceLocation(source, lineno, args[0][1]))
            relabels[args[0][0]] = (args[1][0], SourceLocation(source, lineno, args[0][1]))
        elif head == "active":
            need("one or more grid names", len(args) >= 1)
            active += [(a, lineno, c) for a, c in args]
        elif head == "budget":
            need("a positive number of seconds", len(args) == 1 and _positive(args[0][0]))
            budget = float(args[0][0])
        elif head in switches:
            need("on or off", len(args) == 1 and args[0][0] in ("on", "off"))
            switches[head] = args[0][0] == "on"
        else:
            raise ParseError(f"unknown statement '{head}'", where=where,
                             hint="expected one of safe, layout, relabel, grid, active, alignment, symmetry, budget")
    if name is None:
        raise ParseError("empty ruleset", where=SourceLocation(source, 1, 1), hint="start with 'safe NAME'")
    if layout is None:
        raise ParseError("no 'layout' statement", where=SourceLocation(source, *last),
                         hint='add layout "FILE.layout.json"')
    try:
        lay = FacadeLayout.loads((base / layout[0]).read_text(encoding="utf-8"), str(base / layout[0]))
    except OSError as exc:
        raise ParseError(f"cannot read layout {layout[0]!r}: {exc.strerror}", where=layout[1]) from exc
    except ValueError as exc:  # a NUL in the path, or not UTF-8
        raise ParseError(f"cannot read layout {layout[0]!r}: {exc}", where=layout[1],
                         hint="name a UTF-8 FacadeLayout JSON file") from exc
    except CitygenError as exc:
        raise ParseError(f"layout {layout[0]!r} is invalid: {exc}", where=layout[1]) from exc
    problems = check_partition(lay)
    if problems:  # (was accepted: the editing then moved overlapping or gapped regions)
        raise ParseError(f"layout {layout[0]!r} is not a partition: {problems[0]}", where=layout[1],
                         hint="its terminal regions must cover the facade exactly once (docs/layout-json.md)")
    facade = facade_from_layout(_relabelled(lay, relabels))
    specs = grids or {s.name: s for s in auto_specs(facade)}
    for grid_name, lineno, col in active:
        if grid_name not in specs:
            raise ParseError(f"unknown grid '{grid_name}'", where=SourceLocation(source, lineno, col),
                             hint="grids: " + ", ".join(sorted(specs)))
    chosen = tuple(specs[a] for a, _, _ in active) or tuple(s for s in specs.values() if s.name == "window")
    return SafeRuleset(name, source, facade, tuple(specs.values()), chosen, switches["alignment"],
                       switches["symmetry"], budget)


def _relabelled(layout: FacadeLayout, relabels: dict[str, tuple[str, SourceLocation]]) -> FacadeLayout:
    """``layout`` with each relabelled label's terminals carrying the new label (and a symbol named after it)."""
    present = {r.label for r in layout.leaves}
    for old, (_, where) in relabels.items():
        if old not in present:
            raise ParseError(f"relabel: the layout has no '{old}' terminal", where=where,
                             hint="labels in the layout: " + ", ".join(sorted(str(x) for x in present if x)))

    def visit(region):
        if region.children:
            return replace(region, children=tuple(visit(c) for c in region.children))
        if region.label in relabels:
            new = relabels[region.label][0]
            return replace(region, label=new, symbol=new.capitalize())
        return region

    return replace(layout, root=visit(layout.root)) if relabels else layout


def _positive(text: str) -> bool:
    try:
        return 0.0 < float(text) < float("inf")
    except ValueError:
        return False
