"""The house stacks on the 1.3-4 m faces a real city gives them (a house's narrow side, a bay's cheek, a jog in a
terrace): one window column per storey with wall on both sides, the entrance's door in it, and a fall-back where
not even that fits."""
import dataclasses
from pathlib import Path

import numpy as np
import pytest
from citygen_layers.facade import clear_solved, generate
from citygen_layers.parser import load

from citygen.cli import facade_outcome
from tests import sweep

RULESETS = Path(__file__).resolve().parents[2] / "rulesets"


def layout_of(name, width, height, storey, entrance=True):
    clear_solved()
    request = dataclasses.replace(sweep.request(width, height, storey), entrance=entrance)
    layout = generate(load(RULESETS / name), request)
    return layout, request


def storey_of(request, region):
    return int(np.searchsorted(np.asarray(request.floor_lines), region.y + region.h / 2)) - 1


@pytest.mark.parametrize("width", [1.4, 2.0, 2.4, 3.0])
@pytest.mark.parametrize("height,storey", [(4.5, 3.0), (9.0, 2.6), (12.0, 3.6)])
@pytest.mark.parametrize("entrance", [True, False])
def test_regression_residential_house_narrow_face_is_one_window_column(width, height, storey, entrance):
    """All 78 full-grid faces of 2-3 m fell back: the ground-floor pillars (declared 0.4 m, but always drawn as
    wide as the 0.8 m wall they stand on) never aligned with a one-bay face's walls, and without the entrance the
    door layer's two placeholders needed a column border inside the window bay."""
    layout, request = layout_of("residential_house.layers", width, height, storey, entrance)
    assert facade_outcome(layout, request) == ("dressed", [])
    openings = [r for r in layout.leaves if r.label in ("window", "door")]
    walls = 0.8 / 3                                                    # the wall A at a third of its size
    for r in openings:
        assert r.x >= walls - 1e-6 and r.x + r.w <= width - walls + 1e-6          # wall on both sides
    upper = [r for r in openings if r.label == "window" and storey_of(request, r) > 0]
    assert len(upper) == len(request.floor_lines) - 2                              # one window a storey
    doors = [r for r in openings if r.label == "door"]
    assert len(doors) == int(entrance) and all(d.w >= 0.7 for d in doors)
    assert len([r for r in layout.leaves if r.label == "pillar"]) == 2             # the ground floor keeps its pillars


@pytest.mark.parametrize("width", [1.0, 1.2])
def test_residential_house_entrance_face_too_narrow_for_a_door_falls_back(width):
    layout, request = layout_of("residential_house.layers", width, 9.0, 3.0)
    assert facade_outcome(layout, request)[0] == "fell-back"


@pytest.mark.parametrize("width", [1.4, 2.0, 2.4, 3.0, 4.0])
@pytest.mark.parametrize("height,storey", [(4.5, 3.0), (9.0, 2.6), (13.5, 3.0), (19.5, 3.6)])
@pytest.mark.parametrize("entrance", [True, False])
def test_regression_terraced_house_narrow_face_is_one_window_column(width, height, storey, entrance):
    """All 78 full-grid faces of 2-3 m fell back: the stack's narrowest word was one bay (W Q B W, 6.25 m with its
    margins). The alternation 'bays | one window block' (tried in that order) dresses them: per storey one window
    block W with the wall margins M beside it, the ground floor's shop window or the door, no balcony."""
    layout, request = layout_of("terraced_house.layers", width, height, storey, entrance)
    assert facade_outcome(layout, request) == ("dressed", [])
    assert layout.meta["counters"]["j"] == 0
    margin = 0.5 / 3                                                    # the wall margin M at a third of its size
    openings = [r for r in layout.leaves if r.label in ("window", "door", "shop")]
    for r in openings:
        assert r.x >= margin - 1e-6 and r.x + r.w <= width - margin + 1e-6
        assert r.w <= width - 2 * margin + 1e-6
    assert not [r for r in layout.leaves if r.label in ("balcony", "pillar")]
    storeys = {storey_of(request, r) for r in openings if r.label == "window"}
    assert storeys == set(range(1, len(request.floor_lines) - 1)) or len(request.floor_lines) == 2
    assert len([r for r in openings if r.label == "door"]) == int(entrance)


def test_terraced_house_keeps_its_bays_where_they_fit():
    """The narrow variant is the second alternative: from 5 m on the face is bays and balconies as before."""
    for width in (5.0, 5.5, 8.5, 14.0):
        layout, request = layout_of("terraced_house.layers", width, 9.0, 3.0)
        assert facade_outcome(layout, request) == ("dressed", [])
        assert [r for r in layout.leaves if r.label == "balcony"]


def test_terraced_house_face_too_narrow_for_a_window_block_falls_back():
    layout, request = layout_of("terraced_house.layers", 1.0, 9.0, 3.0, entrance=False)
    assert facade_outcome(layout, request)[0] == "fell-back"


@pytest.mark.parametrize("width", [2.4, 3.2, 4.0])
@pytest.mark.parametrize("height,storey", [(7.0, 3.5), (7.0, 3.0), (10.0, 3.3)])
def test_regression_terraced_house_narrow_face_glazes_its_terrace_storey(width, height, storey):
    """The narrow variant was the window block W, which the bays leave blank on the terrace storey (glazed over
    the balcony blocks B only): a two-storey narrow face had a blank upper storey. Its block V is glazed there."""
    layout, request = layout_of("terraced_house.layers", width, height, storey, entrance=False)
    assert facade_outcome(layout, request) == ("dressed", [])
    top = len(request.floor_lines) - 2
    assert [r for r in layout.leaves if r.label == "window" and storey_of(request, r) == top]
