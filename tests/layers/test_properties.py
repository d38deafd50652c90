"""Hypothesis properties over random stacks and canvas sizes, plus the shipped rulesets against requests."""
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from citygen.layout import check_partition
from citygen.plausible import check_plausible
from citygen.registry import load_registry
from citygen.request import FacadeRequest, check_request
from citygen_layers.align import _Words
from citygen_layers.parser import load, parse
from citygen_layers.facade import clear_solved, generate, solve_request
from citygen_layers.solver import _above

ROOT = Path(__file__).resolve().parents[2]
SIZES = {"A": 0.9, "B": 1.4, "C": 0.5, "D": 1.1, "P": 3.0, "Q": 2.6}
X_PATTERNS = ["A (B A)^k", "c e c ; c := C", "y d y ; d := D", "A (B A)^k", "A (D A)^j"]
Y_PATTERNS = ["P Q^n", "g u ; g := C Q", "P Q^n"]


FLAGS = ("", " attached", " unoccludable")


def random_stack(layers: list[tuple[int, int]], flags: dict[str, str]):
    """A stack over the base layer: ``layers`` are (x pattern, y pattern) indices, ``flags`` the flag of B, C, D
    (also used by ``benchmarks/layers_identity.py``)."""
    lines = [f"symbol {s} size={v}{' opaque' if s in 'APQ' else ''}{flags.get(s, '')}" for s, v in SIZES.items()]
    # the wall-clock limit is only a safety net: with time to spare the expansion budget decides (deterministic)
    lines += ["counter k", "counter j", "counter n in 0..", "budget expansions=3000 time=120"]
    lines += [f"pattern X{i} = {p}" for i, p in enumerate(X_PATTERNS)]
    lines += [f"pattern Y{i} = {p}" for i, p in enumerate(Y_PATTERNS)]
    lines.append("layer base x=X0 y=Y0")
    lines += [f"layer l{i} x=X{x} y=Y{y}" for i, (x, y) in enumerate(layers)]
    return parse("\n".join(lines) + "\n", "random.layers")


@st.composite
def stacks(draw):
    layers = draw(st.lists(st.tuples(st.integers(0, len(X_PATTERNS) - 1), st.integers(0, len(Y_PATTERNS) - 1)),
                           min_size=1, max_size=4))
    return random_stack(layers, {s: draw(st.sampled_from(FLAGS)) for s in "BCD"})


@settings(max_examples=15, deadline=None)
@given(stacks(), st.floats(3.0, 20.0), st.floats(3.0, 12.0))
def test_random_stacks(rs, width, height):
    request = FacadeRequest(width, height, (0.0, height))
    layout = generate(rs, request)
    assert check_partition(layout) == []                          # visible regions of every layer partition it
    if layout.meta.get("fallback"):                               # no plausible layout: a plain wall, findings
        assert layout.meta["findings"] and {r.label for r in layout.leaves} <= {"wall", "door", None}
    else:
        assert {c.layer for c in layout.root.children} == {layer.name for layer in rs.layers}
        assert check_plausible(layout, request) == []
    clear_solved()                                                # solve again, not reuse the kept directions
    assert layout.to_json() == generate(rs, request).to_json()    # deterministic
    sx, sy = solve_request(rs, request)
    for sol in (sx, sy):
        if sol.status != "solved":
            continue
        for m in sol.matrices:                                    # every qualifier constraint holds per column
            net = _Words(m.words, _above(m.rows), m.parents)
            assert all(net.score(col) is not None for col in m.alignment.columns)
        if not sol.sizing.relaxed:                                # one size per symbol
            sizes = defaultdict(set)
            for segs in sol.sizing.segments.values():
                for seg in segs:
                    if seg.letter is not None:
                        sizes[seg.letter.symbol].add(round(seg.t - seg.s, 5))
            assert all(len(v) == 1 for v in sizes.values()), sizes


SHIPPED = ["residential_house", "terraced_house", "tenement"]


@pytest.mark.parametrize("name", SHIPPED)
@settings(max_examples=8, deadline=None)
@given(width=st.floats(4.0, 30.0), height=st.floats(3.0, 24.0), entrance=st.booleans(),
       corner=st.floats(0.0, 0.6))
def test_shipped_rulesets_honour_requests(name, width, height, entrance, corner):
    rs = load(ROOT / "rulesets" / f"{name}.layers")
    base = FacadeRequest.preview(width, height, floor_height=3.0, ground_height=4.0, entrance=entrance)
    request = FacadeRequest(width, height, base.floor_lines, entrance, (corner, corner), base.context)
    layout = generate(rs, request)
    assert check_partition(layout) == []
    assert check_request(layout, request) == []     # a plain wall (fall-back) carries the entrance too
    if not layout.meta.get("fallback"):
        assert check_plausible(layout, request) == []


def test_registry_finds_the_kind():
    registry = load_registry()
    kind = registry.kind_for_path(Path("x.layers"))
    assert kind.id == "layers"
    text = kind.explain(kind.load(ROOT / "rulesets" / "residential_house.layers"), FacadeRequest.preview(6, 3))
    assert "direction x" in text and "alignment group" in text


def test_underconstrained_stack_is_bounded_by_its_budget():
    rs = load(ROOT / "benchmarks" / "data" / "layers" / "underconstrained.layers")
    request = FacadeRequest(17.0, 13.0, (0.0, 13.0))
    layout = generate(rs, request)   # the budget's best-effort sizing is squeezed: a plain wall saying so
    assert check_partition(layout) == []
    sx, sy = solve_request(rs, request)
    assert sx.expansions + sy.expansions <= 2 * rs.options.expansions
    assert layout.meta.get("diagnostics") or layout.meta["status"] == {"x": "solved", "y": "solved"}


