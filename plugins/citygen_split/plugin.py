"""Registers the split-grammar ruleset kind (``kind = "split"``, files ``*.grammar``)."""
from __future__ import annotations

from pathlib import Path

from citygen.hookspecs import hookimpl
from citygen.layout import FacadeLayout
from citygen.registry import RulesetKind
from citygen.request import FacadeRequest
from citygen_split.ast import Grammar
from citygen_split.derive import derive, explain
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
        return derive(ruleset, request)

    def explain(self, ruleset: Grammar, request: FacadeRequest) -> str:
        return explain(ruleset, request)


@hookimpl
def citygen_ruleset_kinds() -> list[RulesetKind]:
    return [SplitGrammarKind()]
