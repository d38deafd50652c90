"""Sequence constraints as an incremental cover automaton (bao2013 §5.1, Fig. 4; §7.2 successor sets).

An arrangement ``⊢ A1 .. An ⊣`` is valid when a chain of sequence instantiations covers it, consecutive
instantiations overlapping in at least one subregion. The automaton state after a prefix is the set of live
partial instantiations ``(sequence, next index, anchored)``; *anchored* means the chain from ⊢ reaches the
instantiation's start. Appending an element advances every partial; a partial completing while anchored
covers the prefix (``covered``), which anchors every partial still open. A prefix is *alive* while it is
covered or an anchored partial is open. States are hashable and transitions memoised, so the automaton is
built lazily as a DFA.
"""
from __future__ import annotations

from collections.abc import Iterable

from citygen_relayout.model import BEGIN, END, Item

State = tuple[frozenset[tuple[int, int, bool]], bool]  # (partials, covered)


class CoverAutomaton:
    """Lazily determinised cover automaton of one composite region's sequences."""

    def __init__(self, sequences: Iterable[tuple[Item, ...]]) -> None:
        self.sequences = tuple(tuple(s) for s in sequences)
        self._starters: dict[str, tuple[int, ...]] = {}
        self._memo: dict[tuple[State, str], State | None] = {}
        self.start: State = (frozenset((k, 1, True) for k, s in enumerate(self.sequences)
                                       if len(s) > 1 and BEGIN in s[0]), False)

    def reversed(self) -> CoverAutomaton:
        """The automaton reading arrangements right to left (sequences reversed, ⊢ and ⊣ swapped)."""
        swap = {BEGIN: END, END: BEGIN}
        return CoverAutomaton(tuple(frozenset(swap.get(x, x) for x in item) for item in reversed(s))
                              for s in self.sequences)

    def _starting(self, symbol: str) -> tuple[int, ...]:
        found = self._starters.get(symbol)
        if found is None:
            found = tuple(k for k, s in enumerate(self.sequences)
                          if len(s) > 1 and symbol in s[0] and BEGIN not in s[0])
            self._starters[symbol] = found
        return found

    def step(self, state: State, symbol: str) -> State | None:
        """State after appending ``symbol``, or None when the prefix can no longer be covered."""
        key = (state, symbol)
        if key in self._memo:
            return self._memo[key]
        partials, _ = state
        live: set[tuple[int, int, bool]] = set()
        covered = False
        for k, i, anchored in partials:
            seq = self.sequences[k]
            if symbol in seq[i]:
                if i + 1 == len(seq):
                    covered = covered or anchored
                else:
                    live.add((k, i + 1, anchored))
        if symbol != END:
            live.update((k, 1, False) for k in self._starting(symbol))
        if covered:
            live = {(k, i, True) for k, i, _ in live}
        result: State | None = (frozenset(live), covered)
        if not covered and not any(a for _, _, a in live):
            result = None
        if symbol == END and not covered:
            result = None
        self._memo[key] = result
        return result

    def candidates(self, state: State) -> set[str]:
        """Symbols (and ⊣) that continue some live partial instantiation: the successor set S of §7.2."""
        out: set[str] = set()
        for k, i, _ in state[0]:
            out |= self.sequences[k][i]
        out.discard(BEGIN)
        return out

    def accepts(self, symbols: Iterable[str]) -> bool:
        """Whether ``⊢ symbols ⊣`` is covered."""
        state: State | None = self.start
        for sym in (*symbols, END):
            state = self.step(state, sym)
            if state is None:
                return False
        return True
