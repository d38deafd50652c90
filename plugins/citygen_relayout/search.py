"""Relayouting (bao2013 §7.1, §7.3): top-down depth-first over composite regions in randomized order.

Each composite region becomes a *frame* holding the resumable ``layout`` generator of its arrangement. When a
frame's generator is exhausted the search backjumps (conflict-directed) to the latest earlier frame it depends
on -- its parent (which fixed its size) or a frame that placed an alignment target or set a same-size
reference it could not meet -- undoing everything after it. After a cutoff of backtracks the whole layout
restarts from the root with fresh random choices: 1000 in the paper (``restarts="fixed"``); by default the
cutoffs follow the Luby sequence 100 x (1, 1, 2, 1, 1, 2, 4, ...), because a bad early choice (a band height no
floor layout fits) is rarely repaired by backtracking and the run times are heavy-tailed. A budget of backtracks
over all attempts bounds the work, a CPU-time limit everything; failure returns a :class:`RelayoutResult`
naming the constraints that blocked most often.
"""
from __future__ import annotations

import itertools
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from citygen.layout import FacadeLayout, Region
from citygen_relayout.arrange import Solution, layout
from citygen_relayout.compiled import PatternRef, compile_model
from citygen_relayout.model import Model, SameSize, SizeRange


RESTARTS = ("luby", "fixed")


def luby(i: int) -> int:
    """The i-th term (from 1) of the Luby et al. (1993) restart sequence 1, 1, 2, 1, 1, 2, 4, 1, 1, 2, ..."""
    k = i.bit_length()
    while i != (1 << k) - 1:
        i -= (1 << (k - 1)) - 1
        k = i.bit_length()
    return 1 << (k - 1)


class _Restart(Exception):
    pass


class _OutOfTime(Exception):
    pass


@dataclass(frozen=True)
class RelayoutResult:
    """Outcome of one relayout: ``layout`` is set only when ``success``."""

    success: bool
    layout: FacadeLayout | None
    status: str
    message: str
    restarts: int = 0
    backtracks: int = 0
    qp_calls: int = 0
    blockers: tuple[tuple[str, int], ...] = ()
    seconds: float = 0.0
    findings: tuple = ()  # the judge's findings on the last complete but implausible layout


@dataclass(slots=True)
class Node:
    """A composite region instance to lay out."""

    uid: int
    symbol: str
    x: float
    y: float
    w: float
    h: float
    anc: dict[str, int]
    door: int | None
    parent_frame: int
    replica_of: int | None = None
    children_uids: dict[int, int] = field(default_factory=dict)
    key: tuple | None = None


@dataclass
class _Frame:
    node: Node
    gen: object
    pending: tuple[Node, ...]
    log_len: int
    conflicts: set[int] = field(default_factory=set)
    blockers: Counter | None = None
    yielded: int = 0


@dataclass
class Constraints:
    """Cross-face constraints of a request (§9.1): floor lines, corner strips, door budget, shared references."""

    floor_lines: tuple[float, ...] | None = None
    corners: tuple[float, float] | None = None
    doors: int | None = None
    shared: dict | None = None  # building-wide same-size references (``across``), filled by the first face
    key_salt: tuple = ()  # distinguishes the module keys of the faces of one building (the request's seed)


