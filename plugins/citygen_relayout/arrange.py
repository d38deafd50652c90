"""The ``layout`` function of bao2013 §7.2-§7.3 for one composite region.

It builds the arrangement ``⊢ A1 .. An ⊣`` element by element: the successor set S comes from the sequences
whose prefix overlaps a postfix of the arrangement (the cover automaton), pruned by frequency, instance, door
budget and minimum-size checks; an element of S is chosen stochastically, its initial size sampled from its
truncated Gaussian, and a QP re-sizes all elements under the newly active constraints (region size, instance
replicas, alignment, same-size, floor lines / corner strips of the request, total size). A failed QP or an
exhausted successor set backtracks. Symmetric regions are built from both ends at once (§7.3). Every complete
arrangement is verified (alignment overlaps, floors, contexts ending at ⊣) and re-solved with the constraints that
became active, then yielded; asking for the next solution resumes the search (chronological backtracking).
"""
from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from itertools import accumulate

import numpy as np

from citygen_relayout.compiled import PatternRef, scaled_bounds
from citygen_relayout.model import BEGIN, END
from citygen_relayout.sizing import solve_sizes


@dataclass(slots=True)
class Row:
    """A linear constraint ``sign * sum_{i < prefix} x_i + sum coefs[i] * x_i (= or <=) rhs`` with its provenance
    for blame and backjumping. The prefix is an element's start (or end) position; ``coefs`` name only elements
    from ``prefix`` on. ``pair`` is ``(u, v)`` for ``x_u - x_v = 0`` (replicas, mirrors: merged variables)."""

    coefs: dict[int, float]
    rhs: float
    eq: bool
    tag: str
    frames: frozenset[int] = frozenset()
    key: tuple = ()
    prefix: int = 0
    sign: int = 1
    pair: tuple[int, int] | None = field(init=False, default=None)

    def __post_init__(self) -> None:
        if self.eq and self.rhs == 0.0 and self.prefix + len(self.coefs) == 2:
            full = {**dict.fromkeys(range(self.prefix), float(self.sign)), **self.coefs} if self.prefix else self.coefs
            if sorted(full.values()) == [-1.0, 1.0]:
                self.pair = tuple(full)


@dataclass
class Solution:
    elements: list[tuple[str, int]]
    sizes: np.ndarray
    align_occ: list[tuple[int, int, int]]  # (alignment index, side, element index)
    same_occ: list[tuple[int, tuple, int, int]]  # (samesize index, scope, first element, length)
    doors: list[int]  # door budget handed to each element (1 = this element holds the face's door)
    cum: list[float] = field(default_factory=list)  # element boundaries relative to the region's start


@dataclass
class _State:
    elems: list[tuple[str, int]] = field(default_factory=list)
    doors: list[int] = field(default_factory=list)
    floor: list[int | None] = field(default_factory=list)  # floor an element is laid out in (None: free)
    xbar: list[float] = field(default_factory=list)
    lo: list[float] = field(default_factory=list)
    hi: list[float] = field(default_factory=list)
    rows: list[Row] = field(default_factory=list)
    x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    same_occ: list[tuple[int, tuple, int, int]] = field(default_factory=list)


def _find(parent: list[int], i: int) -> int:
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


def layout(ctx, node) -> Iterator[Solution]:
    """Yield valid arrangements of composite ``node`` (a ``search.Node``) one after another."""
    return _Layout(ctx, node).run()


