"""Words of a pattern (§3.2--3.4): expansion of alternation, concatenation, counting and substitution."""
from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from citygen_layers.model import Alt, Counter, Node, Pattern, Rep, Seq, Sym, Symbol


@dataclass(frozen=True, slots=True)
class Letter:
    """One occurrence of a symbol in a word. ``size`` is the preferred size, or the sampled size of an unsized
    symbol (§5.1); ``transparent`` comes from the symbol or from being an unsubstituted control letter (§3.4)."""

    symbol: str
    size: float
    transparent: bool = False
    opaque: bool = False
    attached: bool = False
    unoccludable: bool = False
    unsized: bool = False
    mirrored: bool = False

    @property
    def name(self) -> str:
        return self.symbol + ("'" if self.mirrored else "")


#: A raw letter before sizing: (symbol, mirrored, transparent).
Raw = tuple[str, bool, bool]


def count_value(rep: Rep, env: Mapping[str, int]) -> int:
    k = rep.count if isinstance(rep.count, int) else env[rep.count]
    return -k if rep.negate else k


def expand(node: Node, env: Mapping[str, int], leaf: Callable[[str], list[tuple[Raw, ...]]]) -> list[tuple[Raw, ...]]:
    """All words of ``node`` under counter values ``env``, alternations in lexicographic order.

    A repeated body takes one alternative for all its repetitions; a negative count repeats the reflected
    base (reversed, letters mirrored); a zero count yields the empty word.
    """
    if isinstance(node, Sym):
        return leaf(node.name)
    if isinstance(node, Seq):
        parts = [expand(item, env, leaf) for item in node.items]
        return [tuple(itertools.chain.from_iterable(combo)) for combo in itertools.product(*parts)]
    if isinstance(node, Alt):
        return [word for option in node.options for word in expand(option, env, leaf)]
    k = count_value(node, env)
    words = expand(node.body, env, leaf)
    if k < 0:
        words = [tuple((s, not m, t) for s, m, t in reversed(w)) for w in words]
    return list(dict.fromkeys(w * abs(k) for w in words))


def pattern_words(pattern: Pattern, env: Mapping[str, int], symbols: Mapping[str, Symbol]) -> list[tuple[Raw, ...]]:
    """Raw words of a (substituted) pattern: all instances of a substituted letter take one content word."""
    if not pattern.substituted:
        return expand(pattern.control, env, lambda name: [((name, False, symbols[name].transparent),)])
    subs = list(pattern.substitutions)
    contents = [expand(pattern.substitutions[name], env,
                       lambda s: [((s, False, symbols[s].transparent),)]) for name in subs]
    out: list[tuple[Raw, ...]] = []
    for choice in itertools.product(*contents):
        table = dict(zip(subs, choice))

        def leaf(name: str) -> list[tuple[Raw, ...]]:
            if name in table:
                return [table[name]]
            return [((name, False, True),)]

        for word in expand(pattern.control, env, leaf):
            out.append(word)
    return list(dict.fromkeys(out))


def control_words(pattern: Pattern, env: Mapping[str, int], symbols: Mapping[str, Symbol]
                  ) -> dict[tuple[Raw, ...], tuple[tuple[Raw, ...], tuple[int, ...]]]:
    """Per raw word of a substituted pattern (as ``pattern_words`` gives them): its control word and the word
    position where every control letter starts (plus the word's end). The first derivation of a word is kept."""
    subs = list(pattern.substitutions)
    contents = [expand(pattern.substitutions[name], env,
                       lambda s: [((s, False, symbols[s].transparent),)]) for name in subs]
    controls = expand(pattern.control, env, lambda name: [((name, False, name not in pattern.substitutions),)])
    out: dict[tuple[Raw, ...], tuple[tuple[Raw, ...], tuple[int, ...]]] = {}
    for choice in itertools.product(*contents):
        table = dict(zip(subs, choice))
        for control in controls:
            word: list[Raw] = []
            starts = []
            for name, mirrored, transparent in control:
                starts.append(len(word))
                if name not in table:
                    word.append((name, mirrored, transparent))
                elif mirrored:   # a reflected substituted letter is its reflected content
                    word.extend((s, not m, t) for s, m, t in reversed(table[name]))
                else:
                    word.extend(table[name])
            out.setdefault(tuple(word), (control, (*starts, len(word))))
    return out


def counters_of(node: Node) -> set[str]:
    if isinstance(node, Sym):
        return set()
    if isinstance(node, Rep):
        own = {node.count} if isinstance(node.count, str) else set()
        return own | counters_of(node.body)
    children = node.items if isinstance(node, Seq) else node.options
    return set().union(*(counters_of(c) for c in children))


def pattern_counters(pattern: Pattern) -> set[str]:
    return counters_of(pattern.control).union(*(counters_of(c) for c in pattern.substitutions.values()))


def min_measure(pattern: Pattern, fixed: Mapping[str, int], counters: Mapping[str, Counter],
                measure: Callable[[str], float]) -> float:
    """A lower bound of ``sum(measure(letter))`` over the pattern's words when ``fixed`` counters are set and
    the others free (used to bound unbounded counters, Eq. 7)."""

    def smallest(name: str) -> int:
        c = counters[name]
        if c.lo <= 0 and (c.hi is None or c.hi >= 0):
            return 0
        return min(abs(c.lo), abs(c.hi if c.hi is not None else c.lo))

    def walk(node: Node) -> float:
        if isinstance(node, Sym):
            if node.name in pattern.substitutions:
                return walk(pattern.substitutions[node.name])
            return measure(node.name)
        if isinstance(node, Seq):
            return sum(walk(i) for i in node.items)
        if isinstance(node, Alt):
            return min(walk(o) for o in node.options)
        if isinstance(node.count, int):
            k = abs(node.count)
        else:
            k = abs(fixed[node.count]) if node.count in fixed else smallest(node.count)
        return k * walk(node.body)

    try:
        return walk(pattern.control)
    finally:
        del walk    # the recursive closure refers to itself: break the cycle so it is freed at once
