"""Parser of ``.layers`` files (format: ``docs/layers.md``); every error names ``file:line:column``."""
from __future__ import annotations

import math
import re
from pathlib import Path

from citygen.errors import ParseError, SourceLocation, read_user_text
from citygen.layout import MAX_DEPTH
from citygen.nesting import Depth
from citygen_layers.model import (
    Alt, Counter, Layer, Node, Pattern, Rep, Ruleset, Seq, ShapeSpec, SolveOptions, Sym, Symbol,
)

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_']*")
_TOKEN = re.compile(r"\s*(?:(?P<ident>[A-Za-z_][A-Za-z0-9_']*)|(?P<int>\d+)|(?P<op>:=|[()|^\-;=]))")
_FLAGS = ("opaque", "transparent", "attached", "unoccludable")
#: Counters the solver binds from the building request (docs/layers.md "Buildings").
BUILTIN_COUNTERS = {"entrance": Counter("entrance", 0, 1)}


class _Lexer:
    """Tokens of one line with their columns."""

    def __init__(self, text: str, path: str, line: int, offset: int = 0) -> None:
        self.path, self.line = path, line
        self.depth = Depth()
        self.tokens: list[tuple[str, str, int]] = []
        pos = 0
        while pos < len(text):
            if text[pos:].strip() == "":
                break
            m = _TOKEN.match(text, pos)
            if not m:
                col = pos + len(text[pos:]) - len(text[pos:].lstrip()) + 1 + offset
                raise ParseError(f"unexpected character {text[col - 1 - offset]!r}", where=self.loc(col),
                                 hint="patterns use symbols, ( ), |, ^k, ^-k and ^N")
            kind = m.lastgroup or "op"
            self.tokens.append((kind, m.group(kind), m.start(kind) + 1 + offset))
            pos = m.end()
        self.i = 0
        self.end_col = len(text) + 1 + offset

    def loc(self, col: int) -> SourceLocation:
        return SourceLocation(self.path, self.line, col)

    def peek(self) -> tuple[str, str, int] | None:
        return self.tokens[self.i] if self.i < len(self.tokens) else None

    def take(self, expected: str) -> tuple[str, str, int]:
        tok = self.peek()
        if tok is None:
            raise ParseError(f"expected {expected}, found end of line", where=self.loc(self.end_col))
        self.i += 1
        return tok

    def fail(self, expected: str) -> ParseError:
        tok = self.peek()
        found = "end of line" if tok is None else repr(tok[1])
        col = self.end_col if tok is None else tok[2]
        return ParseError(f"expected {expected}, found {found}", where=self.loc(col))


def parse_pattern(lexer: _Lexer, stop: tuple[str, ...] = ()) -> Node:
    """``seq := alt+``, ``alt := power ('|' power)*``, ``power := atom ('^' ['-'] INT|IDENT)?`` (§3.2 precedence:
    counting binds tighter than alternation, which binds tighter than concatenation)."""
    items: list[Node] = []
    while (tok := lexer.peek()) is not None and tok[1] not in (")",) + stop:
        items.append(_alt(lexer))
    if not items:
        raise lexer.fail("a symbol or '('")
    return items[0] if len(items) == 1 else Seq(tuple(items))


def _alt(lexer: _Lexer) -> Node:
    options = [_power(lexer)]
    while (tok := lexer.peek()) is not None and tok[1] == "|":
        lexer.take("'|'")
        options.append(_power(lexer))
    return options[0] if len(options) == 1 else Alt(tuple(options))


def _power(lexer: _Lexer) -> Node:
    kind, text, col = lexer.take("a symbol or '('")
    if kind == "ident":
        node: Node = Sym(text, lexer.loc(col))
    elif text == "(":
        too_deep = lambda message: ParseError(f"pattern {message}", where=lexer.loc(col))  # noqa: E731
        with lexer.depth.inside(too_deep):
            node = parse_pattern(lexer)
        if lexer.take("')'")[1] != ")":
            raise ParseError("expected ')'", where=lexer.loc(col))
    else:
        raise ParseError(f"expected a symbol or '(', found {text!r}", where=lexer.loc(col))
    tok = lexer.peek()
    if tok is not None and tok[1] == "^":
        lexer.take("'^'")
        negate = False
        if (t := lexer.peek()) is not None and t[1] == "-":
            lexer.take("'-'")
            negate = True
        kind, text, col = lexer.take("a count (integer or counter name)")
        if kind == "int":
            node = Rep(node, int(text), negate, lexer.loc(col))
        elif kind == "ident":
            node = Rep(node, text, negate, lexer.loc(col))
        else:
            raise ParseError(f"expected a count after '^', found {text!r}", where=lexer.loc(col))
    return node


