"""Derivation: operator layouts, floors and corners, conditions, stochastic rules, limits."""
from __future__ import annotations

import importlib
import operator
from dataclasses import replace

import numpy as np
import pytest

from citygen.errors import RulesetError
from citygen.layout import FacadeLayout, check_partition
from citygen.request import FaceContext, check_request
from citygen_split import derive, explain, load, parse

from .conftest import grammar, leaves, request


def test_split_layout():
    g = grammar("X --> split(x) { 1: A | '1: B | 1: A }")
    assert leaves(derive(g, request(10, 3))) == [("A", 0, 0, 1, 3), ("B", 1, 0, 8, 3), ("A", 9, 0, 1, 3)]


def test_split_y_goes_bottom_to_top():
    g = grammar("X --> split(y) { 1: A | '1: B }")
    assert leaves(derive(g, request(2, 5))) == [("A", 0, 0, 2, 1), ("B", 0, 1, 2, 4)]


def test_repeat_layout():
    g = grammar("X --> repeat(x) { ~2: A | 1: B }")
    # T = 3, n = round(10 / 3) = 3 tiles of 10/3; the floating A fills 10/3 - 1
    got = leaves(derive(g, request(10, 3)))
    assert [s for s, *_ in got] == ["A", "B"] * 3
    assert [w for *_, w, _ in got] == pytest.approx([10 / 3 - 1, 1] * 3)
    assert got[-1][1] + got[-1][3] == 10


def test_repeat_aba_layout():
    g = grammar("X --> repeatABA(x) { 0.5: A | ~3.6: B }")
    got = leaves(derive(g, request(20, 3)))
    # n = round((20 - 0.5) / 4.1) = 5 B between 6 A; B = (20 - 3) / 5
    assert [s for s, *_ in got] == ["A", "B"] * 5 + ["A"]
    assert [w for *_, w, _ in got] == pytest.approx([0.5, 3.4] * 5 + [0.5])


def test_repeat_aba_with_no_room_is_one_a():
    g = grammar("X --> repeatABA(x) { 0.6: A | ~2.8: B }")
    assert leaves(derive(g, request(2, 3))) == [("A", 0, 0, 2, 3)]


def test_symsplit_layout():
    g = grammar("X --> symsplit(x) { 1: A | '1: B | 2: C }")
    assert leaves(derive(g, request(10, 3))) == [("A", 0, 0, 1, 3), ("B", 1, 0, 3, 3), ("C", 4, 0, 2, 3),
                                                 ("B", 6, 0, 3, 3), ("A", 9, 0, 1, 3)]


def test_grid_layout_with_spans():
    g = grammar("X --> grid { cols: 1 | '1 | 1 ; rows: 1 | ~2 ; A < B / C Window v }")
    assert leaves(derive(g, request(6, 4))) == [("A", 0, 0, 5, 1), ("B", 5, 0, 1, 4), ("C", 0, 1, 1, 3),
                                                ("Window", 1, 1, 4, 3)]


def test_rename_nests_one_region():
    layout = derive(grammar("X --> Y\nY --> A"), request(2, 2))
    assert layout.root.symbol == "X" and layout.root.children[0].symbol == "Y"
    assert layout.root.children[0].children[0].label == "a"


def test_terminal_attributes_and_transparent_label():
    g = parse('X --> split(x) { 1: T | 1: N }\nT --> terminal(window, depth: -0.25, material: glass)\n'
              'N --> terminal(none)')
    t, n = derive(g, request(2, 2)).terminals()
    assert (t.label, t.depth, t.material) == ("window", -0.25, "glass")
    assert n.label is None


def test_asset_resolved_relative_to_grammar_file(tmp_path):
    path = tmp_path / "sub" / "g.grammar"
    path.parent.mkdir()
    path.write_text('X --> terminal(window, asset: "../assets/w.usda")\n')
    assert derive(load(path), request(1, 1)).root.asset == str(tmp_path / "assets" / "w.usda")
    g = parse('X --> terminal(window, asset: "assets/w.usda")')  # not from a file: kept as written
    assert derive(g, request(1, 1)).root.asset == "assets/w.usda"


def test_zero_size_items_are_dropped():
    g = grammar("X --> split(x) { 0.5: A | '1: B | 0.5: A }")
    assert [s for s, *_ in leaves(derive(g, request(0.8, 1)))] == ["A", "A"]


