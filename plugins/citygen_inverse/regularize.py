"""Regularisation of annotated boxes along one axis (wu2014 §3.3): shared lines, equal sizes, equal spacing.

Annotations of real photos (CMP) are noisy by a few pixels, so elements that repeat on the facade are neither the
same size nor on the same row/column lines, and a grammar finds few exact translational repeats. Per axis:

1. *alignment*: the same-side edges (left edges, right edges, ...) of boxes of one label within ``align`` of the
   facade size are clustered to their mean, so a column of windows shares its two lines;
2. *snapping*: all edges (any label) within ``snap`` are clustered into one line (facade ends stay fixed);
3. *equal sizes and spacing*: a QP (``citygen.qp.solve_eq_qp``) moves the lines as little as possible such that
   boxes of one label whose sizes differ by noise get equal sizes, and consecutive boxes of one label in a row
   (boxes overlapping across the axis) whose pitches (start to start) differ by noise get equal pitches.
   Constraints are added closest first; one that would collapse or reorder lines is rejected.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from citygen.qp import solve_eq_qp


@dataclass(frozen=True)
class AxisLines:
    """Regularised lines of one axis and, per box, the indices of its two lines."""

    lines: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    status: str
    equal: tuple[tuple[int, int, int, int], ...] = ()  # accepted (a0, a1, b0, b1): a1 - a0 == b1 - b0


def cluster(values: np.ndarray, tol: float, lo: float = -np.inf, hi: float = np.inf
            ) -> tuple[np.ndarray, np.ndarray]:
    """1-D clustering: sorted distinct centres and, per value, the index of its centre.

    A cluster spans at most ``tol`` (no chaining through dense edges); centres within ``tol`` of ``lo``/``hi``
    become ``lo``/``hi``.
    """
    order = np.argsort(values, kind="stable")
    sorted_v = values[order]
    ids = np.empty(values.size, dtype=int)
    start, k = -np.inf, -1
    for i, v in enumerate(sorted_v):
        if v - start > tol:
            start, k = v, k + 1
        ids[i] = k
    centres = np.bincount(ids, weights=sorted_v) / np.bincount(ids)
    centres[np.abs(centres - lo) <= tol] = lo
    centres[np.abs(centres - hi) <= tol] = hi
    centres, inverse = np.unique(centres, return_inverse=True)
    index = np.empty(values.size, dtype=int)
    index[order] = inverse[ids]
    return centres, index


def _align(lo: np.ndarray, hi: np.ndarray, names: list[str], tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Same-side edges of one label within ``tol`` moved to their mean (never making a box empty)."""
    new_lo, new_hi = lo.copy(), hi.copy()
    labels = np.array(names)
    for name in set(names):
        sel = np.flatnonzero(labels == name)
        for old, new in ((lo, new_lo), (hi, new_hi)):
            centres, idx = cluster(old[sel], tol)
            new[sel] = centres[idx]
    bad = new_hi <= new_lo  # a box thinner than the tolerance keeps its own edges
    return np.where(bad, lo, new_lo), np.where(bad, hi, new_hi)


def _rows(across: np.ndarray) -> np.ndarray:
    """Row id per box: boxes whose cross-axis intervals overlap by half the smaller one share a row."""
    order = np.argsort(across[:, 0] + across[:, 1])
    row = np.empty(len(across), dtype=int)
    k, cur = -1, None
    for i in order:
        a0, a1 = across[i]
        if cur is None or min(a1, cur[1]) - max(a0, cur[0]) < 0.5 * min(a1 - a0, cur[1] - cur[0]):
            k, cur = k + 1, (a0, a1)
        row[i] = k
    return row


def _candidates(lines: np.ndarray, pairs: list[tuple[int, int]], tol: float, rel: float
                ) -> list[tuple[float, tuple[int, int, int, int]]]:
    """Equal-length candidates among distinct line pairs whose lengths differ by less than ``tol``/``rel``."""
    distinct = sorted(set(pairs))
    if len(distinct) < 2:
        return []
    length = np.array([lines[b] - lines[a] for a, b in distinct])
    _, group = cluster(length, tol)
    out = []
    for g in np.unique(group):
        members = [distinct[k] for k in np.flatnonzero(group == g)]
        members.sort(key=lambda p: lines[p[1]] - lines[p[0]])
        for a, b in zip(members, members[1:]):
            la, lb = lines[a[1]] - lines[a[0]], lines[b[1]] - lines[b[0]]
            if 0 < lb - la <= rel * la:
                out.append((lb - la, (*a, *b)))
    return out


def regularize_axis(lo: np.ndarray, hi: np.ndarray, across: np.ndarray, names: list[str], extent: float, *,
                    snap: float, align: float, size: float, rel: float = 0.15) -> AxisLines:
    """Lines for boxes ``[lo, hi]`` (facade coordinates, ``0..extent``) of labels ``names``.

    ``across`` holds each box's interval on the other axis (for rows); ``snap``, ``align`` and ``size`` are
    tolerances in the units of ``extent``.
    """
    lo, hi = _align(lo, hi, names, align) if align > 0 else (lo, hi)
    values = np.concatenate([[0.0, extent], lo, hi])
    lines, idx = cluster(values, snap, 0.0, extent)
    m = lo.size
    lo_i, hi_i = idx[2:2 + m], idx[2 + m:]
    alive = lo_i < hi_i
    candidates: list[tuple[float, tuple[int, int, int, int]]] = []
    labels = np.array(names)
    for name in sorted(set(names)):
        sel = np.flatnonzero((labels == name) & alive)
        if sel.size < 2:
            continue
        candidates += _candidates(lines, [(lo_i[k], hi_i[k]) for k in sel], size, rel)
        row = _rows(across[sel])
        pitches = []
        for r in np.unique(row):
            members = sorted({(lo_i[k], hi_i[k]) for k in sel[row == r]})
            pitches += [(a[0], b[0]) for a, b in zip(members, members[1:]) if b[0] >= a[1]]
        candidates += _candidates(lines, pitches, size, rel)
    lines, equal, status = _solve(lines, candidates, 0.25 * snap, merge=snap)
    keep = np.concatenate([[True], np.diff(lines) > 1e-7 * max(extent, 1.0)])  # lines the QP made coincide
    new_id = np.cumsum(keep) - 1
    equal = tuple(tuple(int(new_id[k]) for k in e) for e in equal)
    return AxisLines(lines[keep], new_id[lo_i], new_id[hi_i], status, equal)


