"""Counting distinct values without holding them: the stage's module prototypes across a city's tile layers."""
from __future__ import annotations

from collections.abc import Hashable, Iterable

import numpy as np

#: Hashes gathered in a Python list before they are merged into the sorted array.
MERGE_EVERY = 65536


class DistinctCount:
    """How many distinct values were :meth:`update`-d, kept as their 64-bit ``hash`` in a sorted numpy array (8
    bytes a value where the values, a city's ~1.8 module prototype keys a building, took ~250 bytes each). Two
    different values with one hash count once: with 64-bit hashes, a chance of ~1e-9 among 200,000 values."""

    def __init__(self) -> None:
        self.seen = np.zeros(0, dtype=np.int64)
        self.fresh: list[int] = []

    def update(self, values: Iterable[Hashable]) -> None:
        self.fresh += map(hash, values)
        if len(self.fresh) >= MERGE_EVERY:
            self._merge()

    def _merge(self) -> None:
        if self.fresh:
            self.seen = np.union1d(self.seen, np.array(self.fresh, dtype=np.int64))
            self.fresh = []

    def __len__(self) -> int:
        self._merge()
        return len(self.seen)
