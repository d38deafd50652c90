"""Size-independent grammars on any face (wu2014 §5), alignment at new sizes (Fig. 12) and readable names."""
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import citygen_split
from citygen.coordinator import plan_floor_lines
from citygen.layout import FacadeLayout, Region, check_partition
from citygen.plausible import check_plausible
from citygen.request import FaceContext, FacadeRequest, check_request
from citygen.scene import Defaults
from citygen_inverse.cmp import import_cmp
from citygen_inverse.extract import extract_grammar
from citygen_inverse.independent import extract_size_independent
from citygen_inverse.slabs import floor_cuts, slab_layouts

from .helpers import assert_reproduces, random_layout
from .test_extract import regular_facade

DATA = Path(__file__).resolve().parents[1] / "data" / "inverse"


@cache
def cmp_layout(name: str = "cmp_b0002") -> FacadeLayout:
    return import_cmp(DATA / f"{name}.xml")


@cache
def grammar(which: str):
    layout = {"cmp": cmp_layout, "regular": regular_facade,
              "random": lambda: random_layout(np.random.default_rng(7))}[which]()
    result = extract_size_independent(layout, "adp", 30, seed=1)
    return layout, result, citygen_split.parse(result.text, f"{which}.grammar")


def request(width, height, levels=None, entrance=True, corner=0.0, seed=0):
    lines = plan_floor_lines(height, levels, Defaults())
    return FacadeRequest(width=width, height=height, floor_lines=lines, entrance=entrance,
                         corner_widths=(min(corner, 0.15 * width),) * 2,
                         context=FaceContext("b", 0, len(lines) - 1, street_facing=True), seed=(seed, "b", 0))


# ---- readable names ------------------------------------------------------------------------------------------
def test_terminals_are_named_by_label_and_cost_is_unchanged():
    layout = regular_facade()
    result = extract_grammar(layout, "adp", 50, seed=0)
    g = citygen_split.parse(result.text, "t")
    terminals = {r.symbol for r in g.rules if type(r.body).__name__ == "Terminal"}
    assert terminals == {"Wall", "Window"}
    assert citygen_split.grammar_cost(g) == pytest.approx(result.cost)
    assert_reproduces(result.text, layout)


def test_second_kind_of_a_label_gets_a_number_and_reserved_names_are_avoided():
    ts = (Region(0, 0, 1, 2, "a", "window", depth=-0.25), Region(1, 0, 1, 2, "b", "window", depth=-0.1),
          Region(2, 0, 1, 2, "c", "facade"), Region(3, 0, 1, 2, "d", "corner"), Region(4, 0, 1, 2, "e", "wall"))
    layout = FacadeLayout(5, 2, Region(0, 0, 5, 2, "F", children=ts))
    result = extract_grammar(layout, "greedy")
    g = citygen_split.parse(result.text, "t")
    terminals = {r.symbol: r.body.label for r in g.rules if type(r.body).__name__ == "Terminal"}
    assert terminals == {"Window": "window", "Window2": "window", "Facade2": "facade", "Corner2": "corner",
                         "Wall": "wall"}
    assert_reproduces(result.text, layout)


# ---- floor slabs ---------------------------------------------------------------------------------------------
def test_regular_facade_is_cut_between_its_window_rows():
    layout = regular_facade(floors=5)
    cuts = floor_cuts(layout)
    assert len(cuts) == 4
    windows = [(t.y, t.y + t.h) for t in layout.terminals() if t.label == "window"]
    assert not any(a < c < b for c in cuts for a, b in windows)


def test_slabs_have_one_door_in_the_entrance_variant_and_none_elsewhere():
    slabs, names = slab_layouts(cmp_layout())
    assert names[:2] == ["GroundDoor", "Ground"] and names[-1] == "Top"
    doors = [slab.count("door") for slab in slabs]
    assert doors[0] == 1 and sum(doors[1:]) == 0
    assert all(check_partition(s) == [] for s in slabs)


def test_a_door_is_carved_when_the_ground_has_none():
    """Regression: a facade without any door still gives a grammar with a door on entrance faces."""
    layout = regular_facade()
    assert layout.count("door") == 0
    slabs, _ = slab_layouts(layout)
    assert slabs[0].count("door") == 1 and check_partition(slabs[0]) == []