def _solve(lines: np.ndarray, candidates: list[tuple[float, tuple[int, int, int, int]]], min_gap: float,
           merge: float = 0.0) -> tuple[np.ndarray, tuple[tuple[int, int, int, int], ...], str]:
    """Least movement of ``lines`` (ends fixed) under the accepted equal-length constraints, closest first.

    A constraint implied by accepted ones is a redundant row, which the QP's dual regularisation tolerates. A
    constraint is rejected when it would bring
    two neighbouring lines closer than ``min_gap`` (or, for lines the snapping left closer, than half their
    distance), unless it makes them coincide and they were less than ``merge`` apart: then the equal lengths say
    that the two edges are one line, which the snapping split only because its clusters span at most ``snap``
    (the caller merges coincident lines)."""
    if not candidates:
        return lines, (), "nothing to regularise"
    n = lines.size
    gap = np.minimum(0.5 * np.diff(lines), min_gap)
    tol = 1e-7 * max(lines[-1], 1.0)
    mergeable = np.diff(lines) < merge
    P, q = np.eye(n), -lines
    rows = [np.eye(n)[0], np.eye(n)[-1]]
    rhs = [lines[0], lines[-1]]
    best, rejected, seen, equal = lines, 0, set(), []
    for _, (a0, a1, b0, b1) in sorted(candidates):
        row = np.zeros(n)
        np.add.at(row, [a1, b0], 1.0)  # (a1 == b0 for consecutive pitches: coefficient 2)
        np.add.at(row, [a0, b1], -1.0)
        key = row.tobytes()
        if key in seen:
            continue
        seen.add(key)
        result = solve_eq_qp(P, q, np.vstack([*rows, row]), np.array([*rhs, 0.0]))
        if result.success and np.all(_apart(np.diff(result.x), gap, tol, mergeable)) and np.allclose(
                np.vstack([*rows, row]) @ result.x, [*rhs, 0.0], atol=tol):
            rows.append(row)
            rhs.append(0.0)
            equal.append((a0, a1, b0, b1))
            best = result.x
        else:
            rejected += 1
    return best, tuple(equal), f"{len(equal)} equal-size/spacing constraints, {rejected} rejected"


def _apart(diff: np.ndarray, gap: np.ndarray, tol: float, mergeable: np.ndarray) -> np.ndarray:
    """Per neighbouring pair of lines: at least ``gap`` apart, or coinciding where that is allowed."""
    return (diff >= gap) | ((np.abs(diff) <= tol) & mergeable)


def integer_lines(lines: np.ndarray, equal: tuple[tuple[int, int, int, int], ...], unit: float) -> np.ndarray:
    """``lines / unit`` on the integer grid with every equal-length constraint still exact and line 0 at 0.

    Rounding each line separately lets lengths the QP made equal drift one unit apart (then they are no longer
    repeats). Instead the constraints are brought to reduced row echelon form over the rationals (pivot = the
    highest line of a row with a unit coefficient); the free lines are rounded and the pivot lines follow from
    them exactly; a free line with fractional coefficients (e.g. 3/2) is rounded to a multiple of their
    denominators, so the pivots are integers too.
    """
    target = np.asarray(lines, dtype=float) / unit
    n = target.size
    rows: list[dict[int, Fraction]] = [{0: Fraction(1)}]
    for a0, a1, b0, b1 in equal:
        row: dict[int, Fraction] = {}
        for k, c in ((a1, 1), (b0, 1), (a0, -1), (b1, -1)):
            row[k] = row.get(k, Fraction(0)) + c
        rows.append({k: c for k, c in row.items() if c})
    pivots: dict[int, dict[int, Fraction]] = {}  # pivot line -> {other line: coefficient}, line = sum
    for row in rows:
        for p, expr in pivots.items():  # eliminate known pivots
            c = row.pop(p, None)
            if c:
                for k, v in expr.items():
                    row[k] = row.get(k, Fraction(0)) + c * v
        row = {k: c for k, c in row.items() if c}
        if not row:
            continue  # redundant constraint
        p = max(row, key=lambda k: (abs(row[k]) == 1, k))
        c = row.pop(p)
        expr = {k: -v / c for k, v in row.items()}
        for q, other in pivots.items():  # keep the form reduced
            d = other.pop(p, None)
            if d:
                for k, v in expr.items():
                    other[k] = other.get(k, Fraction(0)) + d * v
                pivots[q] = {k: v for k, v in other.items() if v}
        pivots[p] = expr
    step = np.ones(n, dtype=np.int64)  # a free line rounds to a multiple of its coefficients' denominators
    for expr in pivots.values():
        for k, v in expr.items():
            step[k] = math.lcm(int(step[k]), v.denominator)
    out = (np.round(target / step) * step).astype(np.int64)
    for p, expr in pivots.items():
        value = sum((v * int(out[k]) for k, v in expr.items()), Fraction(0))
        out[p] = round(value)
    return out
