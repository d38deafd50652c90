"""Recursive-descent parser for the split grammar language (docs/grammar.md) plus its semantic checks."""
from __future__ import annotations

from pathlib import Path

from citygen.errors import ParseError, SourceLocation, read_user_text
from citygen.layout import MAX_DEPTH
from citygen.nesting import Depth
from citygen_split.ast import (
    Attr, Binary, Body, Case, Choice, Const, Expr, Floors, FloorItem, Grammar, Grid, Item, Rename, Repeat,
    RepeatABA, Rule, SimpleBody, Size, Split, SymSplit, Terminal, Unary, Var, successors,
)
from citygen_split.gridspans import GridSpanError, merge_cells
from citygen_split.lexer import Token, tokenize

#: Variables a condition may read (docs/grammar.md, Conditions).
VARIABLES = ("width", "height", "face_width", "face_height", "floor", "floor_count", "entrance", "street",
             "courtyard", "levels")
#: Symbols the evaluator provides without a rule.
BUILTIN_SYMBOLS = ("Corner",)
_OPS = ("split", "repeat", "repeatABA", "symsplit")
_COMPARE = ("==", "!=", "<", "<=", ">", ">=")
_HINT = "see docs/grammar.md for the language"


def parse(text: str, source: str = "<string>") -> Grammar:
    """Parse grammar ``text``; ``source`` names it in errors. Raises :class:`ParseError` (file:line:column)."""
    return _Parser(text, source).grammar()


def load(path: str | Path) -> Grammar:
    """Parse the grammar file at ``path``."""
    path = Path(path)
    return parse(read_user_text(path, ParseError, "grammar"), str(path))