def _strip_comment(line: str) -> str:
    return line.split("#", 1)[0].rstrip()


def _number(text: str, loc: SourceLocation, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ParseError(f"expected a number for {what}, found {text!r}", where=loc) from None
    if not math.isfinite(value):
        raise ParseError(f"expected a finite number for {what}, found {text!r}", where=loc,
                         hint="nan and inf are not allowed: write metres (or a count)")
    return value


def _depth(text: str, loc: SourceLocation, what: str) -> float:
    """:func:`_number` for a depth: at most :data:`~citygen.layout.MAX_DEPTH` metres either way."""
    value = _number(text, loc, what)
    if abs(value) > MAX_DEPTH:
        raise ParseError(f"{what} {value:g} m is beyond +-{MAX_DEPTH:g} m", where=loc,
                         hint="a depth is an offset from the wall in metres (a balcony 1.2, a recessed window -0.25)")
    return value


def _words(line: str) -> list[tuple[str, int]]:
    return [(m.group(), m.start() + 1) for m in re.finditer(r"\S+", line)]


class _FileParser:
    def __init__(self, text: str, path: str) -> None:
        self.path = path
        self.lines = text.splitlines()
        self.symbols: dict[str, Symbol] = {}
        self.counters: dict[str, Counter] = dict(BUILTIN_COUNTERS)
        self.patterns: dict[str, Pattern] = {}
        self.layers: list[Layer] = []
        self.shapes: list[ShapeSpec] = []
        self.canvas = (10.0, 10.0)
        self.floors: tuple[str, SourceLocation] | None = None
        self.options: dict[str, float | int] = {}
        self.last_pattern: str | None = None
        self.storeys: frozenset[str] = frozenset()
        self.cut = False
        self.mirror = False

    def loc(self, line: int, col: int) -> SourceLocation:
        return SourceLocation(self.path, line, col)

    def run(self) -> Ruleset:
        for number, raw in enumerate(self.lines, start=1):
            line = _strip_comment(raw)
            if not line.strip():
                continue
            words = _words(line)
            head, col = words[0]
            if raw[0].isspace() and ":=" in line:
                self._substitution(line, number)
                continue
            self.last_pattern = None
            handler = getattr(self, f"_kw_{head}", None)
            if handler is None:
                raise ParseError(f"unknown statement {head!r}", where=self.loc(number, col),
                                 hint="expected canvas, tolerance, budget, symbol, counter, pattern, layer, shape, "
                                      "floors, occlusion or mirror")
            handler(line, words, number)
        return self._finish()

    # statements ----------------------------------------------------------------------------------------------
    def _kw_canvas(self, line: str, words: list[tuple[str, int]], n: int) -> None:
        if len(words) != 3:
            raise ParseError("expected 'canvas WIDTH HEIGHT'", where=self.loc(n, words[0][1]))
        self.canvas = tuple(_number(w, self.loc(n, c), "canvas size") for w, c in words[1:])  # type: ignore

    def _kw_tolerance(self, line: str, words: list[tuple[str, int]], n: int) -> None:
        if len(words) != 2:
            raise ParseError("expected 'tolerance MU'", where=self.loc(n, words[0][1]))
        self.options["tolerance"] = _number(words[1][0], self.loc(n, words[1][1]), "tolerance")

    def _kw_occlusion(self, line: str, words: list[tuple[str, int]], n: int) -> None:
        if len(words) != 2 or words[1][0] not in ("drop", "cut"):
            raise ParseError("expected 'occlusion drop' or 'occlusion cut'", where=self.loc(n, words[0][1]))
        self.cut = words[1][0] == "cut"

    def _kw_mirror(self, line: str, words: list[tuple[str, int]], n: int) -> None:
        if len(words) != 2 or words[1][0] not in ("none", "building"):
            raise ParseError("expected 'mirror none' or 'mirror building'", where=self.loc(n, words[0][1]))
        self.mirror = words[1][0] == "building"

    def _kw_budget(self, line: str, words: list[tuple[str, int]], n: int) -> None:
        keys = {"expansions": int, "time": float, "candidates": int, "rounds": int, "samples": int,
                "growth": float, "prealign": bool}
        for key, value, col in self._pairs(words[1:], n):
            if key not in keys:
                raise ParseError(f"unknown budget key {key!r}", where=self.loc(n, col),
                                 hint=f"expected one of {', '.join(keys)}")
            if keys[key] is bool:
                if value not in ("true", "false"):
                    raise ParseError(f"expected true or false for {key}, got {value!r}", where=self.loc(n, col))
                self.options[key] = value == "true"
            else:
                self.options[key] = keys[key](_number(value, self.loc(n, col), key))

    def _kw_floors(self, line: str, words: list[tuple[str, int]], n: int) -> None:
        if len(words) < 2:
            raise ParseError("expected 'floors LAYER [STOREY_SYMBOL ...]'", where=self.loc(n, words[0][1]))
        self.floors = (words[1][0], self.loc(n, words[1][1]))
        for word, col in words[2:]:
            if word not in self.symbols:
                raise ParseError(f"unknown storey symbol {word!r}", where=self.loc(n, col),
                                 hint="declare storey symbols before 'floors'")
        self.storeys = frozenset(w for w, _ in words[2:])

    def _kw_symbol(self, line: str, words: list[tuple[str, int]], n: int) -> None:
        name = self._ident(words, 1, n, "a symbol name")
        if name in self.symbols:
            raise ParseError(f"symbol {name!r} declared twice", where=self.loc(n, words[1][1]))
        attrs: dict[str, object] = {}
        for word, col in words[2:]:
            if word in _FLAGS:
                attrs[word] = True
                continue
            key, value, _ = self._pair(word, col, n)
            if key in ("size", "depth"):
                attrs[key] = (_depth if key == "depth" else _number)(value, self.loc(n, col), key)
                if key == "size" and attrs[key] < 0:  # type: ignore[operator]
                    raise ParseError("size must be non-negative", where=self.loc(n, col))
            elif key in ("min", "max"):
                attrs["least" if key == "min" else "most"] = _number(value, self.loc(n, col), key)
            elif key in ("label", "material", "asset"):
                attrs[key] = None if value == "none" else value
            else:
                raise ParseError(f"unknown symbol attribute {key!r}", where=self.loc(n, col),
                                 hint="expected size=, min=, max=, label=, depth=, material=, asset= or a flag "
                                      + "/".join(_FLAGS))
        bounds = [attrs.get(k) for k in ("least", "size", "most")]
        known = [b for b in bounds if b is not None]
        if known != sorted(known) or any(b < 0 for b in known):  # type: ignore[operator]
            raise ParseError(f"symbol {name!r}: expected 0 <= min <= size <= max", where=self.loc(n, words[1][1]))
        self.symbols[name] = Symbol(name, **attrs)  # type: ignore[arg-type]

    def _kw_counter(self, line: str, words: list[tuple[str, int]], n: int) -> None:
        name = self._ident(words, 1, n, "a counter name")
        if name in self.counters:
            raise ParseError(f"counter {name!r} declared twice", where=self.loc(n, words[1][1]))
        rest = words[2:]
        if not rest:
            self.counters[name] = Counter(name)
        elif len(rest) == 2 and rest[0][0] == "=":
            k = int(_number(rest[1][0], self.loc(n, rest[1][1]), "counter value"))
            self.counters[name] = Counter(name, k, k)
        elif len(rest) == 2 and rest[0][0] == "in" and re.fullmatch(r"-?\d+\.\.(-?\d+)?", rest[1][0]):
            lo, hi = rest[1][0].split("..")
            counter = Counter(name, int(lo), int(hi) if hi else None)
            if counter.hi is not None and counter.hi < counter.lo:
                raise ParseError("empty counter range", where=self.loc(n, rest[1][1]))
            self.counters[name] = counter
        else:
            raise ParseError("expected 'counter NAME', 'counter NAME = K' or 'counter NAME in LO..HI'",
                             where=self.loc(n, rest[0][1]))

    def _kw_pattern(self, line: str, words: list[tuple[str, int]], n: int) -> None:
        name = self._ident(words, 1, n, "a pattern name")
        if name in self.patterns:
            raise ParseError(f"pattern {name!r} defined twice", where=self.loc(n, words[1][1]))
        eq = line.find("=", words[1][1] - 1 + len(name))
        if eq < 0 or line[words[1][1] - 1 + len(name):eq].strip():
            raise ParseError("expected '=' after the pattern name", where=self.loc(n, words[1][1] + len(name)))
        body, *subs = line[eq + 1:].split(";")
        lexer = _Lexer(body, self.path, n, eq + 1)
        control = parse_pattern(lexer)
        if lexer.peek() is not None:
            raise lexer.fail("a symbol, '(', '|' or end of pattern")
        self.patterns[name] = Pattern(name, control, {}, self.loc(n, words[1][1]))
        self.last_pattern = name
        offset = eq + 1 + len(body) + 1
        for sub in subs:
            self._substitution(sub, n, offset)
            offset += len(sub) + 1

    def _substitution(self, text: str, n: int, offset: int = 0) -> None:
        if self.last_pattern is None:
            col = offset + len(text) - len(text.lstrip()) + 1
            raise ParseError("a substitution 'x := ...' must follow a pattern", where=self.loc(n, col))
        lexer = _Lexer(text, self.path, n, offset)
        kind, name, col = lexer.take("a control symbol")
        if kind != "ident":
            raise ParseError(f"expected a control symbol, found {name!r}", where=self.loc(n, col))
        if lexer.take("':='")[1] != ":=":
            raise ParseError("expected ':='", where=self.loc(n, col + len(name)))
        content = parse_pattern(lexer)
        if lexer.peek() is not None:
            raise lexer.fail("end of the content pattern")
        old = self.patterns[self.last_pattern]
        if name in old.substitutions:
            raise ParseError(f"symbol {name!r} substituted twice", where=self.loc(n, col))
        if name not in _symbols_of(old.control):
            raise ParseError(f"{name!r} does not occur in the control pattern of {old.name!r}",
                             where=self.loc(n, col))
        self.patterns[old.name] = Pattern(old.name, old.control, {**old.substitutions, name: content}, old.where)

    def _kw_layer(self, line: str, words: list[tuple[str, int]], n: int) -> None:
        name = self._ident(words, 1, n, "a layer name")
        if any(layer.name == name for layer in self.layers):
            raise ParseError(f"layer {name!r} defined twice", where=self.loc(n, words[1][1]))
        attrs: dict[str, tuple[str, int]] = {}
        for key, value, col in self._pairs(words[2:], n):
            if key not in ("x", "y", "depth", "mask", "xgroup", "ygroup"):
                raise ParseError(f"unknown layer attribute {key!r}", where=self.loc(n, col),
                                 hint="expected x=, y=, depth=, mask=, xgroup=, ygroup=")
            attrs[key] = (value, col)
        for key in ("x", "y"):
            if key not in attrs:
                raise ParseError(f"layer {name!r} needs {key}=PATTERN", where=self.loc(n, words[0][1]))
            if attrs[key][0] not in self.patterns:
                raise ParseError(f"unknown pattern {attrs[key][0]!r}", where=self.loc(n, attrs[key][1]),
                                 hint="define patterns before the layers that use them")
        depth = (_depth(attrs["depth"][0], self.loc(n, attrs["depth"][1]), "depth") if "depth" in attrs
                 else 0.02 * len(self.layers))
        mask = frozenset(attrs["mask"][0].split(",")) if "mask" in attrs else None
        groups = (attrs.get("xgroup", ("main", 0))[0], attrs.get("ygroup", ("main", 0))[0])
        self.layers.append(Layer(name, attrs["x"][0], attrs["y"][0], depth, mask, groups))

    def _kw_shape(self, line: str, words: list[tuple[str, int]], n: int) -> None:
        h = self._ident(words, 1, n, "the horizontal symbol")
        v = self._ident(words, 2, n, "the vertical symbol")
        attrs: dict[str, object] = {}
        for key, value, col in self._pairs(words[3:], n):
            if key in ("layer", "pattern", "label", "material", "asset"):
                attrs[key] = None if value == "none" and key == "label" else value
            elif key == "depth":
                attrs[key] = _depth(value, self.loc(n, col), key)
            elif key == "visible":
                if value not in ("true", "false"):
                    raise ParseError("expected visible=true or visible=false", where=self.loc(n, col))
                attrs[key] = value == "true"
            else:
                raise ParseError(f"unknown shape attribute {key!r}", where=self.loc(n, col),
                                 hint="expected layer=, pattern=, label=, depth=, material=, asset=, visible=")
        if attrs.get("label", "") is None:
            attrs["visible"] = False
        self.shapes.append(ShapeSpec(h, v, **attrs))  # type: ignore[arg-type]

    # helpers -------------------------------------------------------------------------------------------------
    def _ident(self, words: list[tuple[str, int]], i: int, n: int, what: str) -> str:
        if i >= len(words):
            end = words[-1][1] + len(words[-1][0])
            raise ParseError(f"expected {what}, found end of line", where=self.loc(n, end))
        if not _IDENT.fullmatch(words[i][0]):
            raise ParseError(f"expected {what}, found {words[i][0]!r}", where=self.loc(n, words[i][1]))
        return words[i][0]

    def _pair(self, word: str, col: int, n: int) -> tuple[str, str, int]:
        key, sep, value = word.partition("=")
        if not sep or not key or not value:
            raise ParseError(f"expected key=value, found {word!r}", where=self.loc(n, col))
        return key, value, col

    def _pairs(self, words: list[tuple[str, int]], n: int) -> list[tuple[str, str, int]]:
        return [self._pair(w, c, n) for w, c in words]

    def _finish(self) -> Ruleset:
        end = self.loc(len(self.lines), 1)
        if not self.layers:
            raise ParseError("a ruleset needs at least one layer", where=end)
        _check_symbols(self.patterns, self.symbols, self.counters, self.layers)
        floors = None
        if self.floors is not None:
            floors, where = self.floors
            if all(layer.name != floors for layer in self.layers):
                raise ParseError(f"floors names unknown layer {floors!r}", where=where)
        options = SolveOptions(**self.options)  # type: ignore[arg-type]
        return Ruleset(Path(self.path).stem, self.canvas, dict(self.symbols), dict(self.counters),
                       dict(self.patterns), tuple(self.layers), tuple(self.shapes), floors, self.storeys,
                       options, self.path, self.cut, self.mirror)


def _symbols_of(node: Node) -> set[str]:
    if isinstance(node, Sym):
        return {node.name}
    if isinstance(node, Rep):
        return _symbols_of(node.body)
    children = node.items if isinstance(node, Seq) else node.options
    return set().union(*(_symbols_of(c) for c in children))


def _walk(node: Node):
    yield node
    if isinstance(node, Rep):
        yield from _walk(node.body)
    elif isinstance(node, (Seq, Alt)):
        for child in (node.items if isinstance(node, Seq) else node.options):
            yield from _walk(child)


def _check_symbols(patterns: dict[str, Pattern], symbols: dict[str, Symbol], counters: dict[str, Counter],
                   layers: list[Layer]) -> None:
    """Undeclared symbols are unsized placeholders, allowed only as unsubstituted control letters (§3.3);
    counters must be declared and used in one direction only (directions are solved independently, §5)."""
    direction_of: dict[str, tuple[str, str]] = {}
    for layer in layers:
        for axis, name in (("x", layer.x), ("y", layer.y)):
            pattern = patterns[name]
            for node in _walk(pattern.control):
                _check_node(node, pattern, symbols, counters, control=pattern.substituted)
                if isinstance(node, Rep) and isinstance(node.count, str):
                    _one_direction(node, axis, pattern, direction_of)
            for content in pattern.substitutions.values():
                for node in _walk(content):
                    _check_node(node, pattern, symbols, counters, control=False)
                    if isinstance(node, Rep) and isinstance(node.count, str):
                        _one_direction(node, axis, pattern, direction_of)


def _check_node(node: Node, pattern: Pattern, symbols: dict[str, Symbol], counters: dict[str, Counter],
                control: bool) -> None:
    if isinstance(node, Rep) and isinstance(node.count, str) and node.count not in counters:
        raise ParseError(f"unknown counter {node.count!r}", where=node.where,
                         hint=f"declare it: 'counter {node.count}'")
    if isinstance(node, Sym) and node.name not in symbols:
        if not control:
            raise ParseError(f"symbol {node.name!r} has no declaration", where=node.where,
                             hint=f"declare 'symbol {node.name} size=...'; only unsubstituted letters of a "
                                  "control pattern may be undeclared (unsized placeholders)")


def _one_direction(node: Rep, axis: str, pattern: Pattern, seen: dict[str, tuple[str, str]]) -> None:
    name = str(node.count)
    if name in seen and seen[name][0] != axis:
        raise ParseError(f"counter {name!r} is used in both directions (also in pattern {seen[name][1]!r})",
                         where=node.where, hint="use one counter per direction; directions are solved apart")
    seen.setdefault(name, (axis, pattern.name))


def parse(text: str, path: str = "<string>") -> Ruleset:
    """Parse the text of a ``.layers`` file."""
    return _FileParser(text, path).run()


def load(path: str | Path) -> Ruleset:
    """Read and parse a ``.layers`` file."""
    path = Path(path)
    return parse(read_user_text(path, ParseError, "ruleset"), str(path))
