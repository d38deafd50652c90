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
    """Results by key, the first remembered forgotten first once their total ``cost`` (leaves: what their size grows
    with) would exceed ``capacity``; a result costing more than a quarter of it is not remembered (a 100 m face
    would push out everything for one use). Safe to share between threads."""

    def __init__(self, capacity: int) -> None:
        self.capacity = capacity
        self._items: dict[Hashable, tuple[Result, int]] = {}
        self._spent = 0
        self._lock = threading.Lock()
        _MEMORIES.append(self)

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, key: Hashable) -> bool:
        return key in self._items

    def lookup(self, key: Hashable) -> Result | None:
        hit = self._items.get(key)
        return None if hit is None else hit[0]

    def remember(self, key: Hashable, result: Result, cost: int) -> None:
        if 4 * cost > self.capacity:
            return
        with self._lock:
            if key in self._items:
                return
            while self._items and self._spent + cost > self.capacity:
                self._spent -= self._items.pop(next(iter(self._items)))[1]
            self._items[key] = (result, cost)
            self._spent += cost

    def get(self, key: Hashable, compute: Callable[[], Result], cost: Callable[[Result], int]) -> Result:
        """The result remembered for ``key``, else ``compute()`` remembered at ``cost(result)``."""
        hit = self._items.get(key)
        if hit is not None:
            return hit[0]
        result = compute()
        self.remember(key, result, cost(result))
        return result

    def clear(self) -> None:
        with self._lock:
            self._items.clear()
            self._spent = 0


_MEMORIES: list[Memory] = []


def forget() -> None:
    """Clear every memory (a process that has seen nothing: ``benchmarks/safe_preview_cpu.py``'s cold column)."""
    for memory in _MEMORIES:
        memory.clear()
