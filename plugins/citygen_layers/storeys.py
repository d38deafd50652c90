"""Substituted storeys stay in their storey (§3.3 with the floor lines): when a word's control word has one letter
per letter of the floor word, control letter *i* stands for floor word letter *i*; where that letter is a storey,
the content substituted for control letter *i* must lie inside that storey's floor. A sizing that puts a
substituted letter across a floor line (its alignment took a sill or head band into the next storey's column) does
not solve the candidate."""
from __future__ import annotations

from collections.abc import Sequence

from citygen_layers.candidates import Candidate, DirectionSpec
from citygen_layers.model import Ruleset
from citygen_layers.sizing import Sizing
from citygen_layers.words import control_words

#: metres a substituted letter may reach over its floor's lines (rounding of the sizing)
SLACK = 1e-6


class StoreyCheck:
    """Finds substituted letters placed outside the floor of their control letter; memoises control words."""

    def __init__(self, ruleset: Ruleset) -> None:
        self.ruleset = ruleset
        self._tables: dict[tuple, dict] = {}

    def _substituted(self, pattern_name: str, env, word) -> tuple[int, list[tuple[int, int, int]]]:
        """The control word's length and ``(control index, first, end)`` word positions of every substituted
        control letter (length 0 when the word has no recorded derivation)."""
        key = (pattern_name, tuple(sorted(env.items())))
        table = self._tables.get(key)
        if table is None:
            table = self._tables[key] = control_words(self.ruleset.patterns[pattern_name], env, self.ruleset.symbols)
        found = table.get(tuple((x.symbol, x.mirrored, x.transparent) for x in word))
        if found is None:
            return 0, []
        control, starts = found
        return len(control), [(i, a, b) for i, ((_, _, unsubstituted), a, b)
                              in enumerate(zip(control, starts, starts[1:])) if not unsubstituted]

    def straddling(self, spec: DirectionSpec, candidate: Candidate, sizing: Sizing,
                   floor_lines: Sequence[float]) -> list[str]:
        """Descriptions of the substituted letters that leave their storey (empty: every storey keeps its own)."""
        floor_word = candidate.words[spec.floor_pattern]
        storeys = spec.storey_letters(floor_word)
        if len(storeys) != len(floor_lines) - 1:
            return []
        floor_of = {i: k for k, i in enumerate(storeys)}
        out = []
        for row in spec.rows:
            if not self.ruleset.patterns[row.pattern].substituted:
                continue
            length, spans = self._substituted(row.pattern, candidate.env, candidate.words[row.pattern])
            if length != len(floor_word):
                continue
            segments = sizing.segments.get((row.group, row.pattern), ())
            for i, first, end in spans:
                floor = floor_of.get(i)
                if floor is None:     # content in a ledge's place: free, as the ledge is
                    continue
                low, high = floor_lines[floor], floor_lines[floor + 1]
                for seg in segments:
                    if first <= seg.index < end and seg.letter is not None and not seg.letter.transparent and \
                            seg.t > seg.s and (seg.s < low - SLACK or seg.t > high + SLACK):
                        out.append(f"{row.pattern}: {seg.letter.symbol} at {seg.s:.2f}-{seg.t:.2f} m leaves "
                                   f"floor {floor} ({low:.2f}-{high:.2f} m)")
        return out


__all__ = ["StoreyCheck"]
