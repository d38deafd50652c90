"""Registers the split-grammar ruleset kind (``kind = "split"``, files ``*.grammar``)."""
from __future__ import annotations

from pathlib import Path

from citygen.hookspecs import hookimpl
from citygen.layout import FacadeLayout
from citygen.registry import RulesetKind
from citygen.request import FacadeRequest
from citygen_split.alternatives import derive_plausible
from citygen_split.ast import Grammar
from citygen_split.derive import explain
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