class _Parser:
    def __init__(self, text: str, source: str) -> None:
        self.source = source
        self.tokens = tokenize(text, source)
        self.pos = 0
        self.grid_uses: list[tuple[str, SourceLocation]] = []
        self.depth = Depth()

    # ---- token helpers --------------------------------------------------------------------------------------
    @property
    def tok(self) -> Token:
        return self.tokens[self.pos]

    def peek(self, k: int = 1) -> Token:
        return self.tokens[min(self.pos + k, len(self.tokens) - 1)]

    def loc(self, tok: Token | None = None) -> SourceLocation:
        tok = tok or self.tok
        return SourceLocation(self.source, tok.line, tok.column)

    def fail(self, message: str, tok: Token | None = None, hint: str = _HINT) -> ParseError:
        return ParseError(message, where=self.loc(tok), hint=hint)

    def expected(self, what: str) -> ParseError:
        return self.fail(f"expected {what}, found {self.tok.describe()}")

    def at(self, kind: str, text: str | None = None) -> bool:
        return self.tok.kind == kind and (text is None or self.tok.text == text)

    def accept(self, kind: str, text: str | None = None) -> Token | None:
        if self.at(kind, text):
            tok = self.tok
            self.pos += 1
            return tok
        return None

    def expect(self, kind: str, text: str | None, what: str) -> Token:
        tok = self.accept(kind, text)
        if tok is None:
            raise self.expected(what)
        return tok

    def op(self, text: str) -> Token:
        return self.expect("OP", text, repr(text))

    # ---- file -----------------------------------------------------------------------------------------------
    def grammar(self) -> Grammar:
        rules: list[Rule] = []
        pragmas: dict[str, object] = {}
        start_tok: Token | None = None
        while not self.at("EOF"):
            if self.at("PRAGMA"):
                tok = self.tok
                name = tok.text[1:]
                if name in pragmas:
                    raise self.fail(f"duplicate pragma @{name}", tok)
                self.pos += 1
                if name == "start":
                    start_tok = self.tok
                    pragmas[name] = self.expect("SYM", None, "a symbol after @start").text
                elif name == "size":
                    pragmas[name] = (self.positive("facade width"), self.positive("facade height"))
                elif name == "name":
                    pragmas[name] = self.expect("STR", None, 'a quoted name after @name').text
                else:
                    raise self.fail(f"unknown pragma @{name}", tok, hint="pragmas are @start, @size, @name")
            elif self.at("SYM"):
                rules.append(self.rule())
            else:
                raise self.expected("a rule 'Symbol --> ...' or a pragma")
        if not rules:
            raise self.fail("the grammar has no rules", hint="write at least one rule 'Facade --> ...'")
        start = pragmas.get("start", rules[0].symbol)
        grammar = Grammar(rules=tuple(rules), start=start, size=pragmas.get("size"),  # type: ignore[arg-type]
                          name=pragmas.get("name"), source=self.source)  # type: ignore[arg-type]
        self.check(grammar, start_tok)
        return grammar

    def rule(self) -> Rule:
        sym = self.tok
        self.pos += 1
        self.expect("OP", "-->", f"'-->' after the symbol {sym.text}")
        return Rule(sym.text, self.body(), loc=self.loc(sym))

    # ---- bodies ---------------------------------------------------------------------------------------------
    def body(self) -> Body:
        if self.at("NAME", "case"):
            return self.case()
        if self.at("NAME", "each") or (self.at("NUM") and self.peek().text == "%"):
            return self.choice()
        return self.simple_body()

    def case(self) -> Case:
        branches = []
        while self.accept("NAME", "case"):
            cond = self.expr()
            self.op(":")
            branches.append((cond, self.simple_body()))
        return Case(tuple(branches), self.otherwise())

    def choice(self) -> Choice:
        each = self.accept("NAME", "each") is not None
        alternatives, total = [], 0.0
        while self.at("NUM"):
            tok = self.tok
            percent = float(self.tok.text)
            self.pos += 1
            self.op("%")
            self.op(":")
            total += percent
            if total > 100 + 1e-9:
                raise self.fail(f"percentages add up to {total:g}%, more than 100%", tok,
                                hint="lower the probabilities; 'else' takes what is left")
            alternatives.append((percent, self.simple_body()))
        if not alternatives:
            raise self.expected("a probability like '50%:' after 'each'")
        return Choice(tuple(alternatives), self.otherwise(), each)

    def otherwise(self) -> SimpleBody | None:
        if self.accept("NAME", "else"):
            self.op(":")
            return self.simple_body()
        return None

    def simple_body(self) -> SimpleBody:
        tok = self.tok
        if tok.kind == "SYM":
            self.pos += 1
            return Rename(tok.text, loc=self.loc(tok))
        if tok.kind == "NAME":
            if tok.text in _OPS:
                return self.split_op()
            if tok.text == "grid":
                return self.grid()
            if tok.text == "floors":
                return self.floors()
            if tok.text == "terminal":
                return self.terminal()
            if tok.text in ("case", "each"):
                raise self.fail(f"'{tok.text}' cannot be nested inside another alternative",
                                hint="give the nested choice its own rule and rename to its symbol")
        raise self.expected("a rule body (split, repeat, repeatABA, symsplit, grid, floors, terminal or a Symbol)")

    def split_op(self) -> SimpleBody:
        op = self.tok
        self.pos += 1
        self.op("(")
        if not (self.tok.kind == "NAME" and self.tok.text in ("x", "y")):
            raise self.expected("an axis x or y")
        axis = self.tok.text
        self.pos += 1
        self.op(")")
        self.op("{")
        items = [self.item()]
        while self.accept("OP", "|"):
            items.append(self.item())
        self.op("}")
        if op.text == "split":
            return Split(axis, tuple(items))  # type: ignore[arg-type]
        if op.text == "repeat":
            return Repeat(axis, tuple(items))  # type: ignore[arg-type]
        if op.text == "symsplit":
            return SymSplit(axis, tuple(items))  # type: ignore[arg-type]
        if len(items) != 2:
            raise self.fail(f"repeatABA takes exactly two items (A and B), found {len(items)}", op)
        return RepeatABA(axis, items[0], items[1])  # type: ignore[arg-type]

    def item(self) -> Item:
        if self.at("SYM"):
            size = Size("rel", 1.0)
        else:
            size = self.size()
            self.op(":")
        sym = self.expect("SYM", None, "a Symbol")
        return Item(size, sym.text, loc=self.loc(sym))

    def size(self) -> Size:
        if self.accept("OP", "'"):
            return Size("rel", self.positive("a relative weight after \"'\""))
        if self.accept("OP", "~"):
            return Size("float", self.positive("a floating size after '~'"))
        if self.at("NUM"):
            return Size("abs", self.positive("a size"))
        raise self.expected("a size (2.5, '1 or ~1.2) or a Symbol")

    def positive(self, what: str) -> float:
        tok = self.expect("NUM", None, what)
        value = float(tok.text)
        if not value > 0:
            raise self.fail(f"{what} must be positive, found {tok.text}", tok)
        return value

    def grid(self) -> Grid:
        start = self.tok
        self.pos += 1
        self.op("{")
        self.expect("NAME", "cols", "'cols:'")
        self.op(":")
        cols = self.sizes()
        self.op(";")
        self.expect("NAME", "rows", "'rows:'")
        self.op(":")
        rows = self.sizes()
        self.op(";")
        cells: list[tuple[str, ...]] = []
        cell_toks: list[list[Token]] = [[]]
        while not self.at("OP", "}"):
            tok = self.tok
            if tok.kind == "SYM" or (tok.kind == "OP" and tok.text == "<") or (tok.kind == "NAME" and tok.text == "v"):
                cell_toks[-1].append(tok)
                self.pos += 1
            elif self.accept("OP", "/"):
                cell_toks.append([])
            else:
                raise self.expected("a grid cell (a Symbol, '<' or 'v'), '/' or '}'")
        self.pos += 1
        for r, row in enumerate(cell_toks):
            if len(row) != len(cols):
                anchor = row[0] if row else start
                raise self.fail(f"grid row {r + 1} has {len(row)} cells, expected {len(cols)} (one per column)", anchor)
            cells.append(tuple(t.text for t in row))
        if len(cells) != len(rows):
            raise self.fail(f"grid has {len(cells)} rows of cells, expected {len(rows)} (one per row size)", start)
        try:
            merge_cells(tuple(cells))
        except GridSpanError as exc:
            raise self.fail(str(exc), cell_toks[exc.row][exc.col],
                            hint="every region spanned with '<' and 'v' must be a rectangle") from None
        self.grid_uses.extend((t.text, self.loc(t)) for row in cell_toks for t in row if t.kind == "SYM")
        return Grid(cols, rows, tuple(cells))

    def sizes(self) -> tuple[Size, ...]:
        sizes = [self.size()]
        while self.accept("OP", "|"):
            sizes.append(self.size())
        return tuple(sizes)

    def floors(self) -> Floors:
        start = self.tok
        self.pos += 1
        self.op("{")
        items, seen = [], set()
        while True:
            tok = self.tok
            if self.accept("OP", "*"):
                floor = None
            else:
                sign = -1 if self.accept("OP", "-") else 1
                num = self.expect("NUM", None, "a floor selector (0, 1, -1, ... or *)")
                if not num.text.isdigit():
                    raise self.fail(f"a floor selector must be a whole number, found {num.text}", num)
                floor = sign * int(num.text)
            if floor in seen:
                raise self.fail(f"duplicate floor selector {'*' if floor is None else floor}", tok)
            seen.add(floor)
            self.op(":")
            sym = self.expect("SYM", None, "a Symbol")
            items.append(FloorItem(floor, sym.text, loc=self.loc(sym)))
            if not self.accept("OP", "|"):
                break
        self.op("}")
        if None not in seen:
            raise self.fail("floors needs a catch-all item '*: Symbol' for the floors no selector names", start)
        return Floors(tuple(items))

    def terminal(self) -> Terminal:
        self.pos += 1
        self.op("(")
        label = self.expect("NAME", None, "a lower-case label (wall, window, ..., none)").text
        values: dict[str, object] = {}
        while self.accept("OP", ","):
            key = self.tok
            self.expect("NAME", None, "a key (depth, material, asset)")
            if key.text in values:
                raise self.fail(f"duplicate terminal key {key.text!r}", key)
            self.op(":")
            if key.text == "depth":
                sign = -1.0 if self.accept("OP", "-") else 1.0
                number = self.tok
                values["depth"] = sign * float(self.expect("NUM", None, "a depth in metres").text)
                if abs(values["depth"]) > MAX_DEPTH:
                    raise self.fail(f"depth {values['depth']:g} m is beyond +-{MAX_DEPTH:g} m", number,
                                    hint="a depth is the terminal's offset from the wall in metres (a balcony 1.2, "
                                         "a recessed window -0.25)")
            elif key.text == "material":
                if self.tok.kind not in ("NAME", "SYM", "STR"):
                    raise self.expected("a material name or quoted string")
                values["material"] = self.tok.text
                self.pos += 1
            elif key.text == "asset":
                values["asset"] = self.expect("STR", None, 'a quoted asset path').text
            else:
                raise self.fail(f"unknown terminal key {key.text!r}", key, hint="keys are depth, material, asset")
        self.op(")")
        return Terminal(None if label == "none" else label, **values)  # type: ignore[arg-type]

    # ---- expressions ----------------------------------------------------------------------------------------
    def expr(self) -> Expr:
        left = self.conj()
        while self.accept("NAME", "or"):
            left = Binary("or", left, self.conj())
        return left

    def conj(self) -> Expr:
        left = self.neg()
        while self.accept("NAME", "and"):
            left = Binary("and", left, self.neg())
        return left

    def neg(self) -> Expr:
        if self.at("NAME", "not"):
            with self.depth.inside(self._too_deep()):
                self.pos += 1
                return Unary("not", self.neg())
        return self.compare()

    def compare(self) -> Expr:
        left = self.sum()
        if self.tok.kind == "OP" and self.tok.text in _COMPARE:
            op = self.tok.text
            self.pos += 1
            left = Binary(op, left, self.sum())
            if self.tok.kind == "OP" and self.tok.text in _COMPARE:
                raise self.fail("comparisons cannot be chained", hint="write 'a < b and b < c'")
        return left

    def sum(self) -> Expr:
        left = self.product()
        while self.tok.kind == "OP" and self.tok.text in ("+", "-"):
            op = self.tok.text
            self.pos += 1
            left = Binary(op, left, self.product())
        return left

    def product(self) -> Expr:
        left = self.unary()
        while self.tok.kind == "OP" and self.tok.text in ("*", "/"):
            op, where = self.tok.text, self.loc()
            self.pos += 1
            left = Binary(op, left, self.unary(), loc=where)
        return left

    def unary(self) -> Expr:
        if self.at("OP", "-"):
            with self.depth.inside(self._too_deep()):
                self.pos += 1
                return Unary("-", self.unary())
        return self.atom()

    def _too_deep(self):
        """The error of an expression nested too deeply, at the current token."""
        tok = self.tok
        return lambda message: self.fail(f"expression {message}", tok, hint="simplify the condition")

    def atom(self) -> Expr:
        tok = self.tok
        if tok.kind == "NUM":
            self.pos += 1
            return Const(float(tok.text))
        if tok.kind == "STR":
            self.pos += 1
            return Const(tok.text)
        if self.at("OP", "("):
            with self.depth.inside(self._too_deep()):
                self.pos += 1
                inner = self.expr()
                self.op(")")
                return inner
        if tok.kind == "NAME":
            self.pos += 1
            if tok.text in ("true", "false"):
                return Const(tok.text == "true")
            if tok.text == "attr":
                self.op("(")
                key = self.expect("STR", None, 'a quoted attribute key').text
                self.op(")")
                return Attr(key)
            if tok.text not in VARIABLES:
                raise self.fail(f"unknown variable {tok.text!r}", tok,
                                hint=f"variables are {', '.join(VARIABLES)} and attr(\"key\")")
            return Var(tok.text, loc=self.loc(tok))
        raise self.expected("a number, string, variable, attr(\"key\") or '('")

    # ---- semantic checks ------------------------------------------------------------------------------------
    def check(self, grammar: Grammar, start_tok: Token | None) -> None:
        seen: dict[str, Rule] = {}
        for rule in grammar.rules:
            if rule.symbol in seen:
                first = seen[rule.symbol].loc
                raise ParseError(f"duplicate rule for {rule.symbol} (first defined at line {first.line})",
                                 where=rule.loc, hint="a symbol has exactly one rule; use case or % alternatives")
            seen[rule.symbol] = rule
        if grammar.start not in seen:
            raise self.fail(f"undefined start symbol {grammar.start}", start_tok)
        uses = [u for rule in grammar.rules for u in successors(rule.body) if u[1] is not None] + self.grid_uses
        for symbol, loc in uses:
            if symbol not in seen and symbol not in BUILTIN_SYMBOLS:
                raise ParseError(f"undefined symbol {symbol}", where=loc,
                                 hint=f"add a rule '{symbol} --> ...' or fix the name")
        for rule in grammar.rules:
            chain = [rule.symbol]
            body = rule.body
            while isinstance(body, Rename) and body.symbol in seen:
                if body.symbol in chain:
                    cycle = " --> ".join(chain[chain.index(body.symbol):] + [body.symbol])
                    raise ParseError(f"rename cycle {cycle}", where=rule.loc,
                                     hint="one of these rules must split or end in a terminal")
                chain.append(body.symbol)
                body = seen[body.symbol].body
