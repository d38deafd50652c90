"""Tokenizer of the ``.relayout`` format: one statement per line, ``#`` comments, file:line:column errors."""
from __future__ import annotations

import re
from dataclasses import dataclass

from citygen.errors import ParseError, SourceLocation

_TOKEN = re.compile(r"""\s*(?:(?P<str>"[^"]*")|(?P<range>\.\.)|(?P<num>-?\d+(?:\.\d+)?%?(?![A-Za-z_]))
                      |(?P<word>[A-Za-z_][A-Za-z0-9_']*)|(?P<label>@[A-Za-z_][A-Za-z0-9_]*)
                      |(?P<punct>[{}()=:<>.|&^$\-⊢⊣?*+]))""", re.VERBOSE)


@dataclass(frozen=True)
class Token:
    kind: str  # str, range, num, word, label, punct
    text: str
    line: int
    column: int


def tokenize(line: str, lineno: int, path: str) -> list[Token]:
    """Tokens of one line (comments stripped)."""
    text = line.split("#", 1)[0].rstrip()
    tokens: list[Token] = []
    pos = 0
    while pos < len(text):
        if text[pos:].strip() == "":
            break
        m = _TOKEN.match(text, pos)
        if m is None or m.end() == pos:
            col = pos + len(text[pos:]) - len(text[pos:].lstrip()) + 1
            raise ParseError(f"unexpected character {text[col - 1]!r}", where=SourceLocation(path, lineno, col),
                             hint="see docs/relayout.md for the statement syntax")
        kind = m.lastgroup or "punct"
        value = m.group(kind)
        tokens.append(Token(kind, value, lineno, m.start(kind) + 1))
        pos = m.end()
    return tokens


class Cursor:
    """Reads the tokens of one statement, raising ParseError with the position of what was unexpected."""

    def __init__(self, tokens: list[Token], path: str, lineno: int, line: str) -> None:
        self.tokens, self.path, self.lineno, self.i = tokens, path, lineno, 0
        self.text = line.split("#", 1)[0].strip()
        self.end_col = len(line.split("#", 1)[0].rstrip()) + 1

    def where(self) -> SourceLocation:
        col = self.tokens[self.i].column if self.i < len(self.tokens) else self.end_col
        return SourceLocation(self.path, self.lineno, col)

    def error(self, expected: str) -> ParseError:
        got = repr(self.tokens[self.i].text) if self.i < len(self.tokens) else "end of line"
        return ParseError(f"expected {expected}, got {got}", where=self.where(),
                          hint="see docs/relayout.md for the statement syntax")

    def peek(self, text: str | None = None, kind: str | None = None) -> bool:
        if self.i >= len(self.tokens):
            return False
        tok = self.tokens[self.i]
        return (text is None or tok.text == text) and (kind is None or tok.kind == kind)

    def take(self, text: str | None = None, kind: str | None = None, expected: str = "") -> Token:
        if not self.peek(text, kind):
            raise self.error(expected or (repr(text) if text else kind or "a token"))
        self.i += 1
        return self.tokens[self.i - 1]

    def accept(self, text: str) -> bool:
        if self.peek(text):
            self.i += 1
            return True
        return False

    def done(self) -> bool:
        return self.i >= len(self.tokens)

    def finish(self) -> None:
        if not self.done():
            raise self.error("end of statement")

    def word(self, expected: str = "a name") -> str:
        return self.take(kind="word", expected=expected).text

    def number(self, expected: str = "a number") -> tuple[float, bool]:
        """A number and whether it carried a ``%``."""
        tok = self.take(kind="num", expected=expected)
        return float(tok.text.rstrip("%")), tok.text.endswith("%")
