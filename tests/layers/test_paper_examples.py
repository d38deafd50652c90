"""The worked examples of ilcik2015 (§4, Fig. 7, Eq. 8, transparent splits)."""
from pathlib import Path

import numpy as np
import pytest

from citygen.layout import check_partition
from citygen.request import FacadeRequest, check_request
from citygen_layers.align import Budget, _Words, align
from citygen_layers.candidates import CandidateGenerator, direction_spec
from citygen_layers.model import Counter
from citygen_layers.parser import load, parse
from citygen_layers.facade import generate, solve_request

RULESETS = Path(__file__).resolve().parents[2] / "rulesets"


def _spec(rs, axis, canvas):
    counters = dict(rs.counters)
    counters["entrance"] = Counter("entrance", 0, 0)
    return direction_spec(rs, axis, canvas, counters)


def test_fig7_counting_and_sizing_candidates():
    rs = parse("symbol B size=3\nsymbol A size=2\nsymbol C size=1.3\ncounter k in 1..\ncounter s in 1..\n"
               "counter t in 1..\npattern P = e b^k e ; b := B\npattern R = A^s C^t A^s\nlayer l x=P y=R\n")
    gen = CandidateGenerator(rs, _spec(rs, "x", 10.0), mu=1.0)
    found = {}
    for k in (1, 2, 3):
        for word in gen.sized_words("P", gen.raw_words("P", {"k": k}), 9.0):
            found.setdefault(k, []).append(word[0].size)
    assert found == {1: [4.0, 3.0], 2: [2.0], 3: [1.0]}
    ygen = CandidateGenerator(rs, _spec(rs, "y", 10.0), mu=1.0)
    fits = {(s, t) for s in range(1, 4) for t in range(1, 8)
            if ygen.sized_words("R", ygen.raw_words("R", {"s": s, "t": t}), 9.0)}
    assert fits == {(1, 4), (1, 5), (2, 1), (2, 2)}



def test_regression_alternation_choices_in_lexicographic_order():
    """§5.1 enumerates alternation choices in lexicographic order; the words of a pattern were sorted by their
    distance to the canvas instead, so a second alternative that happened to sample nearer (here a window bay
    0.1 m off against a plain wall 0.4 m off) displaced the designer's first choice within one tolerance."""
    rs = parse("tolerance 0.5\nsymbol A size=1 opaque label=wall\nsymbol B size=1.5 opaque label=window\n"
               "pattern P = (A A A) | (A B A)\nlayer l x=P y=P\n")
    gen = CandidateGenerator(rs, _spec(rs, "x", 3.4), mu=0.5)
    words = gen.sized_words("P", gen.raw_words("P", {}), 2.9)
    assert ["".join(x.symbol for x in w) for w in words] == ["AAA", "ABA"]
    layout = generate(rs, FacadeRequest(3.4, 3.0, (0.0, 3.0), entrance=False))
    assert {r.label for r in layout.terminals() if r.label} == {"wall"}

def _ceca():
    rs = parse("symbol C size=1 opaque\nsymbol A size=1 opaque\nsymbol B size=1 opaque\n"
               "pattern T = c e c ; c := C\npattern L = A (B A)^2\nlayer low x=L y=L\nlayer top x=T y=L\n")
    spec = _spec(rs, "x", 5.0)
    cand = next(iter(CandidateGenerator(rs, spec, 0.5)))
    words = [cand.words[r.pattern] for r in spec.rows]
    above = np.array([[False, True], [False, False]])
    return words, above


def test_eq8_alignments_of_CeC_ABABA():
    words, above = _ceca()
    net = _Words(words, above)
    # (Ce C / ABA BA): an entry mixes transparent e with C -- rejected by transparent separation
    assert net.score(((0, 2), (0, 3))) is None
    # (C e C / eps ABABA eps): the lower layer makes space for the opaque C
    assert net.score(((0, 1), (0, 0))) is not None
    best = align(words, above, 5.0, 0.5, Budget(1000, 1e18))
    assert best.columns == (((0, 1), (0, 1)), ((1, 2), (1, 4)), ((2, 3), (4, 5)))   # Fig. 8's red path
    assert best.error == pytest.approx(0.0)



def test_column_phi_and_size_skip_epsilon_entries():
    """Phi (Eq. 9) and the column size are over the non-empty entries: epsilon is neither largest nor smallest."""
    net = _Words(*_ceca())
    assert net.score(((0, 1), (0, 0))) == (0.0, 1, 1.0)    # C over epsilon
    assert net.score(((0, 1), (0, 2))) == (1.0, 3, 2.0)    # C over AB

def test_transparent_split_fAf_CeC_ABABA():
    rs = parse("symbol A size=2 opaque\nsymbol B size=3 opaque\nsymbol C size=2\n"
               "pattern F = f a f ; a := A\npattern T = c e c ; c := C\npattern L = A (B A)^2\n"
               "layer low x=L y=L\nlayer mid x=T y=L\nlayer top x=F y=L\n")
    sx, _ = solve_request(rs, FacadeRequest(12.0, 12.0, (0.0, 12.0)))
    assert sx.status == "solved"
    (matrix,) = sx.matrices
    assert len(matrix.alignment.columns) == 5   # f and e split; Omega > 0 only from the sampled sizes
    assert sx.sizing.borders["main"] == pytest.approx((0, 2, 5, 7, 10, 12), abs=1e-3)


def test_section4_residential_house():
    rs = load(RULESETS / "residential_house.layers")
    request = FacadeRequest(6.0, 3.0, (0.0, 1.6, 3.0), entrance=False)
    layout = generate(rs, request)
    assert check_partition(layout) == [] and check_request(layout, request) == []
    assert [c.layer for c in layout.root.children] == ["basic", "windows", "columns", "entrance"]
    pillars = [r for r in layout.terminals() if r.label == "pillar"]
    assert len(pillars) == 2 and all(r.y == 0 and r.h == pytest.approx(1.6) for r in pillars)   # mask = P
    walls = [r for r in layout.terminals() if r.layer == "basic" and r.symbol == "A.P"]
    assert {round(p.x, 6) for p in pillars} <= {round(w.x, 6) for w in walls} | {0.0}   # C aligned with A
    assert layout.meta["status"] == {"x": "solved", "y": "solved"}


def test_regression_solve_leaves_no_reference_cycles():
    """The recursive closures of the depth-first search and of Eq. 7's bound referred to themselves, so each
    search's network (with its edge memo, tens of thousands of tuples) stayed alive until the cyclic collector
    ran -- which a request pauses, so its one collection at the end cost ~10 % of a 26-layer solve."""
    import dataclasses
    import gc

    from citygen_layers.facade import clear_solved

    rs = load(RULESETS / "tenement.layers")
    request = FacadeRequest.preview(16, 15, 3.0, 4.0)
    generate(rs, request)
    gc.collect()
    gc.disable()
    try:
        clear_solved()
        generate(rs, dataclasses.replace(request, corner_widths=(0.375, 0.375)))
        assert gc.collect() == 0
        words, above = _ceca()
        align(words, above, 5.0, 0.5, Budget(1000, 1e18))
        assert gc.collect() == 0
    finally:
        gc.enable()
