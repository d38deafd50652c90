"""The facade layout solver (§5): per direction, candidates -> alignment -> sizing, with tolerance mu raised
until a solution is found (§5), bounded by an expansion/time budget with a best-effort result (§6.3 removed)."""
from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from citygen.errors import RulesetError
from citygen_layers.align import Alignment, Budget, NetworkMemo, align, greedy_alignment
from citygen_layers.candidates import Candidate, CandidateGenerator, DirectionSpec, Row, WordMemo, direction_spec
from citygen_layers.model import Counter, Ruleset
from citygen_layers.prealign import Prealigner
from citygen_layers.sizing import Matrix, Sizing, size_matrices
from citygen_layers.splits import split_transparent
from citygen_layers.storeys import StoreyCheck

#: Bands per row: letter index -> interval the letter must stay inside.
Bands = Mapping[tuple[str, str], Mapping[int, tuple[float, float]]]


@dataclass(frozen=True)
class DirectionSolution:
    """The solved layout of one direction: the chosen candidate, alignment matrices and the placed letters."""

    axis: str
    canvas: float
    mu: float
    status: str                    # "solved" or "best-effort"
    candidate: Candidate
    matrices: tuple[Matrix, ...]
    sizing: Sizing
    expansions: int
    diagnostics: tuple[str, ...] = ()
    timed_out: bool = False        # the CPU-time safety net cut the solve: the result depends on timing


def _above(rows: Sequence[Row]) -> np.ndarray:
    lows, highs = [min(r.layers) for r in rows], [max(r.layers) for r in rows]
    return np.array([[low > high for high in highs] for low in lows], dtype=bool).reshape(len(rows), len(rows))


def _groups(spec: DirectionSpec) -> list[str]:
    return list(dict.fromkeys(r.group for r in spec.rows))


def align_candidate(candidate: Candidate, spec: DirectionSpec, mu: float, budget: Budget,
                    greedy: bool = False, prealigner: Prealigner | None = None,
                    memo: NetworkMemo | None = None) -> tuple[Matrix, ...] | None:
    """Align every group of a candidate; transparent letters are split beforehand (§5.2, as preprocessing).
    With a ``prealigner`` the search is first restricted to the prealigned control columns, and searched without
    the restriction when that finds nothing. ``memo`` shares network rows between the searches of a direction."""
    matrices = []
    for group in _groups(spec):
        rows = tuple(r for r in spec.rows if r.group == group)
        words = tuple(candidate.words[r.pattern] for r in rows)
        identity = tuple(tuple(range(len(w))) for w in words)
        above = _above(rows)
        if greedy:
            matrices.append(Matrix(group, rows, words, identity, words, greedy_alignment(words, above)))
            continue
        split, parents = words, identity
        if any(x.transparent for w in words for x in w):
            split, parents = split_transparent(words, spec.canvas, None if memo is None else memo.splits)
            split, parents = tuple(split), tuple(parents)
        fence = None
        if prealigner is not None:
            fence = prealigner.fence([r.pattern for r in rows], candidate.env, words, split, parents, above,
                                     spec.canvas, mu, budget)
        result = None
        if fence is not None:
            prealigner.restricted += 1
            result = align(split, above, spec.canvas, mu, budget, parents, fence, memo)
            prealigner.fallbacks += result is None
        if result is None:
            result = align(split, above, spec.canvas, mu, budget, parents, memo=memo)
        if result is None:
            return None
        matrices.append(Matrix(group, rows, split, parents, words, result))
    return tuple(matrices)