def test_reproduces_the_input_on_its_own_floor_lines():
    layout = cmp_layout()
    _, result, g = grammar("cmp")
    lines = (0.0, *floor_cuts(layout), layout.height)
    req = FacadeRequest(layout.width, layout.height, lines, entrance=True)
    out = citygen_split.derive(g, req)
    got = sorted((round(t.x, 6), round(t.y, 6), round(t.w, 6), round(t.h, 6), t.label) for t in out.terminals())
    want = sorted((round(t.x, 6), round(t.y, 6), round(t.w, 6), round(t.h, 6), t.label)
                  for t in layout.terminals())
    assert got == want  # cmp_b0002 has one door: nothing is relabelled
    assert citygen_split.grammar_cost(g) == pytest.approx(result.cost)


# ---- the FacadeRequest contract on any face ------------------------------------------------------------------
@pytest.mark.parametrize("which", ["cmp", "regular", "random"])
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(width=st.floats(0.3, 60.0), height=st.floats(1.0, 45.0), levels=st.one_of(st.none(), st.integers(1, 14)),
       entrance=st.booleans(), corner=st.floats(0.0, 0.8))
def test_any_face_meets_the_request(which, width, height, levels, entrance, corner):
    _, _, g = grammar(which)
    req = request(width, height, levels, entrance, corner)
    out = citygen_split.derive(g, req)
    assert check_partition(out) == []
    assert check_request(out, req) == []


@pytest.mark.parametrize("size", [(12.0, 10.0), (3.0, 3.0), (33.0, 24.0)])
def test_preview_requests(size):
    _, _, g = grammar("cmp")
    for entrance in (True, False):
        req = FacadeRequest.preview(*size, entrance=entrance)
        out = citygen_split.derive(g, req)
        assert check_partition(out) == [] and check_request(out, req) == []


# ---- alignment at new sizes (wu2014 Fig. 12) -----------------------------------------------------------------
def _distinct(values, tol=1e-6):
    values = np.sort(np.asarray(values, dtype=float))
    if values.size == 0:
        return values
    return values[np.concatenate([[True], np.diff(values) > tol])]


@pytest.mark.parametrize("width,height,levels", [(14.0, 12.0, 4), (26.0, 18.0, 6), (6.0, 30.0, 9)])
def test_window_columns_stay_aligned_across_floors(width, height, levels):
    layout, _, g = grammar("cmp")
    corner = 0.4
    req = request(width, height, levels, entrance=True, corner=corner)
    out = citygen_split.derive(g, req)
    middle = width - 2 * corner
    n = max(1, round(middle / layout.width))
    scale = middle / n / layout.width
    columns = _distinct([t.x for t in layout.terminals() if t.label in ("window", "door")])
    expected = np.concatenate([corner + k * middle / n + columns * scale for k in range(n)])
    got = [t.x for t in out.terminals() if t.label in ("window", "door")]
    err = np.min(np.abs(np.asarray(got)[:, None] - expected[None, :]), axis=1)
    assert err.max() < 1e-6  # every opening starts on a column line of the input, on every floor
    assert len(_distinct(got)) <= len(expected)


@pytest.mark.parametrize("width", [1.0, 2.0, 3.0, 4.0])
@pytest.mark.parametrize("entrance", [False, True])
def test_narrow_faces_get_one_centred_opening_per_floor(width, entrance):
    """Faces under half the input width: no squeezed tile, at most one opening per floor at its input width,
    centred on the face (so the openings of all floors share one axis); the entrance keeps its door."""
    layout, _, g = grammar("cmp")
    assert width < 0.5 * layout.width
    req = request(width, 15.0, 5, entrance=entrance)
    out = citygen_split.derive(g, req)
    assert check_partition(out) == [] and check_request(out, req) == []
    sizes = {round(t.w, 6) for t in layout.terminals()}
    lines = req.floor_lines
    for lo, hi in zip(lines, lines[1:]):
        openings = [t for t in out.terminals() if t.label in ("window", "door", "shop") and lo - 1e-9 <= t.y < hi - 1e-9]
        assert len(openings) <= 1
        for t in openings:
            assert abs(t.x + 0.5 * t.w - 0.5 * width) < 1e-9
            assert round(t.w, 6) in sizes or t.label == "door"


