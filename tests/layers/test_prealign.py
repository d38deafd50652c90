"""Prealignment of the control patterns (§5.2 heuristic, ``budget prealign=true``)."""
import dataclasses
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from citygen.layout import check_partition
from citygen.plausible import check_plausible
from citygen.request import FacadeRequest, check_request
from citygen_layers.align import Budget
from citygen_layers.candidates import CandidateGenerator, direction_spec
from citygen_layers.model import Counter
from citygen_layers.parser import ParseError, load, parse
from citygen_layers.facade import clear_solved, generate, solve_request
from citygen_layers.prealign import Prealigner
from citygen_layers.solver import align_candidate
from citygen_layers.words import control_words

ROOT = Path(__file__).resolve().parents[2]
STACKS = [ROOT / "rulesets" / f"{n}.layers" for n in ("residential_house", "terraced_house", "tenement")] + \
    [ROOT / "benchmarks" / "data" / "layers" / f"{n}.layers" for n in ("tonhalle26", "underconstrained")]
#: a tall facade: a substituted storey pattern (three letters per storey) against a plain one
TALL = """symbol P size=3.0 opaque
symbol Q size=2.6 opaque
symbol A size=0.9 opaque
symbol D size=1.1
symbol E size=0.3
symbol F size=0.7
counter n in 0..
budget expansions=3000 time=120
pattern X = A
pattern Y0 = P Q^n
pattern Y1 = P (s)^n ; s := E F D
layer base x=X y=Y0
layer l0 x=X y=Y1
"""


def prealigned(rs, on=True):
    return dataclasses.replace(rs, options=dataclasses.replace(rs.options, prealign=on))


def test_budget_line_parses_prealign():
    assert parse(TALL).options.prealign is False
    assert parse(TALL.replace("time=120", "time=120 prealign=true")).options.prealign is True
    with pytest.raises(ParseError, match="true or false"):
        parse(TALL.replace("time=120", "time=120 prealign=yes"))


def test_control_words_map_words_to_control_letters():
    rs = parse(TALL)
    table = control_words(rs.patterns["Y1"], {"n": 2}, rs.symbols)
    word = (("P", False, True),) + tuple((s, False, False) for s in ("E", "F", "D", "E", "F", "D"))
    control, starts = table[word]
    assert [name for name, _, _ in control] == ["P", "s", "s"] and starts == (0, 1, 4, 7)
    reflected = parse(TALL.replace("(s)^n", "(s)^-n"))
    control, starts = control_words(reflected.patterns["Y1"], {"n": 1}, rs.symbols)[
        (("P", False, True), ("D", True, False), ("F", True, False), ("E", True, False))]
    assert control[1] == ("s", True, False) and starts == (0, 1, 4)


@pytest.mark.parametrize("height", [13.0, 16.0])
def test_prealignment_reduces_expansions_on_a_tall_substituted_stack(height):
    rs = parse(TALL)
    request = FacadeRequest(4.0, height, (0.0, height))
    clear_solved()
    off = solve_request(rs, request)[1]
    clear_solved()
    on = solve_request(prealigned(rs), request)[1]
    assert off.status == on.status == "solved"
    assert on.expansions < 0.8 * off.expansions                    # 42 -> 31 and 59 -> 40
    assert max(m.alignment.error for m in on.matrices) <= on.mu + 1e-9
    assert any("prealignment restricted" in d for d in on.diagnostics)


@pytest.mark.parametrize("path", STACKS, ids=lambda p: p.stem)
def test_option_off_is_the_default_solver(path):
    """Off unless the file asks for it (the shipped stacks do: it fences their storeys' bands, test_storeys.py);
    the benchmark stacks do not."""
    rs = load(path)
    request = FacadeRequest.preview(14, 13, 3.0, 4.0)
    clear_solved()
    default = generate(rs, request).to_json()
    clear_solved()
    assert generate(prealigned(rs, rs.options.prealign), request).to_json() == default
    assert ("prealignment" in str(default)) == rs.options.prealign == \
        (path.stem in ("residential_house", "terraced_house", "tenement"))


@pytest.mark.parametrize("path", STACKS, ids=lambda p: p.stem)
@settings(max_examples=4, deadline=None)
@given(width=st.floats(4.0, 30.0), height=st.floats(4.0, 24.0), entrance=st.booleans())
def test_prealigned_layouts_partition_and_honour_requests(path, width, height, entrance):
    rs = prealigned(load(path))
    request = FacadeRequest.preview(width, height, floor_height=3.0, ground_height=4.0, entrance=entrance)
    layout = generate(rs, request)
    assert check_partition(layout) == []
    assert check_request(layout, request) == []     # a plain wall (fall-back) carries the entrance too
    if not layout.meta.get("fallback"):
        assert check_plausible(layout, request) == []


class _Blocking(Prealigner):
    """A prealigner whose columns admit no alignment: the first one holds one letter of the upper word and all
    but one letter of the lower word."""

    def fence(self, patterns, env, words, split, parents, above, canvas, mu, budget):
        return [(1, len(split[1]) - 1), tuple(len(w) for w in split)]


def test_regression_restricted_search_without_result_falls_back_to_the_exact_search():
    rs = parse(TALL)
    counters = dict(rs.counters, entrance=Counter("entrance", 0, 0))
    spec = direction_spec(rs, "y", 16.0, counters)
    candidate = next(c for c in CandidateGenerator(rs, spec, 3.2) if len(c.words["Y0"]) > 3)
    exact = align_candidate(candidate, spec, 3.2, Budget(3000, 1e18))
    blocking = _Blocking(rs)
    fallback = align_candidate(candidate, spec, 3.2, Budget(3000, 1e18), prealigner=blocking)
    assert blocking.restricted == 1 and blocking.fallbacks == 1
    assert exact is not None and [m.alignment for m in fallback] == [m.alignment for m in exact]
