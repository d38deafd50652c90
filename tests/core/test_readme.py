"""The README stays true: its commands exist and its example grammar derives valid facades."""
from __future__ import annotations

import re
from pathlib import Path

import pytest
import tomllib

from citygen.layout import check_partition
from citygen.request import FacadeRequest, check_request

REPO = Path(__file__).resolve().parents[2]
README = (REPO / "README.md").read_text()


def test_quick_start_commands_match_ci():
    blocks = re.findall(r"```\n(python3 -m venv[^\n]*)\n```", README)
    assert len(blocks) == 2, "the quick start has exactly two commands"
    demo, tests = blocks
    assert "citygen generate scenes/helsinki.toml" in demo
    assert tests in (REPO / ".ci" / "run").read_text()
    assert (REPO / "scenes" / "helsinki.toml").exists()
    assert "citygen" in tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["scripts"]


@pytest.mark.parametrize("size", [(16, 14), (3, 7), (40, 30), (1.2, 3.1)])
def test_example_grammar_derives(size):
    from citygen_split import derive, parse
    text = re.search(r"### The split grammar language, by example\n\n```\n(.*?)```", README, re.S).group(1)
    grammar = parse(text, "README.md")
    for entrance in (True, False):
        request = FacadeRequest.preview(*size, floor_height=3.0, ground_height=3.6, entrance=entrance)
        layout = derive(grammar, request)
        assert check_partition(layout) == []
        assert check_request(layout, request) == []
