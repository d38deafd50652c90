"""A bound on how deeply a user's file may nest (parentheses, groups, sets, tables).

Recursive-descent parsers, and the code that walks what they build, recurse once per level: past a few hundred
levels Python stops them with a RecursionError. Parsers count their depth with :class:`Depth` and report the
level past :data:`MAX_NESTING` as an ordinary error at its place in the file.
"""
from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator

#: The deepest nesting a ruleset or scene file may use; hand-written files stay far below it.
MAX_NESTING = 32


class Depth:
    """The current nesting depth of one parse."""

    def __init__(self) -> None:
        self.level = 0

    @contextlib.contextmanager
    def inside(self, fail: Callable[[str], Exception]) -> Iterator[None]:
        """One level deeper while the block runs; past :data:`MAX_NESTING`, raise ``fail(message)`` (an error
        located where the level opens)."""
        if self.level >= MAX_NESTING:
            raise fail(f"nested more than {MAX_NESTING} levels deep")
        self.level += 1
        try:
            yield
        finally:
            self.level -= 1


def depth_of(value: object) -> int:
    """How deeply lists and dicts nest in ``value`` (0 for a scalar), without recursion."""
    deepest, stack = 0, [(value, 0)]
    while stack:
        item, level = stack.pop()
        children = item.values() if isinstance(item, dict) else item if isinstance(item, list) else None
        if children is not None:
            deepest = max(deepest, level + 1)
            stack.extend((child, level + 1) for child in children)
    return deepest
