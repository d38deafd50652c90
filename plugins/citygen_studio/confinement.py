"""What a studio session may touch, and its errors as data: :class:`Confinement` resolves the paths the browser
names (inside the scene's folder, or a ruleset the scene names); :func:`error_data` turns an error into JSON."""
from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from citygen.errors import CitygenError, SourceLocation

#: The largest file dropped on the studio (bytes).
MAX_UPLOAD = 8 * 1024 * 1024


class StudioError(CitygenError):
    """A request the studio refuses: ``status`` is the HTTP status it answers with."""

    def __init__(self, message: str, status: int = 400, **kw: Any) -> None:
        super().__init__(message, **kw)
        self.status = status


def error_data(exc: CitygenError, confinement: Confinement | None = None) -> dict[str, Any]:
    """An error as JSON data: message, hint, and ``file`` / ``line`` / ``column`` when it names a position."""
    where = exc.where
    data: dict[str, Any] = {"message": exc.message, "hint": exc.hint, "kind": type(exc).__name__}
    if isinstance(where, SourceLocation):
        data.update(file=confinement.show(where.path) if confinement else where.path, line=where.line,
                    column=where.column)
    elif where is not None:
        data["where"] = confinement.show(str(where)) if confinement else str(where)
    return data


class Confinement:
    """The files a session may read and write: under ``root``, plus the exact files in ``named``."""

    def __init__(self, root: Path, named: Iterable[Path] = ()) -> None:
        self.root = root.resolve()
        self.named = {p.resolve() for p in named}

    def resolve(self, name: str) -> Path:
        """The file ``name`` (relative to the root, as a scene names it) if it is inside the confinement."""
        if not isinstance(name, str) or not name or "\0" in name or len(name) > 1024 or os.path.isabs(name):
            raise StudioError(f"{name!r} is not a path relative to the scene folder", 400)
        path = (self.root / name).resolve()
        if path in self.named or path.is_relative_to(self.root):
            return path
        raise StudioError(f"{name} is outside the scene folder and not a ruleset the scene names", 403,
                          hint="the studio reads and writes only the scene's folder and its rulesets")

    def show(self, path: str) -> str:
        """``path`` as the browser names it: relative to the root (``../rulesets/x.grammar`` for a named one)."""
        try:
            return os.path.relpath(Path(path).resolve(), self.root)
        except ValueError:
            return Path(path).name
