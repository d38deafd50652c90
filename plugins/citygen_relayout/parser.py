"""Parser of ``.relayout`` model files (syntax in docs/relayout.md).

Pass 1 reads the segmentation (``root``/``split``/``terminal``/``label`` statements, or a ``layout`` JSON);
pass 2 reads the constraints, resolving symbols and ``@label`` sets against it. A model built from a layout gets
the defaults of :mod:`citygen_relayout.inferred` for every composite and symbol its file says nothing about.
"""
from __future__ import annotations

from pathlib import Path

from citygen.errors import LayoutError, ParseError, SourceLocation, read_user_text
from citygen.layout import FacadeLayout
from citygen.nesting import Depth
from citygen_relayout import generators as gen
from citygen_relayout import inferred
from citygen_relayout.hierarchy import Segmentation, symbols_from_layout
from citygen_relayout.model import (ANCHORS, BEGIN, END, Alignment, CompositeRules, Frequency, InstancePolicy, Model,
                                    Pattern, SameSize, SizeRange, Symbol)
from citygen_relayout.tokens import Cursor, tokenize

DEFAULT_RANGE = (0.75, 1.5, 0.1)  # default min, max and sigma as fractions of the input size (§5.1)
_DEFS = {"model", "layout", "root", "split", "terminal", "label"}
_CONSTRAINTS = {"size", "freq", "seq", "repeat", "shuffle", "replicate", "instances", "symmetric", "mirror", "align",
                "samesize"}


def load_model(path: Path | str) -> Model:
    path = Path(path)
    return parse_model(read_user_text(path, ParseError, "model"), str(path), base=path.parent)


def parse_model(text: str, source: str = "<model>", base: Path | None = None) -> Model:
    cursors = []
    for lineno, line in enumerate(text.splitlines(), 1):
        tokens = tokenize(line, lineno, source)
        if tokens:
            cursors.append(Cursor(tokens, source, lineno, line))
    b = _Builder(source, base or Path("."))
    for cur in cursors:
        head = cur.peek(kind="word") and cur.tokens[0].text
        if head not in _DEFS | _CONSTRAINTS:
            raise cur.error("a statement (" + ", ".join(sorted(_DEFS | _CONSTRAINTS)) + ")")
        if head in _DEFS:
            cur.take()
            getattr(b, f"def_{head}")(cur)
            cur.finish()
    b.check_tree(cursors[0] if cursors else None)
    for cur in cursors:
        head = cur.tokens[0].text
        if head in _CONSTRAINTS:
            cur.take()
            getattr(b, f"con_{head}")(cur)
            cur.finish()
    return b.build()


