"""Plausible derivations: a derivation that gives an implausible layout tries the grammar's alternatives.

A grammar has choice points: a ``case`` whose later branches also hold (``else`` last), a ``repeat`` /
``repeatABA`` that could place fewer tiles, a stochastic rule's other alternatives. :func:`derive_plausible`
derives with the first alternative everywhere (the plain semantics of docs/grammar.md); when the layout has
plausibility findings (:func:`citygen.plausible.check_plausible`) or breaks the request
(:func:`citygen.request.check_request`), it walks from each offending terminal up to the root and advances the
deepest choice point on that path that has alternatives left (one fewer tile, the next holding branch, ...), and
derives again, within a budget of derivations. A move is kept when it makes the layout better (fewer request
problems, else fewer offending terminals); else the point's next alternatives are tried (the next three and its
last, e.g. the fewest tiles), and a point none of whose alternatives helps is left for the next point up. Choice points
are keyed by symbol and region size, so regions that derive alike keep deriving alike (a row of equal bays stays
equal). If no layout within the budget is plausible, the result is :func:`citygen.plausible.plain_wall` with the
findings of the best one, and the building's fallback chain takes over. So is a face too large for the grammar's
sizes (:class:`~citygen_split.derive.FaceTooLarge`: a ``too-large`` finding), as soon as its first derivation
passes :data:`~citygen_split.derive.MAX_REGIONS`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from citygen.entrance import enforce_entrance
from citygen.layout import FacadeLayout, Region
from citygen.plausible import DEFAULT_RULES, Finding, PlausibilityRules, check_plausible, plain_wall, summary
from citygen.request import FacadeRequest, check_request
from citygen_split.ast import Grammar
from citygen_split.derive import PLUGIN_ID, FaceTooLarge, PointKey, Subtrees, _Derivation, point_key

#: Most derivations one face may take (the first included).
BUDGET = 24


@dataclass(frozen=True)
class Outcome:
    """The result of :func:`derive_plausible`: the layout returned, the alternatives it was derived with, how many
    derivations it took, and the findings / request problems of the best layout (empty when it is plausible)."""

    layout: FacadeLayout
    alternatives: dict[PointKey, int] = field(default_factory=dict)
    derivations: int = 1
    findings: tuple[Finding, ...] = ()
    problems: tuple[str, ...] = ()


def derive_plausible(grammar: Grammar, request: FacadeRequest, budget: int = BUDGET,
                     rules: PlausibilityRules | None = None, subtrees: Subtrees | None = None) -> Outcome:
    """The first plausible layout of ``grammar`` on ``request`` found by advancing choice points (module doc); a
    plain wall (``meta["fallback"]``, with the entrance's door when the face has one) when none is found within
    ``budget`` derivations. A layout whose only problems are request problems it cannot avoid (e.g. a grammar
    without a door on the entrance face) is returned as it is: the builder repairs the entrance. ``rules``:
    the request's (the scene's), else the defaults. ``subtrees``: the building's (:class:`Subtrees`), which
    the first derivation copies from and adds to."""
    rules = rules or request.plausibility or DEFAULT_RULES
    tried: set[PointKey] = set()
    try:
        # (moves are kept only when better: the last kept is the best)
        best = _attempt(grammar, request, {}, rules, subtrees)
        if (best.findings or best.problems) and best.partial:  # (moves need the choice points inside the copies)
            best = _attempt(grammar, request, {}, rules)
    except FaceTooLarge as exc:
        findings = (Finding("too-large", f"{exc.message} -- {exc.hint}"),)
        return Outcome(_plain(grammar, request, findings), findings=findings)
    derivations = 1
    while (best.findings or best.problems) and derivations < budget:
        key = _next_point(best, tried)
        if key is None:
            break
        k, count, moved = best.alternatives.get(key, 0), best.points[key], False
        for j in dict.fromkeys(min(j, count - 1) for j in (k + 1, k + 2, k + 3, count - 1)):
            if derivations >= budget:
                break
            try:
                attempt = _attempt(grammar, request, {**best.alternatives, key: j}, rules)
            except FaceTooLarge:  # (this alternative makes more: no better)
                attempt = None
            derivations += 1
            if attempt is not None and attempt.score < best.score:
                best, moved = attempt, True
                break
        if not moved:
            tried.add(key)
    if best.findings:
        return Outcome(_plain(grammar, request, best.findings), best.alternatives, derivations, best.findings,
                       best.problems)
    layout = best.layout
    if best.alternatives:
        layout = layout.with_meta({**layout.meta, "alternatives": len(best.alternatives)})
    return Outcome(layout, best.alternatives, derivations, (), best.problems)


def _plain(grammar: Grammar, request: FacadeRequest, findings: tuple[Finding, ...]) -> FacadeLayout:
    """A plain wall (with the entrance's door) naming ``findings``."""
    layout, _ = enforce_entrance(plain_wall(request, f"implausible layout: {summary(list(findings))}", findings,
                                            kind=PLUGIN_ID, ruleset=grammar.source), request)
    return layout


@dataclass(frozen=True)
class _Attempt:
    layout: FacadeLayout
    alternatives: dict[PointKey, int]
    points: dict[PointKey, int]
    findings: tuple[Finding, ...]
    problems: tuple[str, ...]
    partial: bool = False  # (copies of other faces' subtrees: :attr:`points` lacks the choice points inside them)

    @property
    def score(self) -> tuple[int, int]:
        """(request problems, offending terminals): a finding is one terminal, a summary line
        ("... and N more", :func:`citygen.plausible.check_plausible`) N of them."""
        more = sum(int(f.message.split()[2]) for f in self.findings
                   if f.region is None and f.message.startswith("... and "))
        return (len(self.problems), len(self.findings) + more)


def _attempt(grammar: Grammar, request: FacadeRequest, alternatives: dict[PointKey, int],
             rules: PlausibilityRules, subtrees: Subtrees | None = None) -> _Attempt:
    derivation = _Derivation(grammar, request, alternatives=alternatives, subtrees=subtrees)
    layout = derivation.run()
    findings = tuple(check_plausible(layout, request, rules))
    problems = tuple(check_request(layout, request))
    return _Attempt(layout, alternatives, derivation.points, findings, problems, derivation.partial)


def _next_point(attempt: _Attempt, tried: set[PointKey]) -> PointKey | None:
    """The deepest choice point above an offending terminal with an alternative left (findings first, then the
    request's problems: a door is found by its label); None when there is none."""
    regions = [f.region for f in attempt.findings if f.region is not None]
    if attempt.problems and not regions:
        regions = [r for r in attempt.layout.leaves if r.label == "door"]
    if not regions and attempt.findings:  # storey findings: any point, deepest first
        regions = list(attempt.layout.leaves[:200])
    for region in regions:
        for node in reversed(_path(attempt.layout.root, region)):
            for key in (point_key(node.symbol, node.w, node.h), point_key(node.symbol, 0.0, 0.0)):
                count = attempt.points.get(key)
                if count is not None and key not in tried and attempt.alternatives.get(key, 0) + 1 < count:
                    return key
    return None


def _path(root: Region, leaf: Region) -> list[Region]:
    """The regions from ``root`` down to ``leaf`` (by containment: siblings partition their parent)."""
    cx, cy = leaf.x + 0.5 * leaf.w, leaf.y + 0.5 * leaf.h
    path, node = [root], root
    while node.children and node is not leaf:
        inside = [c for c in node.children if c is leaf] or [
            c for c in node.children if c.x <= cx <= c.x + c.w and c.y <= cy <= c.y + c.h]
        if not inside:
            break
        node = inside[0]
        path.append(node)
    return path
