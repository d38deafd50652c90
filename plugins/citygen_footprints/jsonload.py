"""Reading a JSON document with clear errors (file:line:column) and the line where each feature starts."""
from __future__ import annotations

import codecs
import json
from collections.abc import Callable, Iterator
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
        raise _unreadable(path, exc) from None
    except UnicodeDecodeError as exc:
        raise FootprintError(f"not UTF-8 text (byte {exc.start})", where=str(path),
                             hint="GeoJSON and CityJSON files are UTF-8 JSON") from None


def iter_lines(path: Path) -> Iterator[tuple[int, Any]]:
    """(1-based line number, decoded value) of every non-blank line of a JSON Lines file, read a line at a time
    (lines end at ``\\n``; a UTF-8 byte order mark at the start is skipped)."""
    try:
        file = open(path, "rb")  # noqa: SIM115 (closed below, also when the caller stops early)
    except OSError as exc:
        raise _unreadable(path, exc) from None
    with file:
        offset = 0
        for number, raw in enumerate(_lines_of(file, path), start=1):
            start = 3 if offset == 0 and raw.startswith(codecs.BOM_UTF8) else 0
            try:
                line = raw[start:].decode("utf-8")
            except UnicodeDecodeError as exc:
                raise FootprintError(f"not UTF-8 text (byte {offset + start + exc.start})",
                                     where=SourceLocation(str(path), number, None),
                                     hint="GeoJSON and CityJSON files are UTF-8 JSON") from None
            offset += len(raw)
            if not line.strip():
                continue
            try:
                value = json.loads(line)
            except json.JSONDecodeError as exc:
                raise FootprintError(f"not valid JSON: {exc.msg}", where=SourceLocation(str(path), number, exc.colno),
                                     hint="each line of a JSON Lines file must be one JSON value") from None
            except RecursionError:
                raise FootprintError("JSON nested too deeply", where=SourceLocation(str(path), number, None)) from None
            yield number, value


def _lines_of(file, path: Path) -> Iterator[bytes]:
    try:
        yield from file
    except OSError as exc:
        raise _unreadable(path, exc) from None


def _unreadable(path: Path, exc: OSError) -> FootprintError:
    return FootprintError(f"cannot read footprint file: {exc.strerror or exc}", where=str(path),
                          hint="check the [footprints] path in the scene")


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


#: Characters read from a file at a time by :func:`stream_object` (at least: a value longer than the buffer doubles
#: the read, so a long value costs a few decode attempts, not one per chunk).
CHUNK = 1 << 20


class _Reader:
    """A text file read in chunks, decoded value by value: only the chunk being decoded is held."""

    def __init__(self, file) -> None:
        self.file, self.buf, self.pos, self.eof = file, "", 0, False
        self.line, self.counted = 1, 0  # (1-based line at buf[counted])

    def more(self) -> bool:
        """Append the next chunk (dropping what is decoded); False at the end of the file."""
        chunk = self.file.read(max(CHUNK, len(self.buf) - self.pos))
        if not chunk:
            self.eof = True
            return False
        self.line += self.buf.count("\n", self.counted, self.pos)
        self.buf, self.pos, self.counted = self.buf[self.pos:] + chunk, 0, 0
        return True

    def peek(self) -> str:
        """The next character that is not whitespace ("" at the end of the file)."""
        while True:
            self.pos = _skip(self.buf, self.pos)
            if self.pos < len(self.buf) or not self.more():
                return self.buf[self.pos:self.pos + 1]

    def take(self, char: str) -> None:
        if self.peek() != char:
            raise json.JSONDecodeError(f"Expecting {char!r}", self.buf, self.pos)
        self.pos += 1

    def decode(self) -> Any:
        """The next JSON value (read on until it is whole: a number is whole once something follows it)."""
        self.peek()
        while True:
            try:
                value, end = _DECODER.raw_decode(self.buf, self.pos)
                if end < len(self.buf) or self.eof:
                    self.pos = end
                    return value
            except json.JSONDecodeError:
                if self.eof:
                    raise
            self.more()

    def line_here(self) -> int:
        """The 1-based line of the next character."""
        self.line += self.buf.count("\n", self.counted, self.pos)
        self.counted = self.pos
        return self.line


def stream_object(path: Path, array_key: str, each: Callable[[int, Any, int], Any], kind: str
                  ) -> dict[str, Any] | None:
    """A top-level object of ``type`` ``kind`` read a chunk at a time: ``each(index, element, line)`` is called for
    each element of its ``array_key`` array as it is decoded, and the members other than that array are returned
    (the array as ``[]``) -- the file's text and its elements are never all in memory. ``None`` when the file is not
    such an object (another type, not an object, the array twice) or cannot be read or decoded: :func:`load_json`
    reads it whole then, with its errors (file:line:column)."""
    try:
        with open(path, encoding="utf-8-sig") as file:
            return _stream(_Reader(file), array_key, each, kind)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, RecursionError):
        return None


def _stream(reader: _Reader, array_key: str, each: Callable[[int, Any, int], Any], kind: str
            ) -> dict[str, Any] | None:
    if reader.peek() != "{":
        return None
    reader.pos += 1
    doc: dict[str, Any] = {}
    if reader.peek() == "}":
        return None
    while True:
        key = reader.decode()
        if not isinstance(key, str) or key in doc:
            return None
        reader.take(":")
        if key == array_key and reader.peek() == "[":
            reader.pos += 1
            doc[key], index = [], 0
            if reader.peek() == "]":
                reader.pos += 1
            else:
                while True:
                    reader.peek()
                    line = reader.line_here()
                    each(index, reader.decode(), line)
                    index += 1
                    if reader.peek() != ",":
                        reader.take("]")
                        break
                    reader.pos += 1
        else:
            doc[key] = reader.decode()
            if key == "type" and doc[key] != kind:
                return None
        if reader.peek() != ",":
            reader.take("}")
            break
        reader.pos += 1
    return doc if reader.peek() == "" and doc.get("type") == kind and isinstance(doc.get(array_key), list) else None
