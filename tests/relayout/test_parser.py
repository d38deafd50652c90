"""The .relayout format: shipped models parse, bad input names file:line:column and what was expected."""
from __future__ import annotations

import json

import pytest

from citygen.errors import ParseError
from citygen_relayout import parse_model
from citygen_relayout.model import ANCHORS

GOOD = """model tiny
root F 7 3
split F x W:1 Win:1 W:1 Win:1 W:1 Win:1 W:1
terminal W wall
terminal Win window depth -0.25 material "glass"
size Win 80%..120% sigma 5%
repeat F : W (Win W)+
freq F Win 1..5 relative
instances F Win 1..2
align Win.center = Win.center
samesize (W Win) = (Win W) within F
"""


def test_good_model_parses(models):
    m = parse_model(GOOD, "tiny.relayout")
    assert m.root == "F" and m.symbols["F"].children == ("W", "Win", "W", "Win", "W", "Win", "W")
    rng = m.sizes[("Win", "x")]
    assert (rng.lo, rng.hi, rng.sigma) == pytest.approx((0.8, 1.2, 0.05))
    assert m.rules["F"].frequencies[0].relative
    assert m.rules["F"].instances["Win"].hi == 2
    assert m.alignments[0].a_anchor == ANCHORS["center"]
    assert m.samesizes[0].within == "F"
    for model in models.values():
        assert model.terminal_count() > 20


@pytest.mark.parametrize("text, where, expected", [
    ("root F 6 3\nsplit F z A:6\nterminal A wall\n", "2:9", "split axis x or y"),
    ("root F 6 3\nsplit F x A:6\nterminal A wall\nfrobnicate F\n", "4:1", "a statement"),
    ("root F 6 3\nsplit F x A:6\nterminal A wall\nsize A 2..1\n", "4:11", "an upper bound >= 2"),
    ("root F 6 3\nsplit F x A:6\nterminal A wall\nseq F : A B\n", "4:11", "B is not a child"),
    ("root F 6 3\nsplit F x A:6\nterminal A wall\nalign A.middle = A.min\n", "4:9", "min, center or max"),
    ("root F 6 3\nsplit F x A:6\nterminal A wall\nsamesize (A = A\n", "4:13", "a symbol, @label"),
    ("root F 6 3\nsplit F x A:4\nterminal A wall\n", "2:7", "sum to 4"),
    ("root F 6 3\nsplit F x A:3 B:3\nterminal A wall\n", "2:7", "neither split nor terminal"),
    ("root F 6 3\nsplit F x A:6\nterminal A wall\nfreq A A 1..2\n", "4:6", "needs a composite"),
    ("root F 6 3\nsplit F x A:6\nterminal A wall depth ~\n", "3:23", "unexpected character"),
    ("root F 6 -3\n", "1:10", "the input height > 0"),
    ("model x\n", "1:1", "no segmentation"),
])
def test_parse_errors_name_file_line_column(text, where, expected):
    with pytest.raises(ParseError) as info:
        parse_model(text, "bad.relayout")
    assert str(info.value.where) == f"bad.relayout:{where}"
    assert expected in str(info.value)


def test_layout_statement_builds_the_hierarchy_from_json(tmp_path):
    flat = {"schema_version": 1, "width": 4.0, "height": 2.0, "root": {
        "x": 0, "y": 0, "w": 4, "h": 2, "symbol": "Facade", "children": [
            {"x": 0, "y": 0, "w": 1, "h": 2, "symbol": "Wall", "label": "wall"},
            {"x": 1, "y": 0, "w": 1, "h": 1, "symbol": "Door", "label": "door"},
            {"x": 1, "y": 1, "w": 1, "h": 1, "symbol": "Window", "label": "window"},
            {"x": 2, "y": 0, "w": 2, "h": 2, "symbol": "Wall", "label": "wall"}]}}
    (tmp_path / "f.json").write_text(json.dumps(flat))
    m = parse_model('layout "f.json"\nfreq Facade Wall 1..3\n', str(tmp_path / "f.relayout"), base=tmp_path)
    root = m.symbols[m.root]
    assert root.split == "x" and len(root.children) == 3
    column = m.symbols[root.children[1]]
    assert column.split == "y" and [m.symbols[c].label for c in column.children] == ["door", "window"]
    assert m.symbols[root.children[0]].name != m.symbols[root.children[2]].name  # different sizes: two symbols


def test_missing_layout_file_is_a_parse_error(tmp_path):
    with pytest.raises(ParseError) as info:
        parse_model('layout "nope.json"\n', "m.relayout", base=tmp_path)
    assert str(info.value.where) == "m.relayout:1:8"
