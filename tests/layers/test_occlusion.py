"""Occlusion of a layer's shapes by the visible shapes above (compose._occluded)."""
from citygen_layers.compose import _occluded

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
    assert _occluded(grids, [[[], [], [0], []], [[], [], [0], []]])[0] == {}
    # a shape no taller than the railing is covered by it
    assert _occluded([([(0.0, 1.0)], RAILING), grids[1]], [[[], [], [0], []], [[], [], [0], []]])[0] == {2: {0}}
