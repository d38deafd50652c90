"""Size-independent grammars on any face (wu2014 §5), alignment at new sizes (Fig. 12) and readable names."""
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import citygen_split
from citygen.coordinator import plan_floor_lines
from citygen.layout import FacadeLayout, Region, check_partition
from citygen.request import FaceContext, FacadeRequest, check_request
from citygen.scene import Defaults
from citygen_inverse.cmp import import_cmp
from citygen_inverse.extract import extract_grammar
from citygen_inverse.independent import extract_size_independent, floor_cuts, slab_layouts

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
