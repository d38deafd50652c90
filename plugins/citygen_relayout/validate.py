"""Validator of relayout results: partition plus every hard constraint of the model (bao2013 §5.1).

Independent of the search: it re-reads the region tree of a :class:`FacadeLayout` (symbols ``S`` or ``S'k``
for instance ``k``) and checks splits, sequences (cover automaton), frequencies, instances and replicas, region
sizes, symmetry, alignment and same-size constraints. Returns human-readable problems; empty means valid.
"""
from __future__ import annotations

from citygen.layout import FacadeLayout, Region, check_partition
from citygen_relayout.compiled import compile_model, scaled_bounds
from citygen_relayout.model import BEGIN, END, Model


def _base(symbol: str) -> tuple[str, int]:
    name, _, inst = symbol.partition("'")
    return name, int(inst) if inst.isdigit() else 0


def validate(layout: FacadeLayout, model: Model, *, entrance: bool | None = None, tol: float = 1e-6) -> list[str]:
    """Problems of ``layout`` against ``model``; ``entrance=False`` relaxes door-only frequency minimums (§9.1)."""
    problems = check_partition(layout)
    v = _Validator(model, entrance, tol * max(layout.width, layout.height, 1.0))
    v.region(layout.root, None, {})
    v.alignments()
    v.samesizes()
    return problems + v.problems


