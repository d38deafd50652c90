"""citygen hook implementations of the photo plugin (mueller2007): the ``layout from-photo`` source."""
from __future__ import annotations

from citygen.hookspecs import hookimpl
from citygen.registry import LayoutSource

from citygen_photo.commands import FromPhoto


@hookimpl
def citygen_layout_sources() -> list[LayoutSource]:
    return [FromPhoto()]