class _Layout:
    def __init__(self, ctx, node) -> None:
        self.ctx, self.node = ctx, node
        model = ctx.model
        self.sym = model.symbols[node.symbol]
        self.rules = model.rules[node.symbol]
        self.axis = self.sym.split
        self.off, self.total = (node.x, node.w) if self.axis == "x" else (node.y, node.h)
        self.input_size = self.sym.extent[0 if self.axis == "x" else 1]
        self.auto = ctx.compiled.automata[node.symbol]
        self.rauto = ctx.compiled.reverse_automata.get(node.symbol)
        self.symmetric = self.rules.symmetric
        self.alphabet = frozenset(self.sym.children)
        self.freq = [(f, *self._freq_bounds(f)) for f in self.rules.frequencies]
        self.inst = {s: scaled_bounds(p.lo, p.hi, p.relative, self.total, self.input_size)
                     for s, p in self.rules.instances.items()}
        self.st = _State()
        self.ortho = "y" if self.axis == "x" else "x"
        self.across = node.h if self.axis == "x" else node.w
        comp = ctx.compiled
        self.min_extent, self.max_extent = comp.bounds[node.door == 0]
        self.min_size = {c: max(comp.size(c, self.axis).lo, self.min_extent[(c, self.axis)]) for c in self.alphabet}
        # floors of the request this region spans (§9.1): along y they are searched, across they prune
        self.floors = ctx.spanned_floors(node.y, node.y + node.h)
        self.straddles = self.floors is not None and self.axis == "x"
        # a face of one floor holds one storey: the facade's arrangement places one element holding openings
        self.one_storey = (self.axis == "y" and node.symbol == model.root and ctx.floor_lines is not None
                           and ctx.floor_lines.size == 2)

    def _freq_bounds(self, f) -> tuple[int, int]:
        lo, hi = scaled_bounds(f.lo, f.hi, f.relative, self.total, self.input_size)
        if self.node.door == 0 and all(self.ctx.compiled.door[m] for m in f.members):
            lo = 0  # a face without entrance drops door-bearing regions (request, §9.1)
        return lo, hi

    # ---------------------------------------------------------------- search
    def run(self) -> Iterator[Solution]:
        st0 = self.auto.start
        rst0 = self.rauto.start if self.rauto else None
        yield from self._extend(st0, rst0)

    def _mult(self) -> int:
        return 2 if self.symmetric else 1

    def _centre(self, sym: str) -> bool:
        """Whether ``sym``, as the last element of a symmetric half, may be its centre (counted once)."""
        return self.symmetric and self.ctx.model.mirrored(sym) == sym

    def _weights(self, n: int, mirror: bool = False) -> list[float]:
        """How often each of the first ``n`` elements occurs in the finished arrangement: twice in the half of a
        symmetric region, except a last element that may be the centre (§7.3)."""
        if not self.symmetric or mirror:
            return [1.0] * n
        w = [2.0] * n
        if n and self._centre(self.st.elems[n - 1][0]):
            w[-1] = 1.0
        return w

    def _final_ok(self, centre: bool) -> bool:
        """Frequencies and the door budget of the finished arrangement (the last element the centre, or not)."""
        mult = self._mult()
        last = self.st.elems[-1][0] if self.st.elems else None

        def total(members) -> int:
            return self._count(members) * mult - (1 if centre and last in members else 0)
        for f, lo, hi in self.freq:
            if not lo <= total(f.members) <= hi:
                self.ctx.blame(f"{f.text} (line {f.line})")
                return False
        if self.node.door is not None:
            doors = self._doors() * mult - (self.st.doors[-1] if centre and self.st.doors else 0)
            if doors != self.node.door:
                self.ctx.blame("entrance door budget of the face")
                return False
        return True

    def _count(self, members) -> int:
        return sum(1 for s, _ in self.st.elems if s in members)

    def _doors(self) -> int:
        return sum(self.st.doors)

    def _successors(self, state, rstate) -> list[tuple[str, int, object, object]]:
        ctx, st, comp = self.ctx, self.st, self.ctx.compiled
        mult = self._mult()
        used_lo = sum(st.lo) * mult
        out = []
        cands = self.auto.candidates(state)
        if self.symmetric:  # the left half is followed by its mirror image, not by ⊣ (§7.3)
            cands = (cands - {END}) | {END}
        for sym in sorted(cands):
            if sym != END and sym not in self.alphabet:
                continue
            nxt = state if (self.symmetric and sym == END) else self.auto.step(state, sym)
            if nxt is None:
                continue
            rnxt = None
            if self.symmetric and sym != END:
                rnxt = self.rauto.step(rstate, ctx.model.mirrored(sym))  # the mirrored right end, read backwards
                if rnxt is None:
                    ctx.blame(f"sequences at the right end of symmetric {self.node.symbol}")
                    continue
            if sym == END:
                if not self._can_end():
                    continue
                out.append(((END, 0, 0), nxt, rnxt))
                continue
            doors = [0]
            step = 1 if self._centre(sym) else mult
            if self.node.door is not None and comp.door[sym]:
                doors = [d for d in (1, 0) if (d == 1 and self._doors() * mult + step <= self.node.door)
                         or (d == 0 and comp.doorless[sym])]
            if self.node.door and not self.symmetric and self._doors() < self.node.door \
                    and not comp.door_ahead(self.node.symbol, nxt):
                doors = [d for d in doors if d]  # the door must come now: nothing later can hold it
            if not doors:
                ctx.blame("entrance door budget of the face")
                continue
            if any(sym in f.members and self._count(f.members) * mult + step > hi for f, _, hi in self.freq):
                ctx.blame(next(f"{f.text} (line {f.line})" for f, _, hi in self.freq if sym in f.members
                               and self._count(f.members) * mult + step > hi))
                continue
            if used_lo + self.min_size[sym] * step > self.total + 1e-9:
                ctx.blame(f"minimum size of {sym} in {self.node.symbol}")
                continue
            if self.straddles and comp.bound[(sym, "y")]:
                ctx.blame("floor lines of the building")
                continue
            if self.one_storey and comp.opening[sym] and any(comp.opening[s] for s, _ in st.elems):
                ctx.blame("floor lines of the building")
                continue
            if self.min_extent[(sym, self.ortho)] > self.across + 1e-9:
                ctx.blame(f"minimum {self.ortho}-extent {self.min_extent[(sym, self.ortho)]:.2f} of {sym} "
                          f"in {self.node.symbol}")
                continue
            for inst in self._instances(sym):
                out.extend(((sym, inst, d), nxt, rnxt) for d in doors)
        return out

    def _instances(self, sym: str) -> list[int]:
        if sym not in self.inst:
            return [0]
        used = {i for s, i in self.st.elems if s == sym}
        choices = sorted(used)
        if len(used) < self.inst[sym][1]:
            choices.append(len(used))
        return choices

    def _can_end(self) -> bool:
        for sym, (lo, _) in self.inst.items():
            if any(s == sym for s, _ in self.st.elems) and len({i for s, i in self.st.elems if s == sym}) < lo:
                self.ctx.blame(f"instances of {sym} in {self.node.symbol}")
                return False
        centre = bool(self.st.elems) and self._centre(self.st.elems[-1][0])
        if not (self._final_ok(False) or (centre and self._final_ok(True))):
            return False
        if self._empty_floor():
            self.ctx.blame("every storey gets an opening")
            return False
        return bool(self.st.elems)

    def _empty_floor(self) -> bool:
        """Whether a y-arrangement that puts its openings in floors leaves a floor it could hold one in (it covers
        at least the smallest opening-bearing child) without any: a storey without windows is not a storey. An
        opening-bearing element spanning floors (it places its openings itself) counts for the floors its
        provisional interval overlaps."""
        st, opening = self.st, self.ctx.compiled.opening
        if self.axis != "y" or self.floors is None or self.symmetric or not any(k is not None for k in st.floor):
            return False
        lines, (k0, k1) = self.ctx.floor_lines, self.floors
        taken = {k for k in st.floor if k is not None}
        if any(k is None and opening[s] for k, (s, _) in zip(st.floor, st.elems)):
            if st.x.size != len(st.elems):
                return False
            pos = self.off + np.concatenate([[0.0], np.cumsum(st.x)])
            for v, (k, (s, _)) in enumerate(zip(st.floor, st.elems)):
                if k is None and opening[s]:
                    taken.update(j for j in range(k0, k1 + 1)
                                 if min(pos[v + 1], lines[j + 1]) - max(pos[v], lines[j]) > 1e-6)
        least = min((self.min_size[s] for s, _ in st.elems if opening[s]), default=0.0)
        a, b = self.off, self.off + self.total
        return any(k not in taken and min(b, lines[k + 1]) - max(a, lines[k]) >= least - 1e-9
                   for k in range(k0, k1 + 1))

    def _order(self, cands: list) -> list:
        """Stochastic order of the successor set: ⊣ is favoured once the sampled sizes fill the region."""
        if len(cands) < 2:  # (one order; the stream advances as for the draw below)
            self.ctx.rng.random(len(cands))
            return cands
        st = self.st
        filled = (sum(st.xbar) * self._mult()) / self.total if self.total > 0 else 1.0
        stretch = sum(st.hi) * self._mult() >= self.total
        weights = []
        for (sym, _, _), _, _ in cands:
            if sym == END:
                weights.append(8.0 if stretch and filled > 0.9 else 0.4 if stretch else 0.05)
            else:
                mean = self.ctx.compiled.size(sym, self.axis).mean * self._mult()
                weights.append(1.0 if filled + mean / max(self.total, 1e-9) <= 1.05 else 0.05)
        keys = self.ctx.rng.random(len(cands)) ** (1.0 / np.asarray(weights))  # weighted random permutation
        return [cands[i] for i in np.argsort(-keys).tolist()]

    def _extend(self, state, rstate) -> Iterator[Solution]:
        ctx, st = self.ctx, self.st
        for (sym, inst, door), nxt, rnxt in self._order(self._successors(state, rstate)):
            ctx.tick()
            if sym == END:
                sol = self._complete()
                if sol is not None:
                    yield sol
                continue
            nrows, nsame, x_saved = len(st.rows), len(st.same_occ), st.x
            self._push(sym, inst, door)
            pushed = len(st.rows)
            for floor in self._floor_options(len(st.elems) - 1, sym, door):
                st.floor[-1] = floor
                if floor is not None:
                    self._floor_rows(len(st.elems) - 1, floor)
                if self._solve(new_from=nrows) and self._accept():
                    yield from self._extend(nxt, rnxt)
                del st.rows[pushed:]
                st.x = x_saved
            self._pop(nrows, nsame)
        ctx.backtrack()

    def _floor_options(self, v: int, sym: str, door: int) -> list[int | None]:
        """Floors element ``v`` may be laid out in, most plausible first (floor lines are searched, §9.1).

        Only along y in a region spanning floor lines, and only for elements holding an opening. An element
        with an opening across its whole height must lie within one floor (the ground floor for the door);
        any other one may also span floor lines (``None``), which its own arrangement then has to absorb.
        """
        comp = self.ctx.compiled
        if self.axis != "y" or self.floors is None or not comp.opening[sym]:
            return [None]
        bound = comp.bound[(sym, "y")]
        lines, (k0, k1) = self.ctx.floor_lines, self.floors
        start, size = self._position(v)
        first = max([k for k in self.st.floor[:v] if k is not None], default=k0)
        if door and bound:  # the door lies in the ground floor
            first, k1 = 0, 0 if k0 == 0 else -1
        ranked = []
        for k in range(first, k1 + 1):
            room = min(lines[k + 1], self.off + self.total) - max(lines[k], self.off)
            if room + 1e-9 < self.min_size[sym]:
                continue
            overlap = min(start + size, lines[k + 1]) - max(start, lines[k])
            ranked.append((-overlap, k))
        ranked.sort()
        # the floors the provisional interval overlaps (the nearest one when it overlaps none)
        options: list[int | None] = [k for o, k in ranked if o < 0] or [k for _, k in ranked[:1]]
        if not bound and (len(options) != 1 or ranked[0][0] > -size + 1e-9):
            options.append(None)  # spanning: only when it provisionally crosses a line or fits no floor
        elif not options:
            self.ctx.blame("floor lines of the building")
        return options

    def _floor_rows(self, v: int, k: int) -> None:
        """Element ``v`` starts at or above floor line ``k`` and ends at or below line ``k + 1``."""
        lines = self.ctx.floor_lines
        self.st.rows.append(Row({}, self.off - lines[k], False, "floor lines of the building", key=("floor", v),
                                prefix=v, sign=-1))
        self.st.rows.append(Row({}, lines[k + 1] - self.off, False, "floor lines of the building",
                                key=("floor", v), prefix=v + 1))

    def _accept(self) -> bool:
        """Randomly reject an append whose QP strained the sizes (§7.3): p = exp(-error / temperature)."""
        temp = self.ctx.accept_temperature
        if temp <= 0:
            return True
        xbar = np.asarray(self.st.xbar)
        err = float(np.sum((self.st.x - xbar) ** 2) / max(float(np.sum(xbar ** 2)), 1e-12))
        if err == 0.0 or self.ctx.rng.random() < np.exp(-err / temp):
            return True
        self.ctx.blame(f"QP error of {self.node.symbol} (random rejection)")
        return False

    # ---------------------------------------------------------------- elements and rows
    def _push(self, sym: str, inst: int, door: int) -> None:
        st, rng = self.st, self.ctx.compiled.size(sym, self.axis)
        st.elems.append((sym, inst))
        st.doors.append(door)
        st.floor.append(None)
        st.lo.append(self.min_size[sym])
        st.hi.append(min(rng.hi, self.max_extent[(sym, self.axis)]))
        st.xbar.append(self.ctx.sample_size(rng))
        v = len(st.elems) - 1
        for u, e in enumerate(st.elems[:-1]):
            if e == (sym, inst) and st.doors[u] == door:
                st.rows.append(Row({v: 1.0, u: -1.0}, 0.0, True, f"instance replicas of {sym}"))
                break
        if not self.symmetric:
            self._activate(len(st.elems))
            if self.axis == "x":
                self._request_rows(v, sym)

    def _pop(self, nrows: int, nsame: int) -> None:
        st = self.st
        for lst in (st.elems, st.doors, st.floor, st.lo, st.hi, st.xbar):
            lst.pop()
        del st.rows[nrows:]
        del st.same_occ[nsame:]

    def _tokens(self, complete: bool) -> list[str]:
        return [BEGIN, *(s for s, _ in self.st.elems), *([END] if complete else [])]

    def _activate(self, end: int, complete: bool = False) -> None:
        """Rows of alignment / same-size occurrences whose pattern ends at arrangement position ``end``."""
        elems = self.st.elems
        last = BEGIN if end == 0 else elems[end - 1][0] if end <= len(elems) else END if complete else None
        refs = self.ctx.compiled.by_last.get(last)
        if not refs:
            return
        toks = self._tokens(complete)
        for ref in refs:
            items = ref.pattern.items
            start = end - len(items) + 1
            if start < 0 or any(toks[start + j] not in items[j] for j in range(len(items))):
                continue
            first = start + len(ref.pattern.before) - 1  # element index (position 1 is element 0)
            if first < 0 or first + len(ref.pattern.body) > len(self.st.elems):
                continue
            if ref.kind == "align":
                self._align_row(ref, first)
            else:
                self._same_row(ref, first, len(ref.pattern.body))

    def _position(self, v: int) -> tuple[float, float]:
        """Provisional start and size of element ``v`` (current solution before it, sampled size for it)."""
        x = self.st.x
        start = self.off + float(np.sum(x[:v])) if v <= x.size else self.off + float(np.sum(x)) + \
            float(np.sum(self.st.xbar[x.size:v]))
        size = float(x[v]) if v < x.size else self.st.xbar[v]
        return start, size

    def _align_row(self, ref: PatternRef, v: int, interval: tuple[float, float] | None = None) -> bool | None:
        """Align element ``v`` with the overlapping placed region of the other side; False if none overlaps,
        None if the row exists already but the solution still violates it."""
        al = self.ctx.model.alignments[ref.index]
        lam = al.a_anchor if ref.side == 0 else al.b_anchor
        start, size = interval or self._position(v)
        targets = self.ctx.align_targets(ref, self.axis, start, start + size, self.node.anc)
        if interval is not None:  # verification: the first overlapping target it is not aligned with
            targets = [t for t in targets if abs(start + lam * size - t[2]) > 1e-6 * max(1.0, self.total)]
        if not targets:
            return False
        target = targets[0]
        key = ("align", ref.index, ref.side, v, target[:2])
        if any(r.key == key for r in self.st.rows):  # already required, yet still not aligned: unfixable
            self.ctx.blame(f"{al.text} (line {al.line})", frozenset({target[3]}))
            return None
        self.st.rows.append(Row({v: lam}, target[2] - self.off, True, f"{al.text} (line {al.line})",
                                frozenset({target[3]}), key, prefix=v))
        return True

    def _same_row(self, ref: PatternRef, v: int, length: int) -> None:
        ss = self.ctx.model.samesizes[ref.index]
        scope = self.ctx.same_scope(ss, self.node)
        if scope is None:
            return
        body = {i: 1.0 for i in range(v, v + length)}
        tag = f"{ss.text} (line {ss.line})"
        known = self.ctx.same_ref(ref.index, scope)
        if known is not None:
            self.st.rows.append(Row(body, known[0], True, tag, frozenset({known[1]})))
        else:
            first = next(((f, n) for k, sc, f, n in self.st.same_occ if k == ref.index and sc == scope), None)
            if first is not None and first[0] != v:
                coefs = dict(body)
                for i in range(first[0], first[0] + first[1]):
                    coefs[i] = coefs.get(i, 0.0) - 1.0
                self.st.rows.append(Row(coefs, 0.0, True, tag))
        if all(o[2] != v or o[0] != ref.index for o in self.st.same_occ):
            self.st.same_occ.append((ref.index, scope, v, length))

    def _request_rows(self, v: int, sym: str, interval: tuple[float, float] | None = None) -> None:
        """Floor-line (y) and corner-strip (x) rows of a region holding a full-extent opening (request, §9.1)."""
        ctx = self.ctx
        if not ctx.compiled.bound[(sym, self.axis)]:
            return
        start, size = interval or self._position(v)
        if self.axis == "y" and ctx.floor_lines is not None:
            lines = ctx.floor_lines
            j = 0 if self.st.doors[v] else \
                int(np.clip(np.searchsorted(lines, start + 0.5 * size) - 1, 0, len(lines) - 2))
            self.st.rows.append(Row({}, self.off - lines[j], False, "floor lines of the building", key=("floor", v),
                                    prefix=v, sign=-1))
            self.st.rows.append(Row({}, lines[j + 1] - self.off, False, "floor lines of the building",
                                    key=("floor", v), prefix=v + 1))
        elif self.axis == "x" and ctx.corners is not None and any(ctx.corners):
            left, right = ctx.corners
            self.st.rows.append(Row({}, self.off - left, False, "corner strips of the face", key=("corner", v),
                                    prefix=v, sign=-1))
            self.st.rows.append(Row({}, ctx.width - right - self.off, False, "corner strips of the face",
                                    key=("corner", v), prefix=v + 1))

    # ---------------------------------------------------------------- QP
    def _solve(self, new_from: int, total_eq: bool = False, mirror: bool = False) -> bool:
        """QP over the current arrangement; replica/symmetry equalities merge variables (exact reduction)."""
        st = self.st
        n = len(st.elems)
        rows = st.rows
        weights = self._weights(n, mirror)
        if not total_eq and len(rows) == new_from and st.x.size == n - 1:
            last = min(max(st.xbar[-1], st.lo[-1]), st.hi[-1])
            if float(np.dot(np.asarray(weights[:-1]), st.x)) + weights[-1] * last <= self.total + 1e-9:
                st.x = np.append(st.x, last)  # no newly active row: the previous optimum is still optimal
                return True
        group = None  # union-find forest of merged variables; a root is its set's least element
        general = []
        for r in rows:
            if r.pair is not None:
                if group is None:
                    group = list(range(n))
                u, v = _find(group, r.pair[0]), _find(group, r.pair[1])
                if u < v:
                    group[v] = u
                elif v < u:
                    group[u] = v
            else:
                general.append(r)
        xbar = np.array(st.xbar)
        # relative deviations (default): a large region absorbs a change in proportion to its size
        ew = 1.0 / np.maximum(xbar, max(0.02 * self.total, 1e-3)) ** 2 if self.ctx.relative else np.ones(n)
        if group is None:  # no merged variables
            mem, m = range(n), n
            member = None
            w, gx, glo, ghi = ew, xbar, st.lo, st.hi
        else:
            gid = group  # (parents precede their children: each element's root in one pass)
            for i, parent in enumerate(group):
                gid[i] = gid[parent]
            col = {g: k for k, g in enumerate(sorted(set(gid)))}
            m = len(col)
            mem = [col[g] for g in gid]
            member = np.array(mem)
            w = np.bincount(member, weights=ew, minlength=m)
            gx = np.bincount(member, weights=xbar * ew, minlength=m) / w
            glo, ghi = [-np.inf] * m, [np.inf] * m
            for g, a, b in zip(mem, st.lo, st.hi):
                if a > glo[g]:
                    glo[g] = a
                if b < ghi[g]:
                    ghi[g] = b
        counts = [(0,) * m]  # counts[p][g]: how many of the first p elements are in group g
        if any(r.prefix for r in general):
            count = [0] * m
            for g in mem:
                count[g] += 1
                counts.append(tuple(count))
        seen: set[tuple] = set()
        eq_rows, le_rows = [], []
        for r in general:
            sign = r.sign
            vec = [float(sign * c) for c in counts[r.prefix]] if r.prefix else [0.0] * m
            for i, c in r.coefs.items():
                vec[mem[i]] += c
            key = (r.eq, r.rhs, *vec)
            if key not in seen:
                seen.add(key)
                (eq_rows if r.eq else le_rows).append((vec, r.rhs))
        total = [0.0] * m  # the total size row: each group's weight in the finished arrangement
        for g, c in zip(mem, weights):
            total[g] += c
        (eq_rows if total_eq else le_rows).append((total, self.total))
        x = solve_sizes(gx, glo, ghi, [v for v, _ in eq_rows] + [v for v, _ in le_rows],
                        [b for _, b in eq_rows] + [b for _, b in le_rows], len(eq_rows), w)
        self.ctx.qp_calls += 1
        if x is None:
            blamed = rows[new_from:] or rows
            for r in blamed:
                self.ctx.blame(r.tag, r.frames)
            self.ctx.blame(f"total size of {self.node.symbol}" if total_eq or not blamed
                           else f"size ranges in {self.node.symbol}")
            return False
        st.x = x if member is None else x[member]
        return True

    # ---------------------------------------------------------------- completion
    def _complete(self) -> Solution | None:
        st = self.st
        saved_rows, saved_same, saved_x = list(st.rows), list(st.same_occ), st.x
        try:
            if self.symmetric:
                return self._complete_symmetric()
            self._activate(len(st.elems) + 1, complete=True)
            return self._finish(new_from=len(saved_rows))
        finally:
            st.rows, st.same_occ, st.x = saved_rows, saved_same, saved_x

    def _complete_symmetric(self) -> Solution | None:
        """Finish a symmetric arrangement: the last element ends at the midpoint or is centred on it (§7.3)."""
        st, mirror = self.st, self.ctx.model.mirrored
        left = list(st.elems)
        options = []
        if left and mirror(left[-1][0]) == left[-1][0] and self._final_ok(True):
            options.append(left[:-1])  # odd: the last element is the centre
        if self._final_ok(False):
            options.append(left)
        for base in self.ctx.rng.permutation(len(options)):
            half = options[base]
            centre = left[len(half):]
            full = [*half, *centre, *[(mirror(s), i) for s, i in reversed(half)]]
            if not self.auto.accepts([s for s, _ in full]):
                self.ctx.blame(f"sequences of symmetric {self.node.symbol}")
                continue
            sol = self._finish_full(full, len(half))
            if sol is not None:
                return sol
        return None

    def _finish_full(self, full: list[tuple[str, int]], half: int) -> Solution | None:
        st = self.st
        saved = (list(st.elems), list(st.xbar), list(st.lo), list(st.hi), list(st.doors))
        n = len(full)
        idx = [i if i < n - half else n - 1 - i for i in range(n)]
        st.elems = full
        st.xbar, st.lo, st.hi = [saved[1][k] for k in idx], [saved[2][k] for k in idx], [saved[3][k] for k in idx]
        st.doors = [saved[4][k] if i == k else 0 for i, k in enumerate(idx)]
        st.rows = [Row({i: 1.0, n - 1 - i: -1.0}, 0.0, True, f"symmetry of {self.node.symbol}")
                   for i in range(half)]
        for u in range(n):
            for w in range(u):
                if full[w] == full[u] and st.doors[w] == st.doors[u]:
                    st.rows.append(Row({u: 1.0, w: -1.0}, 0.0, True, f"instance replicas of {full[u][0]}"))
                    break
            self._request_rows(u, full[u][0])
        st.same_occ = []
        st.x = np.zeros(0)
        for end in range(1, n + 2):
            self._activate(end, complete=end == n + 1)
        try:
            return self._finish(new_from=0, mirror=True)
        finally:
            st.elems, st.xbar, st.lo, st.hi, st.doors = (list(a) for a in saved)

    def _finish(self, new_from: int, mirror: bool = False) -> Solution | None:
        for _ in range(6):
            if not self._solve(new_from, total_eq=True, mirror=mirror):
                return None
            extra = self._violations()
            if extra is None:
                return None
            if not extra:
                return self._solution()
            new_from = len(self.st.rows) - extra
        self.ctx.blame(f"alignment of {self.node.symbol} (no fixpoint)")
        return None

    def _violations(self) -> int | None:
        """Add rows for constraints the solved arrangement violates; their number, or None if unfixable."""
        st, ctx = self.st, self.ctx
        before = len(st.rows)
        pos = self.off + np.concatenate([[0.0], np.cumsum(st.x)])
        toks = self._tokens(True)
        for end in range(1, len(toks)):
            for ref in ctx.compiled.by_last.get(toks[end], ()):
                if ref.kind != "align":
                    continue
                items = ref.pattern.items
                start = end - len(items) + 1
                if start < 0 or any(toks[start + j] not in items[j] for j in range(len(items))):
                    continue
                v = start + len(ref.pattern.before) - 1
                if 0 <= v < len(st.elems) and self._align_row(ref, v, interval=(pos[v], st.x[v])) is None:
                    return None
        for v, (sym, _) in enumerate(st.elems):
            if ctx.compiled.bound[(sym, self.axis)] and not ctx.inside(self.axis, pos[v], pos[v + 1]):
                if any(r.key and r.key[0] in ("floor", "corner") and r.key[1] == v for r in st.rows):
                    ctx.blame("floor lines of the building" if self.axis == "y" else "corner strips of the face")
                    return None
                self._request_rows(v, sym, interval=(pos[v], st.x[v]))
        return len(st.rows) - before

    def _solution(self) -> Solution:
        st = self.st
        align_occ = []
        toks = self._tokens(True)
        for end in range(1, len(toks)):
            for ref in self.ctx.compiled.by_last.get(toks[end], ()):
                items = ref.pattern.items
                start = end - len(items) + 1
                if ref.kind == "align" and start >= 0 and all(toks[start + j] in items[j] for j in range(len(items))):
                    v = start + len(ref.pattern.before) - 1
                    if 0 <= v < len(st.elems):
                        align_occ.append((ref.index, ref.side, v))
        return Solution(list(st.elems), st.x.copy(), align_occ, list(st.same_occ), list(st.doors),
                        list(accumulate(st.x.tolist(), initial=0.0)))
