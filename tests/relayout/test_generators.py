"""Sequence generators and the cover automaton against the paper's §5.2 / §6 examples."""
from __future__ import annotations

from citygen_relayout.generators import Node, repetition, replication, two_shuffle
from citygen_relayout.model import BEGIN, END
from citygen_relayout.sequences import CoverAutomaton

B, E = frozenset({BEGIN}), frozenset({END})


def f(*names):
    return frozenset(names)


def item(*names):
    return Node("item", item=f(*names))


def as_text(seqs):
    return sorted(" ".join("⊢" if i == B else "⊣" if i == E else "{" + ",".join(sorted(i)) + "}" for i in s)
                  for s in seqs)


def test_repetition_optional_c_gives_the_papers_sequences():
    # §6: "by selecting C as optional, the repetition generator creates ⊢CD, ⊢D, DC⊣, D⊣"
    pattern = Node("seq", parts=(Node("?", parts=(item("C"),)), item("D"), Node("?", parts=(item("C"),))))
    assert as_text(repetition(pattern)) == sorted(["⊢ {C} {D}", "⊢ {D}", "{D} {C} ⊣", "{D} ⊣"])


def test_two_shuffle_gives_the_papers_pairs():
    # §6: GH···HG with I and J gives GH, HG, HI, IH, HJ, JH
    seqs = two_shuffle((f("G"), f("H"), f("I"), f("H"), f("J"), f("H"), f("G")))
    assert sorted("".join(next(iter(i)) for i in s) for s in seqs) == sorted(["GH", "HG", "HI", "IH", "HJ", "JH"])


def test_replication_is_the_input_with_tokens():
    assert replication((f("A"), f("B"))) == [(B, f("A"), f("B"), E)]


def test_repetition_language_of_side_ornaments_is_exact():
    # E = O (P Q R) (S P Q R)* T : one or more PQR separated by S, embraced by O and T (§6)
    pqr = (item("P"), item("Q"), item("R"))
    pattern = Node("seq", parts=(item("O"), *pqr, Node("*", parts=(Node("seq", parts=(item("S"), *pqr)),)), item("T")))
    auto = CoverAutomaton(repetition(pattern))
    assert auto.accepts("OPQRT")
    assert auto.accepts("OPQRSPQRSPQRT")
    assert not auto.accepts("OT")
    assert not auto.accepts("OPQRST")
    assert not auto.accepts("OPQRPQRT")


def test_space_m_repetition_accepts_zero_or_more_ornaments():
    space = item("L", "N")
    pattern = Node("seq", parts=(space, Node("*", parts=(Node("seq", parts=(item("M"), space)),))))
    auto = CoverAutomaton(repetition(pattern))
    for word in ("L", "N", "LML", "NMLMN"):
        assert auto.accepts(word), word
    for word in ("", "M", "LM", "LL", "MLM"):
        assert not auto.accepts(word), word


def test_cover_needs_overlapping_instantiations():
    # Fig. 4 style: sequences overlap in at least one subregion
    auto = CoverAutomaton([(B, f("A"), f("B")), (f("B"), f("C"), E)])
    assert auto.accepts("ABC")
    assert not auto.accepts("AB")  # nothing covers B⊣
    two = CoverAutomaton([(B, f("A")), (f("B"), E)])
    assert not two.accepts("AB")  # adjacent but not overlapping


def test_successor_set_comes_from_prefixes_overlapping_the_postfix():
    auto = CoverAutomaton(two_shuffle((f("G"), f("H"), f("J"))) + [(B, f("G")), (f("G"), E)])
    state = auto.step(auto.start, "G")
    assert auto.candidates(state) == {"H", END}
    state = auto.step(state, "H")
    assert auto.candidates(state) == {"G", "J"}
