"""citygen hook implementations of the inverse plugin: the ``layout`` and ``grammar`` commands."""
from __future__ import annotations

from citygen.hookspecs import hookimpl
from citygen.registry import Command

from citygen_inverse.commands import GrammarCommand, LayoutCommand


@hookimpl
def citygen_commands() -> list[Command]:
    return [LayoutCommand(), GrammarCommand()]
