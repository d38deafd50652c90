"""The faces of a building share the subtrees that derive alike on all of them (issue 24): a later face copies a
face-invariant subtree that an earlier face derived at the same place, and its layout is the one it derives alone
(the same regions, coordinates to the bit, keys, terminal arrays and choices)."""
from __future__ import annotations

import json

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from citygen.registry import load_registry
from citygen.request import FaceContext, FacadeRequest
from citygen_split import load
from citygen_split.alternatives import derive_plausible
from citygen_split.derive import Subtrees, _Derivation

from .conftest import REPO, grammar, request

KIND = load_registry().ruleset_kind("split")
GRAMMARS = {name: load(REPO / "rulesets" / f"{name}.grammar") for name in ("apartment", "historic", "office", "house")}


def fingerprint(layout):
    """Everything a consumer reads of ``layout``: its tree (fields and keys in tree order), meta and terminal
    arrays (rectangles to the bit, each terminal's source by value)."""
    regions, stack = [], [layout.root]
    while stack:
        r = stack.pop()
        regions.append((r.x, r.y, r.w, r.h, r.symbol, r.label, r.depth, r.material, r.asset, r.layer, r.key,
                        len(r.children)))
        stack.extend(reversed(r.children))
    sources, index = layout.leaf_sources
    of_terminal = [(s.symbol, s.label, s.depth, s.material, s.asset, s.layer, s.key) for s in sources]
    return (regions, json.dumps(dict(layout.meta), sort_keys=True, default=str), layout.leaf_rects.tobytes(),
            [of_terminal[i] for i in index.tolist()])


def building(widths, seeds, entrance, lines):
    return [FacadeRequest(width=w, height=lines[-1], floor_lines=lines, entrance=k == entrance,
                          corner_widths=(0.4, 0.4), context=FaceContext("way/7", k, len(widths), street_facing=True),
                          seed=(seed, "way/7", k))
            for k, (w, seed) in enumerate(zip(widths, seeds))]


def test_an_equal_face_copies_the_earlier_faces_storeys_and_derives_what_it_derives_alone():
    g = GRAMMARS["apartment"]
    lines = (0.0, 4.2, 7.2, 10.2, 13.2)
    first, second = building([14.3, 14.3], [3, 4], -1, lines)
    subtrees = Subtrees(g)
    _Derivation(g, first, subtrees=subtrees).run()
    assert subtrees.derived
    derivation = _Derivation(g, second, subtrees=subtrees)
    shared = derivation.run()
    assert derivation.partial  # (copies were placed)
    alone = _Derivation(g, second)
    assert fingerprint(shared) == fingerprint(alone.run())
    assert derivation.count == alone.count and len(derivation.sources) >= len(alone.sources)


def test_a_subtree_is_not_copied_to_another_place():
    """A subtree is copied only where an earlier face had it: elsewhere its coordinates would round otherwise than
    a fresh derivation's (here the storeys of two faces are equal, but their corner strips are swapped)."""
    g = GRAMMARS["apartment"]
    lines = (0.0, 4.2, 7.2, 10.2)
    left, right = (FacadeRequest(width=14.3, height=lines[-1], floor_lines=lines, corner_widths=corners,
                                 context=FaceContext("way/7", k, 2), seed=(3, "way/7", k))
                   for k, corners in enumerate([(0.7, 0.4), (0.4, 0.7)]))
    subtrees = Subtrees(g)
    _Derivation(g, left, subtrees=subtrees).run()
    derivation = _Derivation(g, right, subtrees=subtrees)
    assert fingerprint(derivation.run()) == fingerprint(_Derivation(g, right).run())
    assert not derivation.partial


def test_an_implausible_face_with_copies_moves_the_choice_points_inside_them():
    """Regression guard: a copy does not note the choice points inside it, so a face whose first derivation has
    copies and is implausible derives again without them; its choices then move as they do alone (here the row's
    repeat places two bays, not three with 2.5 cm walls) instead of falling back to a plain wall."""
    g = grammar("F --> floors { *: Row }\nRow --> repeat(x) { ~1: Bay }\n"
                "Bay --> split(x) { '1: Wall | 0.95: Window | '1: Wall }\n")
    assert "Row" in g.face_invariant
    requests = [request(3.0, 4.0, (0.0, 2.0, 4.0), seed=(k,)) for k in range(2)]
    layouts = KIND.generate_building(g, requests)
    for layout, req in zip(layouts, requests):
        assert layout.count("window") == 4 and not layout.meta.get("fallback")
        assert fingerprint(layout) == fingerprint(derive_plausible(g, req).layout)


def test_subtrees_belong_to_one_grammar():
    subtrees = Subtrees(GRAMMARS["house"])
    try:
        _Derivation(GRAMMARS["office"], request(10.0, 6.0), subtrees=subtrees)
    except ValueError as exc:
        assert "another grammar" in str(exc)
    else:
        raise AssertionError("a derivation took another grammar's subtrees")


@settings(max_examples=40, deadline=None)
@given(name=st.sampled_from(sorted(GRAMMARS)),
       widths=st.lists(st.sampled_from([2.9, 6.1, 9.35, 14.3, 23.77]), min_size=2, max_size=5),
       seeds=st.lists(st.integers(0, 3), min_size=5, max_size=5),
       entrance=st.integers(-1, 4),
       storeys=st.lists(st.sampled_from([2.9, 3.0, 3.3]), min_size=1, max_size=4))
def test_property_a_building_derives_each_face_as_it_derives_alone(name, widths, seeds, entrance, storeys):
    lines = tuple(np.cumsum([0.0, 4.1, *storeys]).tolist())
    requests = building(widths, seeds, entrance, lines)
    g = GRAMMARS[name]
    together = KIND.generate_building(g, requests)
    alone = [derive_plausible(g, req).layout for req in requests]
    assert [fingerprint(layout) for layout in together] == [fingerprint(layout) for layout in alone]
