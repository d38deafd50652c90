"""Choosing topological jumps for a target size (dang2014 §4-5, made non-interactive and bounded in cost).

The paper proposes variations and lets the user pick. For a target width we try column counts around the one
the grid's pitch suggests (one fewer, that one, one more). The counts lie on one greedy path of jumps: each step
ranks every single jump of the active grids (insert a source column at any position, or remove a column) by the
width mismatch it leaves, an analytic estimate of its distortion; the spatial optimisation scores the
``FINALISTS`` best of distinct width changes and compares the winner with up to ``POSITIONS`` other jumps of its
width change (other positions); the path's states at the counts are the variations. A far wider target
(``FAR_COPIES`` or more insertions to the nearest count) is met by single jumps of many copies instead: each
candidate gets the copy count whose width mismatch is least, and the winner's counts around it are the variations
(:func:`far_variations`). Jumps apply to the natural (unsized) facade, so copies keep the input's sizes, and
sibling pieces of one region are merged back after every jump. Each call has a work budget (leaves sized by the
spatial optimisation, a deterministic stand-in for CPU time): once spent, steps take the estimate's best jump
unscored, and the facade resized without jumps is always a variation. Heights do the same with floors (see
:mod:`citygen_safe.floors`).
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from citygen.layout import FLOOR_BOUND_LABELS
from citygen.plausible import DEFAULT_RULES, PlausibilityRules
from citygen_safe.bounds import MARGIN, minimum_extents
from citygen_safe.grids import FacadeGrid, GridSpec, detect_grid
from citygen_safe.jump import (Jump, boundary_gaps, insert_slab, insertion_gap, merge_leaves, remove_slab,
                               removal_slab, source_columns)
from citygen_safe.leaves import EPS, Facade
from citygen_safe.memory import Memory
from citygen_safe.optimise import Lines, SpatialResult, optimise_widths
from citygen_safe.rank import defects, penalty, reference_widths
from citygen_safe.ruleset import BUDGET_S
from citygen_safe.tree import Node, decompose

FINALISTS = 3  #: jumps per greedy step scored by the spatial optimisation (the rest by their width mismatch)
POSITIONS = 4  #: other positions of the winning width change the spatial optimisation compares with it
NEAR_BEST = 1.05  #: variations within this factor of the least distortion are the generator's choices
#: Leaves sized by the spatial optimisation per nominal CPU second (calibrated on the project's 2-core machine):
#: the budget counts work, not time, so the same request gives the same facade on any machine and under any load.
LEAVES_PER_SECOND = 12_000
MAX_LEAVES = 8000  #: column jumps stop before a facade would have more leaves (the QP's cost per leaf grows beyond)
FAR_COPIES = 4  #: column insertions to the nearest count from which its counts are single jumps of many copies


class Work:
    """The work spent by one edit: leaves sized by the spatial optimisation (shared by the settings it made)."""

    __slots__ = ("spent",)

    def __init__(self) -> None:
        self.spent = 0


@dataclass(frozen=True)
class Settings:
    """How an edit is solved: active grid specs, constraint switches, labels never duplicated or removed (the
    door, whose budget the building coordinator owns), corner strips and the labels kept out of them, and the
    budget in nominal CPU seconds (``work`` counts what is spent, in leaves: ``units`` is the budget's), the
    plausibility ``rules`` whose sizes bound the QP, and the labels kept ``centre``d (the input's centred door)."""

    active: tuple[GridSpec, ...]
    alignment: bool = True
    symmetry: bool = True
    keep: frozenset[str] = frozenset({"door"})
    corners: tuple[float, float] = (0.0, 0.0)
    corner_labels: frozenset[str] = frozenset()
    budget: float = BUDGET_S
    rules: PlausibilityRules = DEFAULT_RULES
    centre: frozenset[str] = frozenset()
    work: Work = field(default_factory=Work, compare=False, repr=False)

    @property
    def units(self) -> float:
        """The budget in leaves sized."""
        return self.budget * LEAVES_PER_SECOND

    @property
    def fixed(self) -> frozenset[str]:
        """Labels whose leaves are never merged: grid elements and floor-bound openings."""
        return FLOOR_BOUND_LABELS | self.keep | {label for spec in self.active for label in spec.labels}


@dataclass(frozen=True)
class Variation:
    """A facade after ``jumps`` and the spatial optimisation, with its distortion E(x) and its defects (cut or
    fused elements, slivers, an off-centre door: :mod:`citygen_safe.rank`)."""

    jumps: tuple[Jump, ...]
    facade: Facade
    objective: float
    dropped: tuple[str, ...] = ()
    defects: tuple[str, ...] = ()

    @property
    def cost(self) -> float:
        """The ranking: E(x) plus the plausibility terms of its defects (:func:`citygen_safe.rank.penalty`)."""
        return self.objective + penalty(self.defects)


@dataclass(frozen=True)
class Candidate:
    """A single jump of a facade: the size change ``delta`` it makes, the distance ``offset`` of its place from the
    facade's middle, the ``slabs`` it copies (insertion) or cuts out (removal) and how to apply it ``copies``
    times (insertions; removals once)."""

    jump: Jump
    delta: float
    offset: float
    slabs: tuple[tuple[float, float], ...]
    apply: Callable[[int], Facade | None]

    def changes(self, facade: Facade, labels: frozenset[str]) -> bool:
        """Whether the jump would copy or remove a leaf with one of ``labels`` (tested before applying it)."""
        if self.jump.op == "insert":
            return any(f.label in labels and f.x < hi - EPS and f.right > lo + EPS
                       for f in facade.leaves for lo, hi in self.slabs)
        return any(f.label in labels and f.x >= lo - EPS and f.right <= hi + EPS
                   for f in facade.leaves for lo, hi in self.slabs)


@dataclass(frozen=True)
class Path:
    """A state of a greedy path: the natural (unsized) facade after ``jumps`` and its decomposition tree."""

    facade: Facade
    root: Node
    jumps: tuple[Jump, ...] = ()


def grids_of(facade: Facade, specs: Sequence[GridSpec]) -> list[FacadeGrid]:
    return [g for g in (detect_grid(facade, s) for s in specs) if g is not None]


def size(facade: Facade, settings: Settings, target: float, lines: Lines | None = None,
         root: Node | None = None) -> SpatialResult:
    """The spatial optimisation of ``facade`` at width ``target`` (``lines`` refer to nodes of ``root``), leaves
    bounded by the plausibility rules' sizes and wall slabs thinner than a sliver collapsed."""
    settings.work.spent += len(facade.leaves)
    root = root or decompose(facade)
    centred = () if facade.transposed else [i for i, f in enumerate(facade.leaves) if f.label in settings.centre]
    key = (id(facade), id(root), settings.active, id(settings.rules))
    known = SIZED.lookup(key)
    if known is None or known[0] is not facade or known[1] is not root:
        known = (facade, root, grids_of(facade, settings.active), minimum_extents(facade, root, settings.rules))
        SIZED.remember(key, known, len(facade.leaves))
    return optimise_widths(facade, root, known[2], target, lines=lines,
                           corners=settings.corners, corner_labels=settings.corner_labels,
                           alignment=settings.alignment, symmetry=settings.symmetry, minimum=known[3],
                           collapse_below=settings.rules.sliver + MARGIN, centred=centred)


#: the grids and least leaf extents of facades sized before, by facade and tree (identity: remembered jumps and
#: merges give the same objects again; each entry holds both, so their ids stay theirs), active grids and rules
SIZED: Memory[tuple] = Memory(25_000)  #: (capacity in leaves)


def kept(facade: Facade, labels: frozenset[str]) -> int:
    return sum(1 for f in facade.leaves if f.label in labels)


def column_candidates(facade: Facade, settings: Settings, grow: bool) -> list[Candidate]:
    """Every single jump of the active grids with its width change."""
    out, middle = [], 0.5 * facade.width
    for spec in settings.active:
        grid = detect_grid(facade, spec)
        if grid is None or len(grid.columns) < 2 and not grow:
            continue
        if grow:
            for s in source_columns(facade, grid):
                slab = grid.columns[s]
                gaps = ([(p, insertion_gap(grid, p)) for p in range(1, len(grid.columns))]
                        if len(grid.columns) > 1 else boundary_gaps(slab, facade.width))
                for p, gap in gaps:
                    if gap is not None:
                        out.append(Candidate(Jump("insert", spec.name, "x", s, p),
                                             gap[1] - gap[0] + slab[1] - slab[0], abs(gap[0] - middle), (gap, slab),
                                             lambda m, gap=gap, slab=slab: insert_slab(facade, gap, slab, m)))
        else:
            for c in range(len(grid.columns)):
                cut = removal_slab(grid, c)
                if cut is not None:
                    out.append(Candidate(Jump("remove", spec.name, "x", c), cut[0] - cut[1],
                                         abs(0.5 * (cut[0] + cut[1]) - middle), (cut,),
                                         _remover(facade, grid, c)))
    return out


def _remover(facade: Facade, grid: FacadeGrid, column: int) -> Callable[[int], Facade | None]:
    """Remove ``column`` ``m`` times (None when that would leave no column)."""
    def apply(m: int) -> Facade | None:
        slab = removal_slab(grid, column, m)
        return None if slab is None else remove_slab(facade, slab)
    return apply


def choose(path: Path, candidates: list[Candidate], settings: Settings, target: float, deadline: float,
           copies: int | None = 1) -> tuple[Candidate, int, Path, SpatialResult | None] | None:
    """The best jump of ``path`` towards ``target``: the candidate, its number of copies ``k``, the state after one
    copy and that state's QP result (None: not scored). Candidates are ranked by the size mismatch that ``k``
    copies leave (then nearest the middle, then by description); ``copies`` None gives each candidate the ``k``
    whose mismatch is least. The QP scores the first ``FINALISTS`` of distinct size changes that keep the kept labels
    (none when one size change is on offer; fewer once the work ``deadline`` has passed) as single jumps at their
    per-copy share of the size change, then compares the winner with up to ``POSITIONS`` other jumps of its size
    change (other positions, the next nearest the middle; a rival must be strictly better). None when no jump is
    possible."""
    gap = target - path.facade.width

    def count(cand: Candidate) -> int:
        return copies if copies is not None else max(1, round(gap / cand.delta)) if cand.delta * gap > 0 else 1

    order = sorted(candidates, key=lambda c: (round(abs(gap - count(c) * c.delta), 2), round(c.offset, 2),
                                              str(c.jump)))
    want = kept(path.facade, settings.keep)
    finalists: list[tuple[Candidate, Facade]] = []
    seen: set[float] = set()
    for cand in order:
        if round(cand.delta, 2) in seen or cand.changes(path.facade, settings.keep):
            continue
        new = cand.apply(1)
        if kept(new, settings.keep) == want:
            seen.add(round(cand.delta, 2))
            finalists.append((cand, new))
            if len(finalists) == FINALISTS:
                break
    best: tuple[float, Candidate, Path, SpatialResult | None] | None = None
    for cand, new in finalists:
        state = Path(*merge_leaves(new, settings.fixed), path.jumps + (cand.jump,))
        if len(finalists) == 1 or settings.work.spent > deadline:
            best = best or (0.0, cand, state, None)
            break
        res = size(state.facade, settings, path.facade.width + gap / count(cand), root=state.root)
        if res.success and (best is None or res.objective < best[0]):
            best = (res.objective, cand, state, res)
    if best is None:
        return None
    _, cand, state, res = best
    rivals = [c for c in order if c is not cand and round(c.delta, 2) == round(cand.delta, 2)
              and not c.changes(path.facade, settings.keep)][:POSITIONS]
    scout = path.facade.width + gap / count(cand)
    for alt in rivals:  # other positions of the winning size change: the QP compares them with the winner's
        if settings.work.spent > deadline:
            break
        if res is None:
            res = size(state.facade, settings, scout, root=state.root)
        new = alt.apply(1)
        if kept(new, settings.keep) != want:
            continue
        other = Path(*merge_leaves(new, settings.fixed), path.jumps + (alt.jump,))
        r = size(other.facade, settings, scout, root=other.root)
        if r.success and (not res.success or r.objective < res.objective - 1e-9 * max(1.0, res.objective)):
            cand, state, res = alt, other, r
    return cand, count(cand), state, res


def greedy_step(path: Path, candidates: list[Candidate], settings: Settings, target: float, deadline: float,
                copies: int = 1) -> tuple[Path, SpatialResult | None] | None:
    """The next state of ``path`` and its QP result (None: not scored), by :func:`choose`. ``copies`` > 1 repeats
    the chosen jump that many times in one step (far targets), unscored (or takes it once when the repeat is not
    possible). None when no jump is possible."""
    chosen = choose(path, candidates, settings, target, deadline, copies)
    if chosen is None:
        return None
    cand, k, state, res = chosen
    bulk = repeated(path, cand, k, settings)
    return (state, res) if bulk is None else (bulk, None)


def repeated(path: Path, cand: Candidate, k: int, settings: Settings) -> Path | None:
    """``path`` after ``k`` > 1 copies of ``cand`` in one jump (one band of ``k`` copies); None when ``k`` is 1 or
    the repeat is not possible (it would copy or remove a kept label)."""
    if k < 2:
        return None
    bulk = cand.apply(k)
    if bulk is None or kept(bulk, settings.keep) != kept(path.facade, settings.keep):
        return None
    return Path(*merge_leaves(bulk, settings.fixed), path.jumps + (cand.jump,) * k)


def mixed(path: Path, first: Candidate, a: int, second: Candidate, b: int, settings: Settings) -> Path | None:
    """``path`` after ``b`` copies of insertion ``second`` and then ``a`` copies of insertion ``first`` (its gap and
    slab moved with the content right of the first band): two jumps of many copies, for a width that one column
    kind repeated misses. None when ``first``'s gap or slab straddles the band's place or a kept label would be
    copied."""
    c0, width = second.slabs[0][0], b * second.delta
    if any(lo < c0 - EPS < hi - EPS for lo, hi in first.slabs):
        return None
    gap, slab = ((lo + width, hi + width) if lo >= c0 - EPS else (lo, hi) for lo, hi in first.slabs)
    bulk = insert_slab(second.apply(b), gap, slab, a)
    if kept(bulk, settings.keep) != kept(path.facade, settings.keep):
        return None
    return Path(*merge_leaves(bulk, settings.fixed), path.jumps + (second.jump,) * b + (first.jump,) * a)


def far_variations(start: Path, settings: Settings, target: float, deadline: float, notes: list[str]
                   ) -> list[tuple[Path, SpatialResult]]:
    """States of a facade far narrower than ``target``, each one insertion jump of ``m`` copies of one source
    column (the same insertion repeated as one band), and their QP results.

    Every candidate gets the count ``k`` that leaves the least width mismatch; :func:`choose` ranks them by that
    mismatch and the QP scores the finalists as single copies. The winner's counts ``k - 1, k, k + 1`` are the
    states, plus, when it fits the width closer than they do, the winner's copies mixed with copies of one other
    insertion (:func:`mixed`; the split with the least mismatch). States are sized in order of their mismatch
    while the work ``deadline`` and ``MAX_LEAVES`` allow (leaves estimated from one copy's, before a state is
    built); when none fits, the largest count of the winner that does (noted in ``notes``)."""
    candidates = column_candidates(start.facade, settings, True)
    chosen = choose(start, candidates, settings, target, deadline, None)
    if chosen is None:
        return []
    cand, k, one, _ = chosen
    gap = target - start.facade.width
    n0, per_copy = len(start.facade.leaves), len(one.facade.leaves) - len(start.facade.leaves)
    counts = sorted({max(1, k - 1), k, k + 1})
    options = [(round(abs(gap - m * cand.delta), 2), 1, m, None, 0) for m in counts]
    others = [c for c in candidates if round(c.delta, 2) != round(cand.delta, 2)
              and not c.changes(start.facade, settings.keep)]
    mixes = [(round(abs(gap - (m - b) * cand.delta - b * c.delta), 2), 1, m, c, b)
             for m in counts for c in others for b in range(1, m)]
    best_mix = min(mixes, key=lambda o: (o[0], o[4], o[2]), default=None)
    if best_mix is not None and best_mix[0] < min(o[0] for o in options):
        options.append(best_mix)
    twin = _twin(start.facade, cand, candidates, settings)
    if twin is not None:  # half the copies on the other side of a centred door: tried first, one-sided if none fits
        options += [(round(abs(gap - (m - m // 2) * cand.delta - m // 2 * twin.delta), 2), 0, m, twin, m // 2)
                    for m in counts if m > 1]
    out = []
    balanced = False
    for _, one_sided, m, other, b in sorted(options, key=lambda o: (o[1], o[0], o[2], o[4])):
        leaves = n0 + m * per_copy
        if leaves > MAX_LEAVES or settings.work.spent + leaves > deadline or one_sided and balanced:
            continue
        if other is None:
            state = one if m == 1 else repeated(start, cand, m, settings)
        else:
            state = mixed(start, cand, m - b, other, b, settings)
        if state is not None:
            out.append((state, size(state.facade, settings, target, root=state.root)))
            balanced = balanced or not one_sided and out[-1][1].success
    if not out:
        fit = min(k, int((min(MAX_LEAVES, deadline - settings.work.spent) - n0) // max(1, per_copy)))
        notes.append(f"budget {settings.budget:g} s or {MAX_LEAVES} leaves reached: {max(0, fit)} of {k} column jumps")
        state = one if fit == 1 else repeated(start, cand, fit, settings) if fit > 1 else None
        if state is not None:
            out.append((state, size(state.facade, settings, target, root=state.root)))
    return out


def _twin(facade: Facade, cand: Candidate, candidates: list[Candidate], settings: Settings) -> Candidate | None:
    """The insertion of ``cand``'s source column on the other side of the centred door, nearest ``cand``'s mirror
    image about it (None: no centred label, or no such insertion)."""
    doors = [f for f in facade.leaves if f.label in settings.centre]
    if len(doors) != 1:
        return None
    middle = doors[0].x + 0.5 * doors[0].w
    side = cand.slabs[0][0] < middle
    twins = [c for c in candidates if c.jump.source == cand.jump.source and c.jump.grid == cand.jump.grid
             and (c.slabs[0][0] < middle) != side and not c.changes(facade, settings.keep)]
    return min(twins, key=lambda c: (abs(c.slabs[0][0] + cand.slabs[0][0] - 2 * middle), str(c.jump)), default=None)


def pitch(facade: Facade, settings: Settings) -> float | None:
    """Mean distance between consecutive columns of the first active grid with two or more columns; else, for a
    one-column grid, the mean width change of its insertions at the facade boundary (its width plus the mean gap
    to the boundaries)."""
    grids = grids_of(facade, settings.active)
    for grid in grids:
        if len(grid.columns) > 1:
            return (grid.columns[-1][0] - grid.columns[0][0]) / (len(grid.columns) - 1)
    for grid in grids:
        lo, hi = grid.columns[0]
        return 0.5 * (facade.width + hi - lo)
    return None


def width_variations(facade: Facade, settings: Settings, target: float, limit: int = 8,
                     deadline: float = float("inf"), notes: list[str] | None = None) -> list[Variation]:
    """The distinct variations of ``facade`` at width ``target``, least cost first (ties by jump description),
    for ``limit`` wanted: the column counts within ``spread(limit)`` of the one the pitch suggests.

    The resized facade without jumps is always tried (the fallback when the budget is spent); budget cuts
    are appended to ``notes``."""
    notes = notes if notes is not None else []
    start = Path(*merge_leaves(facade, settings.fixed))
    facade = start.facade
    reference = reference_widths(facade)
    found: list[Variation] = []
    _add(found, start, size(facade, settings, target, root=start.root), reference, settings)
    step = pitch(facade, settings)
    best_k = 0 if step is None else int(round((target - facade.width) / step))
    counts = {best_k + d for d in range(-spread(limit), spread(limit) + 1)} - {0} if step is not None else set()
    for sign in (1, -1):
        wanted = sorted(abs(k) for k in counts if k * sign > 0)
        if sign > 0 and wanted and wanted[0] >= FAR_COPIES:
            for state, res in far_variations(start, settings, target, deadline, notes):
                _add(found, state, res, reference, settings)
            continue
        path, res = start, None
        while wanted and len(path.jumps) < wanted[-1]:
            if settings.work.spent > deadline:
                notes.append(f"budget {settings.budget:g} s spent after {len(path.jumps)} of {wanted[-1]} "
                             "column jumps")
                if path.jumps and len(path.jumps) not in wanted:  # the partial path: fewer jumps, one more QP
                    _add(found, path, res or size(path.facade, settings, target, root=path.root), reference,
                         settings)
                break
            ahead = min(k for k in wanted if k > len(path.jumps)) - len(path.jumps)
            copies = _affordable(path, ahead, deadline, settings)
            if copies == 0:
                notes.append(f"budget {settings.budget:g} s or {MAX_LEAVES} leaves reached: {len(path.jumps)} "
                             f"of {wanted[-1]} column jumps")
                if path.jumps and len(path.jumps) not in wanted:
                    _add(found, path, res or size(path.facade, settings, target, root=path.root), reference,
                         settings)
                break
            nxt = greedy_step(path, column_candidates(path.facade, settings, sign > 0), settings, target, deadline,
                              copies)
            if nxt is None:
                break
            path, res = nxt
            if len(path.jumps) in wanted:
                _add(found, path, res or size(path.facade, settings, target, root=path.root), reference, settings)
    found.sort(key=lambda v: (v.cost, [str(j) for j in v.jumps]))
    unique, seen = [], set()
    for v in found:
        key = tuple(sorted((round(f.x, 6), round(f.w, 6), f.origin) for f in v.facade.leaves))
        if key not in seen:
            seen.add(key)
            unique.append(v)
    return unique


def _affordable(path: Path, copies: int, deadline: float, settings: Settings) -> int:
    """How many of ``copies`` column copies the next step can make before the work ``deadline``: its finalists and
    the final sizing each cost one unit per leaf, a copy adds about one column's share of the leaves, and the facade
    stays within ``MAX_LEAVES`` (tree rebuilds and the KKT factorisation grow faster than linearly). 0: none."""
    grids = grids_of(path.facade, settings.active)
    columns = max((len(g.columns) for g in grids), default=1)
    n = len(path.facade.leaves)
    per_copy = max(1.0, n / max(1, columns))
    left = min((deadline - settings.work.spent) / (FINALISTS + 1), MAX_LEAVES)
    return max(0, min(copies, int((left - n) // per_copy)))


def spread(limit: int) -> int:
    """How many column counts either side of the pitch's count are tried for ``limit`` variations."""
    return max(1, limit // 2)


def _add(found: list[Variation], path: Path, res: SpatialResult, reference: dict[int, float],
         settings: Settings) -> None:
    if res.success:
        found.append(Variation(path.jumps, res.facade, res.objective, res.dropped,
                               defects(path.facade, res.facade, reference, settings.centre,
                                       any(j.op == "remove" for j in path.jumps), settings.rules)))


def pick(variations: Sequence[Variation], rng: np.random.Generator) -> Variation:
    """One of the near-best variations (cost within NEAR_BEST of the least), chosen by ``rng``."""
    best = variations[0].cost
    near = [v for v in variations if v.cost <= best * NEAR_BEST + 1e-9]
    return near[int(rng.integers(len(near)))]
