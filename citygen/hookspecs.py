"""Every citygen hook, in pipeline order.

Hooks only *register* things; behaviour lives in the registered objects (see ``citygen.registry`` for their
interfaces). A plugin is any module or object with ``@hookimpl`` functions, announced under the ``citygen``
entry-point group::

    [project.entry-points.citygen]
    my_kind = "my_package.plugin"

Each hook returns a list; the plugin manager concatenates them, checks ids for duplicates, and records which
distribution every object came from (``citygen plugins``).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import pluggy

if TYPE_CHECKING:
    from citygen.registry import (
        Command,
        FootprintImporter,
        LayoutSource,
        RoofBuilder,
        RulesetKind,
    )

PROJECT = "citygen"
hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)


@hookspec
def citygen_footprint_importers() -> list[FootprintImporter]:
    """Register footprint importers (GeoJSON, CityJSON, ...), chosen by file suffix or a scene's ``format``."""


@hookspec
def citygen_roof_builders() -> list[RoofBuilder]:
    """Register roof builders; a scene or footprint attribute ``roof:shape`` selects one by id. The pipeline asks
    a builder how tall its roof rises at a pitch (``rise``) to split a building's height into walls and roof, then
    has it ``build`` the roof to exactly that height (``RoofSpec.height``)."""


@hookspec
def citygen_ruleset_kinds() -> list[RulesetKind]:
    """Register facade ruleset kinds (split grammar, layer stack, relayout model, ...)."""


@hookspec
def citygen_layout_sources() -> list[LayoutSource]:
    """Register layout sources: ``citygen layout NAME ...`` sub-commands that make a FacadeLayout from something
    else (an annotation, a photo)."""


@hookspec
def citygen_commands() -> list[Command]:
    """Register CLI sub-commands (``citygen NAME ...``)."""
