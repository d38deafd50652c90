"""Transparent splits (§5.2): letters of control patterns are invisible, so they may be cut into parts where
other words have boundaries. Done as a preprocessing step on the words of one alignment matrix."""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from citygen_layers.words import Letter


def split_transparent(words: Sequence[Sequence[Letter]], canvas: float
                      ) -> tuple[list[tuple[Letter, ...]], list[tuple[int, ...]]]:
    """Cut transparent letters at the (canvas-scaled) boundaries of the other words.

    Returns the new words and, per word, the index of the original letter each part belongs to; parts keep
    the letter's flags and take the length of their piece as size.
    """
    bounds = []
    for w in words:
        cum = np.concatenate([[0.0], np.cumsum([x.size for x in w])])
        scale = canvas / cum[-1] if cum[-1] > 0 else 1.0
        bounds.append(cum * scale)
    out_words: list[tuple[Letter, ...]] = []
    out_parents: list[tuple[int, ...]] = []
    eps = 1e-6 * max(canvas, 1.0)
    for r, w in enumerate(words):
        others = np.unique(np.concatenate([bounds[o][1:-1] for o in range(len(words)) if o != r] or [np.zeros(0)]))
        scale = bounds[r][-1] / max(sum(x.size for x in w), 1e-12)
        letters: list[Letter] = []
        parents: list[int] = []
        for i, letter in enumerate(w):
            a, b = bounds[r][i], bounds[r][i + 1]
            cuts = others[(others > a + eps) & (others < b - eps)] if letter.transparent else np.zeros(0)
            edges = np.concatenate([[a], cuts, [b]])
            for lo, hi in zip(edges[:-1], edges[1:]):
                size = (hi - lo) / scale if cuts.size else letter.size
                letters.append(replace(letter, size=float(size)))
                parents.append(i)
        out_words.append(tuple(letters))
        out_parents.append(tuple(parents))
    return out_words, out_parents
