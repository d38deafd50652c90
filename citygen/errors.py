"""One error hierarchy for citygen.

Every error carries *where* (a file:line:col, or a scene/building/face path), *which plugin* when one is
involved, and a *hint* saying what to do. ``str(err)`` renders all three on one line so CLI reports and logs
stay readable.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class SourceLocation:
    """A position in a text file (1-based line and column)."""

    path: str
    line: int | None = None
    column: int | None = None

    def __str__(self) -> str:
        parts = [self.path]
        if self.line is not None:
            parts.append(str(self.line))
            if self.column is not None:
                parts.append(str(self.column))
        return ":".join(parts)


class CitygenError(Exception):
    """Base class of every error citygen raises on purpose."""

    def __init__(self, message: str, *, where: str | SourceLocation | None = None,
                 plugin: str | None = None, hint: str | None = None) -> None:
        super().__init__(message)
        self.message = message
        self.where = where
        self.plugin = plugin
        self.hint = hint

    def __str__(self) -> str:
        text = self.message
        if self.where is not None:
            text = f"{self.where}: {text}"
        if self.plugin:
            text = f"{text} [plugin {self.plugin}]"
        if self.hint:
            text = f"{text} -- {self.hint}"
        return text


class ParseError(CitygenError):
    """A text file (ruleset, scene, layout) does not follow its format. ``where`` is file:line:column."""


class SceneError(CitygenError):
    """A scene file is malformed or names something that does not exist."""


class FootprintError(CitygenError):
    """One footprint cannot be turned into a building; the building is skipped, the city goes on."""


class RulesetError(CitygenError):
    """A ruleset is invalid, or cannot be evaluated for a request."""


class LayoutError(CitygenError):
    """A FacadeLayout violates its contract (partition, sizes, schema)."""


class PluginError(CitygenError):
    """A plugin failed to load, registered a duplicate id, or broke its contract."""


class SolverError(CitygenError):
    """A solver failed or ran out of budget where a result object cannot be returned."""


class ExportError(CitygenError):
    """A stage could not be written or fails validation."""


def read_user_text(path: Path, error: type[CitygenError], what: str, encoding: str = "utf-8") -> str:
    """The text of a file a user wrote; a file that cannot be read or is not UTF-8 raises ``error`` naming the
    path (``what``: "scene", "ruleset", ... in the message)."""
    try:
        return path.read_text(encoding=encoding)
    except OSError as exc:
        raise error(f"cannot read {what}: {exc.strerror or exc}", where=str(path)) from exc
    except UnicodeDecodeError as exc:
        raise error(f"{what} is not UTF-8 text (byte {exc.object[exc.start]:#04x} at offset {exc.start})",
                    where=str(path), hint="save the file as UTF-8") from None