class Search:
    def __init__(self, model: Model, width: float, height: float, rng: np.random.Generator,
                 constraints: Constraints | None = None, budget_s: float = 10.0, backtrack_budget: int = 12000,
                 restarts: str = "luby", accept_temperature: float = 0.0, relative: bool = True,
                 judge: Callable[[FacadeLayout], Sequence] | None = None) -> None:
        if restarts not in RESTARTS:
            raise ValueError(f"restarts must be one of {RESTARTS}, got {restarts!r}")
        self.model, self.compiled = model, compile_model(model)
        self.width, self.height, self.rng = float(width), float(height), rng
        c = constraints or Constraints()
        self.floor_lines = None if c.floor_lines is None else np.asarray(c.floor_lines, float)
        self.lines = None if c.floor_lines is None else self.floor_lines.tolist()  # (the same, as floats)
        self.eps = 1e-6 * max(self.width, self.height, 1.0)  # positions this close are equal
        self.corners, self.doors, self.shared, self.key_salt = c.corners, c.doors, c.shared, c.key_salt
        self.budget_s, self.backtrack_budget, self.restarts = budget_s, backtrack_budget, restarts
        self.max_backtracks = 0  # cutoff of the current attempt
        self.accept_temperature = accept_temperature
        self.relative = relative  # QP on relative size deviations (x - xbar)^2 / xbar^2; False: the paper's
        self.judge = judge  # findings of a complete layout (empty: accepted)
        self.blockers: Counter[str] = Counter()
        self.dead: Counter[str] = Counter()  # regions whose arrangements were exhausted without any solution
        self.dead_causes: Counter[str] = Counter()
        self.qp_calls = self.backtracks = self.total_backtracks = 0
        self.frames: list[_Frame] = []

    # ---------------------------------------------------------------- services used by arrange.layout
    def tick(self) -> None:
        self._ticks += 1
        if self._ticks & 63 == 0 and time.process_time() > self.deadline:
            raise _OutOfTime

    def backtrack(self) -> None:
        self.backtracks += 1
        self.total_backtracks += 1
        if self.backtracks > self.max_backtracks:
            raise _Restart

    def blame(self, tag: str, frames: frozenset[int] = frozenset()) -> None:
        self.blockers[tag] += 1
        if self.frames:
            frame = self.frames[self.current]
            if frame.blockers is None:
                frame.blockers = Counter()
            frame.blockers[tag] += 1
        if frames and self.frames:
            self.frames[self.current].conflicts.update(f for f in frames if f < self.current)

    def sample_size(self, rng: SizeRange) -> float:
        """Initial size from the truncated Gaussian of §5.1 (rejection sampling, clipped fallback)."""
        if rng.hi - rng.lo < 1e-12 or rng.sigma <= 0:
            return min(max(rng.mean, rng.lo), rng.hi)
        for value in self.rng.normal(rng.mean, rng.sigma, 6):
            if rng.lo <= value <= rng.hi:
                return float(value)
        return float(self.rng.uniform(rng.lo, rng.hi))

    def align_targets(self, ref: PatternRef, axis: str, a: float, b: float, anc: dict[str, int]) -> list[tuple]:
        """Placed regions of the other side overlapping ``[a, b]``: ``(start, end, anchor pos, frame)``; ``anc``
        are the ancestors (scopes) of the asking region."""
        al = self.model.alignments[ref.index]
        other, lam = (1, al.b_anchor) if ref.side == 0 else (0, al.a_anchor)
        scope = anc.get(al.within) if al.within else 0
        if scope is None:
            return []
        found = []
        for (s, e, sc), frame in self.placed.get((ref.index, other, axis), {}).items():
            overlap = min(b, e) - max(a, s)
            if sc == scope and overlap > 1e-6:
                found.append((overlap, (s, e, s + lam * (e - s), frame)))
        found.sort(key=lambda t: -t[0])
        return [t for _, t in found]

    def same_scope(self, ss: SameSize, node: Node) -> tuple | None:
        if ss.within:
            uid = node.anc.get(ss.within)
            return None if uid is None else ("within", uid)
        return ("building",) if ss.across else ("face",)

    def same_ref(self, index: int, scope: tuple) -> tuple[float, int] | None:
        if scope == ("building",) and self.shared is not None and index in self.shared:
            return self.shared[index], -1
        return self.refs.get((index, scope))

    def spanned_floors(self, a: float, b: float) -> tuple[int, int] | None:
        """``(first, last)`` floor indices of the y-range ``[a, b]`` when floor lines cross it, else None."""
        lines = self.floor_lines
        if lines is None or lines.size < 3:
            return None
        eps = self.eps
        k0 = int(lines.searchsorted(a + eps, side="right")) - 1
        k1 = int(lines.searchsorted(b - eps, side="left")) - 1
        k0, k1 = max(k0, 0), min(k1, lines.size - 2)
        return (k0, k1) if k1 > k0 else None

    def inside(self, axis: str, a: float, b: float) -> bool:
        eps = self.eps
        if axis == "y":
            if self.floor_lines is None:
                return True
            lines = self.lines
            j = min(max(int(self.floor_lines.searchsorted(0.5 * (a + b))) - 1, 0), len(lines) - 2)
            return a >= lines[j] - eps and b <= lines[j + 1] + eps
        if not self.corners:
            return True
        return a >= self.corners[0] - eps and b <= self.width - self.corners[1] + eps

    # ---------------------------------------------------------------- the search
    def run(self) -> RelayoutResult:
        t0 = time.perf_counter()
        self.deadline = time.process_time() + self.budget_s  # CPU time: other processes do not make it fire
        too_small = self._static_check()
        if too_small:
            return RelayoutResult(False, None, "infeasible", too_small, seconds=time.perf_counter() - t0)
        self._ticks = 0
        status = "exhausted"
        restarts = root_failures = 0
        findings: tuple = ()
        for restarts in itertools.count():
            left = self.backtrack_budget - self.total_backtracks
            if left <= 0:
                break
            self.max_backtracks = min(left, 1000 if self.restarts == "fixed" else 100 * luby(restarts + 1))
            try:
                if self._attempt():
                    built = self._build()
                    found = tuple(self.judge(built)) if self.judge is not None else ()
                    if not found:
                        return RelayoutResult(True, built, "solved", "ok", restarts, self.total_backtracks,
                                              self.qp_calls, seconds=time.perf_counter() - t0)
                    findings, status = found, "implausible"
                    self.blockers.update(f"implausible: {f.code}" for f in found if hasattr(f, "code"))
                    self.total_backtracks += self.max_backtracks  # a rejected layout costs its attempt's cutoff
                    continue
                status = "infeasible-root"
                if not self.frames[0].yielded and not self.accept_temperature:
                    # the root itself has no arrangement: retrying will not help
                    root_failures += 1
                    if root_failures >= 2:
                        break
            except _Restart:
                status = "restart-limit"
            except _OutOfTime:
                status = "timeout"
                break
        top = tuple((self.dead_causes or self.blockers).most_common(5))
        names = "; ".join(f"{tag} ({n}x)" for tag, n in top) or "no candidate arrangement for the root"
        if self.dead:
            names = ("no arrangement for " + ", ".join(f"{r} ({n}x)" for r, n in self.dead.most_common(3))
                     + "; there: " + names)
        msg = (f"no {self.model.name} layout of {self.width:g} x {self.height:g} found ({status}, "
               f"{restarts + 1} attempts, {self.total_backtracks} backtracks); blocking constraints: {names}")
        if findings:
            msg += "; the last complete layout was implausible: " + "; ".join(str(f) for f in findings[:3])
        return RelayoutResult(False, None, status, msg, restarts, self.total_backtracks, self.qp_calls, top,
                              time.perf_counter() - t0, findings)

    def _static_check(self) -> str | None:
        """A reason when the target is outside the root's static extent bounds (see ``bounds``)."""
        root = self.model.root
        for axis, size in (("x", self.width), ("y", self.height)):
            mins, maxs = self.compiled.bounds[self.doors == 0]
            lo, hi = mins[(root, axis)], maxs[(root, axis)]
            if size < lo - 1e-9 or size > hi + 1e-9:
                word = "width" if axis == "x" else "height"
                return (f"no {self.model.name} layout of {self.width:g} x {self.height:g}: the model's {word} must lie "
                        f"in {lo:.3f}..{hi:.3f} m (region-size ranges and sequences of {root} and below)")
        return None

    def _reset(self) -> None:
        self.frames, self.log = [], []
        self.placed: dict[tuple, dict] = {}
        self.refs: dict[tuple, tuple[float, int]] = {}
        self.solutions: dict[int, tuple[Node, Solution]] = {}
        self.replicas: dict[tuple, int] = {}
        self._nodes: dict[int, Node] = {}
        self.backtracks = 0
        self.current = 0
        self._uid = 0

    def _attempt(self) -> bool:
        self._reset()
        root = Node(0, self.model.root, 0.0, 0.0, self.width, self.height, {self.model.root: 0}, self.doors, -1)
        self._nodes[0] = root
        pending = [root]
        while pending:
            node = pending.pop()
            gen = self._generator(node)  # may register the node as a replica source; kept across retries
            frame = _Frame(node, gen, tuple(pending), len(self.log),
                           {node.parent_frame} if node.parent_frame >= 0 else set())
            self.frames.append(frame)
            m = self.current = len(self.frames) - 1
            while True:
                sol = next(frame.gen, None)
                if sol is not None:
                    frame.yielded += 1
                    pending = list(frame.pending)
                    pending.extend(self._apply(m, sol))
                    break
                if not frame.yielded:
                    node = frame.node
                    self.dead[f"{node.symbol} ({node.w:.1f} x {node.h:.1f} m)"] += 1
                    self.dead_causes.update(frame.blockers or {})
                self.backtrack()
                earlier = [c for c in frame.conflicts if c < m]
                if not earlier:
                    return False
                target = max(earlier)
                self._undo(target)
                self.frames[target].conflicts |= {c for c in frame.conflicts if c < target}
                frame = self.frames[target]
                m = self.current = target
        return True

    def _undo(self, target: int) -> None:
        """Drop frames after ``target`` and every effect of ``target``'s current solution."""
        stop = self.frames[target].log_len
        while len(self.log) > stop:
            self.log.pop()()
        del self.frames[target + 1:]

    def _generator(self, node: Node):
        """The first laid-out instance of a (parent, symbol, instance) is the source of its replicas."""
        if node.replica_of is None and node.key is not None:
            if node.key in self.replicas:
                node.replica_of = self.replicas[node.key]
            else:
                self.replicas[node.key] = node.uid
                self._log(lambda k2=node.key: self.replicas.pop(k2, None))
        if node.replica_of is None:
            return layout(self, node)
        return self._replica(node)

    def _replica(self, node: Node):
        """A replica instance (§5.1 instances): the source's arrangement, verified at its own position with the
        whole subtree below it (which ``_apply`` then places in the same frame)."""
        if self._verify(node.replica_of, node.x, node.y, node.w, node.h, node.anc):
            yield self.solutions[node.replica_of][1]

    def _source(self, uid: int) -> int:
        """The laid-out region whose arrangement region ``uid`` has (itself, or the source of a replica)."""
        src = self._nodes[uid].replica_of
        return uid if src is None else src

    def _verify(self, src: int, x: float, y: float, w: float, h: float, anc: dict[str, int]) -> bool:
        """Whether the subtree of source region ``src`` moved to ``(x, y)`` meets the request's floors and
        corners and aligns with the regions placed so far (its inner alignments hold by translation)."""
        src_node, sol = self.solutions[src]
        comp = self.compiled
        axis = self.model.symbols[src_node.symbol].split
        off = x if axis == "x" else y
        pos = [off + c for c in sol.cum]
        straddles = axis == "x" and self.spanned_floors(y, y + h) is not None
        for v, (sym, _) in enumerate(sol.elements):
            if (comp.bound[(sym, axis)] and not self.inside(axis, pos[v], pos[v + 1])) or \
                    (straddles and comp.bound[(sym, "y")]):
                self.blame("floor lines of the building" if axis == "y" or straddles else "corner strips of the face")
                return False
        for k, side, v in sol.align_occ:
            ref = PatternRef("align", k, side, None)
            al = self.model.alignments[k]
            lam = al.a_anchor if side == 0 else al.b_anchor
            for s, e, t, frame in self.align_targets(ref, axis, pos[v], pos[v + 1], anc):
                if abs(pos[v] + lam * (pos[v + 1] - pos[v]) - t) > self.eps:
                    self.blame(f"{al.text} (line {al.line})", frozenset({frame}))
                    return False
        for v, (sym, _) in enumerate(sol.elements):
            if comp.composite[sym]:
                a, b = pos[v], pos[v + 1]
                inner = {**anc, sym: -1} if sym in comp.scoped else anc  # a new scope: nothing placed in it yet
                child = self._source(src_node.children_uids[v])
                if not (self._verify(child, a, y, b - a, h, inner) if axis == "x" else
                        self._verify(child, x, a, w, b - a, inner)):
                    return False
        return True

    def _log(self, undo) -> None:
        self.log.append(undo)

    def _apply(self, m: int, sol: Solution) -> list[Node]:
        """Register the frame's arrangement; return its composite children in randomized order. A replica's
        subtree is placed at once (its regions stay implicit: the source's, moved)."""
        node = self.frames[m].node
        if node.replica_of is not None:
            self._place(m, node.replica_of, node.x, node.y, node.w, node.h, node.anc)
            return []
        axis = self.model.symbols[node.symbol].split
        self.solutions[node.uid] = (node, sol)
        self._log(lambda uid=node.uid: self.solutions.pop(uid, None))
        pos = self._register(m, sol, axis, node.x if axis == "x" else node.y, node.anc)
        children = []
        composite, scoped = self.compiled.composite, self.compiled.scoped
        horizontal = axis == "x"
        for v, (sym, inst) in enumerate(sol.elements):
            if not composite[sym]:
                continue
            a, b = pos[v], pos[v + 1]
            self._uid += 1
            uid = self._uid
            door = None if node.door is None else sol.doors[v]
            anc = {**node.anc, sym: uid} if sym in scoped else node.anc
            child = Node(uid, sym, a, node.y, b - a, node.h, anc, door, m) if horizontal else \
                Node(uid, sym, node.x, a, node.w, b - a, anc, door, m)
            child.key = (node.uid, sym, inst, door)
            self._nodes[uid] = child
            children.append(child)
        node.children_uids = {v: c.uid for v, c in zip(
            [v for v, (sym, _) in enumerate(sol.elements) if composite[sym]], children)}
        if len(children) < 2:
            return children
        order = self.rng.permutation(len(children))
        return [children[i] for i in order]

    def _register(self, m: int, sol: Solution, axis: str, off: float, anc: dict[str, int]) -> list[float]:
        """Record the alignment occurrences and same-size references of an arrangement at ``off``; its
        element boundaries."""
        cum = sol.cum
        pos = [off + c for c in cum]
        for k, side, v in sol.align_occ:
            within = self.model.alignments[k].within
            scope = anc.get(within) if within else 0
            table = self.placed.setdefault((k, side, axis), {})
            key = (round(pos[v], 9), round(pos[v + 1], 9), scope)
            if key not in table:
                table[key] = m
                self._log(lambda t=table, k2=key: t.pop(k2, None))
        for k, scope, v, n in sol.same_occ:
            if scope == ("building",) and self.shared is not None:
                if k not in self.shared:
                    self.shared[k] = cum[v + n] - cum[v]
                    self._log(lambda k2=k: self.shared.pop(k2, None))
            elif (k, scope) not in self.refs:
                self.refs[(k, scope)] = (cum[v + n] - cum[v], m)
                self._log(lambda k2=(k, scope): self.refs.pop(k2, None))
        return pos

    def _place(self, m: int, src: int, x: float, y: float, w: float, h: float, anc: dict[str, int]) -> None:
        """Register the subtree of source region ``src`` moved to ``(x, y)`` (a replica) in frame ``m``."""
        src_node, sol = self.solutions[src]
        axis = self.model.symbols[src_node.symbol].split
        pos = self._register(m, sol, axis, x if axis == "x" else y, anc)
        composite, scoped = self.compiled.composite, self.compiled.scoped
        for v, (sym, _) in enumerate(sol.elements):
            if composite[sym]:
                a, b = pos[v], pos[v + 1]
                inner = anc
                if sym in scoped:  # a new scope for ``within`` constraints
                    self._uid += 1
                    inner = {**anc, sym: self._uid}
                child = self._source(src_node.children_uids[v])
                if axis == "x":
                    self._place(m, child, a, y, b - a, h, inner)
                else:
                    self._place(m, child, x, a, w, b - a, inner)

    # ---------------------------------------------------------------- output
    def _build(self) -> FacadeLayout:
        root = self.frames[0].node
        self._sources: set[int] = set()
        stack, direct = [root.uid], []
        while stack:  # the replica sources of the final tree, and every region below them
            uid = stack.pop()
            node = self._nodes[uid]
            if node.replica_of is not None:
                direct.append(node.replica_of)
            else:
                stack.extend(node.children_uids.values())
        while direct:
            uid = self._source(direct.pop())
            if uid not in self._sources:
                self._sources.add(uid)
                direct.extend(self._nodes[uid].children_uids.values())
        region = self._region(root.uid, root.x, root.y, root.w, root.h, (self.model.root, 0), None)
        return FacadeLayout(self.width, self.height, region,
                            meta={"kind": "relayout", "model": self.model.name})

    def _region(self, uid: int, x: float, y: float, w: float, h: float, element: tuple[str, int],
                key: int | None) -> Region:
        """The region of laid-out region ``uid`` (or of a replica of it) at ``(x, y)``."""
        symbols, names, template = self.model.symbols, self.compiled.names, self.compiled.template
        sym = symbols[element[0]]
        node, sol = self.solutions[uid]
        horizontal = sym.split == "x"
        pos = [(x if horizontal else y) + c for c in sol.cum]
        kids = []
        for v, child in enumerate(sol.elements):
            a, b = pos[v], pos[v + 1]
            if not self.compiled.composite[child[0]]:
                kids.append(Region.stamped(template(child), a, y, b - a, h) if horizontal else
                            Region.stamped(template(child), x, a, w, b - a))
            else:
                src = self._source(node.children_uids[v])
                kids.append(self._region(src, a, y, b - a, h, child, self._key(src)) if horizontal else
                            self._region(src, x, a, w, b - a, child, self._key(src)))
        return Region(x, y, w, h, names(element), sym.label, sym.depth, sym.material, sym.asset,
                      children=tuple(kids), key=key)

    def _key(self, src: int) -> int | None:
        """Module key of the copies of a replicated region (§7.3 replicas: identical subtrees), else None."""
        if src not in self._sources:
            return None
        return hash((self.key_salt, self.compiled.code, self._nodes[src].symbol, src))
