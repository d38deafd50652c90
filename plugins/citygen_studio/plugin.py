"""citygen hook implementations of the studio plugin: the ``studio`` command."""
from __future__ import annotations

from citygen.hookspecs import hookimpl
from citygen.registry import Command
from citygen_studio.command import StudioCommand


@hookimpl
def citygen_commands() -> list[Command]:
    return [StudioCommand()]