# ---- floors and corner strips --------------------------------------------------------------------------------

FLOORS = "X --> floors { 0: A | -1: C | *: B }"


def test_floors_split_exactly_at_floor_lines():
    lines = (0.0, 4.0, 7.1, 10.2, 13.3)
    got = leaves(derive(grammar(FLOORS), request(10, 13.3, lines)))
    assert [(s, y, h) for s, _, y, _, h in got] == [("A", 0, 4), ("B", 4, 3.1), ("B", 7.1, 3.1), ("C", 10.2, 3.1)]


def test_floors_inside_a_band_are_clipped_and_keep_building_floor_indices():
    g = grammar("X --> split(y) { '1: F | 1: Wall }\nF --> floors { 0: A | -1: C | *: B }")
    got = leaves(derive(g, request(10, 9, (0.0, 3.0, 6.0, 9.0))))
    # the top floor keeps its selector (-1) although the band cuts it at y = 8
    assert [(s, y, h) for s, _, y, _, h in got] == [("A", 0, 3), ("B", 3, 3), ("C", 6, 2), ("Wall", 8, 1)]


def test_floor_variable_inside_slices():
    g = grammar("X --> floors { *: F }\nF --> case floor == 1: Window\n else: Wall")
    got = derive(grammar("X --> floors { *: F }\nF --> case floor == 1 and floor_count == 3: Window\n else: Wall"),
                 request(4, 9, (0.0, 3.0, 6.0, 9.0)))
    assert got.labels() == ["wall", "window", "wall"]
    assert derive(g, request(4, 9)).labels() == ["wall"]  # no floor lines: one floor


def test_corner_strips_are_walls_in_every_slice():
    r = request(10, 6, (0.0, 3.0, 6.0), corner_widths=(0.5, 0.8))
    got = leaves(derive(grammar(FLOORS), r))
    assert got == [("Corner", 0, 0, 0.5, 3), ("A", 0.5, 0, 8.7, 3), ("Corner", 9.2, 0, 0.8, 3),
                   ("Corner", 0, 3, 0.5, 3), ("C", 0.5, 3, 8.7, 3), ("Corner", 9.2, 3, 0.8, 3)]
    assert {t.label for t in derive(grammar(FLOORS), r).terminals() if t.symbol == "Corner"} == {"wall"}


def test_corner_strips_only_where_the_region_overlaps_them():
    g = grammar("X --> split(x) { 2: F | '1: Wall }\nF --> floors { *: A }")
    got = leaves(derive(g, request(10, 3, corner_widths=(0.5, 0.5))))
    assert got == [("Corner", 0, 0, 0.5, 3), ("A", 0.5, 0, 1.5, 3), ("Wall", 2, 0, 8, 3)]


def test_grammar_may_define_corner():
    g = grammar("X --> floors { *: A }\nCorner --> terminal(deco)")
    assert derive(g, request(4, 3, corner_widths=(1, 1))).labels() == ["deco", "a", "deco"]


def test_corner_strips_wider_than_face_are_scaled_to_half():
    got = leaves(derive(grammar(FLOORS), request(2, 3, corner_widths=(1.5, 1.5))))
    assert got == [("Corner", 0, 0, 0.5, 3), ("A", 0.5, 0, 1, 3), ("Corner", 1.5, 0, 0.5, 3)]


# ---- conditions ------------------------------------------------------------------------------------------------

LEVELS = "building:levels"


def conditional(cond: str):
    return grammar(f"X --> case {cond}: Window\n else: Wall")


