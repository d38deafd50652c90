"""Transparent splits (§5.2): letters of control patterns are invisible, so they may be cut into parts where
other words have boundaries. Done as a preprocessing step on the words of one alignment matrix."""
from __future__ import annotations

import bisect
import itertools
from collections.abc import Sequence
from dataclasses import replace

from citygen_layers.words import Letter

MIN_PIECE = 0.02


def split_transparent(words: Sequence[Sequence[Letter]], canvas: float, memo: dict | None = None
                      ) -> tuple[list[tuple[Letter, ...]], list[tuple[int, ...]]]:
    """Cut transparent letters at the (canvas-scaled) boundaries of the other words that touch a visible
    letter -- of the words without transparent letters when there are any (the structure the placeholders stand
    for); cuts closer than ``MIN_PIECE`` of the canvas to another cut or an end are dropped.

    Returns the new words and, per word, the index of the original letter each part belongs to; parts keep
    the letter's flags and take the length of their piece as size. ``memo`` (a dict kept by the caller, e.g.
    for one direction solve) keeps each word's bounds and split per canvas and cuts, by the identities of its
    letters (it keeps the letters, so the identities stay unique): candidates share most words and letters.
    """
    memo = {} if memo is None else memo
    ids = [tuple(map(id, w)) for w in words]
    bounds, touch = [], []
    for w, key in zip(words, ids):
        known = memo.get((key, canvas))
        if known is None:
            flags = [not x.transparent for x in w]
            cum = list(itertools.accumulate((x.size for x in w), initial=0.0))
            scale = canvas / cum[-1] if cum[-1] > 0 else 1.0
            known = memo[key, canvas] = ([c * scale for c in cum], [a or b for a, b in zip(flags[:-1], flags[1:])],
                                         tuple(w))
        bounds.append(known[0])
        touch.append(known[1])
    out_words: list[tuple[Letter, ...]] = []
    out_parents: list[tuple[int, ...]] = []
    eps = MIN_PIECE * max(canvas, 1e-9)
    plain = [o for o, w in enumerate(words) if w and not any(x.transparent for x in w)]
    common: list[float] | None = None
    for r, w in enumerate(words):
        if not any(x.transparent for x in w):
            out_words.append(tuple(w))
            out_parents.append(tuple(range(len(w))))
            continue
        if common is None or not plain:    # with plain words, the same for every word with transparent letters
            common = sorted({v for o in (plain or range(len(words))) if o != r
                             for v, t in zip(bounds[o][1:-1], touch[o]) if t})
        key = (ids[r], canvas, tuple(common))
        known = memo.get(key)
        if known is None:
            known = memo[key] = (*_split(w, bounds[r], common, eps), tuple(w))
        out_words.append(known[0])
        out_parents.append(known[1])
    return out_words, out_parents


def _split(w: Sequence[Letter], bounds: Sequence[float], others: Sequence[float], eps: float
           ) -> tuple[tuple[Letter, ...], tuple[int, ...]]:
    """One word's transparent letters cut at the sorted boundaries ``others`` (its own are ``bounds``)."""
    scale = bounds[-1] / max(sum(x.size for x in w), 1e-12)
    letters: list[Letter] = []
    parents: list[int] = []
    for i, letter in enumerate(w):
        a, b = bounds[i], bounds[i + 1]
        # the cuts strictly inside (a + eps, b - eps): a slice of the sorted boundaries
        inside = others[bisect.bisect_right(others, a + eps):bisect.bisect_left(others, b - eps)] \
            if letter.transparent else []
        cuts = inside[:1] + [v for u, v in itertools.pairwise(inside) if v - u > eps]
        if not cuts:
            letters.append(letter)
            parents.append(i)
            continue
        edges = [a, *cuts, b]
        for lo, hi in zip(edges[:-1], edges[1:]):
            letters.append(replace(letter, size=(hi - lo) / scale))
            parents.append(i)
    return tuple(letters), tuple(parents)
