"""Mutations of user-written input files, for the fuzz harness (``benchmarks/fuzz_readers.py``) and the bounded
property tests of every reader: delete/duplicate/swap lines and tokens, numbers replaced by edge values, stray
brackets, unicode, truncation; JSON documents also mutated as trees (values of the wrong type, keys removed).

Every mutation is a pure function of the text and a ``random.Random``, so a case is reproduced from its seed.
"""
from __future__ import annotations

import json
import math
import random
import re
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]

_NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?![\w.])")
_TOKEN = re.compile(r"[\w.+-]+|[^\w\s]")

#: Edge values for a number, per dialect (each is valid syntax where the format has NaN/inf at all).
NUMBERS = {
    "dsl": ("0", "-1", "nan", "inf", "-inf", "1e308", "1e-308", "1e400", "99999999999999999999999999", "-0", ""),
    "toml": ("0", "-1", "nan", "inf", "-inf", "1e308", "1e-308", "99999999999999999999999999", "-0.0", '""',
             "[]", "{}", "true"),
    "json": ("0", "-1", "NaN", "Infinity", "-Infinity", "1e308", "1e-308", "1e400", "99999999999999999999999999",
             '""', "null", "[]", "{}", "true", '"x"'),
}
#: Tokens that break structure or types.
ODD = ("", "[", "]", "{", "}", "(", ")", "'", '"', "|", ":", "=", ",", "..", "*", "%", "^", "é", "\u200b",
       "\U0001f3e0", "\x00", "true", "null", "x" * 300, "-", "#", ";", "\t", "\\")

#: Values a JSON tree mutation puts in place of a node.
JSON_VALUES: tuple[Any, ...] = (0, -1, math.nan, math.inf, -math.inf, 1e308, 1e-308, 10 ** 30, 10 ** 400, "", "x",
                                None, [], {}, True, "\U0001f3e0", [[]], [0, 0], {"type": None})


def _lines(text: str) -> list[str]:
    return text.splitlines(keepends=True) or [""]


def delete_line(text: str, rng: random.Random) -> str:
    lines = _lines(text)
    del lines[rng.randrange(len(lines))]
    return "".join(lines)


def duplicate_line(text: str, rng: random.Random) -> str:
    lines = _lines(text)
    i = rng.randrange(len(lines))
    lines.insert(i, lines[i] if lines[i].endswith("\n") else lines[i] + "\n")
    return "".join(lines)


def swap_lines(text: str, rng: random.Random) -> str:
    lines = _lines(text)
    i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
    lines[i], lines[j] = lines[j], lines[i]
    return "".join(line if line.endswith("\n") else line + "\n" for line in lines)


def _spans(pattern: re.Pattern[str], text: str) -> list[tuple[int, int]]:
    return [m.span() for m in pattern.finditer(text)]


def _replace(text: str, span: tuple[int, int], new: str) -> str:
    return text[:span[0]] + new + text[span[1]:]


def delete_token(text: str, rng: random.Random) -> str:
    spans = _spans(_TOKEN, text)
    return _replace(text, rng.choice(spans), "") if spans else text


def duplicate_token(text: str, rng: random.Random) -> str:
    spans = _spans(_TOKEN, text)
    if not spans:
        return text
    a, b = rng.choice(spans)
    return text[:b] + " " + text[a:b] + text[b:]


def swap_tokens(text: str, rng: random.Random) -> str:
    spans = _spans(_TOKEN, text)
    if len(spans) < 2:
        return text
    first, second = sorted(rng.sample(spans, 2))
    return (text[:first[0]] + text[second[0]:second[1]] + text[first[1]:second[0]] + text[first[0]:first[1]]
            + text[second[1]:])


def odd_token(text: str, rng: random.Random) -> str:
    """Replace a token by a bracket, quote, operator, unicode or a very long word."""
    spans = _spans(_TOKEN, text)
    return _replace(text, rng.choice(spans), rng.choice(ODD)) if spans else text


def insert_odd(text: str, rng: random.Random) -> str:
    i = rng.randrange(len(text) + 1)
    return text[:i] + rng.choice(ODD) + text[i:]


def truncate(text: str, rng: random.Random) -> str:
    return text[:rng.randrange(len(text) + 1)]