class _Builder:
    def __init__(self, source: str, base: Path) -> None:
        self.source, self.base = source, base
        self.name = Path(source).stem
        self.root: str | None = None
        self.root_size: tuple[float, float] | None = None
        self.splits: dict[str, tuple[str, list[tuple[str, float]]]] = {}
        self.terminals: dict[str, dict] = {}
        self.labels: dict[str, str] = {}
        self.lines: dict[str, SourceLocation] = {}
        self.symbols: dict[str, Symbol] = {}
        self.sizes: dict[tuple[str, str], SizeRange] = {}
        self.sequences: dict[str, list] = {}
        self.freqs: dict[str, list[Frequency]] = {}
        self.instances: dict[str, dict[str, InstancePolicy]] = {}
        self.symmetric: set[str] = set()
        self.mirror: dict[str, str] = {}
        self.alignments: list[Alignment] = []
        self.samesizes: list[SameSize] = []
        self.segmentation: Segmentation | None = None  # when the segmentation came from a layout JSON
        self.depth = Depth()

    # ---- pass 1: segmentation
    def def_model(self, cur: Cursor) -> None:
        self.name = cur.word("a model name")

    def def_layout(self, cur: Cursor) -> None:
        tok = cur.take(kind="str", expected='a quoted path of a FacadeLayout JSON')
        path = self.base / tok.text.strip('"')
        tolerance = 1e-3
        if cur.accept("tolerance"):
            tolerance = cur.number("a relative size tolerance")[0]
        where = SourceLocation(self.source, tok.line, tok.column)
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            raise ParseError(f"cannot read layout {path.name}: {exc.strerror}", where=where) from exc
        except ValueError as exc:  # a NUL in the path, or not UTF-8
            raise ParseError(f"cannot read layout {path.name!r}: {exc}", where=where,
                             hint="name a UTF-8 FacadeLayout JSON file") from exc
        try:
            layout = FacadeLayout.loads(text, str(path))
            self.segmentation = symbols_from_layout(layout, tolerance)
            self.symbols, self.root = dict(self.segmentation.symbols), self.segmentation.root
        except LayoutError as exc:
            raise ParseError(f"layout {path.name}: {exc.message}",
                             where=SourceLocation(self.source, tok.line, tok.column), hint=exc.hint) from exc

    def def_root(self, cur: Cursor) -> None:
        self.root = cur.word("the root symbol")
        self.root_size = (self._positive(cur, "the input width"), self._positive(cur, "the input height"))

    def def_split(self, cur: Cursor) -> None:
        name = cur.word("a composite symbol")
        axis = cur.word("x or y")
        if axis not in ("x", "y"):
            cur.i -= 1
            raise cur.error("split axis x or y")
        children = []
        while not cur.done():
            child = cur.word("a child symbol")
            cur.take(":", expected="':' and the child's input size")
            children.append((child, self._positive(cur, "the child's input size")))
        if not children:
            raise cur.error("children as SYMBOL:SIZE")
        self.splits[name] = (axis, children)
        self.lines[name] = SourceLocation(self.source, cur.lineno, cur.tokens[1].column)

    def def_terminal(self, cur: Cursor) -> None:
        name = cur.word("a terminal symbol")
        attrs: dict = {"label": cur.word("a label")}
        while not cur.done():
            key = cur.word("depth, material or asset")
            if key == "depth":
                attrs["depth"] = cur.number()[0]
            elif key in ("material", "asset"):
                attrs[key] = cur.take(kind="str", expected="a quoted string").text.strip('"')
            else:
                cur.i -= 1
                raise cur.error("depth, material or asset")
        self.terminals[name] = attrs
        self.lines[name] = SourceLocation(self.source, cur.lineno, cur.tokens[1].column)

    def def_label(self, cur: Cursor) -> None:
        name = cur.word("a symbol")
        self.labels[name] = cur.word("a label")

    def _positive(self, cur: Cursor, what: str) -> float:
        value, _ = cur.number(what)
        if value <= 0:
            cur.i -= 1
            raise cur.error(f"{what} > 0")
        return value

    def check_tree(self, first: Cursor | None) -> None:
        """Turn the authored statements into symbols (unless a layout JSON gave them)."""
        where = SourceLocation(self.source, first.lineno if first else 1, 1)
        if not self.symbols:
            if self.root is None or self.root_size is None:
                raise ParseError("model has no segmentation", where=where,
                                 hint="give 'root SYMBOL W H' with split/terminal statements, or 'layout \"file\"'")
            self._author(self.root, self.root_size, where)
        for name, label in self.labels.items():
            sym = self._symbol(name, where)
            self.symbols[name] = Symbol(**{**sym.__dict__, "label": label})

    def _author(self, name: str, extent: tuple[float, float], where: SourceLocation,
                axis: str | None = None) -> None:
        if name in self.symbols:
            k = {"x": 0, "y": 1}.get(axis)
            if k is not None and abs(self.symbols[name].extent[k] - extent[k]) > 1e-6 * max(1.0, extent[k]):
                raise ParseError(f"symbol {name} is used with two different {axis}-sizes", where=where,
                                 hint="identical regions share a symbol; give different regions different symbols")
            return
        if name in self.splits:
            axis, children = self.splits[name]
            total = sum(s for _, s in children)
            along = extent[0] if axis == "x" else extent[1]
            if abs(total - along) > 1e-6 * max(1.0, along):
                raise ParseError(f"children of {name} sum to {total:g}, its {axis}-size is {along:g}",
                                 where=self.lines[name])
            self.symbols[name] = Symbol(name, extent, split=axis, children=tuple(c for c, _ in children))
            for child, size in children:
                self._author(child, (size, extent[1]) if axis == "x" else (extent[0], size), self.lines[name], axis)
        elif name in self.terminals:
            self.symbols[name] = Symbol(name, extent, **self.terminals[name])
        else:
            raise ParseError(f"symbol {name} is neither split nor terminal", where=where,
                             hint=f"add 'terminal {name} LABEL' or 'split {name} x|y ...'")

    def _symbol(self, name: str, where: SourceLocation) -> Symbol:
        if name not in self.symbols:
            raise ParseError(f"unknown symbol {name}", where=where)
        return self.symbols[name]

    # ---- pass 2: constraints
    def _composite(self, cur: Cursor) -> Symbol:
        where = cur.where()
        sym = self._symbol(cur.word("a composite symbol"), where)
        if sym.is_terminal:
            raise ParseError(f"{sym.name} is a terminal; this constraint needs a composite region", where=where)
        return sym

    def _item(self, cur: Cursor, scope: tuple[str, ...] | None) -> frozenset[str]:
        """SYMBOL | @label | {item ...} | ^ | $, resolved within ``scope`` (child symbols) or globally."""
        where = cur.where()
        if cur.accept("^") or cur.accept("⊢"):
            return frozenset({BEGIN})
        if cur.accept("$") or cur.accept("⊣"):
            return frozenset({END})
        if cur.accept("{"):
            out: set[str] = set()
            with self.depth.inside(lambda message: ParseError(f"set {message}", where=where)):
                while not cur.accept("}"):
                    if cur.done():
                        raise cur.error("'}'")
                    out |= self._item(cur, scope)
            return frozenset(out)
        pool = scope if scope is not None else tuple(self.symbols)
        if cur.peek(kind="label"):
            label = cur.take().text[1:]
            found = frozenset(s for s in pool if self.symbols[s].label == label)
            if not found:
                raise ParseError(f"no region labelled {label} here", where=where)
            return found
        name = cur.word("a symbol, @label, {set}, ^ or $")
        if name not in pool:
            raise ParseError(f"{name} is not " + ("a child of this region" if scope else "a symbol"), where=where)
        return frozenset({name})

    def _items(self, cur: Cursor, scope: tuple[str, ...] | None, close: str | None = None) -> tuple:
        items = []
        while not cur.done() and not (close and cur.peek(close)):
            items.append(self._item(cur, scope))
        if close:
            cur.take(close, expected=f"'{close}'")
        if not items:
            raise cur.error("at least one item")
        return tuple(items)

    def _range(self, cur: Cursor) -> tuple[float, float, bool]:
        lo, lo_pct = cur.number("a lower bound")
        cur.take("..", expected="'..'")
        hi, hi_pct = cur.number("an upper bound")
        if hi < lo:
            cur.i -= 1
            raise cur.error(f"an upper bound >= {lo:g}")
        return lo, hi, lo_pct or hi_pct

    def con_size(self, cur: Cursor) -> None:
        where = cur.where()
        sym = self._symbol(cur.word("a symbol"), where)
        lo, hi, pct = self._range(cur)
        mean = sigma = None
        axes = ("x", "y")
        while not cur.done():
            key = cur.word("mean, sigma or axis")
            if key == "mean":
                mean = cur.number()[0]
            elif key == "sigma":
                sigma = cur.number()[0]
            elif key == "axis":
                axes = (cur.word("x or y"),)
            else:
                cur.i -= 1
                raise cur.error("mean, sigma or axis")
        for axis in axes:
            base = sym.extent[0 if axis == "x" else 1]
            a, b = (lo * base / 100, hi * base / 100) if pct else (lo, hi)
            m = base if mean is None else (mean * base / 100 if pct else mean)
            s = DEFAULT_RANGE[2] * base if sigma is None else (sigma * base / 100 if pct else sigma)
            self.sizes[(sym.name, axis)] = SizeRange(a, b, min(max(m, a), b), s)

    def con_freq(self, cur: Cursor) -> None:
        parent = self._composite(cur)
        members = self._item(cur, parent.children)
        while cur.peek("|") or cur.peek("&") or cur.peek("-"):
            op = cur.take().text
            other = self._item(cur, parent.children)
            members = members | other if op == "|" else members & other if op == "&" else members - other
        lo, hi, _ = self._range(cur)
        relative = cur.accept("relative")
        self.freqs.setdefault(parent.name, []).append(
            Frequency(frozenset(members), lo, hi, relative, cur.text, cur.lineno))

    def _add_sequences(self, parent: str, seqs: list) -> None:
        self.sequences.setdefault(parent, []).extend(s for s in seqs if s not in self.sequences.get(parent, []))

    def con_seq(self, cur: Cursor) -> None:
        parent = self._composite(cur)
        cur.take(":", expected="':' and the sequence")
        self._add_sequences(parent.name, [self._items(cur, parent.children)])

    def con_shuffle(self, cur: Cursor) -> None:
        parent = self._composite(cur)
        cur.take(":", expected="':' and the sub-sequence to shuffle")
        self._add_sequences(parent.name, gen.two_shuffle(self._items(cur, parent.children)))

    def con_replicate(self, cur: Cursor) -> None:
        parent = self._composite(cur)
        if cur.accept(":"):
            self._add_sequences(parent.name, gen.replication(self._items(cur, parent.children), bounded=False))
        else:
            items = tuple(frozenset({c}) for c in parent.children)
            self._add_sequences(parent.name, gen.replication(items))

    def con_repeat(self, cur: Cursor) -> None:
        parent = self._composite(cur)
        cur.take(":", expected="':' and a pattern")
        node = self._pattern(cur, parent.children, close=None)
        self._add_sequences(parent.name, gen.repetition(node))

    def _pattern(self, cur: Cursor, scope: tuple[str, ...], close: str | None) -> gen.Node:
        parts = []
        while not cur.done() and not (close and cur.peek(close)):
            where = cur.where()
            if cur.accept("("):
                with self.depth.inside(lambda message: ParseError(f"group {message}", where=where)):
                    node = self._pattern(cur, scope, ")")
            else:
                node = gen.Node("item", item=self._item(cur, scope))
            for op in "?*+":
                if cur.accept(op):
                    node = gen.Node(op, parts=(node,))
                    break
            parts.append(node)
        if close:
            cur.take(close, expected=f"'{close}'")
        if not parts:
            raise cur.error("a pattern item")
        return gen.Node("seq", parts=tuple(parts))

    def con_instances(self, cur: Cursor) -> None:
        parent = self._composite(cur)
        where = cur.where()
        name = cur.word("a child symbol")
        if name not in parent.children:
            raise ParseError(f"{name} is not a child of {parent.name}", where=where)
        lo, hi, _ = self._range(cur)
        relative = cur.accept("relative")
        self.instances.setdefault(parent.name, {})[name] = InstancePolicy(lo, hi, relative)

    def con_symmetric(self, cur: Cursor) -> None:
        self.symmetric.add(self._composite(cur).name)

    def con_mirror(self, cur: Cursor) -> None:
        where = cur.where()
        a = self._symbol(cur.word("a symbol"), where).name
        where = cur.where()
        b = self._symbol(cur.word("its mirror symbol"), where).name
        self.mirror[a], self.mirror[b] = b, a

    def _side(self, cur: Cursor, anchored: bool) -> tuple[Pattern, float]:
        before = after = ()
        if cur.accept("("):
            group = self._items(cur, None, ")")
            if cur.accept("<"):
                before = group
                group = None
        else:
            group = None
        if group is None:
            if cur.accept("("):
                group = self._items(cur, None, ")")
            else:
                group = (self._item(cur, None),)
        anchor = 0.0
        if anchored:
            if len(group) != 1:
                raise cur.error("one aligned item")
            cur.take(".", expected="'.' and min, center or max")
            where = cur.where()
            name = cur.word("min, center or max")
            if name not in ANCHORS:
                raise ParseError(f"expected min, center or max, got {name!r}", where=where)
            anchor = ANCHORS[name]
        if cur.accept(">"):
            cur.take("(", expected="'(' and the succeeding context")
            after = self._items(cur, None, ")")
        return Pattern(group, before, after), anchor

    def _tail(self, cur: Cursor) -> tuple[str | None, bool]:
        within, across = None, False
        while not cur.done():
            if cur.accept("within"):
                within = self._composite(cur).name
            elif cur.accept("across"):
                across = True
            else:
                raise cur.error("within SYMBOL or across")
        return within, across

    def con_align(self, cur: Cursor) -> None:
        a, la = self._side(cur, True)
        cur.take("=", expected="'='")
        b, lb = self._side(cur, True)
        within, across = self._tail(cur)
        if across:
            raise cur.error("within (alignment holds within one face)")
        self.alignments.append(Alignment(a, la, b, lb, within, cur.text, cur.lineno))

    def con_samesize(self, cur: Cursor) -> None:
        a, _ = self._side(cur, False)
        cur.take("=", expected="'='")
        b, _ = self._side(cur, False)
        within, across = self._tail(cur)
        self.samesizes.append(SameSize(a, b, within, across, cur.text, cur.lineno))

    def build(self) -> Model:
        rules, seg = {}, self.segmentation
        for name, sym in self.symbols.items():
            if sym.is_terminal:
                continue
            seqs, freqs = self.sequences.get(name), self.freqs.get(name, [])
            if not seqs and seg is not None:
                seqs = inferred.sequences(sym, self.symbols, seg)
                freqs = freqs or inferred.frequencies(sym, self.symbols)
            seqs = seqs or gen.replication(tuple(frozenset({c}) for c in sym.children))
            mirrored = name in self.symmetric or (seg is not None and name not in self.sequences
                                                  and inferred.symmetric(sym, self.symbols))
            rules[name] = CompositeRules(tuple(seqs), tuple(freqs), dict(self.instances.get(name, {})), mirrored)
        sizes = dict(self.sizes)
        lo, hi, sig = DEFAULT_RANGE
        bands = _band_parts(self.symbols) if seg is not None else frozenset()
        for sym in self.symbols.values():
            for axis, base in zip("xy", sym.extent):
                sizes.setdefault((sym.name, axis), inferred.size_range(sym, axis, _role(sym.name, seg, bands))
                                 if seg is not None else SizeRange(lo * base, hi * base, base, sig * base))
        return Model(self.name, self.root, dict(self.symbols), sizes, rules, tuple(self.alignments),
                     tuple(self.samesizes), dict(self.mirror), self.source,
                     inferred.terminal_minimums(self.symbols) if seg is not None else {})


def _role(name: str, seg: Segmentation, bands: frozenset[str]) -> str | None:
    """A symbol's role in the facade's storey segmentation (``storey``, ``gap``, ``top``), or ``band`` for a part
    of a row without openings (a molding or wall band), if it has one."""
    if seg.storeys and name in seg.symbols[seg.root].children:
        return "gap" if name in seg.gaps else "top" if name in seg.bands else "storey"
    return "band" if name in bands else None


def _band_parts(symbols) -> frozenset[str]:
    """Terminals of rows (x-splits) that hold no opening: they stretch with the facade's width."""
    memo: dict[str, bool] = {}
    return frozenset(c for sym in symbols.values() if sym.split == "x"
                     and not any(inferred.opening_bearing(k, symbols, memo) for k in sym.children)
                     for c in sym.children if symbols[c].is_terminal)
