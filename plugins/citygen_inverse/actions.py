"""Candidate rules for a region (the actions of wu2014 §4.1) and the splitting heuristic of §4.4.

Along each axis a region's valid split lines cut it into *atoms*; every split rule groups consecutive atoms.
Candidates are: every atom its own child; for each repeated region inside (§4.3) the grouping that keeps its
instances whole; the same with runs of identical groups merged into one child (which a repeat rule then
explains). Each grouping is written with the cheapest operator that fits its child sequence: ``repeat`` (periodic),
``repeatABA`` (A B A ... A), ``symsplit`` (odd palindrome) or ``split``. A region no line separates (a pinwheel,
wu2014 §6.3) gets a ``grid`` rule over its terminals.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from citygen_inverse.regions import Box, LayoutIndex
from citygen_inverse.symmetry import RepeatedRegions


@dataclass(frozen=True)
class CostModel:
    """wu2014 Eq. 1-2 operator costs (symsplit/grid/floors priced like split, repeatABA like repeat)."""

    split: float = 0.1
    repeat: float = 0.5
    lambda1: float = 1.0
    lambda2: float = 1.0


@dataclass(frozen=True)
class Action:
    """A rule ``sym -> op alpha`` for one region signature.

    ``items`` are ``(sig, relative box)`` of the successors written in the rule (for ``repeat`` one tile, for
    ``repeatABA`` A then B, for ``symsplit`` the first half and the centre, for ``grid`` every cell region);
    ``children`` the distinct non-terminal successor signatures with a relative box of one instance each;
    ``cuts`` the interior split lines (relative, along ``axis``) used by protection.
    """

    op: str
    axis: int
    items: tuple[tuple[int, Box], ...]
    children: tuple[tuple[int, Box], ...]
    cost: float
    heuristic: float
    cuts: tuple[int, ...]
    grid_lines: tuple[tuple[int, ...], tuple[int, ...]] = ((), ())


def _ops(seq: list[tuple[int, int]], model: CostModel) -> tuple[str, float, int]:
    """Cheapest operator for a child sequence of (signature, size along the axis): (op, cost, items written)."""
    k = len(seq)
    best = ("split", model.split + k, k)
    for p in range(1, k):
        if k % p == 0 and seq == seq[:p] * (k // p):
            if model.repeat + p < best[1]:
                best = ("repeat", model.repeat + p, p)
            break
    if k >= 3 and k % 2 == 1 and len(set(seq[0::2])) == 1 and len(set(seq[1::2])) == 1 and seq[0] != seq[1]:
        if model.repeat + 2 < best[1]:
            best = ("repeatABA", model.repeat + 2, 2)
    if k >= 3 and k % 2 == 1 and seq == seq[::-1] and model.split + (k + 1) // 2 < best[1]:
        best = ("symsplit", model.split + (k + 1) // 2, (k + 1) // 2)
    return best


def region_actions(index: LayoutIndex, sig: int, sym: RepeatedRegions, model: CostModel) -> list[Action]:
    """All candidate rules for the region signature ``sig`` (its representative box)."""
    box = index.sigs[sig].box
    x0, y0, x1, y1 = box
    inside = np.flatnonzero((sym.boxes[:, 0] >= x0) & (sym.boxes[:, 1] >= y0) & (sym.boxes[:, 2] <= x1)
                            & (sym.boxes[:, 3] <= y1)
                            & ~((sym.boxes[:, 0] == x0) & (sym.boxes[:, 1] == y0) & (sym.boxes[:, 2] == x1)
                                & (sym.boxes[:, 3] == y1)))
    inst = sym.boxes[inside]
    weight = sym.terminals[inside] / index.sigs[sig].n
    if index.sigs[sig].period is not None:
        return _periodic(index, sig, model, inst, weight)
    actions: list[Action] = []
    for axis in (0, 1):
        cuts = index.cuts(box, axis)
        if cuts.size == 0:
            continue
        bounds = np.concatenate([[box[axis]], cuts, [box[axis + 2]]])
        m = bounds.size - 1
        groupings = {tuple(range(1, m))}  # a grouping = the atom boundaries kept
        lo, hi = inst[:, axis], inst[:, axis + 2]
        for g in np.unique(sym.group[inside]):
            sel = sym.group[inside] == g
            covered = np.zeros(m + 1, dtype=bool)  # covered[k]: boundary k lies strictly inside an instance
            for a, b in zip(lo[sel], hi[sel]):
                covered[(bounds > a) & (bounds < b)] = True
            groupings.add(tuple(k for k in range(1, m) if not covered[k]))
        atoms = [(index.sig(_piece(box, axis, bounds[k], bounds[k + 1])), int(bounds[k + 1] - bounds[k]))
                 for k in range(m)]
        groupings.update(_repeated_runs(atoms))
        seen = set()
        for keep in groupings:
            for merge_runs in (False, True):
                edges = [0, *keep, m]
                pieces = [_piece(box, axis, bounds[a], bounds[b]) for a, b in zip(edges, edges[1:])]
                sigs = [index.sig(p) for p in pieces]
                if merge_runs:
                    pieces, sigs = _merge_runs(index, box, axis, pieces, sigs)
                if len(pieces) < 2 or tuple(p[axis] for p in pieces) in seen:
                    continue
                seen.add(tuple(p[axis] for p in pieces))
                actions.append(_make(index, box, axis, pieces, sigs, model, lo, hi, weight))
    if not actions:
        actions.append(_grid(index, sig, model))
    return actions


def _periodic(index: LayoutIndex, sig: int, model: CostModel, inst: np.ndarray, weight: np.ndarray
              ) -> list[Action]:
    """A periodic region (any tile count shares its signature) only gets ``repeat`` rules: over whole tiles, or
    over the tile's atoms written inline."""
    box = index.sigs[sig].box
    axis, p = index.sigs[sig].period
    lo, hi = inst[:, axis], inst[:, axis + 2]
    starts = range(box[axis], box[axis + 2], p)
    tiles = [_piece(box, axis, a, a + p) for a in starts]
    out = [_make(index, box, axis, tiles, [index.sig(t) for t in tiles], model, lo, hi, weight)]
    cuts = index.cuts(box, axis)
    if cuts.size + 1 > len(tiles):
        bounds = np.concatenate([[box[axis]], cuts, [box[axis + 2]]])
        atoms = [_piece(box, axis, a, b) for a, b in zip(bounds, bounds[1:])]
        out.append(_make(index, box, axis, atoms, [index.sig(t) for t in atoms], model, lo, hi, weight))
    return [a for a in out if a.op == "repeat"]  # (always: for >= 2 tiles repeat is the cheapest operator)