def number_mutation(dialect: str) -> Callable[[str, random.Random], str]:
    def edge_number(text: str, rng: random.Random) -> str:
        spans = _spans(_NUMBER, text)
        return _replace(text, rng.choice(spans), rng.choice(NUMBERS[dialect])) if spans else text
    edge_number.__name__ = f"edge_number_{dialect}"
    return edge_number


def text_mutations(dialect: str) -> tuple[Callable[[str, random.Random], str], ...]:
    return (delete_line, duplicate_line, swap_lines, delete_token, duplicate_token, swap_tokens, odd_token,
            insert_odd, truncate, number_mutation(dialect), number_mutation(dialect), number_mutation(dialect))


def number_spans(text: str) -> list[tuple[int, int]]:
    """Where the numbers are (for exhaustive edge-value replacement)."""
    return _spans(_NUMBER, text)


def _nodes(doc: Any, path: tuple = ()) -> list[tuple]:
    found = [path]
    if isinstance(doc, dict):
        for key, value in doc.items():
            found += _nodes(value, path + (key,))
    elif isinstance(doc, list):
        for index, value in enumerate(doc):
            found += _nodes(value, path + (index,))
    return found


def mutate_tree(doc: Any, rng: random.Random) -> Any:
    """A deep copy of ``doc`` with one node replaced, removed or duplicated."""
    doc = json.loads(json.dumps(doc))
    path = rng.choice(_nodes(doc))
    if not path:
        return rng.choice(JSON_VALUES)
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    key = path[-1]
    action = rng.randrange(4)
    if action == 0 and isinstance(parent, dict):
        del parent[key]
    elif action == 0 and isinstance(parent, list):
        del parent[key]
    elif action == 1 and isinstance(parent, list):
        parent.insert(key, json.loads(json.dumps(parent[key])))
    elif action == 2 and isinstance(parent, list) and len(parent) > 1:
        other = rng.randrange(len(parent))
        parent[key], parent[other] = parent[other], parent[key]
    else:
        parent[key] = rng.choice(JSON_VALUES)
    return doc


def mutate_json(text: str, rng: random.Random, rounds: int = 1) -> str:
    doc = json.loads(text)
    for _ in range(rounds):
        doc = mutate_tree(doc, rng)
    return json.dumps(doc, indent=1)


def mutate(text: str, dialect: str, rng: random.Random) -> str:
    """One random mutation (JSON: a tree mutation half of the time); occasionally two stacked."""
    rounds = 2 if rng.random() < 0.25 else 1
    for _ in range(rounds):
        if dialect == "json" and rng.random() < 0.5:
            try:
                text = mutate_json(text, rng)
                continue
            except ValueError:
                pass
        text = rng.choice(text_mutations(dialect))(text, rng)
    return text


def scratch_rulesets(directory: Path) -> Path:
    """A copy of the shipped ``rulesets/`` in ``directory`` (so mutated rulesets find the files they name)."""
    target = directory / "rulesets"
    if not target.exists():
        shutil.copytree(REPO / "rulesets", target)
    return target


def load_and_generate(path: Path) -> None:
    """Load a ruleset through its kind in the default registry and generate a 12 x 9 m preview; a CitygenError
    is a fine answer to bad input, anything else propagates (and so does a layout with a non-finite number)."""
    from citygen.errors import CitygenError
    from citygen.registry import default_registry
    from citygen.request import FacadeRequest
    kind = default_registry().kind_for_path(path)
    try:
        layout = kind.generate(kind.load(path), FacadeRequest.preview(12, 9))
    except CitygenError:
        return
    for r in layout.root.terminals():
        assert all(math.isfinite(v) for v in (r.x, r.y, r.w, r.h, r.depth)), r


def fuzz_ruleset(scratch: Path, original: Path, seed: int) -> None:
    """Mutate ``original`` (seeded), write it into ``scratch`` next to the shipped rulesets, load and generate."""
    text = mutate(original.read_text(encoding="utf-8"), "dsl", random.Random(seed))
    path = scratch / f"fuzz{original.suffix}"
    path.write_text(text, encoding="utf-8")
    load_and_generate(path)
