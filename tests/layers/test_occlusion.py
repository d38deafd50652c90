"""Occlusion of a layer's shapes by the visible shapes above (compose._occluded), and the cut of a shape partly
covered (``occlusion cut``)."""
from pathlib import Path

import pytest
from citygen_layers.compose import _occluded
from citygen_layers.facade import clear_solved, generate
from citygen_layers.parser import load, parse

from citygen.cli import facade_outcome
from citygen.layout import check_partition
from citygen.request import FacadeRequest
from tests import sweep

#: y spans of the terraced house at 8.5 x 19.5 m, 3 m storeys: a French window band and, above it, a railing band
LOW = 3.9999999999999982
WINDOW = [(0.0, 3.599999990249999), (3.599999990249999, 0.4000000097499994), (LOW, 2.399999889500007),
          (6.399999889500005, 0.7000001104999933)]
RAILING = [(0.0, 3.599999990249999), (3.599999990249999, 0.4000000097499994), (LOW, 1.199999958500002),
           (5.1999999585, 1.9000000414999985)]


def test_regression_a_window_behind_a_railing_is_not_occluded_at_a_rounding_half():
    """The French windows behind the terraced house's large balcony vanished: the railing's top 5.1999999585 is a
    rounding half at 9 decimals; the cut list was rounded by numpy (5.199999958), the look-ups by Python
    (5.199999959), so the railing's cells ran to the next cut, the window's top, and covered the whole window."""
    grids = [([(0.0, 1.0)], WINDOW), ([(0.0, 1.0)], RAILING)]
    assert _occluded(grids, [[[], [], [0], []], [[], [], [0], []]])[0][0] == {}
    # a shape no taller than the railing is covered by it
    assert _occluded([([(0.0, 1.0)], RAILING), grids[1]], [[[], [], [0], []], [[], [], [0], []]])[0][0] == {2: {0}}


def test_a_partly_covered_shape_is_cut_to_its_uncovered_pieces():
    """One 2 x 3 m wall cell under a 1 x 1 m window in its middle: nine fine cells, the centre covered; the cut
    gives the rows below and above whole and the middle row as wall | hidden | wall."""
    grids = [([(0.0, 2.0)], [(0.0, 3.0)]), ([(0.0, 0.5), (0.5, 1.0), (1.5, 0.5)], [(0.0, 1.0), (1.0, 1.0), (2.0, 1.0)])]
    covered, parts = _occluded(grids, [[[0]], [[], [1], []]], cut=True)
    assert covered[0] == {} and list(parts[0]) == [0] and list(parts[0][0]) == [0]
    assert parts[0][0][0] == [(0.0, 0.0, 2.0, 1.0, True), (0.0, 1.0, 0.5, 1.0, True), (0.5, 1.0, 1.0, 1.0, False),
                              (1.5, 1.0, 0.5, 1.0, True), (0.0, 2.0, 2.0, 1.0, True)]
    assert _occluded(grids, [[[0]], [[], [1], []]])[1] == [{}, {}]          # without the cut: kept whole


STACK = """
{occlusion}
symbol A size=1 opaque label=wall
symbol B size=1.2 opaque label=wall
symbol P size=3 opaque
symbol V size=1
symbol F size=1.4 label=window
symbol H size=0.6
counter k in 1..
counter n in 0..
pattern Bx = A (B A)^k
pattern By = P^n
pattern Wx = A (w A)^k ; w := B
pattern Wy = (q)^n ; q := V F H
layer basic x=Bx y=By
layer windows x=Wx y=Wy mask=F
floors basic
shape B F label=window
"""


@pytest.mark.parametrize("occlusion, in_front", [("", True), ("occlusion cut", False)])
def test_regression_a_lower_wall_stands_in_front_of_an_upper_window_unless_cut(occlusion, in_front):
    """A stack written without hiding the lower layer by hand: the basic layer's bay wall (at the wall plane) stood
    in front of the windows layer's recessed window in 3-D. With ``occlusion cut`` the bay wall is cut around the
    window: sill and head pieces stay wall, the window alone shows, the layer still tiles the face."""
    clear_solved()
    request = FacadeRequest.preview(5.0, 6.0, floor_height=3.0, ground_height=3.0, entrance=False)
    layout = generate(parse(STACK.format(occlusion=occlusion), "cut.layers"), request)
    assert facade_outcome(layout, request) == ("dressed", []) and check_partition(layout) == []
    windows = [r for r in layout.leaves if r.label == "window"]
    walls = [r for r in layout.leaves if r.layer == "basic" and r.label == "wall"]
    assert windows
    front = [(w, v) for w in walls for v in windows if w.depth > v.depth
             and min(w.x + w.w, v.x + v.w) - max(w.x, v.x) > 1e-6 and min(w.y + w.h, v.y + v.h) - max(w.y, v.y) > 1e-6]
    assert bool(front) == in_front
    if not in_front:     # the bay's sill and head pieces stay wall: with the windows they fill the bay's column
        column = [r for r in walls + windows if abs(r.x - windows[0].x) < 1e-6 and abs(r.w - windows[0].w) < 1e-6]
        assert sum(r.h for r in column) == pytest.approx(6.0) and len(column) == 3 * 2


@pytest.mark.parametrize("name", ["residential_house.layers", "terraced_house.layers", "tenement.layers"])
@pytest.mark.parametrize("width,height,storey", [(2.4, 9.0, 3.0), (6.0, 12.0, 2.6), (13.7, 19.5, 3.6)])
def test_shipped_stacks_composite_and_no_wall_stands_in_front_of_a_window(name, width, height, storey):
    """The shipped stacks composite (occlusion cut) instead of hiding a lower layer's cells with visible=false
    (the residential house's window bays, the terraced house's storey cells, the tenement's wall-layer bays)."""
    rs = load(Path(__file__).resolve().parents[2] / "rulesets" / name)
    hidden_by_hand = {("B", "P"), ("B", "Q"), ("W", "S"), ("B", "S"), ("B", "T"), ("W", "G"), ("W", "R")}
    assert rs.cut and not [s for s in rs.shapes if s.visible is False and (s.h, s.v) in hidden_by_hand]
    clear_solved()
    request = sweep.request(width, height, storey)
    layout = generate(rs, request)
    assert facade_outcome(layout, request) == ("dressed", [])
    order = [c.layer for c in layout.root.children]
    terms = [r for r in layout.leaves if r.label]
    assert not [(a, b) for a in terms for b in terms if b.label in ("window", "door", "shop")
                and order.index(a.layer) < order.index(b.layer) and a.depth > b.depth
                and min(a.x + a.w, b.x + b.w) - max(a.x, b.x) > 1e-6
                and min(a.y + a.h, b.y + b.h) - max(a.y, b.y) > 1e-6]
