"""Ruleset kinds that read edited, unsaved texts in place of their files: what lets the studio generate the city from
the editor's texts without writing the user's files."""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from citygen.layout import FacadeLayout
from citygen.registry import Registry, RulesetKind
from citygen.request import FacadeRequest


class EditedKind(RulesetKind):
    """``kind`` with the files in ``texts`` (resolved paths) read as those texts, parsed by ``parse(kind, path,
    text)``; everything else is ``kind``'s own."""

    def __init__(self, kind: RulesetKind, texts: Mapping[Path, str],
                 parse: Callable[[RulesetKind, Path, str], Any]) -> None:
        self.kind, self.texts, self.parse = kind, texts, parse
        self.id, self.suffixes, self.description = kind.id, kind.suffixes, kind.description

    def load(self, path: Path) -> Any:
        text = self.texts.get(Path(path).resolve())
        return self.kind.load(path) if text is None else self.parse(self.kind, path, text)

    def loads(self, text: str, path: Path) -> Any:
        return self.kind.loads(text, path)

    def generate(self, ruleset: Any, request: FacadeRequest) -> FacadeLayout:
        return self.kind.generate(ruleset, request)

    def generate_building(self, ruleset: Any, requests: Sequence[FacadeRequest]) -> list[FacadeLayout]:
        return self.kind.generate_building(ruleset, requests)

    def explain(self, ruleset: Any, request: FacadeRequest) -> str:
        return self.kind.explain(ruleset, request)

    def render_png(self, layout: FacadeLayout, path: Path, floor_lines: Sequence[float] = ()) -> None:
        self.kind.render_png(layout, path, floor_lines)

    def __getattr__(self, name: str) -> Any:  # (what a kind offers beyond the interface)
        return getattr(self.kind, name)


def edited_registry(registry: Registry, texts: Mapping[Path, str],
                    parse: Callable[[RulesetKind, Path, str], Any]) -> Registry:
    """``registry`` whose ruleset kinds read the files in ``texts`` as those texts (a copy: ``registry`` is left
    as it is). Worker processes rebuild the registry from the plugins and would read the files: run it in one."""
    kinds = {kid: EditedKind(kind, texts, parse) for kid, kind in registry.ruleset_kinds.items()}
    return replace(registry, ruleset_kinds=kinds)
