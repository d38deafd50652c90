"""Sequence generators of bao2013 §5.2: replication, repetition and two-shuffle.

Each returns sequences (tuples of items, an item being a frozenset of symbols or the ⊢/⊣ token) that are added
to a composite region's sequence constraints.

The repetition generator takes a pattern with ``?`` (optional), ``*`` (zero or more) and ``+`` (one or more)
on items and parenthesised groups. It builds the pattern's position automaton (Glushkov) and cuts it at *pivot*
positions -- positions whose item shares no symbol with any other position, so reaching one fixes the automaton
state. The emitted sequences are the paths from ⊢ or a pivot to the next pivot or ⊣; adjacent instantiations
overlap in the pivot, so the covered arrangements are exactly the pattern's language (the paper's Fig. 7
outputs: ``⊢CD, ⊢D, DC⊣, D⊣`` for ``C? D C?``). A loop without a pivot falls back to the pattern's bigrams, a
superset of its language.
"""
from __future__ import annotations

from dataclasses import dataclass

from citygen_relayout.model import BEGIN, END, Item

Sequence = tuple[Item, ...]


def replication(arrangement: tuple[Item, ...], bounded: bool = True) -> list[Sequence]:
    """The input arrangement (or a selected sub-sequence) as one valid sequence, with ⊢ ⊣ when ``bounded``."""
    seq = tuple(arrangement)
    if bounded:
        seq = (frozenset({BEGIN}), *seq, frozenset({END}))
    return [seq]


def two_shuffle(items: tuple[Item, ...]) -> list[Sequence]:
    """All distinct length-two sub-sequences of ``items`` and their reversals."""
    out: list[Sequence] = []
    for a, b in zip(items, items[1:]):
        for pair in ((a, b), (b, a)):
            if pair not in out:
                out.append(pair)
    return out


@dataclass(frozen=True)
class Node:
    """Repetition pattern AST: ``op`` is 'item', 'seq', '?', '*' or '+'."""

    op: str
    item: Item | None = None
    parts: tuple[Node, ...] = ()


def repetition(pattern: Node) -> list[Sequence]:
    """Sequences whose overlapping instantiations cover exactly the language of ``pattern`` (see module doc)."""
    items: list[Item] = []
    follow: dict[int, set[int]] = {}
    nullable, first, last = _glushkov(pattern, items, follow)
    start, stop = -1, -2
    follow[start] = set(first)
    for p in last:
        follow.setdefault(p, set()).add(stop)
    if nullable:
        follow[start].add(stop)
    label = {start: frozenset({BEGIN}), stop: frozenset({END}), **dict(enumerate(items))}
    pivots = {p for p, it in enumerate(items) if all(not (it & o) for q, o in enumerate(items) if q != p)}
    out: list[Sequence] = []
    for origin in [start, *sorted(pivots)]:
        if not _paths(origin, follow, pivots, label, out):
            return _bigrams(follow, label)
    return out


def _paths(origin: int, follow: dict[int, set[int]], pivots: set[int], label: dict[int, Item],
           out: list[Sequence]) -> bool:
    """Append every path origin -> next pivot/⊣; False when a pivot-free loop makes them infinite."""
    stack = [(origin, (origin,))]
    while stack:
        pos, path = stack.pop()
        for nxt in sorted(follow.get(pos, ())):
            if nxt == -2 or nxt in pivots:
                seq = tuple(label[p] for p in (*path, nxt))
                if seq not in out:
                    out.append(seq)
            elif nxt in path:
                return False
            else:
                stack.append((nxt, (*path, nxt)))
    return True


def _bigrams(follow: dict[int, set[int]], label: dict[int, Item]) -> list[Sequence]:
    out: list[Sequence] = []
    for p, nxts in follow.items():
        for q in nxts:
            pair = (label[p], label[q])
            if pair not in out:
                out.append(pair)
    return out


def _glushkov(node: Node, items: list[Item], follow: dict[int, set[int]]) -> tuple[bool, set[int], set[int]]:
    """(nullable, first, last) of ``node``; fills ``items`` (positions) and ``follow``."""
    if node.op == "item":
        items.append(node.item)
        p = len(items) - 1
        return False, {p}, {p}
    if node.op == "seq":
        nullable, first, last = True, set(), set()
        for part in node.parts:
            n2, f2, l2 = _glushkov(part, items, follow)
            for p in last:
                follow.setdefault(p, set()).update(f2)
            if nullable:
                first |= f2
            last = (last | l2) if n2 else l2
            nullable = nullable and n2
        return nullable, first, last
    inner_nullable, first, last = _glushkov(node.parts[0], items, follow)
    if node.op in "*+":
        for p in last:
            follow.setdefault(p, set()).update(first)
    return (node.op in "?*") or inner_nullable, first, last
