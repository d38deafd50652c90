"""Candidate generation (§5.1): enumeration, pruning by canvas size (Eq. 7) and sampling of unsized symbols."""
from __future__ import annotations

import itertools
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from citygen_layers.model import Counter, Ruleset
from citygen_layers.words import Letter, Raw, min_measure, pattern_counters, pattern_words

HARD_COUNT_LIMIT = 64


@dataclass(frozen=True)
class Row:
    """One row of an alignment matrix: the word of a pattern shared by the layers ``layers`` (stack indices)."""

    pattern: str
    layers: tuple[int, ...]
    group: str


@dataclass(frozen=True)
class Candidate:
    """Counter values and one word per pattern (§5.1): a tuple of words, one per layer."""

    env: Mapping[str, int]
    words: Mapping[str, tuple[Letter, ...]]


@dataclass(frozen=True)
class DirectionSpec:
    """What one direction's solve needs: canvas size, rows, and the pattern bound to floor heights (if any)."""

    axis: str
    canvas: float
    rows: tuple[Row, ...]
    counters: Mapping[str, Counter]
    floor_pattern: str | None = None
    floor_heights: tuple[float, ...] = ()
    storeys: frozenset[str] = frozenset()

    def storey_letters(self, word: tuple[Letter, ...]) -> list[int]:
        """Indices of the letters of the floor word that are storeys (one per floor line interval)."""
        return [i for i, x in enumerate(word) if not self.storeys or x.symbol in self.storeys]


def direction_spec(ruleset: Ruleset, axis: str, canvas: float, counters: Mapping[str, Counter],
                   floor_heights: Sequence[float] = ()) -> DirectionSpec:
    """Rows per alignment group, uppermost first (the paper's i = 1), patterns shared by layers merged."""
    merged: dict[tuple[str, str], list[int]] = {}
    for index, layer in enumerate(ruleset.layers):
        pattern = layer.x if axis == "x" else layer.y
        group = layer.groups[0 if axis == "x" else 1]
        merged.setdefault((group, pattern), []).append(index)
    rows = sorted((Row(p, tuple(idx), g) for (g, p), idx in merged.items()), key=lambda r: -max(r.layers))
    floor_pattern = None
    if axis == "y" and ruleset.floors is not None and floor_heights:
        floor_pattern = ruleset.layer(ruleset.floors).y
    return DirectionSpec(axis, canvas, tuple(rows), counters, floor_pattern, tuple(floor_heights),
                         ruleset.storeys)


def make_letter(raw: Raw, size: float | None, ruleset: Ruleset) -> Letter:
    name, mirrored, transparent = raw
    sym = ruleset.symbols.get(name)
    if sym is None:
        return Letter(name, float(size or 0.0), True, unsized=True, mirrored=mirrored)
    transparent = transparent or sym.transparent
    return Letter(name, float(size if size is not None else (sym.size or 0.0)), transparent,
                  sym.opaque and not transparent, sym.attached, sym.unoccludable, sym.size is None, mirrored)


def sample_sizes(lo: float, hi: float, step: float, count: int) -> list[float]:
    """Uniform samples (multiples of ``step``) of an unsized symbol's size in ``[lo, hi]``, positive, nearest the
    interval's centre first (ties: larger first); the midpoint when no multiple falls inside (§5.1, Fig. 7)."""
    lo = max(lo, 0.0)
    if hi < lo - 1e-12:
        return []
    grid = np.arange(np.ceil(lo / step - 1e-9), np.floor(hi / step + 1e-9) + 1) * step if step > 0 else np.zeros(0)
    grid = grid[grid > 1e-12]
    if grid.size == 0:
        return [0.5 * (lo + hi)]
    centre = 0.5 * (lo + hi)
    order = sorted(grid.tolist(), key=lambda v: (round(abs(v - centre), 9), -v))
    return order[:count]


@dataclass
class WordMemo:
    """What the candidate generators of one direction's solve share across tolerance rounds (none of it depends
    on mu): raw words per pattern and counter values, letters per raw letter and size, the lower bounds of
    pattern measures per counter value that bound unbounded counters, and each pattern's counters."""

    raw: dict[tuple, list[tuple[Raw, ...]]] = field(default_factory=dict)
    letters: dict[tuple[Raw, float | None], Letter] = field(default_factory=dict)
    measures: dict[tuple[str, str, int], float] = field(default_factory=dict)
    counters: dict[str, frozenset[str]] = field(default_factory=dict)