@pytest.mark.parametrize("width,height,levels", [(14.0, 12.0, 4), (26.0, 18.0, 6)])
def test_window_rows_stay_aligned_within_each_floor(width, height, levels):
    layout, _, g = grammar("cmp")
    req = request(width, height, levels)
    out = citygen_split.derive(g, req)
    slabs, _ = slab_layouts(layout)
    most = max(len(_distinct([t.y for t in s.terminals() if t.label == "window"])) for s in slabs)
    lines = req.floor_lines
    for lo, hi in zip(lines, lines[1:]):
        ys = [t.y for t in out.terminals() if t.label == "window" and lo - 1e-9 <= t.y < hi - 1e-9]
        assert len(_distinct(ys)) <= most  # siblings aligned in the input share their bottom edge


def test_wider_faces_get_more_bays_not_wider_windows():
    layout, _, g = grammar("cmp")
    narrow = citygen_split.derive(g, request(layout.width, 12.0, 4))
    wide = citygen_split.derive(g, request(4 * layout.width, 12.0, 4))
    w0 = min(t.w for t in narrow.terminals() if t.label == "window")
    w1 = min(t.w for t in wide.terminals() if t.label == "window")
    assert w1 == pytest.approx(w0, rel=1e-6)  # a relative-only grammar would make them 4x wider
    assert wide.count("window") > 3 * narrow.count("window")
    assert wide.count("door") == 1


# ---- issue 21: storeys kept, carved doors of a door's size ---------------------------------------------------
def test_every_row_of_openings_gets_its_own_slab_even_where_pilasters_cross_storeys():
    """Regression (issue 21): cmp_b0009's pillars span three window storeys, so no line cut them apart and one
    slab of 17 m was squeezed into one storey (balconies 0.14 m tall at 20 x 12 m, two storeys lost)."""
    layout = cmp_layout("cmp_b0009")
    rows = []
    for a, b in sorted((t.y, t.y + t.h) for t in layout.terminals() if t.label in ("window", "door", "shop")):
        if rows and a < rows[-1][1] - 1e-9:
            rows[-1][1] = max(rows[-1][1], b)
        else:
            rows.append([a, b])
    cuts = floor_cuts(layout)
    assert len(cuts) == len(rows) - 1
    slabs, _ = slab_layouts(layout)
    assert all(check_partition(s) == [] for s in slabs)
    assert all(s.height < 7.0 for s in slabs)  # (was one slab of 17.5 m)


def _plinth_facade():
    """Door-less: a 0.5 m plinth along the ground, shop windows above it, two floors of windows."""
    ts = [Region(0, 0, 12, 0.5, "P", "wall")]
    for c in range(4):
        ts += [Region(3 * c, 0.5, 1, 3, "W", "wall"), Region(3 * c + 1, 0.5, 1.6, 2.5, "S", "shop"),
               Region(3 * c + 1, 3.0, 1.6, 0.5, "W", "wall"), Region(3 * c + 2.6, 0.5, 0.4, 3, "W", "wall")]
    for f in range(2):
        y = 3.5 + 3 * f
        ts += [Region(0, y, 12, 1, "W", "wall"), Region(0, y + 2.5, 12, 0.5, "W", "wall")]
        ts += [r for c in range(4) for r in (Region(3 * c, y + 1, 1, 1.5, "W", "wall"),
               Region(3 * c + 1, y + 1, 1, 1.5, "N", "window"), Region(3 * c + 2, y + 1, 1, 1.5, "W", "wall"))]
    return FacadeLayout(12, 9.5, Region(0, 0, 12, 9.5, "F", children=tuple(ts)))