class _Validator:
    def __init__(self, model: Model, entrance: bool | None, eps: float) -> None:
        self.model, self.comp, self.entrance, self.eps = model, compile_model(model), entrance, eps
        self.problems: list[str] = []
        self.occ: dict[tuple, list] = {}  # (kind, index, side) -> [(axis, start, end, scope-ancestors)]

    def region(self, r: Region, axis: str | None, anc: dict[str, int]) -> None:
        name, _ = _base(r.symbol)
        sym = self.model.symbols.get(name)
        if sym is None:
            self.problems.append(f"{r.symbol}: not a symbol of model {self.model.name}")
            return
        anc = {**anc, name: id(r)}
        if sym.is_terminal:
            if r.children:
                self.problems.append(f"{r.symbol}: terminal symbol with children")
            elif r.label != sym.label:
                self.problems.append(f"{r.symbol}: label {r.label!r}, model says {sym.label!r}")
            return
        if not r.children:
            self.problems.append(f"{r.symbol}: composite symbol without children")
            return
        a = sym.split
        kids = sorted(r.children, key=lambda c: c.x if a == "x" else c.y)
        self.split(r, kids, a)
        names = [_base(c.symbol) for c in kids]
        syms = [n for n, _ in names]
        rules = self.model.rules[name]
        where = f"{r.symbol} at ({r.x:.3f}, {r.y:.3f})"
        if not self.comp.automata[name].accepts(syms):
            self.problems.append(f"{where}: arrangement {' '.join(syms)} is not covered by its sequences")
        total, size_in = (r.w, sym.extent[0]) if a == "x" else (r.h, sym.extent[1])
        for f in rules.frequencies:
            lo, hi = scaled_bounds(f.lo, f.hi, f.relative, total, size_in)
            if self.entrance is False and all(self.comp.door[m] for m in f.members):
                lo = 0
            n = sum(1 for s in syms if s in f.members)
            if not lo <= n <= hi:
                self.problems.append(f"{where}: {f.text} counts {n}, allowed {lo}..{hi} (line {f.line})")
        for s, pol in rules.instances.items():
            distinct = {i for n, i in names if n == s}
            lo, hi = scaled_bounds(pol.lo, pol.hi, pol.relative, total, size_in)
            if distinct and not lo <= len(distinct) <= hi:
                self.problems.append(f"{where}: {len(distinct)} distinct instances of {s}, allowed {lo}..{hi}")
        first: dict[tuple[str, int], Region] = {}
        for c, key in zip(kids, names):
            ext = c.w if a == "x" else c.h
            rng = self.model.sizes[(key[0], a)]
            if not rng.lo - self.eps <= ext <= rng.hi + self.eps:
                self.problems.append(f"{c.symbol} in {where}: size {ext:.4f} outside {rng.lo:.4f}..{rng.hi:.4f}")
            key = (*key, any(t.label == "door" for t in c.terminals()))  # the door holder is its own instance
            if key in first and not _same_shape(first[key], c, self.eps):
                self.problems.append(f"{c.symbol} in {where}: replica differs from its first instance")
            first.setdefault(key, c)
        if rules.symmetric:
            self.symmetry(where, kids, syms, a)
        self.occurrences(kids, syms, a, anc)
        for c in kids:
            self.region(c, a, anc)

    def split(self, r: Region, kids: list[Region], a: str) -> None:
        pos = r.x if a == "x" else r.y
        for c in kids:
            start, ext = (c.x, c.w) if a == "x" else (c.y, c.h)
            ortho = (c.y, c.h, r.y, r.h) if a == "x" else (c.x, c.w, r.x, r.w)
            if abs(start - pos) > self.eps or abs(ortho[0] - ortho[2]) > self.eps or abs(ortho[1] - ortho[3]) > self.eps:
                self.problems.append(f"{c.symbol}: does not continue the {a}-split of {r.symbol}")
            pos = start + ext
        if abs(pos - ((r.x + r.w) if a == "x" else (r.y + r.h))) > self.eps:
            self.problems.append(f"{r.symbol}: children do not fill it along {a}")

    def symmetry(self, where: str, kids: list[Region], syms: list[str], a: str) -> None:
        n = len(kids)
        for i in range(n // 2 + 1):
            j = n - 1 - i
            if self.model.mirrored(syms[i]) != syms[j]:
                self.problems.append(f"{where}: symmetric region is not a palindrome ({syms[i]} vs {syms[j]})")
                return
            si, sj = (kids[i].w, kids[j].w) if a == "x" else (kids[i].h, kids[j].h)
            if abs(si - sj) > self.eps:
                self.problems.append(f"{where}: mirrored regions {syms[i]}, {syms[j]} differ in size")
                return

    def occurrences(self, kids: list[Region], syms: list[str], a: str, anc: dict[str, int]) -> None:
        toks = [BEGIN, *syms, END]
        for end in range(1, len(toks)):
            for ref in self.comp.by_last.get(toks[end], ()):
                items = ref.pattern.items
                start = end - len(items) + 1
                if start < 0 or any(toks[start + j] not in items[j] for j in range(len(items))):
                    continue
                v = start + len(ref.pattern.before) - 1
                n = len(ref.pattern.body)
                if v < 0 or v + n > len(kids):
                    continue
                s0 = kids[v].x if a == "x" else kids[v].y
                last = kids[v + n - 1]
                s1 = (last.x + last.w) if a == "x" else (last.y + last.h)
                self.occ.setdefault((ref.kind, ref.index, ref.side), []).append((a, s0, s1, anc))

    def alignments(self) -> None:
        for k, al in enumerate(self.model.alignments):
            left = self.occ.get(("align", k, 0), [])
            right = self.occ.get(("align", k, 1), [])
            for a1, s1, e1, anc1 in left:
                for a2, s2, e2, anc2 in right:
                    if a1 != a2 or min(e1, e2) - max(s1, s2) <= 1e-6 or (s1, e1, anc1) is (s2, e2, anc2):
                        continue
                    if al.within and (al.within not in anc1 or anc1.get(al.within) != anc2.get(al.within)):
                        continue
                    if anc1 is anc2 and (s1, e1) != (s2, e2):
                        continue  # siblings of one arrangement never overlap
                    p1 = s1 + al.a_anchor * (e1 - s1)
                    p2 = s2 + al.b_anchor * (e2 - s2)
                    if abs(p1 - p2) > 1e-5 * max(1.0, abs(p1)):
                        self.problems.append(f"align {al.text} (line {al.line}): {a1} {s1:.3f}..{e1:.3f} and "
                                             f"{s2:.3f}..{e2:.3f} overlap but are not aligned")
                        if len(self.problems) > 50:
                            return

    def samesizes(self) -> None:
        for k, ss in enumerate(self.model.samesizes):
            groups: dict[object, list[float]] = {}
            for side in (0, 1):
                for _, s, e, anc in self.occ.get(("same", k, side), []):
                    if ss.within:
                        if ss.within not in anc:
                            continue
                        key = anc[ss.within]
                    else:
                        key = 0
                    groups.setdefault(key, []).append(e - s)
            for sizes in groups.values():
                if max(sizes) - min(sizes) > 1e-5 * max(1.0, max(sizes)):
                    self.problems.append(f"samesize {ss.text} (line {ss.line}): sizes {min(sizes):.4f} and "
                                         f"{max(sizes):.4f} differ")


def _same_shape(a: Region, b: Region, eps: float) -> bool:
    if abs(a.w - b.w) > eps or abs(a.h - b.h) > eps or a.symbol != b.symbol or len(a.children) != len(b.children):
        return False
    return all(abs((ca.x - a.x) - (cb.x - b.x)) <= eps and abs((ca.y - a.y) - (cb.y - b.y)) <= eps
               and _same_shape(ca, cb, eps) for ca, cb in zip(a.children, b.children))
