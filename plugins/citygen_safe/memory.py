"""Results of pure functions of facades, remembered by their (hashable, value-compared) arguments.

An edit sizes many facades that earlier edits made too: every edit of a ruleset starts from the same input layout
and its first jumps give the same states whatever the target size (jumps act on the natural, unsized facade), the
faces of a city share them, and a ruleset text edited in the studio parses to an equal facade. The structural
steps (decomposition trees, jumps, leaf merging) depend on their arguments only, so remembering them changes no
result; the spatial optimisation, which depends on the target, is always solved (and its work always counted).
Facades compare by value, their regions without the ``key`` hint (not compared; layouts read from JSON, as
``.safe`` inputs are, carry none).
"""
from __future__ import annotations

import threading
from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

Result = TypeVar("Result")


class Memory(Generic[Result]):
    """At most ``size`` results by key, the first remembered forgotten first; safe to share between threads."""

    def __init__(self, size: int) -> None:
        self.size = size
        self._items: dict[Hashable, Result] = {}
        self._lock = threading.Lock()
        _MEMORIES.append(self)

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, key: Hashable) -> bool:
        return key in self._items

    def lookup(self, key: Hashable) -> Result | None:
        return self._items.get(key)

    def remember(self, key: Hashable, result: Result) -> None:
        with self._lock:
            if len(self._items) >= self.size:
                self._items.pop(next(iter(self._items)))
            self._items[key] = result

    def get(self, key: Hashable, compute: Callable[[], Result]) -> Result:
        """The result remembered for ``key``, else ``compute()`` remembered."""
        hit = self._items.get(key)
        if hit is None:
            hit = compute()
            self.remember(key, hit)
        return hit

    def clear(self) -> None:
        with self._lock:
            self._items.clear()


_MEMORIES: list[Memory] = []


def forget() -> None:
    """Clear every memory (a process that has seen nothing: ``benchmarks/safe_preview_cpu.py``'s cold column)."""
    for memory in _MEMORIES:
        memory.clear()
