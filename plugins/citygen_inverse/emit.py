"""Write an extracted grammar in citygen's grammar DSL (docs/grammar.md) with readable names.

Terminals are named by their label (``Window``, ``Wall``, ``Door``); a second terminal kind of one label (another
depth) gets a number (``Window2``). Their size comes from the parent split, so terminals of one label and depth
share one symbol whatever their size, and terminal rules cost nothing (docs/grammar.md, Cost): naming does not
change the Eq. 1 cost. Non-terminals are named from their dominant label and place (``WindowBand3`` spans the
facade width, ``WallColumn1`` its height, else ``...Group``); the axiom is ``Facade``.

Sizes are written in one of three modes: ``exact`` (absolute metres: deriving at the input size reproduces the
input), ``independent`` (wu2014 §5: relative weights except thin structures, floating repeat tiles) and ``linear``
(every size relative, repeats written out as splits of their tile count: the derivation is then the input scaled
along each axis, so every edge aligned in the input stays aligned at any size -- used by
:mod:`citygen_inverse.independent`, see docs/inverse.md "Alignment").
"""
from __future__ import annotations

from collections import Counter

from citygen_inverse.actions import Action
from citygen_inverse.regions import LayoutIndex

THIN = 0.3  # metres: parts thinner than this keep absolute sizes in size-independent grammars


def _num(v: float) -> str:
    text = f"{v:.9g}"
    return text if "e" not in text else f"{v:.12f}".rstrip("0").rstrip(".")


