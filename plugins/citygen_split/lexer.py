"""Tokens of the split grammar language, each with its 1-based line and column."""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

from citygen.errors import ParseError, SourceLocation

#: Token kinds: SYM (upper-case symbol), NAME (lower-case word or keyword), NUM, STR, PRAGMA (@word), OP, EOF.
_TOKEN = re.compile(r"""
    (?P<ws>[ \t\r\n]+|\#[^\n]*)
  | (?P<NUM>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)
  | (?P<SYM>[A-Z][A-Za-z0-9_]*)
  | (?P<NAME>[a-z_][A-Za-z0-9_]*)
  | (?P<STR>"(?:[^"\\\n]|\\.)*")
  | (?P<PRAGMA>@[A-Za-z_]+)
  | (?P<OP>-->|==|!=|<=|>=|[-<>+*/(){}|:;,%'~])
""", re.VERBOSE)


@dataclass(frozen=True)
class Token:
    kind: str
    text: str
    line: int
    column: int

    def describe(self) -> str:
        if self.kind == "EOF":
            return "end of file"
        return f"{self.text!r}"


def tokenize(text: str, source: str) -> list[Token]:
    """Split ``text`` into tokens; an unknown character or unterminated string is a :class:`ParseError`."""
    tokens: list[Token] = []
    pos, line, line_start = 0, 1, 0
    while pos < len(text):
        match = _TOKEN.match(text, pos)
        column = pos - line_start + 1
        if match is None:
            char = text[pos]
            what = "unterminated string (missing closing '\"')" if char == '"' else f"unexpected character {char!r}"
            raise ParseError(what, where=SourceLocation(source, line, column),
                             hint="see docs/grammar.md for the language")
        kind = match.lastgroup
        value = match.group()
        if kind != "ws":
            if kind == "STR":
                value = re.sub(r"\\(.)", r"\1", value[1:-1])
            elif kind == "NUM" and not math.isfinite(float(value)):
                raise ParseError(f"number {value} is too large", where=SourceLocation(source, line, column),
                                 hint="sizes, depths and percentages are metres or percent: write a usual number")
            tokens.append(Token(kind, value, line, column))
        newlines = value.count("\n") if kind == "ws" else 0
        if newlines:
            line += newlines
            line_start = pos + value.rindex("\n") + 1
        pos = match.end()
    tokens.append(Token("EOF", "", line, pos - line_start + 1))
    return tokens
