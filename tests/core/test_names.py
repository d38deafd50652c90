"""Prim names made without USD (citygen.usd.names) are USD's own: the footprint planning names every building in a
process that never imports ``pxr``."""
from __future__ import annotations

from hypothesis import example, given, settings
from hypothesis import strategies as st
from pxr import Tf

from citygen.usd.names import prim_name, valid_identifier


@settings(max_examples=400, deadline=None)
@given(st.text(alphabet=st.characters(blacklist_categories=("Cs",)), max_size=12))
@example("")
@example("way/123")
@example("1abc")
@example("\x00b")
@example("a\x00b")
@example("äbc-1")
@example("日本")
def test_valid_identifier_is_tf_make_valid_identifier(text):
    assert valid_identifier(text) == Tf.MakeValidIdentifier(text)


def test_a_lone_surrogate_raises_as_it_does_in_usd():
    for make in (valid_identifier, Tf.MakeValidIdentifier):
        try:
            make("a\ud800")
        except UnicodeEncodeError:
            continue
        raise AssertionError(f"{make} accepted a lone surrogate")


def test_prim_names_are_unique_and_valid():
    taken: set[str] = set()
    names = [prim_name(raw, taken) for raw in ("way/1", "way_1", "way/1", "", "9")]
    assert names == ["way_1", "way_1_2", "way_1_3", "_", "__2"]
