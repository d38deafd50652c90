"""Sizing and placement of shapes (§5.3): the constrained least-squares problem over letter bounds ``s, t``.

Stitching (within an entry and at column borders), full coverage and column alignment identify letter bounds
with shared position variables (one per column border per matrix, one per letter border inside an entry), which
is the paper's system with its equality constraints eliminated exactly. What remains: the objective over the
prototype letter of each sized symbol, synchronisation of every letter (and across alignment groups) with its
prototype, ``s <= t``, a least size of visible sized letters (:data:`LEAST`, beyond the paper), and the
building's pins (floor lines) and bands (corner strips, floor bands).
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from citygen_layers.align import Alignment
from citygen_layers.candidates import Row
from citygen_layers.lsq import solve_lsq
from citygen_layers.words import Letter

#: Constraint kinds given up, in order, when the system has no solution (each step is reported; "least" includes
#: the symbols' min= and max=).
RELAXATIONS = (((), ""),
               (("least",), "minimum sizes dropped (letters shrink below a third of their size)"),
               (("least", "sync"), "synchronisation of symbol sizes dropped (pins and bands leave no common size)"),
               (("least", "sync", "band"), "corner/floor bands dropped (no room for them)"),
               (("least", "sync", "band", "pin"), "floor pins dropped (the words cannot meet the floor lines)"))

#: The least share of its size a visible sized letter keeps (``t - s >= LEAST * size``). The paper's objective
#: shrinks every letter of a column by the same metres, so a 0.12 m sill or a 0.25 m ledge in a storey 0.4 m
#: lower than its letters vanishes; with this bound such a candidate is not solved and the next one is taken.
LEAST = 1.0 / 3.0

#: Weight that ties an unsized symbol to its sampled size; only picks one optimum among equal ones.
UNSIZED_WEIGHT = 1e-4


@dataclass(frozen=True)
class Matrix:
    """One alignment matrix: the rows of an alignment group, their (possibly split) words and alignment."""

    group: str
    rows: tuple[Row, ...]
    words: tuple[tuple[Letter, ...], ...]
    parents: tuple[tuple[int, ...], ...]
    originals: tuple[tuple[Letter, ...], ...]
    alignment: Alignment


@dataclass(frozen=True)
class Segment:
    """A placed letter ``[s, t]`` of a row, or a hole (``letter is None``) where the layer made space."""

    s: float
    t: float
    letter: Letter | None
    index: int = -1


@dataclass(frozen=True)
class Sizing:
    segments: Mapping[tuple[str, str], tuple[Segment, ...]]
    success: bool
    message: str
    relaxed: tuple[str, ...] = field(default=())
    borders: Mapping[str, tuple[float, ...]] = field(default_factory=dict)   # column borders per group


def size_matrices(matrices: Sequence[Matrix], canvas: float,
                  pins: Mapping[tuple[str, str], Sequence[tuple[float, float]]] | None = None,
                  bands: Mapping[tuple[str, str], Mapping[int, tuple[float, float]]] | None = None,
                  ranges: Mapping[str, tuple[float | None, float | None]] | None = None) -> Sizing:
    """Solve §5.3 for all matrices of one direction (cross-group constraints through shared prototypes).
    ``ranges`` are the symbols' declared ``(min, max)``: a visible letter keeps its min (instead of a third of its
    size) and its max."""
    pins, bands, ranges = pins or {}, bands or {}, ranges or {}
    nvar = 0
    letter_vars: dict[tuple[str, str], list[list[int]]] = {}
    border_vars: dict[str, list[int]] = {}
    holes: dict[tuple[str, str], list[tuple[int, int]]] = {}
    eq_rows: list[tuple[dict[int, float], float, str]] = []   # (coefficients, rhs, kind)
    ineq: list[tuple[dict[int, float], float, str]] = []
    for matrix in matrices:
        ncol = len(matrix.alignment.columns)
        border = list(range(nvar, nvar + ncol + 1))
        border_vars[matrix.group] = border
        nvar += ncol + 1
        eq_rows += [({border[0]: 1.0}, 0.0, "cover"), ({border[-1]: 1.0}, canvas, "cover")]
        ineq += [({border[j]: 1.0, border[j + 1]: -1.0}, 0.0, "order") for j in range(ncol)]
        for r, row in enumerate(matrix.rows):
            key = (row.group, row.pattern)
            spans = [[-1, -1] for _ in matrix.originals[r]]
            holes[key] = []
            parents = matrix.parents[r]
            for j, col in enumerate(matrix.alignment.columns):
                a, b = col[r]
                if a == b:
                    holes[key].append((border[j], border[j + 1]))
                    continue
                prev = border[j]
                for i in range(a, b):
                    if i + 1 < b and parents[i + 1] == parents[i]:
                        continue
                    end = border[j + 1] if i == b - 1 else nvar
                    if i < b - 1:
                        nvar += 1
                    p = parents[i]
                    if spans[p][0] < 0:
                        spans[p][0] = prev
                    spans[p][1] = end
                    prev = end
            letter_vars[key] = spans
    # objective, synchronisation (prototype letters), s <= t, pins and bands
    obj: list[tuple[dict[int, float], float]] = []
    proto: dict[str, tuple[int, int]] = {}
    pinned = {letter.symbol for m in matrices for r, row in enumerate(m.rows)
              if (row.group, row.pattern) in pins for letter in m.originals[r]}
    for matrix in matrices:
        for r, row in enumerate(matrix.rows):
            key = (row.group, row.pattern)
            for i, letter in enumerate(matrix.originals[r]):
                s, t = letter_vars[key][i]
                ineq.append(({s: 1.0, t: -1.0}, 0.0, "order"))
                if not (letter.transparent or letter.unsized) and letter.size > 0.0 and key not in pins:
                    least, most = ranges.get(letter.symbol, (None, None))
                    ineq.append(({s: 1.0, t: -1.0}, -(LEAST * letter.size if least is None else least), "least"))
                    if most is not None:
                        ineq.append(({t: 1.0, s: -1.0}, most, "least"))
                if key in pins:
                    lo, hi = pins[key][i]
                    eq_rows += [({s: 1.0}, lo, "pin"), ({t: 1.0}, hi, "pin")]
                if i in bands.get(key, {}):
                    lo, hi = bands[key][i]
                    ineq += [({s: -1.0}, -lo, "band"), ({t: 1.0}, hi, "band")]
                if letter.symbol in pinned:
                    # storeys vary with the floor lines: each instance outside the floor word keeps its own size
                    if key not in pins:
                        obj.append(({t: 1.0, s: -1.0}, letter.size))
                    continue
                if letter.symbol not in proto:
                    proto[letter.symbol] = (s, t)
                    w = UNSIZED_WEIGHT if letter.unsized else 1.0
                    obj.append(({t: np.sqrt(w), s: -np.sqrt(w)}, np.sqrt(w) * letter.size))
                else:
                    ps, pt = proto[letter.symbol]
                    if (ps, pt) != (s, t):
                        eq_rows.append((_add({t: 1.0, s: -1.0}, {pt: -1.0, ps: 1.0}), 0.0, "sync"))
    D, d = _matrix([(c, r, "") for c, r in obj], nvar)
    relaxed: list[str] = []
    result = None
    for drop, why in RELAXATIONS:
        if why:
            relaxed.append(why)
        A, b = _matrix([e for e in eq_rows if e[2] not in drop], nvar)
        G, h = _matrix([e for e in ineq if e[2] not in drop], nvar)
        result = solve_lsq(D, d, A, b, G, h)
        if result.success:
            break
    if not result.success:
        return Sizing({}, False, result.message, tuple(relaxed))
    x = np.clip(result.x, 0.0, canvas).tolist()
    segments = {}
    for matrix in matrices:
        for r, row in enumerate(matrix.rows):
            key = (row.group, row.pattern)
            # (s, t, letter index) of the letters, then of the holes (index -1), in order of (s, t, index)
            spans = [(x[s], x[t], i) for i, (s, t) in enumerate(letter_vars[key])]
            spans += [(x[a], x[b], -1) for a, b in holes[key] if x[b] - x[a] > 1e-9]
            letters = matrix.originals[r]
            segments[key] = tuple(Segment(s, t, letters[i] if i >= 0 else None, i)
                                  for s, t, i in sorted((s, max(t, s), i) for s, t, i in spans))
    borders = {g: tuple(x[v] for v in vs) for g, vs in border_vars.items()}
    return Sizing(segments, True, result.message, tuple(relaxed), borders)


def _add(a: dict[int, float], b: dict[int, float]) -> dict[int, float]:
    out = dict(a)
    for k, v in b.items():
        out[k] = out.get(k, 0.0) + v
    return out


def _matrix(rows: list[tuple[dict[int, float], float, str]], n: int) -> tuple[sp.csr_matrix, np.ndarray]:
    """The rows (coefficients by variable) as a canonical CSR matrix (sorted columns, no zeros), and the rhs."""
    indptr, indices, data = [0], [], []
    for coef, _, _ in rows:
        for j in sorted(coef):
            v = coef[j]
            if v != 0.0:
                indices.append(j)
                data.append(v)
        indptr.append(len(indices))
    mat = sp.csr_matrix((np.array(data, dtype=float), np.array(indices, dtype=np.int32),
                         np.array(indptr, dtype=np.int32)), shape=(len(rows), n))
    return mat, np.array([rhs for _, rhs, _ in rows], dtype=float)