def test_regression_storey_instances_keep_sizes_in_26_layer_stack():
    """Transparent storey letters of control patterns once had no objective and collapsed (sync dropped)."""
    rs = load(ROOT / "benchmarks" / "data" / "layers" / "tonhalle26.layers")
    layout = generate(rs, FacadeRequest.preview(24, 19, floor_height=3.0, ground_height=4.5, entrance=False))
    assert check_partition(layout) == [] and not layout.meta.get("diagnostics")


def test_regression_no_hole_inside_split_letter():
    """An epsilon column between two parts of one split letter made the letter overlap the hole."""
    rs = load(ROOT / "rulesets" / "terraced_house.layers")
    layout = generate(rs, FacadeRequest.preview(14, 16, floor_height=3.0, ground_height=4.0))
    assert check_partition(layout) == []


def test_preview_renders(tmp_path):
    from citygen_layers.preview import render
    rs = load(ROOT / "rulesets" / "tenement.layers")
    out = render(generate(rs, FacadeRequest.preview(16, 15, 3.0, 4.0)), tmp_path / "t.png")
    assert out.stat().st_size > 1000
    assert np.isfinite(out.stat().st_size)


@pytest.mark.parametrize(("width", "corner"), [(3.5, 0.6), (4.0, 0.375), (4.0, 0.6), (5.0, 0.375)])
def test_regression_narrow_entrance_face_keeps_its_door(width, corner):
    """The terraced house's door follows its full-width bay W into the corner strips on narrow faces; it was made
    wall (no door at all), later cut at the strip line and carved, with shops and pillars 0 m wide around it.
    Such a face now gets a plausible layout with its door, or a plain wall that says why (issue 21)."""
    rs = load(ROOT / "rulesets" / "terraced_house.layers")
    base = FacadeRequest.preview(width, 7.5, floor_height=3.0, ground_height=4.0, entrance=True)
    request = FacadeRequest(width, 7.5, base.floor_lines, True, (corner, corner), base.context)
    layout = generate(rs, request)
    assert check_partition(layout) == []
    if layout.meta.get("fallback"):
        assert layout.meta["findings"] and {r.label for r in layout.leaves} <= {"wall", "door", None}
    else:
        assert check_request(layout, request) == [] and check_plausible(layout, request) == []
        assert layout.count("door") == 1


def test_conform_cuts_openings_at_the_corner_strip():
    from citygen.layout import FacadeLayout, Region
    from citygen_layers.compose import conform
    window = Region(0.0, 1.0, 2.0, 1.5, "W", "window", depth=-0.25, layer="l")
    wall = Region(2.0, 1.0, 4.0, 1.5, "V", "wall", layer="l")
    layout = FacadeLayout(6.0, 2.5, Region(0, 0, 6, 2.5, "S", children=(
        Region(0, 0, 6, 2.5, "l", layer="l", children=(Region(0, 0, 6, 1, "V", "wall", layer="l"), window, wall)),)))
    fixed, notes = conform(layout, (0.0, 2.5), (0.5, 0.5))
    assert check_partition(fixed) == [] and "cut at the strip line" in notes[0]
    windows = [r for r in fixed.leaves if r.label == "window"]
    assert [(r.x, r.w) for r in windows] == [(0.5, 1.5)]
    fixed, notes = conform(layout, (0.0, 2.5), (1.5, 0.5))  # under half of the window is left: all wall
    assert fixed.count("window") == 0 and "made wall" in notes[0]


@pytest.mark.parametrize("name", SHIPPED)
def test_building_faces_reuse_directions_and_layouts_equal_fresh_solves(name):
    """Faces of one building share height and floor lines, opposite faces their width: those directions are
    solved once per process, and every layout equals the one of a solve from scratch."""
    rs = load(ROOT / "rulesets" / f"{name}.layers")
    base = FacadeRequest.preview(9.0, 10.0, floor_height=3.0, ground_height=4.0)
    faces = [FacadeRequest(w, 10.0, base.floor_lines, i == 0, (0.375, 0.375), base.context)
             for i, w in enumerate((9.0, 14.0, 9.0, 14.0))]
    clear_solved()
    reused = [generate(rs, face).to_json() for face in faces]
    assert solve_request(rs, faces[3])[0] is solve_request(rs, faces[1])[0]
    assert solve_request(rs, faces[3])[1] is solve_request(rs, faces[2])[1]
    fresh = []
    for face in faces:
        clear_solved()
        fresh.append(generate(rs, face).to_json())
    assert reused == fresh


def test_solves_cut_by_the_wall_clock_are_not_kept():
    rs = parse("symbol A size=1 opaque\ncounter k\npattern X = A A^k\npattern Y = A A\nbudget time=0\n"
               "layer l x=X y=Y\n")
    request = FacadeRequest(5.0, 4.0, (0.0, 4.0))
    first = solve_request(rs, request)
    assert first[0].timed_out and first[0].status == "best-effort"
    assert solve_request(rs, request)[0] is not first[0]


def test_generate_leaves_the_garbage_collector_as_it_found_it():
    import gc
    rs = load(ROOT / "rulesets" / "residential_house.layers")
    request = FacadeRequest(6.0, 3.0, (0.0, 1.6, 3.0), True)
    assert gc.isenabled()
    generate(rs, request)
    assert gc.isenabled()
    gc.disable()
    try:
        generate(rs, request)
        assert not gc.isenabled()  # a caller that paused it keeps it paused
    finally:
        gc.enable()