@pytest.mark.parametrize(("cond", "kw", "label"), [
    ("width < 3", {}, "window"),
    ("height >= 3 and face_height == 3", {}, "window"),
    ("face_width > 2", {}, "window"),
    ("entrance", {"entrance": True}, "window"),
    ("entrance", {}, "wall"),
    ("not street", {}, "window"),
    ("street", {"context": FaceContext("b", 0, 4, street_facing=True)}, "window"),
    ("courtyard", {"context": FaceContext("b", 0, 4, is_courtyard=True)}, "window"),
    ("levels == 4 and floor == 0 and floor_count == 1", {"context": FaceContext("b", 0, 4)}, "window"),
    ('attr("building") == "church"', {"context": FaceContext("b", 0, 1, attributes={"building": "church"})}, "window"),
    ('attr("building:levels") >= 5', {"context": FaceContext("b", 0, 1, attributes={LEVELS: "6"})}, "window"),
    ('attr("building:levels") >= 5', {"context": FaceContext("b", 0, 1, attributes={LEVELS: "x"})}, "wall"),
    ('attr("building:levels") != 5', {"context": FaceContext("b", 0, 1, attributes={LEVELS: "x"})}, "window"),
    ('attr("missing") == ""', {}, "window"),
    ("(width + 0.5) * 2 / 4 == 1.5 and -width < 0 and 2 - 1 - 1 == 0", {}, "window"),
])
def test_condition_variables(cond, kw, label):
    assert derive(conditional(cond), request(2.5, 3, **kw)).labels() == [label]


def test_case_without_match_or_else_is_wall():
    g = parse("X --> case width > 100: Y\nY --> terminal(window)")
    assert derive(g, request(2, 2)).labels() == ["wall"]


def test_division_by_zero_names_the_rule():
    with pytest.raises(RulesetError, match="rule X"):
        derive(conditional("1 / (width - width) > 1"), request(2, 2))


def test_arithmetic_on_text_names_the_rule():
    with pytest.raises(RulesetError, match="rule X"):
        derive(conditional('attr("k") + 1 > 1'), request(2, 2, context=FaceContext("b", 0, 1, attributes={"k": "a"})))


# ---- stochastic rules --------------------------------------------------------------------------------------

CHOICE = "X --> repeat(x) { 1: Bay }\nBay --> {each}50%: Window\n else: Wall"


def labels_for(each: bool, seed: int) -> list[str]:
    g = grammar(CHOICE.replace("{each}", "each " if each else ""))
    return derive(g, request(40, 3, seed=(seed,))).labels()


def test_stochastic_rule_decided_once_per_face():
    for seed in range(10):
        assert len(set(labels_for(False, seed))) == 1
    assert {labels_for(False, seed)[0] for seed in range(20)} == {"window", "wall"}


def test_each_decides_per_region():
    labels = labels_for(True, 1)
    assert 5 < labels.count("window") < 35


def test_probabilities_are_honoured():
    g = grammar("X --> repeat(x) { 1: Bay }\nBay --> each 20%: Window 30%: Door\n else: Wall")
    labels = derive(g, request(3000, 3)).labels()
    assert labels.count("window") / 3000 == pytest.approx(0.2, abs=0.03)
    assert labels.count("door") / 3000 == pytest.approx(0.3, abs=0.03)


def test_rest_without_else_goes_to_first_alternative():
    g = grammar("X --> repeat(x) { 1: Bay }\nBay --> each 10%: Window")
    assert set(derive(g, request(50, 3)).labels()) == {"window"}


def test_derivation_is_deterministic_and_seeded():
    g = load(__import__("pathlib").Path(__file__).resolve().parents[2] / "rulesets" / "apartment.grammar")
    r = request(30, 18, (0.0, 4.0, 7.5, 11.0, 14.5, 18.0), entrance=True, seed=(7, 3))
    assert derive(g, r) == derive(g, r)
    seeds = {tuple(t.symbol for t in derive(g, replace(r, seed=(s,))).terminals()) for s in range(12)}
    assert len(seeds) > 1


# ---- limits ------------------------------------------------------------------------------------------------

def test_unbounded_recursion_names_the_rule():
    g = grammar("X --> split(x) { '1: X | '1: A }")
    with pytest.raises(RulesetError, match="rule X went deeper than"):
        derive(g, request(10, 3))


def test_conditional_rename_cycle_found_while_deriving():
    g = grammar("X --> case width > 1: Y\n else: A\nY --> X")
    with pytest.raises(RulesetError, match="rename cycle X --> Y --> X"):
        derive(g, request(10, 3))


def test_self_recursion_through_fallback_terminates():
    g = grammar("X --> split(x) { 2: Wall | '1: X }")
    layout = derive(g, request(9, 3))
    assert [round(t.w, 9) for t in layout.terminals()] == [2, 2, 2, 2, 1]
    assert check_partition(layout) == []