def _repeated_runs(atoms: list[tuple[int, int]], limit: int = 16) -> list[tuple[int, ...]]:
    """Groupings that keep every occurrence of a repeated atom substring whole (1-D symmetry along the axis)."""
    m = len(atoms)
    found: list[tuple[float, tuple[int, ...]]] = []
    for length in range(2, m // 2 + 1):
        starts: dict[tuple[int, ...], list[int]] = {}
        for i in range(m - length + 1):
            starts.setdefault(tuple(atoms[i:i + length]), []).append(i)
        for occ in starts.values():
            chosen, end = [], -1
            for i in occ:
                if i >= end:
                    chosen.append(i)
                    end = i + length
            if len(chosen) >= 2:
                inner = {i + d for i in chosen for d in range(1, length)}
                found.append(((length - 1) * (len(chosen) - 1), tuple(k for k in range(1, m) if k not in inner)))
    found.sort(key=lambda t: -t[0])
    return [keep for _, keep in found[:limit]]


def _piece(box: Box, axis: int, a: int, b: int) -> Box:
    return (int(a), box[1], int(b), box[3]) if axis == 0 else (box[0], int(a), box[2], int(b))


def _merge_runs(index: LayoutIndex, box: Box, axis: int, pieces: list[Box], sigs: list[int]
                ) -> tuple[list[Box], list[int]]:
    out_p, out_s, start = [], [], 0
    for k in range(1, len(pieces) + 1):
        if k == len(pieces) or sigs[k] != sigs[start] or _len(pieces[k], axis) != _len(pieces[start], axis):
            merged = _piece(box, axis, pieces[start][axis], pieces[k - 1][axis + 2])
            out_p.append(merged)
            out_s.append(index.sig(merged) if k - start > 1 else sigs[start])
            start = k
    return out_p, out_s


def _len(p: Box, axis: int) -> int:
    return p[axis + 2] - p[axis]


def _rel(box: Box, p: Box) -> Box:
    return (p[0] - box[0], p[1] - box[1], p[2] - box[0], p[3] - box[1])


def _make(index: LayoutIndex, box: Box, axis: int, pieces: list[Box], sigs: list[int], model: CostModel,
          lo: np.ndarray, hi: np.ndarray, weight: np.ndarray) -> Action:
    op, cost, k = _ops([(s, _len(p, axis)) for s, p in zip(sigs, pieces)], model)
    cuts = np.array([p[axis] for p in pieces[1:]], dtype=np.int64)
    crossing = (lo[:, None] < cuts[None, :]) & (hi[:, None] > cuts[None, :])
    line_cost = float(weight @ crossing.sum(axis=1)) if crossing.size else 0.0
    items = tuple((s, _rel(box, p)) for s, p in zip(sigs[:k], pieces[:k]))
    children, seen = [], set()
    for s, p in zip(sigs, pieces):
        if s not in seen and index.sigs[s].n > 1:
            seen.add(s)
            children.append((s, _rel(box, p)))
    return Action(op, axis, items, tuple(children), cost, model.lambda1 * cost + model.lambda2 * line_cost,
                  tuple(int(c - box[axis]) for c in cuts))


def _grid(index: LayoutIndex, sig: int, model: CostModel) -> Action:
    """gridsplit (wu2014 §4.7) over the terminals of a region that no single line separates."""
    box = index.sigs[sig].box
    idx = index.inside(box)
    xs = tuple(int(v - box[0]) for v in np.unique(np.concatenate([index.X0[idx], index.X1[idx]])))
    ys = tuple(int(v - box[1]) for v in np.unique(np.concatenate([index.Y0[idx], index.Y1[idx]])))
    items = []
    for k in idx[np.lexsort((index.X0[idx], index.Y0[idx]))]:
        cell = (int(index.X0[k]), int(index.Y0[k]), int(index.X1[k]), int(index.Y1[k]))
        items.append((index.sig(cell), _rel(box, cell)))
    cost = model.split + len(items)
    return Action("grid", 0, tuple(items), (), cost, model.lambda1 * cost, (), (xs, ys))