class CandidateGenerator:
    """Lazily yields candidates for one direction at tolerance ``mu`` in lexicographic counter order."""

    def __init__(self, ruleset: Ruleset, spec: DirectionSpec, mu: float, budget=None,
                 memo: WordMemo | None = None) -> None:
        self.ruleset, self.spec, self.mu = ruleset, spec, mu
        self.budget = budget      # an align.Budget: every counter assignment examined costs one unit
        self.patterns = list(dict.fromkeys(r.pattern for r in spec.rows))
        self._memo = memo if memo is not None else WordMemo()
        known = self._memo.counters
        for p in self.patterns:
            if p not in known:
                known[p] = frozenset(pattern_counters(ruleset.patterns[p]))
        self._own = {p: known[p] for p in self.patterns}
        self.counter_names = sorted(set().union(*self._own.values()))
        self._raw_cache = self._memo.raw
        self._letters = self._memo.letters
        self._sized_cache: dict[tuple, list[tuple[Letter, ...]]] = {}
        self._pinned: dict[str, float] = {}

    # counters ------------------------------------------------------------------------------------------------
    def counter_range(self, name: str) -> range:
        counter = self.spec.counters[name]
        if counter.hi is not None and counter.hi - counter.lo <= HARD_COUNT_LIMIT:
            return range(counter.lo, counter.hi + 1)
        limit = HARD_COUNT_LIMIT
        users = [p for p in self.patterns if name in self._own[p]]
        for k in range(max(counter.lo, 0), HARD_COUNT_LIMIT + 1):
            over = False
            for p in users:
                if p == self.spec.floor_pattern:
                    over |= self._measure(p, name, k) > len(self.spec.floor_heights)
                else:
                    over |= self._measure(p, name, k) > self.spec.canvas + self.mu
            if over:
                limit = k - 1
                break
        lo = max(counter.lo, -limit)
        hi = limit if counter.hi is None else min(counter.hi, limit)
        return range(lo, max(hi, lo - 1) + 1)

    def _measure(self, pattern: str, name: str, k: int) -> float:
        """Lower bound of the pattern's size (of its storey count for the floor pattern) with counter ``name``
        at ``k`` and the other counters free."""
        key = (pattern, name, k)
        value = self._memo.measures.get(key)
        if value is None:
            if pattern == self.spec.floor_pattern:
                storey = self.spec.storeys
                value = min_measure(self.ruleset.patterns[pattern], {name: k}, self.spec.counters,
                                    lambda s: 1.0 if not storey or s in storey else 0.0)
            else:
                value = min_measure(self.ruleset.patterns[pattern], {name: k}, self.spec.counters, self._size_of)
            self._memo.measures[key] = value
        return value

    def _size_of(self, name: str) -> float:
        sym = self.ruleset.symbols.get(name)
        return float(sym.size) if sym is not None and sym.size is not None else 0.0

    # words ---------------------------------------------------------------------------------------------------
    def _raw_key(self, pattern: str, env: Mapping[str, int]) -> tuple:
        own = self._own.get(pattern)
        if own is None:
            own = pattern_counters(self.ruleset.patterns[pattern])
        return pattern, tuple(sorted((k, v) for k, v in env.items() if k in own))

    def raw_words(self, pattern: str, env: Mapping[str, int]) -> list[tuple[Raw, ...]]:
        key = self._raw_key(pattern, env)
        if key not in self._raw_cache:
            self._raw_cache[key] = pattern_words(self.ruleset.patterns[pattern], env, self.ruleset.symbols)
        return self._raw_cache[key]

    def _words(self, pattern: str, env: Mapping[str, int], lo: float) -> list[tuple[Letter, ...]]:
        """``sized_words`` of the pattern's raw words under ``env``, memoised (many counter assignments share
        them: only the pattern's own counters, ``lo`` and the pinned sizes matter)."""
        key = (self._raw_key(pattern, env), lo, tuple(sorted(self._pinned.items())))
        words = self._sized_cache.get(key)
        if words is None:
            words = self._sized_cache[key] = self.sized_words(pattern, self.raw_words(pattern, env), lo)
        return words

    def _letter(self, raw: Raw, size: float | None) -> Letter:
        letter = self._letters.get((raw, size))
        if letter is None:
            letter = self._letters[(raw, size)] = make_letter(raw, size, self.ruleset)
        return letter

    def sized_words(self, pattern: str, raws: list[tuple[Raw, ...]], lo: float) -> list[tuple[Letter, ...]]:
        """Words of ``pattern`` whose size respects Eq. 7 (``lo <= |w| <= canvas + mu``), unsized symbols sampled;
        the floor pattern instead must have one letter per floor, sized to the floor heights. Alternation choices
        keep their lexicographic order (§5.1: the first alternative is the designer's first choice); the samples
        of one choice come nearest the canvas first."""
        hi = self.spec.canvas + self.mu
        out: list[tuple[int, tuple[Letter, ...]]] = []      # (index of the raw word: its choices, word)
        for index, raw in enumerate(raws):
            letters = [self._letter(r, self._pinned.get(r[0]) if pattern != self.spec.floor_pattern else None)
                       for r in raw]
            if pattern == self.spec.floor_pattern:
                if len(self.spec.storey_letters(tuple(letters))) != len(self.spec.floor_heights):
                    continue
                if not self.spec.storeys:   # every letter is a storey: sized to the floor heights, pinned
                    out.append((index, tuple(self._letter(r, h) for r, h in zip(raw, self.spec.floor_heights))))
                    continue
            unsized = [i for i, letter in enumerate(letters) if letter.unsized]
            total = sum(letter.size for letter in letters)
            if not unsized:
                if lo - 1e-9 <= total <= hi + 1e-9:
                    out.append((index, tuple(letters)))
                continue
            n = len(unsized)
            for size in sample_sizes((lo - total) / n, (hi - total) / n, self.mu, self.ruleset.options.samples):
                word = list(letters)
                for i in unsized:
                    word[i] = self._letter(raw[i], size)
                out.append((index, tuple(word)))
        out.sort(key=lambda e: (e[0], abs(sum(letter.size for letter in e[1]) - self.spec.canvas)))
        return [word for _, word in out]

    def opaque_size(self, word: tuple[Letter, ...]) -> float:
        return sum(letter.size for letter in word if letter.opaque)

    def lower_bound(self, row_index: int, words: Mapping[str, tuple[Letter, ...]] | None) -> float:
        """Eq. 7 lower bound l_i: upper layers of the same group may make space for their opaque symbols."""
        row = self.spec.rows[row_index]
        slack = 0.0
        for upper in self.spec.rows[:row_index]:
            if upper.group != row.group or min(upper.layers) <= max(row.layers):
                continue
            if words is None:
                slack += max((self.opaque_size(w) for w in self._loose.get(upper.pattern, [])), default=0.0)
            else:
                slack += self.opaque_size(words[upper.pattern])
        return self.spec.canvas - self.mu - slack

    def __iter__(self) -> Iterator[Candidate]:
        ranges = [self.counter_range(name) for name in self.counter_names]
        for values in itertools.product(*ranges):
            if self.budget is not None and not self.budget.spend():
                return
            env = dict(zip(self.counter_names, values))
            self._loose: dict[str, list[tuple[Letter, ...]]] = {}
            self._pinned = self._pinned_sizes(env)
            lists = {}
            for index, row in enumerate(self.spec.rows):   # uppermost first, so slack uses known words
                if row.pattern in lists:
                    continue
                lo = self.lower_bound(index, None)
                words = self._words(row.pattern, env, lo)
                if not words:
                    break
                self._loose[row.pattern] = words
                lists[row.pattern] = words
            if len(lists) < len(self.patterns):
                continue
            for count, combo in enumerate(itertools.product(*(lists[p] for p in self.patterns))):
                if count % 64 == 63 and self.budget is not None and not self.budget.spend():
                    return
                words = dict(zip(self.patterns, combo))
                if all(self._fits(i, words) for i in range(len(self.spec.rows))):
                    yield Candidate(env, words)

    def _pinned_sizes(self, env: Mapping[str, int]) -> dict[str, float]:
        """Symbols of a pinned floor word take their mean floor height in every other word of the candidate."""
        floor = self.spec.floor_pattern
        if floor is None or self.spec.storeys:
            return {}
        self._pinned = {}
        words = self._words(floor, env, 0.0)
        if not words:
            return {}
        heights: dict[str, list[float]] = {}
        for letter in words[0]:
            heights.setdefault(letter.symbol, []).append(letter.size)
        return {k: float(np.mean(v)) for k, v in heights.items()}

    def _fits(self, index: int, words: Mapping[str, tuple[Letter, ...]]) -> bool:
        row = self.spec.rows[index]
        if row.pattern == self.spec.floor_pattern and not self.spec.storeys:
            return True
        size = sum(letter.size for letter in words[row.pattern])
        return self.lower_bound(index, words) - 1e-9 <= size <= self.spec.canvas + self.mu + 1e-9