def direction_solutions(ruleset: Ruleset, spec: DirectionSpec, budget: Budget,
                        bands: Callable[[Candidate], Bands] | None = None,
                        floor_lines: Sequence[float] = ()) -> Iterator[DirectionSolution]:
    """The solved layouts of one direction in the solver's order: candidates in lexicographic order, the first
    that aligns within mu (raised round by round) first, each candidate once, all within one budget.

    A candidate is solved only when its sizing keeps every constraint: one size per symbol (synchronisation),
    pins and bands. One whose pins and bands leave no common size is skipped (the next counter assignment or
    candidate may admit one), not sized without synchronisation. When no candidate is solved, the sequence is
    one best-effort solution: the first candidate whose sizing had to relax, else the first candidate aligned
    greedily."""
    options = ruleset.options
    mu = options.tolerance if options.tolerance is not None else 0.05 * spec.canvas
    mu = max(mu, 1e-3)
    diagnostics: list[str] = []
    fallback: tuple[Candidate, float] | None = None
    relaxed: DirectionSolution | None = None
    relaxed_at = solved = 0
    seen: set[tuple] = set()
    # per hash of a candidate's words (hashed once: letters are slow to hash), [words, matrices, cutoff searched,
    # done (yielded or rejected: never sized again)]
    cache: dict[int, list[list]] = {}
    memo = WordMemo()
    network = NetworkMemo()
    prealigner = Prealigner(ruleset) if options.prealign else None
    storeys = StoreyCheck(ruleset) if spec.floor_pattern is not None and len(floor_lines) > 2 else None
    for _ in range(options.rounds):
        for index, candidate in enumerate(CandidateGenerator(ruleset, spec, mu, budget, memo)):
            if index >= options.candidates or budget.exhausted:
                break
            fallback = fallback or (candidate, mu)
            key = tuple(candidate.words[r.pattern] for r in spec.rows)
            bucket = cache.setdefault(hash(key), [])
            entry = next((e for e in bucket if e[0] == key), None)
            if entry is None:
                entry = [key, None, 0.0, False]
                bucket.append(entry)
            _, matrices, cutoff, done = entry
            if done:
                continue
            if matrices is None and cutoff < mu:
                # searched with the next round's tolerance, so a failure is not repeated in that round
                cutoff = mu * options.growth
                matrices = align_candidate(candidate, spec, cutoff, budget, prealigner=prealigner, memo=network)
                entry[1:3] = matrices, cutoff
            if matrices is not None and all(m.alignment.error <= mu + 1e-9 and
                                            m.alignment.size <= spec.canvas + mu + 1e-9 for m in matrices):
                entry[3] = True
                solution = _sized(ruleset, spec, candidate, matrices, mu, "solved", budget, bands, floor_lines,
                                  [*diagnostics, *_prealignment_notes(spec, prealigner)])
                straddling = [] if storeys is None or solution.sizing.relaxed else \
                    storeys.straddling(spec, candidate, solution.sizing, floor_lines)
                if straddling:    # a substituted storey's content across a floor line: not solved (storeys.py)
                    note = f"substituted letters leave their storey: {straddling[0]}"
                    solution = replace(solution, sizing=replace(solution.sizing, relaxed=(note,)),
                                       diagnostics=(*solution.diagnostics, f"{spec.axis}: {note}"))
                if solution.sizing.relaxed and prealigner is not None:
                    # searched again at a larger mu, where the control words may prealign (they failed at this
                    # one, so the search ran unfenced) and keep each substituted letter's content in its column
                    entry[1:4] = None, mu, False
                if solution.sizing.relaxed:
                    if relaxed is None:
                        relaxed, relaxed_at = replace(solution, status="best-effort"), len(diagnostics)
                    continue
                placed = _placement(solution)
                if placed in seen:      # another sample of an unsized letter, sized to the same layout
                    continue
                seen.add(placed)
                solved += 1
                yield solution
        if budget.exhausted:
            break
        mu *= options.growth
    if solved:
        return
    if budget.exhausted:
        why = "time" if budget.timed_out else "expansion"
        diagnostics.append(f"{spec.axis}: {why} budget exhausted at mu={mu:.3g} after {budget.used} "
                           "expansions; best-effort layout")
    elif relaxed is not None:
        diagnostics.append(f"{spec.axis}: the candidates aligned within mu={mu / options.growth:.3g} leave no "
                           "common size per symbol (pins and bands); best-effort layout")
    else:
        diagnostics.append(f"{spec.axis}: no alignment within mu={mu / options.growth:.3g}; best-effort layout")
    diagnostics += _prealignment_notes(spec, prealigner)
    if relaxed is not None:
        yield replace(relaxed, diagnostics=(*relaxed.diagnostics, *diagnostics[relaxed_at:]))
        return
    late = False
    if fallback is None:
        *fallback, late = _any_candidate(ruleset, spec, diagnostics)
    candidate, mu_c = fallback
    matrices = align_candidate(candidate, spec, mu_c, budget, greedy=True)
    for m in matrices:
        diagnostics += [f"{spec.axis}/{m.group}: {v}" for v in m.alignment.violations]
    solution = _sized(ruleset, spec, candidate, matrices, mu_c, "best-effort", budget, bands, floor_lines,
                      diagnostics)
    yield replace(solution, timed_out=True) if late else solution