@pytest.mark.parametrize("ground", [2.6, 3.0, 4.0, 5.5])
def test_a_carved_door_is_a_door_on_any_ground_floor(ground):
    """Regression (issue 21): doors carved into door-less facades were hatches 0.49-1.79 m tall (carved into the
    largest wall touching the ground: here the 0.5 m plinth)."""
    layout = _plinth_facade()
    slabs, _ = slab_layouts(layout)
    door = next(t for t in slabs[0].terminals() if t.label == "door")
    assert door.y == 0 and door.h >= 0.75 * slabs[0].height and check_partition(slabs[0]) == []
    g = citygen_split.parse(extract_size_independent(layout, "greedy").text, "plinth")
    req = FacadeRequest.preview(12.0, ground + 6.0, floor_height=3.0, ground_height=ground)
    out = citygen_split.derive(g, req)
    doors = [t for t in out.terminals() if t.label == "door"]
    assert len(doors) == 1 and doors[0].y == 0 and doors[0].h >= 1.9
    assert not any(t.label == "shop" and t.w < 0.8 for t in out.terminals())  # no shop cut into a sliver


# ---- issue 21: bays repeat, not the whole facade; pinwheels opened ------------------------------------------
def _pilastered_facade(bays=4, floors=3):
    """Pilasters 0.6 m at both ends, ``bays`` bays of 2.5 m (wall | window 1.2 m | wall), a ground floor of
    shop bays, string courses across the whole width."""
    W = 1.2 + 2.5 * bays
    ts = [Region(0, 0, 0.6, 3.5 + 3 * floors, "P", "pillar", depth=0.1),
          Region(W - 0.6, 0, 0.6, 3.5 + 3 * floors, "P", "pillar", depth=0.1)]
    for b in range(bays):
        x = 0.6 + 2.5 * b
        ts += [Region(x, 0, 0.4, 3.5, "W", "wall"), Region(x + 0.4, 0, 1.7, 2.8, "S", "shop"),
               Region(x + 0.4, 2.8, 1.7, 0.7, "W", "wall"), Region(x + 2.1, 0, 0.4, 3.5, "W", "wall")]
    for f in range(floors):
        y = 3.5 + 3 * f
        ts += [Region(0.6, y, W - 1.2, 0.2, "C", "molding", depth=0.05)]
        for b in range(bays):
            x = 0.6 + 2.5 * b
            ts += [Region(x, y + 0.2, 0.65, 2.8, "W", "wall"), Region(x + 0.65, y + 0.2, 1.2, 0.8, "W", "wall"),
                   Region(x + 0.65, y + 1.0, 1.2, 1.5, "N", "window", depth=-0.25),
                   Region(x + 0.65, y + 2.5, 1.2, 0.5, "W", "wall"), Region(x + 1.85, y + 0.2, 0.65, 2.8, "W", "wall")]
    H = 3.5 + 3 * floors
    return FacadeLayout(W, H, Region(0, 0, W, H, "F", children=tuple(ts)))


def test_bays_are_found_between_the_pilasters():
    from citygen_inverse.bays import find_bays
    slabs, _ = slab_layouts(_pilastered_facade())
    bays = find_bays(slabs[1:])
    assert bays.count == 4 and bays.start == pytest.approx(0.6) and bays.tile == pytest.approx(2.5)


@pytest.mark.parametrize("factor", [1.7, 2.0, 3.0])
def test_a_wider_face_repeats_the_bays_not_the_whole_facade(factor):
    """Regression (issue 21): at 1.7x its width the whole facade was duplicated side by side, with its pilasters
    in the middle (a seam); now the pilasters stay at the ends and the bays repeat between them."""
    layout = _pilastered_facade()
    text = extract_size_independent(layout, "greedy").text
    assert "4 bays of 2.50 m" in text
    g = citygen_split.parse(text, "pilasters")
    req = FacadeRequest.preview(factor * layout.width, layout.height, floor_height=3.0, ground_height=3.5)
    out = citygen_split.derive(g, req)
    assert check_partition(out) == [] and check_request(out, req) == []
    pillars = {round(t.x, 6) for t in out.terminals() if t.label == "pillar"}
    assert pillars == {0.0, round(req.width - 0.6, 6)}
    windows = [t for t in out.terminals() if t.label == "window"]
    bays = round((req.width - 1.2) / 2.5)
    assert len(windows) == 3 * bays
    assert all(abs(t.w - 1.2 * (req.width - 1.2) / bays / 2.5) < 1e-6 for t in windows)


