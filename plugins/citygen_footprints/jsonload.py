"""Reading a JSON document with clear errors (file:line:column) and the line where each feature starts."""
from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from citygen.errors import FootprintError, SourceLocation

_DECODER = json.JSONDecoder()
_WHITESPACE = " \t\r\n"


def _skip(text: str, pos: int) -> int:
    while pos < len(text) and text[pos] in _WHITESPACE:
        pos += 1
    return pos


def _expect(text: str, pos: int, char: str) -> int:
    pos = _skip(text, pos)
    if pos >= len(text) or text[pos] != char:
        raise json.JSONDecodeError(f"Expecting {char!r}", text, pos)
    return pos + 1


def _scan_object(text: str, array_key: str, each: Callable[[int, Any, int], Any] | None = None
                 ) -> tuple[dict[str, Any], list[int]]:
    """Decode a top-level object; for the array under ``array_key`` also return each element's 1-based start line,
    and store ``each(index, element, line)`` in place of each element (given ``each``)."""
    pos = _expect(text, 0, "{")
    doc: dict[str, Any] = {}
    lines: list[int] = []
    pos = _skip(text, pos)
    if pos < len(text) and text[pos] == "}":
        return doc, lines
    while True:
        key, pos = _DECODER.raw_decode(text, _skip(text, pos))
        if not isinstance(key, str):
            raise json.JSONDecodeError("Expecting property name enclosed in double quotes", text, pos)
        pos = _skip(text, _expect(text, pos, ":"))
        if key == array_key and pos < len(text) and text[pos] == "[":
            items: list[Any] = []
            lines, line, previous = [], 1, 0
            pos = _skip(text, pos + 1)
            if pos < len(text) and text[pos] == "]":
                pos += 1
            else:
                while True:
                    pos = _skip(text, pos)
                    line += text.count("\n", previous, pos)
                    lines.append(line)
                    previous = pos
                    item, pos = _DECODER.raw_decode(text, pos)
                    items.append(item if each is None else each(len(items), item, line))
                    pos = _skip(text, pos)
                    if pos < len(text) and text[pos] == ",":
                        pos += 1
                        continue
                    pos = _expect(text, pos, "]")
                    break
            doc[key] = items
        else:
            doc[key], pos = _DECODER.raw_decode(text, pos)
        pos = _skip(text, pos)
        if pos < len(text) and text[pos] == ",":
            pos += 1
            continue
        pos = _expect(text, pos, "}")
        break
    if _skip(text, pos) != len(text):
        raise json.JSONDecodeError("Extra data", text, _skip(text, pos))
    return doc, lines


def _read_text(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise FootprintError(f"cannot read footprint file: {exc.strerror or exc}", where=str(path),
                             hint="check the [footprints] path in the scene") from None
    except UnicodeDecodeError as exc:
        raise FootprintError(f"not UTF-8 text (byte {exc.start})", where=str(path),
                             hint="GeoJSON and CityJSON files are UTF-8 JSON") from None


def read_lines(path: Path) -> list[tuple[int, Any]]:
    """(1-based line number, decoded value) of every non-blank line of a JSON Lines file."""
    out = []
    for number, line in enumerate(_read_text(path).splitlines(), start=1):
        if not line.strip():
            continue
        try:
            out.append((number, json.loads(line)))
        except json.JSONDecodeError as exc:
            raise FootprintError(f"not valid JSON: {exc.msg}", where=SourceLocation(str(path), number, exc.colno),
                                 hint="each line of a JSON Lines file must be one JSON value") from None
    return out


def load_json(path: Path, array_key: str = "features", each: Callable[[int, Any, int], Any] | None = None
              ) -> tuple[Any, list[int]]:
    """The decoded document and the 1-based line of each element of its ``array_key`` array (if any); with
    ``each``, ``each(index, element, line)`` stands in the array for each element, called as it is decoded.

    Raises FootprintError naming ``file:line:column`` for unreadable files and JSON syntax errors.
    """
    text = _read_text(path)
    try:
        if text.lstrip().startswith("{"):
            doc, lines = _scan_object(text, array_key, each)
        else:
            doc, lines = json.loads(text), []
    except json.JSONDecodeError as exc:
        raise FootprintError(f"not valid JSON: {exc.msg}", where=SourceLocation(str(path), exc.lineno, exc.colno),
                             hint="fix the JSON syntax at that position") from None
    except RecursionError:
        raise FootprintError("JSON nested too deeply", where=str(path)) from None
    return doc, lines