def _placement(solution: DirectionSolution) -> tuple:
    """What a direction solution places: every row's letters and their bounds (to the micrometre)."""
    return tuple((key, tuple((seg.letter.symbol if seg.letter else None, round(seg.s, 6), round(seg.t, 6))
                             for seg in segments))
                 for key, segments in sorted(solution.sizing.segments.items()))


def solve_direction(ruleset: Ruleset, spec: DirectionSpec, budget: Budget,
                    bands: Callable[[Candidate], Bands] | None = None,
                    floor_lines: Sequence[float] = ()) -> DirectionSolution:
    """The first of :func:`direction_solutions`."""
    return next(direction_solutions(ruleset, spec, budget, bands, floor_lines))


def _prealignment_notes(spec: DirectionSpec, prealigner: Prealigner | None) -> list[str]:
    if prealigner is None or not (prealigner.restricted or prealigner.failed):
        return []
    return [f"{spec.axis}: prealignment restricted {prealigner.restricted} matrix searches, "
            f"{prealigner.fallbacks} found nothing and were searched unrestricted; "
            f"{prealigner.failed} control alignments failed"]


def _any_candidate(ruleset: Ruleset, spec: DirectionSpec, diagnostics: list[str]
                   ) -> tuple[Candidate, float, bool]:
    """A candidate when none fits Eq. 7 within the rounds: a very loose tolerance, then without floor binding.
    The flag tells whether an attempt was cut by the CPU-time limit."""
    big = 10.0 * spec.canvas + 1.0
    late = False
    for attempt in (spec, replace(spec, floor_pattern=None)):
        budget = Budget(ruleset.options.expansions, time.process_time() + max(ruleset.options.time, 0.5))
        for candidate in CandidateGenerator(ruleset, attempt, big, budget):
            if attempt.floor_pattern is None and spec.floor_pattern is not None:
                diagnostics.append(f"floor pattern {spec.floor_pattern!r} has no word with "
                                   f"{len(spec.floor_heights)} letters; floors are not bound")
            diagnostics.append(f"{spec.axis}: candidate taken at tolerance {big:.3g}")
            return candidate, big, late or budget.timed_out
        late |= budget.timed_out
    names = ", ".join(dict.fromkeys(r.pattern for r in spec.rows))
    raise RulesetError(f"patterns {names} produce no word of size up to {big:.3g} in direction {spec.axis}",
                       where=ruleset.source, plugin="layers",
                       hint="check counters' ranges and symbol sizes against the canvas")


