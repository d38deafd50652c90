"""The split-grammar ruleset kind (``.grammar``): a CGA-style facade grammar (wu2014 §3.1, §4.7; mueller2007 §5).

Public API: :func:`parse`, :func:`load`, :func:`derive`, :func:`explain`, :func:`grammar_cost`,
:func:`format_grammar` and the AST in :mod:`citygen_split.ast`. The language is specified in docs/grammar.md.
"""
from citygen_split.ast import Grammar, Rule
from citygen_split.cost import grammar_cost, rule_cost
from citygen_split.derive import derive, explain
from citygen_split.format import format_grammar
from citygen_split.parser import load, parse

__all__ = ["Grammar", "Rule", "derive", "explain", "format_grammar", "grammar_cost", "load", "parse", "rule_cost"]
