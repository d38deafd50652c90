"""Registers the split-grammar ruleset kind (``kind = "split"``, files ``*.grammar``)."""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from citygen.hookspecs import hookimpl
from citygen.layout import FacadeLayout
from citygen.registry import RulesetKind
from citygen.request import FacadeRequest
from citygen_split.alternatives import derive_plausible
from citygen_split.ast import Grammar
from citygen_split.derive import Subtrees, explain
from citygen_split.parser import load, parse


class SplitGrammarKind(RulesetKind):
    """CGA-style split grammars (docs/grammar.md)."""

    id = "split"
    suffixes = (".grammar",)
    description = "split grammar: split, repeat, repeatABA, symsplit, grid and floors rules with conditions (wu2014)"

    def load(self, path: Path) -> Grammar:
        return load(path)

    def loads(self, text: str, path: Path) -> Grammar:
        return parse(text, str(path))

    def generate(self, ruleset: Grammar, request: FacadeRequest) -> FacadeLayout:
        """The grammar's first plausible derivation, else a plain wall with findings
        (:mod:`citygen_split.alternatives`)."""
        return derive_plausible(ruleset, request).layout

    def generate_building(self, ruleset: Grammar, requests: Sequence[FacadeRequest]) -> list[FacadeLayout]:
        """:meth:`generate` of each face, the faces sharing the subtrees that derive alike on all of them
        (:class:`citygen_split.derive.Subtrees`)."""
        subtrees = Subtrees(ruleset)
        return [derive_plausible(ruleset, request, subtrees=subtrees).layout for request in requests]

    def explain(self, ruleset: Grammar, request: FacadeRequest) -> str:
        outcome = derive_plausible(ruleset, request)
        head = [f"# {len(outcome.alternatives)} choice point(s) moved to other alternatives in "
                f"{outcome.derivations} derivations"] if outcome.derivations > 1 else []
        if outcome.findings:
            head.append(f"# no plausible derivation: plain wall ({outcome.layout.meta['fallback']})")
        return "\n".join([*head, explain(ruleset, request, outcome.alternatives)])


@hookimpl
def citygen_ruleset_kinds() -> list[RulesetKind]:
    return [SplitGrammarKind()]
