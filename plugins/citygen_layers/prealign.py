"""Prealignment of the control patterns (§5.2, "Heuristics and Optimizations"): a heuristic, off by default.

Substituted patterns often share a control pattern, and control words are much shorter than the words after the
substitution. The control words of an alignment group are aligned first -- once per distinct tuple of control
words, shared by every candidate whose words derive from them -- and the words are then aligned with the search
restricted to the prealigned columns: the letters that replace one control letter stay inside that control
letter's column, and Phi is evaluated only for edges inside a prealigned column. The restriction can select
another alignment than the exact search, or none (the caller then searches without it).
"""
from __future__ import annotations

import bisect
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from citygen_layers.align import Alignment, Budget, align
from citygen_layers.model import Ruleset
from citygen_layers.splits import split_transparent
from citygen_layers.words import Letter, control_words, pattern_counters


@dataclass(frozen=True)
class Control:
    """The control word of a word (a substituted letter becomes one letter of its content's size) and the word
    position where each control letter starts, plus the word's end."""

    word: tuple[Letter, ...]
    starts: tuple[int, ...]


def _collapse(name: str, letters: Sequence[Letter]) -> Letter:
    """A substituted control letter: its content's size, opaque if any content letter is (so a prealigned column
    may hold the opaque entry the full words put in it), attached if its content starts or ends attached."""
    return Letter(name, sum(x.size for x in letters), all(x.transparent for x in letters),
                  any(x.opaque for x in letters), letters[0].attached or letters[-1].attached)


@dataclass
class Prealigner:
    """Control words and prealignments of one direction's solve, with counts for its diagnostics."""

    ruleset: Ruleset
    derivations: dict[tuple, dict] = field(default_factory=dict)
    aligned: dict[tuple, tuple[Alignment, tuple[tuple[int, ...], ...]] | None] = field(default_factory=dict)
    restricted: int = 0      # matrices searched inside prealigned columns
    failed: int = 0          # control words without an alignment within mu
    fallbacks: int = 0       # restricted searches that found nothing, followed by the unrestricted search

    def control(self, pattern_name: str, env: Mapping[str, int], word: tuple[Letter, ...]) -> Control:
        """The control word of ``word``, a word of pattern ``pattern_name`` under counter values ``env``."""
        pattern = self.ruleset.patterns[pattern_name]
        plain = Control(word, tuple(range(len(word) + 1)))
        if not pattern.substituted:
            return plain
        own = pattern_counters(pattern)
        key = (pattern_name, tuple(sorted((k, v) for k, v in env.items() if k in own)))
        table = self.derivations.get(key)
        if table is None:
            table = self.derivations[key] = control_words(pattern, env, self.ruleset.symbols)
        found = table.get(tuple((x.symbol, x.mirrored, x.transparent) for x in word))
        if found is None:
            return plain
        letters, starts = [], []
        for (name, _, unsubstituted), a, b in zip(found[0], found[1], found[1][1:]):
            if a < b:    # a substituted letter with empty content has no column of its own
                letters.append(word[a] if unsubstituted else _collapse(name, word[a:b]))
                starts.append(a)
        return Control(tuple(letters), (*starts, len(word)))

    def fence(self, patterns: Sequence[str], env: Mapping[str, int], words: Sequence[tuple[Letter, ...]],
              split: Sequence[tuple[Letter, ...]], parents: Sequence[tuple[int, ...]], above: np.ndarray,
              canvas: float, mu: float, budget: Budget) -> list[tuple[int, ...]] | None:
        """Ends of the prealigned columns in the positions of the (split) words, or None when there is nothing
        to restrict (no control word is shorter than its word, or the prealignment has one column) or the
        control words have no alignment within ``mu``."""
        controls = [self.control(p, env, w) for p, w in zip(patterns, words)]
        if all(len(c.word) == len(w) for c, w in zip(controls, words)):
            return None
        cwords = tuple(c.word for c in controls)
        key = (cwords, above.tobytes(), canvas, mu)
        if key not in self.aligned:
            csplit, cparents = cwords, tuple(tuple(range(len(w))) for w in cwords)
            if any(x.transparent for w in cwords for x in w):
                csplit, cparents = split_transparent(cwords, canvas)
                csplit, cparents = tuple(csplit), tuple(cparents)
            result = align(csplit, above, canvas, mu, budget, cparents)
            self.aligned[key] = None if result is None else (result, cparents)
        found = self.aligned[key]
        if found is None:
            self.failed += 1
            return None
        alignment, cparents = found
        ends = []
        for col in alignment.columns[:-1]:
            cut = [b for _, b in col]
            if any(0 < q < len(cp) and cp[q - 1] == cp[q] for q, cp in zip(cut, cparents)):
                continue   # inside a split control letter: not a boundary of the full words
            ends.append(tuple(
                bisect.bisect_left(parents[r], c.starts[cparents[r][q] if q < len(cparents[r]) else len(c.word)])
                for r, (q, c) in enumerate(zip(cut, controls))))
        if not ends:
            return None
        return [*ends, tuple(len(w) for w in split)]


__all__ = ["Control", "Prealigner"]
