"""Named regression tests for bugs found while building the relayout."""
from __future__ import annotations

from citygen_relayout import parse_model, relayout, validate
from citygen_relayout.sequences import CoverAutomaton

REPLICAS = """model replicas
root F 4 6
split F y Row:2 Row:2 Row:2
split Row x Cell:2 Cell:2
split Cell y Glass:2
terminal Glass window
repeat F : Row+
"""


def test_replica_popped_before_its_source_is_laid_out():
    # composite children are pushed in random order: the first one popped must become the replica source
    # (used to raise KeyError when a later sibling had been registered as the source first)
    model = parse_model(REPLICAS, "replicas.relayout")
    for seed in range(30):
        result = relayout(model, 4.0, 6.0, seed=seed)
        assert result.success and validate(result.layout, model) == []


def test_reverse_automaton_reads_the_mirrored_right_end_once():
    # the right end of a symmetric region was mirrored twice (sequences and symbols), so no symmetric region
    # with a mirror pair at its ends could be laid out
    from citygen_relayout.model import BEGIN, END
    auto = CoverAutomaton([(frozenset({BEGIN}), frozenset({"P"}), frozenset({"W"})),
                           (frozenset({"W"}), frozenset({"Q"}), frozenset({END}))])
    rev = auto.reversed()
    state = rev.step(rev.start, "Q")  # the actual right-most symbol is Q = mirror(P)
    assert state is not None and rev.step(state, "W") is not None


def test_backjump_keeps_the_replica_source_of_the_retried_frame():
    # undoing a frame to retry it also removed its registration as replica source, so a later sibling became
    # a second, different "source" and replicas diverged
    text = REPLICAS.replace("repeat F : Row+", "repeat F : Row+\nalign Cell.min = Cell.min\nsize Cell 0.5..3.5")
    model = parse_model(text, "replicas.relayout")
    for seed in range(30):
        result = relayout(model, 5.0, 7.0, seed=seed)
        assert result.success and validate(result.layout, model) == []


def test_alignment_between_rows_with_independent_gaps():
    # windows of two rows with different counts: every overlapping pair is centred (exercises backtracking
    # over elements whose provisional positions come from the previous QP solution)
    text = """model stale
root F 6 4
split F y A:2 B:2
split A x W:1 X:1 W:1 X:1 W:1 X:1
split B x V:2 Y:2 V:2
terminal W wall
terminal V wall
terminal X window
terminal Y window
repeat A : W (X W)* X
repeat B : V (Y V)*
size W 0.3..3
size V 0.3..4
align X.center = Y.center
instances A W 1..6
instances B V 1..6
"""
    model = parse_model(text, "stale.relayout")
    for seed in range(40):
        result = relayout(model, 6.0 + seed % 7, 4.0, seed=seed)
        assert result.success, result.message
        assert validate(result.layout, model) == []