def _sized(ruleset: Ruleset, spec: DirectionSpec, candidate: Candidate, matrices: tuple[Matrix, ...], mu: float,
           status: str, budget: Budget, bands: Callable[[Candidate], Bands] | None, floor_lines: Sequence[float],
           diagnostics: list[str]) -> DirectionSolution:
    pins = {}
    band_map = {k: dict(v) for k, v in bands(candidate).items()} if bands is not None else {}
    storey_bands: dict = {}
    if spec.floor_pattern is not None:
        for r in spec.rows:
            word = candidate.words[r.pattern]
            storeys = spec.storey_letters(word)
            if r.pattern != spec.floor_pattern or len(storeys) != len(floor_lines) - 1:
                continue
            floors = list(zip(floor_lines[:-1], floor_lines[1:]))
            if spec.storeys:    # storey letters stay inside their floor, other letters (ledges) are free
                storey_bands.setdefault((r.group, r.pattern), {}).update(zip(storeys, floors))
            else:
                pins[(r.group, r.pattern)] = floors
    ranges = {s.name: (s.least, s.most) for s in ruleset.symbols.values() if (s.least, s.most) != (None, None)}
    sizing = size_matrices(matrices, spec.canvas, pins, _merge(band_map, storey_bands), ranges)
    if sizing.success and spec.axis == "y" and floor_lines and bands is not None:
        extra = _floor_bands(sizing, band_map, floor_lines)
        if extra:
            sizing = size_matrices(matrices, spec.canvas, pins, _merge(extra, storey_bands), ranges)
    if not sizing.success:
        raise RulesetError(f"sizing failed in direction {spec.axis}: {sizing.message}", where=ruleset.source,
                           plugin="layers")
    diagnostics += [f"{spec.axis}: {r}" for r in sizing.relaxed]
    return DirectionSolution(spec.axis, spec.canvas, mu, status, candidate, matrices, sizing, budget.used,
                             tuple(diagnostics), budget.timed_out)


def _merge(a: Bands, b: Bands) -> dict:
    out = {k: dict(v) for k, v in a.items()}
    for k, v in b.items():
        out.setdefault(k, {}).update(v)
    return out


def _floor_bands(sizing: Sizing, wanted: Bands, lines: Sequence[float]) -> dict | None:
    """Keep letters that make openings inside the floor holding their centre (second pass, only if needed)."""
    lines_arr = np.asarray(lines)
    out: dict = {}
    straddle = False
    for key, letters in wanted.items():
        out[key] = {}
        for seg in sizing.segments.get(key, ()):
            if seg.index in letters:
                k = int(np.clip(np.searchsorted(lines_arr, 0.5 * (seg.s + seg.t), side="right") - 1, 0,
                                len(lines) - 2))
                out[key][seg.index] = (float(lines[k]), float(lines[k + 1]))
                straddle |= seg.s < lines[k] - 1e-9 or seg.t > lines[k + 1] + 1e-9
    return out if straddle else None


def axis_solutions(ruleset: Ruleset, axis: str, extent: float, floor_lines: Sequence[float] = (),
                   entrance: bool = False, bands: Callable[[Candidate], Bands] | None = None
                   ) -> Iterator[DirectionSolution]:
    """:func:`direction_solutions` of one direction of a canvas side ``extent`` (floor lines bind the vertical
    direction only)."""
    counters: dict[str, Counter] = dict(ruleset.counters)
    counters["entrance"] = Counter("entrance", int(entrance), int(entrance))
    options = ruleset.options
    heights = tuple(np.diff(np.asarray(floor_lines, dtype=float))) if axis == "y" and len(floor_lines) > 1 else ()
    budget = Budget(options.expansions, time.process_time() + options.time / 2)
    return direction_solutions(ruleset, direction_spec(ruleset, axis, extent, counters, heights), budget, bands,
                               floor_lines if axis == "y" else ())


def solve_axis(ruleset: Ruleset, axis: str, extent: float, floor_lines: Sequence[float] = (),
               entrance: bool = False, bands: Callable[[Candidate], Bands] | None = None) -> DirectionSolution:
    """The first solution of :func:`axis_solutions`."""
    return next(axis_solutions(ruleset, axis, extent, floor_lines, entrance, bands))


def solve(ruleset: Ruleset, width: float, height: float, floor_lines: Sequence[float] = (),
          entrance: bool = False, corner_widths: tuple[float, float] = (0.0, 0.0),
          x_bands: Callable[[Candidate], Bands] | None = None,
          y_bands: Callable[[Candidate], Bands] | None = None) -> tuple[DirectionSolution, DirectionSolution]:
    """Solve both directions for a canvas ``width x height`` (the outer product is built by ``compose``)."""
    return (solve_axis(ruleset, "x", width, (), entrance, x_bands),
            solve_axis(ruleset, "y", height, floor_lines, entrance, y_bands))


__all__ = ["Alignment", "DirectionSolution", "axis_solutions", "direction_solutions", "solve", "solve_axis",
           "solve_direction"]