class GrammarWriter:
    def __init__(self, index: LayoutIndex, rules: dict[int, Action], names: list[str] | None = None,
                 reserved: frozenset[str] = frozenset()) -> None:
        self.index = index
        self.rules = rules
        self.names: dict[int, str] = {}
        self.reserved = {"Corner", *reserved}  # Corner has a built-in meaning in ``floors`` (docs/grammar.md)
        roots = [index.sig(b) for b in index.roots]
        for k, r in enumerate(roots):
            self.names.setdefault(r, names[k] if names else ("Facade" if len(roots) == 1 else f"Facade{k + 1}"))
        self.roots = roots
        self._order = self._walk()

    def _walk(self) -> list[int]:
        order, seen, stack = [], set(), list(reversed(self.roots))
        while stack:
            s = stack.pop()
            if s in seen:
                continue
            seen.add(s)
            order.append(s)
            if s in self.rules:
                stack.extend(reversed([c for c, _ in self.rules[s].items]))
        counters: Counter[str] = Counter()
        taken = set(self.reserved) | set(self.names.values())
        terminal_names: dict[tuple[str | None, float], str] = {}
        fw = max(b[2] - b[0] for b in self.index.roots)
        fh = max(b[3] - b[1] for b in self.index.roots)
        for s in order:
            if s in self.names:
                continue
            info = self.index.sigs[s]
            if info.n == 1:
                kind = self.index.kinds[info.terminal]
                key = (kind.label, kind.depth)
                if key not in terminal_names:
                    terminal_names[key] = _fresh((kind.label or "none").capitalize(), counters, taken, first="")
                self.names[s] = terminal_names[key]
                continue
            x0, y0, x1, y1 = info.box
            idx = self.index.inside(info.box)
            labels = Counter(self.index.kinds[self.index.sym[k]].label for k in idx)
            labels.pop("wall", None)
            base = (labels.most_common(1)[0][0] if labels else "wall").capitalize()
            base += "Band" if x1 - x0 == fw else "Column" if y1 - y0 == fh else "Group"
            self.names[s] = _fresh(base, counters, taken)
        return order

    def _item(self, s: int, rel: tuple[int, int, int, int], axis: int, mode: str) -> str:
        v = (rel[2 + axis] - rel[axis]) * self.index.quantum  # the item's own size (free extents share a symbol)
        if mode == "linear":
            return f"'{_num(v)}: {self.names[s]}"
        if mode == "exact" or v < THIN:
            prefix = ""
        else:
            prefix = "~" if mode == "float" else "'"
        return f"{prefix}{_num(v)}: {self.names[s]}"

    def body(self, s: int, mode: str) -> str:
        """The rule body of signature ``s`` with sizes in ``mode`` (exact, independent or linear)."""
        a = self.rules[s]
        axis = "xy"[a.axis]
        items = list(a.items)
        if a.op == "grid":
            return self._grid(a, mode)
        op = a.op
        if mode == "linear" and op in ("repeat", "repeatABA"):
            items, op = self._expand(s, a), "split"
        item_mode = {"exact": "exact", "linear": "linear"}.get(mode, "float" if op in ("repeat", "repeatABA")
                                                                     else "rel")
        text = " | ".join(self._item(c, box, a.axis, item_mode) for c, box in items)
        return f"{op}({axis}) {{ {text} }}"

    def _expand(self, s: int, a: Action) -> list[tuple[int, tuple[int, int, int, int]]]:
        """The successors a repeat or repeatABA places at the input size (its tile count is fixed by the input;
        so the index must not share periodic signatures across counts)."""
        extent = self.index.sigs[s].box[2 + a.axis] - self.index.sigs[s].box[a.axis]
        sizes = [box[2 + a.axis] - box[a.axis] for _, box in a.items]
        items = list(a.items)
        if a.op == "repeat":
            return items * (extent // sum(sizes))
        n = (extent - sizes[0]) // sum(sizes)
        return items * n + items[:1]

    def _grid(self, a: Action, mode: str) -> str:
        q = self.index.quantum
        xs, ys = a.grid_lines
        def sizes(lines):
            out = []
            for lo, hi in zip(lines, lines[1:]):
                v = (hi - lo) * q
                out.append(f"'{_num(v)}" if mode == "linear" or (mode == "independent" and v >= THIN) else _num(v))
            return " | ".join(out)
        cells = [["?"] * (len(xs) - 1) for _ in range(len(ys) - 1)]
        for c, (x0, y0, x1, y1) in a.items:
            c0, c1, r0, r1 = xs.index(x0), xs.index(x1), ys.index(y0), ys.index(y1)
            for r in range(r0, r1):
                for col in range(c0, c1):
                    cells[r][col] = self.names[c] if (r, col) == (r0, c0) else ("<" if r == r0 else "v")
        rows = " / ".join(" ".join(row) for row in cells)
        return f"grid {{ cols: {sizes(xs)} ; rows: {sizes(ys)} ; {rows} }}"

    def terminal(self, s: int) -> str:
        kind = self.index.kinds[self.index.sigs[s].terminal]
        depth = f", depth: {_num(kind.depth)}" if kind.depth else ""
        return f"terminal({kind.label or 'none'}{depth})"

    def text(self, header: list[str], independent: bool = False, floors: bool = False) -> str:
        """The grammar file: header comments, ``@size`` (or the joint axiom), rules in derivation order."""
        lines = [f"# {h}" for h in header]
        if len(self.roots) == 1:
            b = self.index.roots[0]
            lines.append(f"@size {_num((b[2] - b[0]) * self.index.quantum)} {_num((b[3] - b[1]) * self.index.quantum)}")
        else:
            share = 100 // len(self.roots)
            alts = "  ".join(f"{share}%: {self.names[r]}" for r in self.roots[:-1])
            lines.append(f"Facade --> {alts}  else: {self.names[self.roots[-1]]}")
        extra: list[str] = []
        for s in self._order:
            if s not in self.rules:
                continue
            if floors and s == self.roots[0] and len(self.roots) == 1:
                body = self._floors(s, extra)
                if body:
                    lines.append(f"{self.names[s]} --> {body}")
                    continue
            lines.append(f"{self.names[s]} --> {self.body(s, 'independent' if independent else 'exact')}")
        lines.extend(extra)
        lines.extend(self.terminal_rules())
        return "\n".join(lines) + "\n"

    def rule_lines(self, mode: str) -> list[str]:
        """Every rule (non-terminals in derivation order, then terminals) with sizes in ``mode``."""
        body = [f"{self.names[s]} --> {self.body(s, mode)}" for s in self._order if s in self.rules]
        return body + self.terminal_rules()

    def terminal_rules(self) -> list[str]:
        lines, written = [], set()
        for s in self._order:
            if s not in self.rules and self.index.sigs[s].n == 1 and self.names[s] not in written:
                written.add(self.names[s])
                lines.append(f"{self.names[s]} --> {self.terminal(s)}")
        return lines

    def _floors(self, s: int, extra: list[str]) -> str | None:
        """``floors`` for a facade split along y into [ground...] [repeated floors] [top...] (wu2014 §5)."""
        a = self.rules[s]
        if a.axis != 1 or a.op not in ("split", "repeat"):
            return None
        if a.op == "repeat":
            tile = list(a.items)
            return f"floors {{ *: {self._group('Floor', tile, extra)} }}"
        items = list(a.items)
        reps = [k for k, (c, _) in enumerate(items) if c in self.rules and self.rules[c].op == "repeat"
                and self.rules[c].axis == 1]
        if not reps:
            return None
        k = max(reps, key=lambda i: items[i][1][3] - items[i][1][1])
        tile = list(self.rules[items[k][0]].items)
        parts = [f"*: {self._group('Floor', tile, extra)}"]
        if k > 0:
            parts.insert(0, f"0: {self._group('Ground', items[:k], extra)}")
        if k < len(items) - 1:
            parts.insert(1 if k > 0 else 0, f"-1: {self._group('Top', items[k + 1:], extra)}")
        return f"floors {{ {' | '.join(parts)} }}"

    def _group(self, name: str, items: list[tuple[int, tuple[int, int, int, int]]], extra: list[str]) -> str:
        if len(items) == 1:
            return self.names[items[0][0]]
        text = " | ".join(self._item(c, box, 1, "rel") for c, box in items)
        extra.append(f"{name} --> split(y) {{ {text} }}")
        return name



def _fresh(base: str, counters: Counter[str], taken: set[str], first: str | None = None) -> str:
    """``base`` + the next free number (``first`` for the first one, e.g. "" so the first window is ``Window``)."""
    while True:
        counters[base] += 1
        name = f"{base}{first if counters[base] == 1 and first is not None else counters[base]}"
        if name not in taken:
            taken.add(name)
            return name