def test_region_limit_counts_every_region_of_copied_subtrees(monkeypatch):
    """Copies of a subtree derived once count all their regions, as if each were derived: a face of 10 bays of
    3 regions is 1 + 10 * 3 regions; one fewer allowed is an error, exactly that many is not."""
    derivation = importlib.import_module("citygen_split.derive")
    g = grammar("X --> repeat(x) { 1: Bay }\nBay --> split(y) { 1: A | '1: B }")
    assert "Bay" in g.translation_invariant
    monkeypatch.setattr(derivation, "MAX_REGIONS", 31)
    assert len(derive(g, request(10, 3)).terminals()) == 20
    monkeypatch.setattr(derivation, "MAX_REGIONS", 30)
    with pytest.raises(RulesetError, match="beyond 30 regions"):
        derive(g, request(10, 3))


def test_a_floor_condition_keeps_its_subtree_per_floor_and_the_rest_is_copied_across_floors():
    """Storeys of equal height share the subtrees no ``floor`` condition reaches (issue 24); a symbol that reads
    ``floor`` (and every symbol above it) is derived per floor, so its floors still differ."""
    g = grammar("X --> floors { *: Row }\nRow --> repeat(x) { 2: Bay }\nBay --> case floor == 1: Entry\n else: Win\n"
                "Entry --> terminal(door)\nWin --> split(y) { 1: Sill | '1: Glass }\nSill --> terminal(sill)\n"
                "Glass --> terminal(window)")
    assert g.floor_invariant >= {"Win", "Sill", "Glass", "Entry"} and not {"X", "Row", "Bay"} & g.floor_invariant
    assert {"Row", "Bay"} <= g.translation_invariant
    layout = derive(g, request(6, 9, (0.0, 3.0, 6.0, 9.0)))
    rows = [[t.label for t in layout.terminals() if lo <= t.y < lo + 3] for lo in (0.0, 3.0, 6.0)]
    assert rows == [["sill", "window"] * 3, ["door"] * 3, ["sill", "window"] * 3]
    assert check_partition(layout) == []


def test_subtrees_alike_on_every_face_share_their_key_across_the_faces_of_a_building():
    """A subtree no ``choice`` and no face variable reaches derives alike on every face, so its key (the module
    search's hint) is scoped by the grammar, not the face's seed: the search hashes it once per building (issue 24).
    A subtree reading ``entrance`` or drawing a ``choice`` keeps the face's own key, as does every subtree of a
    derivation with forced alternatives."""
    g = grammar("X --> split(x) { '1: Bay | '1: Deco }\nBay --> case entrance: Entry\n else: Win\n"
                "Deco --> 50%: Win\n else: Entry\nEntry --> terminal(door)\n"
                "Win --> split(y) { 1: Sill | '1: Glass }\nSill --> terminal(sill)\nGlass --> terminal(window)")
    assert g.face_invariant >= {"Win", "Sill", "Glass", "Entry"} and not {"X", "Bay", "Deco"} & g.face_invariant

    def keys(layout):
        bay, deco = layout.root.children
        return bay.key, deco.key, bay.children[0].key

    a, b = (derive(g, request(4, 3, seed=(s,))) for s in (1, 2))
    (bay_a, deco_a, win_a), (bay_b, deco_b, win_b) = keys(a), keys(b)
    assert win_a == win_b and bay_a != bay_b and deco_a != deco_b
    forced = keys(derive(g, request(4, 3, seed=(2,)), {("Deco", 0.0, 0.0): 1}))
    assert forced[2] != win_a


def test_non_positive_facade_is_an_error():
    with pytest.raises(RulesetError, match="not positive"):
        derive(grammar("X --> A"), request(0, 3))


# ---- explain -----------------------------------------------------------------------------------------------

DOOR = "X --> floors { 0: G | *: A }\nG --> case entrance: split(x) { '1: Wall | 1: Door | '1: Wall }\n else: Wall"


def test_explain_lists_the_tree_with_sizes_and_choices():
    g = grammar(DOOR)
    text = explain(g, request(5, 6, (0.0, 3.0, 6.0), entrance=True, corner_widths=(0.5, 0.5)))
    lines = text.splitlines()
    assert lines[0] == "X 5.000 x 6.000 at (0.000, 0.000): floors"
    assert "  G 4.000 x 3.000 at (0.500, 0.000): case 1: split(x)" in lines
    assert "    Door 1.000 x 3.000 at (2.000, 0.000): terminal door" in lines
    assert "  Corner 0.500 x 3.000 at (0.000, 0.000): corner strip, wall" in lines


