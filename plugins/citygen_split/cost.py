"""Grammar cost after wu2014 Eq. 1-2: the sum over rules of ``cost_op(op) + |alpha|``.

Operators beyond the paper's split (0.1) and repeat (0.5) are priced as documented in docs/grammar.md (Cost):
``symsplit`` and ``floors`` like split, ``repeatABA`` like repeat with ``|alpha| = 2``, ``grid`` like split with
``|alpha|`` = its merged regions, a rename ``|alpha| = 1`` with no operator cost, terminals 0. A conditional or
stochastic rule costs the sum of its alternatives plus ``split_cost`` per condition or probability.
"""
from __future__ import annotations

from citygen_split.ast import (
    Body, Case, Choice, Floors, Grammar, Grid, Rename, Repeat, RepeatABA, Rule, Split, SymSplit, Terminal,
)


def grammar_cost(grammar: Grammar, split_cost: float = 0.1, repeat_cost: float = 0.5) -> float:
    """Eq. 1: the sum of :func:`rule_cost` over the grammar's rules."""
    return sum(rule_cost(rule, split_cost, repeat_cost) for rule in grammar.rules)


def rule_cost(rule: Rule, split_cost: float = 0.1, repeat_cost: float = 0.5) -> float:
    """Eq. 2 for one rule."""
    return _body_cost(rule.body, split_cost, repeat_cost)


def _body_cost(body: Body, split_cost: float, repeat_cost: float) -> float:
    if isinstance(body, Terminal):
        return 0.0
    if isinstance(body, Rename):
        return 1.0
    if isinstance(body, (Split, SymSplit)):
        return split_cost + len(body.items)
    if isinstance(body, Repeat):
        return repeat_cost + len(body.items)
    if isinstance(body, RepeatABA):
        return repeat_cost + 2
    if isinstance(body, Floors):
        return split_cost + len(body.items)
    if isinstance(body, Grid):
        return split_cost + len(body.regions)
    if isinstance(body, Case):
        alts = [b for _, b in body.branches] + ([body.otherwise] if body.otherwise is not None else [])
        return split_cost * len(body.branches) + sum(_body_cost(b, split_cost, repeat_cost) for b in alts)
    if isinstance(body, Choice):
        alts = [b for _, b in body.alternatives] + ([body.otherwise] if body.otherwise is not None else [])
        return split_cost * len(body.alternatives) + sum(_body_cost(b, split_cost, repeat_cost) for b in alts)
    raise TypeError(f"not a rule body: {body!r}")