def test_a_door_lands_in_the_middle_bay_and_the_ground_floor_keeps_the_bays():
    layout = _pilastered_facade()
    g = citygen_split.parse(extract_size_independent(layout, "greedy").text, "pilasters")
    req = FacadeRequest.preview(2 * layout.width, layout.height, floor_height=3.0, ground_height=3.5)
    out = citygen_split.derive(g, req)
    doors = [t for t in out.terminals() if t.label == "door"]
    assert len(doors) == 1 and doors[0].h >= 1.9 and doors[0].y == 0
    assert abs(doors[0].x + 0.5 * doors[0].w - 0.5 * req.width) < 2.5  # in a middle bay


def test_pinwheels_are_opened_where_walls_allow_and_keep_the_label_map():
    """Issue 21: 26 of 78 ADP grammars held grid rules, 8 of them of 67-133 items. A pinwheel of walls around
    a window is cut open (walls cut in two); the label map is unchanged."""
    from citygen_inverse.pinwheels import open_pinwheels
    ts = (Region(0, 0, 2, 1, "a", "wall"), Region(2, 0, 1, 2, "b", "wall"), Region(1, 2, 2, 1, "c", "wall"),
          Region(0, 1, 1, 2, "d", "wall"), Region(1, 1, 1, 1, "e", "window"))
    layout = FacadeLayout(3, 3, Region(0, 0, 3, 3, "F", children=ts))
    assert "grid" in extract_grammar(layout, "greedy").text
    opened = open_pinwheels(layout)
    assert check_partition(opened) == [] and "grid" not in extract_grammar(opened, "greedy").text
    for layout_ in (layout, random_layout(np.random.default_rng(3), pinwheel=0.5)):
        opened = open_pinwheels(layout_)
        assert check_partition(opened) == []
        for px in np.linspace(0.05, layout_.width - 0.05, 23):
            for py in np.linspace(0.05, layout_.height - 0.05, 19):
                assert _label_at(opened, px, py) == _label_at(layout_, px, py)


def _label_at(layout, x, y):
    return next(t.label for t in layout.terminals() if t.x <= x < t.x + t.w and t.y <= y < t.y + t.h)


@pytest.mark.parametrize("factor", [0.8, 1.0, 1.3])
def test_no_storey_loses_its_windows_at_other_heights(factor):
    """Regression (issue 21): cmp_b0009's three pillared window storeys were one slab given to one building
    storey (the other storeys took other slabs), squeezed to 0.14 m balconies and 0.3 m windows."""
    layout = cmp_layout("cmp_b0009")
    g = citygen_split.parse(extract_size_independent(layout, "greedy").text, "b0009")
    req = FacadeRequest.preview(layout.width, factor * layout.height, floor_height=3.0, ground_height=4.0)
    out = citygen_split.derive(g, req)
    lines = req.floor_lines
    for lo, hi in zip(lines[1:], lines[2:]):
        assert any(t.label == "window" and lo - 1e-9 <= t.y < hi for t in out.terminals()), (lo, hi)
    assert check_plausible(out, req) == []


@cache
def _b0009_grammar():
    return citygen_split.parse(extract_size_independent(cmp_layout("cmp_b0009"), "greedy").text, "b0009")


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(wf=st.floats(0.4, 2.5), hf=st.floats(0.4, 2.5), storey=st.floats(2.6, 3.6), entrance=st.booleans())
def test_extracted_grammars_never_report_a_broken_facade_as_dressed(wf, hf, storey, entrance):
    """Issue 21 property: the split kind's generator on an extracted grammar at random sizes is dressed or falls
    back with findings, never implausible or breaking the request."""
    from citygen.cli import facade_outcome
    from citygen.registry import default_registry
    layout = cmp_layout("cmp_b0009")
    req = FacadeRequest.preview(wf * layout.width, max(hf * layout.height, 3.0), floor_height=storey,
                                ground_height=max(storey, 4.0), entrance=entrance)
    out = default_registry().ruleset_kind("split").generate(_b0009_grammar(), req)
    outcome, reasons = facade_outcome(out, req)
    assert outcome in ("dressed", "fell-back"), reasons
