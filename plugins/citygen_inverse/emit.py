"""Write an extracted grammar in citygen's grammar DSL (docs/grammar.md) with readable names.

Terminals are named from their labels (``Window1``, ``Wall2``: identical regions share a symbol); non-terminals
from their dominant label and place (``WindowBand3`` spans the facade width, ``WallColumn1`` its height, else
``...Group``); the axiom is ``Facade``. ``exact`` sizes are absolute metres, so deriving at the input size
reproduces the input. ``size_independent`` (wu2014 §5) turns sizes into relative weights except thin structures,
repeat tiles into floating sizes that fill any extent, and a facade whose rows form floors into a ``floors`` rule
that follows the building's floor lines.
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
    def __init__(self, index: LayoutIndex, rules: dict[int, Action], names: list[str] | None = None) -> None:
        self.index = index
        self.rules = rules
        self.names: dict[int, str] = {}
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
        terminal_names: dict[int, str] = {}
        fw = max(b[2] - b[0] for b in self.index.roots)
        fh = max(b[3] - b[1] for b in self.index.roots)
        for s in order:
            if s in self.names:
                continue
            info = self.index.sigs[s]
            if info.n == 1:
                kind = info.terminal
                if kind not in terminal_names:
                    label = (self.index.kinds[kind].label or "none").capitalize()
                    counters[label] += 1
                    terminal_names[kind] = f"{label}{counters[label]}"
                self.names[s] = terminal_names[kind]
                continue
            x0, y0, x1, y1 = info.box
            idx = self.index.inside(info.box)
            labels = Counter(self.index.kinds[self.index.sym[k]].label for k in idx)
            labels.pop("wall", None)
            base = (labels.most_common(1)[0][0] if labels else "wall").capitalize()
            base += "Band" if x1 - x0 == fw else "Column" if y1 - y0 == fh else "Group"
            counters[base] += 1
            self.names[s] = f"{base}{counters[base]}"
        return order

    def _item(self, s: int, rel: tuple[int, int, int, int], axis: int, mode: str) -> str:
        v = (rel[2 + axis] - rel[axis]) * self.index.quantum  # the item's own size (free extents share a symbol)
        if mode == "exact" or v < THIN:
            prefix = ""
        else:
            prefix = "~" if mode == "float" else "'"
        return f"{prefix}{_num(v)}: {self.names[s]}"

    def body(self, s: int, independent: bool) -> str:
        a = self.rules[s]
        axis = "xy"[a.axis]
        rel = "rel" if independent else "exact"
        flo = "float" if independent else "exact"
        if a.op == "grid":
            return self._grid(s, a, independent)
        mode = flo if a.op in ("repeat", "repeatABA") else rel
        text = " | ".join(self._item(c, box, a.axis, mode) for c, box in a.items)
        return f"{a.op}({axis}) {{ {text} }}"

    def _grid(self, s: int, a: Action, independent: bool) -> str:
        q = self.index.quantum
        xs, ys = a.grid_lines
        def sizes(lines):
            out = []
            for lo, hi in zip(lines, lines[1:]):
                v = (hi - lo) * q
                out.append(f"'{_num(v)}" if independent and v >= THIN else _num(v))
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
            lines.append(f"{self.names[s]} --> {self.body(s, independent)}")
        lines.extend(extra)
        written = set()
        for s in self._order:
            if s not in self.rules and self.index.sigs[s].n == 1 and self.names[s] not in written:
                written.add(self.names[s])
                lines.append(f"{self.names[s]} --> {self.terminal(s)}")
        return "\n".join(lines) + "\n"

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