def test_layout_meets_request_for_door_grammar():
    g = grammar(DOOR)
    r = request(5, 6, (0.0, 3.0, 6.0), entrance=True, corner_widths=(0.5, 0.5))
    assert check_request(derive(g, r), r) == []


def test_reused_subtrees_equal_a_full_derivation():
    from citygen_split.derive import _Derivation
    from .conftest import RULESETS
    for path in RULESETS:
        g = load(path)
        r = request(37.3, 21.1, (0.0, 4.2, 7.6, 11.0, 14.4, 17.8, 21.1), entrance=True, corner_widths=(0.3, 0.6),
                    seed=(5,))
        full = _Derivation(g, r, trace=True).run()  # tracing derives every region
        fast = derive(g, r)
        assert leaves(fast) == leaves(full) and fast.labels() == full.labels()


def test_place_keeps_equal_tiles_bit_identical():
    g = grammar("X --> repeat(x) { 0.7: A | '1: B }")
    widths = {t.w for t in derive(g, request(23.9, 3)).terminals()[:-2]}
    assert len(widths) == 2


def test_leaves_noted_while_deriving_are_the_trees_terminals():
    """The derivation hands the layout its terminals' arrays (fresh, copied, corner strips, dropped empty items;
    repeated subtrees are lazily moved copies): they are the tree's terminals, in tree order, bit for bit, for
    every shipped grammar and a tricky one."""
    from citygen.layout import _collect_leaves
    from .conftest import RULESETS
    tricky = grammar("X --> floors { 0: E | *: Bays }\nE --> split(x) { 5: A | '1: B }\n"
                     "Bays --> repeat(x) { ~2: Bay }\nBay --> split(x) { '1: A | 1: Win | '1: A }\n"
                     "Win --> split(y) { 1: C | '1: Window }")
    for g in [tricky, *map(load, RULESETS)]:
        r = request(23.3, 12.5, (0.0, 3.5, 6.5, 9.5, 12.5), entrance=True, corner_widths=(0.4, 0.7), seed=(3,))
        layout = derive(g, r)
        rects, (sources, index) = layout.leaf_rects, layout.leaf_sources  # (made by the derivation)
        walked: list = []
        _collect_leaves(layout.root, walked.append)
        assert len(layout.leaves) == len(walked) and all(map(operator.is_, layout.leaves, walked)), g.source
        # the arrays are the tree's terminals bit for bit; each terminal equals its source but for x and y
        assert rects.tobytes() == np.array([(r.x, r.y, r.w, r.h) for r in walked]).tobytes(), g.source
        assert all(replace(r, x=0.0, y=0.0) == replace(sources[i], x=0.0, y=0.0)
                   for r, i in zip(walked, index.tolist())), g.source
        assert layout.leaf_labels[1].tolist() == FacadeLayout(layout.width, layout.height,
                                                              layout.root).leaf_labels[1].tolist()
    layout = derive(grammar("X --> terminal(wall)"), request(4, 3))
    assert layout.leaves == (layout.root,)


def test_repeated_terminals_share_their_source():
    """A repeated terminal (a moved copy of the first one of its symbol, size and floor) shares that one's source in
    ``leaf_sources``: each source is the first terminal of its kind, so the checks map over the distinct
    terminals only (e.g. 71 instead of 150 per face of the synthetic city)."""
    from .conftest import RULESETS
    for g in map(load, RULESETS):
        r = request(31.7, 12.5, (0.0, 3.5, 6.5, 9.5, 12.5), entrance=True, seed=(4,))
        layout = derive(g, r)
        sources, index = layout.leaf_sources
        assert len(set(map(id, sources))) == len(sources) < len(layout.leaves), g.source
        _, first = np.unique(index, return_index=True)
        assert np.array_equal(index[np.sort(first)], np.arange(len(sources))), g.source  # (in tree order)
        assert all(layout.leaves[i] is sources[index[i]] for i in first.tolist()), g.source
