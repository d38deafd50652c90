"""The studio's memory of answers: parsed texts, previews and builds are computed once per input, and a save or a
changed file is a new input."""
from __future__ import annotations

import pytest

from citygen.registry import default_registry
from citygen_studio.memo import Memo
from citygen_studio.session import FaceRequestSize, Session
from tests.studio.test_api import make_scene


def test_memo_keeps_the_most_recently_used():
    memo: Memo[int] = Memo(2)
    assert [memo.get(k, lambda k=k: k * 10) for k in (1, 2, 1, 3)] == [10, 20, 10, 30]
    assert memo.get(2, lambda: -1) == -1  # (2 was the least recently used: dropped for 3)
    assert memo.get(1, lambda: -1) == -1 and (memo.hits, memo.misses) == (1, 5)
    with pytest.raises(ZeroDivisionError):
        memo.get(4, lambda: 1 // 0)
    assert memo.get(4, lambda: 4) == 4  # (an exception is not kept)


@pytest.fixture
def session(tmp_path):
    return Session(default_registry(), make_scene(tmp_path))


def test_previews_are_remembered_by_text_and_size(session):
    text = (session.confinement.root / "house.grammar").read_text()
    size = FaceRequestSize(12, 9)
    first = session.preview("house.grammar", text, size)
    assert session.preview("house.grammar", text, FaceRequestSize(12, 9)) is first
    assert session.preview("house.grammar", text + "\n# edited\n", size) is not first
    assert session.preview("house.grammar", text, FaceRequestSize(13, 9)) is not first
    assert session.parsed.misses == 2  # (two texts parsed, the second size reused the parsed text)
    variations = session.variations("house.grammar", text, size, 4)
    assert session.variations("house.grammar", text, size, 4) is variations
    assert session.variations("house.grammar", text, size, 3) is not variations


def test_builds_are_remembered_until_a_ruleset_text_changes(session):
    path = session.confinement.root / "house.grammar"
    first = session.build(0)
    assert session.build(0) is first
    edited = path.read_text().replace("terminal(window", "terminal(blind")
    assert session.build(0, {"house.grammar": edited}) is not first
    session.save("house.grammar", edited)  # the file now says what the edit said
    assert session.build(0) is session.build(0, {"house.grammar": edited})
    path.write_text(path.read_text() + "\n# changed outside the studio\n")
    assert session.build(0) is not session.build(0, {"house.grammar": edited})
