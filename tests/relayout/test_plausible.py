"""Issue 21 for relayout: plausible facades at sizes nobody tuned a model for, and models built from layouts.

Regression tests name the defect each one pins; the hypothesis property runs the sweep's classification over
random sizes for every shipped model.
"""
from __future__ import annotations

import json

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from citygen.plausible import check_plausible
from citygen.registry import default_registry
from citygen.request import FacadeRequest
from citygen_relayout import load_model, parse_model, relayout, validate
from citygen_relayout.building import generate_face
from tests import sweep

from .conftest import RULESETS
from .test_plugin import run_command

SYMMETRIC = """model sym
root Facade 10.8 6.6
split Facade y Ground:3.6 Upper:3.0
split Ground x Pier:0.8 Shop:2.8 Pier:0.8 Entry:2.0 Pier:0.8 Shop:2.8 Pier:0.8
split Upper x Wall:1.2 Bay:1.2 Wall:1.2 Bay:1.2 Wall:1.2 Bay:1.2 Wall:1.2 Bay:1.2 Wall:1.2
split Bay y Sill:0.15 Window:1.6 Head:1.25
split Entry y Door:2.6 Transom:1.0
split Shop y Base:0.6 ShopWin:2.4 Fascia:0.6
terminal Wall wall
terminal Pier pillar
terminal Sill sill
terminal Window window
terminal Head wall
terminal Door door
terminal Transom wall
terminal Base wall
terminal ShopWin shop
terminal Fascia cornice
repeat Ground : Pier (Shop Pier)* Entry (Pier Shop)* Pier
symmetric Ground
freq Ground Entry 1..1
"""


def flat_layout(storeys: int = 3, bays: int = 4) -> dict:
    """A flat, annotation-like layout (labelled rectangles, no hierarchy): a ground floor with a centred door
    between window bays, ``storeys - 1`` upper floors of ``bays`` windows on sill strips, a cornice band."""
    bay, pier = 1.2, 1.0
    width = bays * bay + (bays + 1) * pier
    kids = []

    def rect(x, y, w, h, label):
        kids.append({"x": x, "y": y, "w": w, "h": h, "symbol": label.capitalize(), "label": label})

    height = 4.0 + 3.0 * (storeys - 1) + 0.8
    for k in range(bays + 1):  # piers, one per storey
        rect(k * (bay + pier), 0.0, pier, 4.0, "wall")
        for s in range(1, storeys):
            rect(k * (bay + pier), 4.0 + 3.0 * (s - 1), pier, 3.0, "wall")
    for k in range(bays):
        x = pier + k * (bay + pier)
        if k == bays // 2:
            rect(x, 0.0, bay, 2.4, "door")
            rect(x, 2.4, bay, 1.6, "wall")
        else:
            rect(x, 0.0, bay, 1.0, "wall")
            rect(x, 1.0, bay, 2.0, "window")
            rect(x, 3.0, bay, 1.0, "wall")
        for s in range(1, storeys):
            y = 4.0 + 3.0 * (s - 1)
            rect(x, y, bay, 0.8, "wall")
            rect(x, y + 0.8, bay, 0.1, "sill")
            rect(x, y + 0.9, bay, 1.5, "window")
            rect(x, y + 2.4, bay, 0.6, "wall")
    rect(0.0, height - 0.8, width, 0.8, "cornice")
    return {"schema_version": 1, "width": width, "height": height,
            "root": {"x": 0, "y": 0, "w": width, "h": height, "symbol": "Facade", "children": kids}}


@pytest.fixture(scope="module")
def flat_model(tmp_path_factory):
    base = tmp_path_factory.mktemp("flat")
    (base / "flat.layout.json").write_text(json.dumps(flat_layout()))
    return parse_model('model flat\nlayout "flat.layout.json"\n', str(base / "flat.relayout"), base=base)


def _storeys(layout) -> int:
    return sum(1 for c in layout.root.children if c.symbol.startswith(("Ground", "Storey")))


def test_imported_layout_is_segmented_into_storeys_and_bays(models):
    """Was: guillotine cuts split the storeys of cmp_b0035 into thin rows (95 symbols for 121 terminals), so the
    number of storeys could not vary. Now the facade is Ground, Gap, Storey, Top."""
    model = models["cmp_b0035"]
    assert model.symbols[model.root].children == ("Ground", "Gap", "Storey", "Top")
    assert len(model.symbols) < 70
    for height in (12.0, 21.0):  # one storey of the model per floor of the building
        request = sweep.request(15.6, height, 3.0)
        layout = generate_face(model, request)
        assert not layout.meta.get("fallback"), layout.meta["fallback"]
        assert _storeys(layout) == len(request.floor_lines) - 1


def test_a_layout_alone_varies_storey_and_bay_counts(flat_model):
    """A model that is only ``layout "file"``: its defaults repeat storeys and bays, keep the door between bays."""
    small = generate_face(flat_model, sweep.request(flat_model.width, flat_model.height, 3.0))
    big = generate_face(flat_model, sweep.request(2 * flat_model.width, 1.8 * flat_model.height, 3.0))
    assert not small.meta.get("fallback") and not big.meta.get("fallback"), (small.meta, big.meta)
    assert _storeys(big) > _storeys(small)
    windows = lambda lay: sum(1 for r in lay.leaves if r.label == "window")  # noqa: E731
    assert windows(big) > windows(small)
    assert validate(big, flat_model) == []


def test_symbols_are_listed_with_labels_and_sizes(capsys):
    """Was: symbol names of an imported layout could only be found by dumping JSON."""
    assert run_command([str(RULESETS / "cmp_b0035.relayout"), "--symbols"]) == 0
    out = capsys.readouterr().out
    assert "Ground  split y  15.61 x 5.09 m" in out
    assert any(line.strip().startswith("Door  door  1.57 x 3.64 m") for line in out.splitlines())


def test_relayout_without_size_or_symbols_says_what_to_give(capsys):
    assert run_command([str(RULESETS / "cmp_b0035.relayout")]) == 2
    assert "--size" in capsys.readouterr().err


def test_symmetric_region_with_a_centred_door_solves():
    """Was: ``symmetric`` with a centred door failed at every size, the input size included (the centre element
    was counted twice against ``freq .. 1..1`` and the door budget)."""
    model = parse_model(SYMMETRIC, "sym.relayout")
    for width in (10.8, 14.0):
        result = relayout(model, width, 6.6, seed=0)
        assert result.success, result.message
        ground = next(c for c in result.layout.root.children if c.symbol == "Ground")
        door = next(r for r in result.layout.leaves if r.label == "door")
        assert abs(door.x + door.w / 2 - width / 2) < 1e-6
        assert [c.symbol for c in ground.children] == [c.symbol for c in reversed(ground.children)]
        assert validate(result.layout, model) == []
    face = generate_face(model, FacadeRequest.preview(10.8, 6.6, floor_height=3.0, ground_height=3.6))
    assert not face.meta.get("fallback"), face.meta.get("fallback")


def test_door_stays_centred_between_bays(models):
    """Was: the door landed at the facade's end in 11 of 15 variations of a model from an imported layout. The
    ground row of cmp_b0035 reads the same from both ends with the door in the middle, so it is laid out
    symmetric and the door stays centred, as in the input."""
    model = models["cmp_b0035"]
    assert model.rules["Row8"].symmetric
    for seed in range(6):
        result = relayout(model, 26.0, 12.0, seed=seed)
        assert result.success, result.message
        door = next(r for r in result.layout.leaves if r.label == "door")
        windows = [r for r in result.layout.leaves if r.label == "window" and r.y < door.y + door.h]
        assert any(w.x < door.x for w in windows) and any(w.x > door.x + door.w for w in windows)
        assert abs(door.x + door.w / 2 - 13.0) < 0.2


@pytest.mark.parametrize("size", [(20.0, 12.0), (26.0, 15.5), (9.0, 7.0), (40.0, 19.5)])
def test_model_from_a_layout_dresses_buildings_at_other_sizes(models, size):
    """Was: on a building (its floor lines) cmp_b0035 fell back to plain walls at every size but the input's, and
    the default 75-150 % size ranges blocked wider faces."""
    request = sweep.request(*size, 3.0)
    layout = generate_face(models["cmp_b0035"], request)
    assert not layout.meta.get("fallback"), layout.meta.get("fallback")
    assert check_plausible(layout, request) == []


def test_an_implausible_model_falls_back_with_its_findings():
    """The generator holds its candidates to check_plausible: a model that can only make 0.2 m windows is not
    'solved'; the face falls back and the findings say why."""
    model = parse_model("root F 6 3\nsplit F x W:2.9 V:0.2 W:2.9\nterminal W wall\nterminal V window\n"
                        "size V 0.2..0.25\n", "thin.relayout")
    assert not relayout(model, 6.0, 3.0).success
    request = FacadeRequest.preview(6.0, 3.0, floor_height=3.0, ground_height=3.0, entrance=False)
    layout = generate_face(model, request)
    assert layout.meta["fallback"].startswith("no ") and "small-opening" in " ".join(layout.meta["findings"])


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(name=st.sampled_from([n for n in sweep.SHIPPED if n.endswith(".relayout")]),
       width=st.floats(2.0, 60.0), height=st.floats(3.0, 60.0), storey=st.sampled_from(sweep.STOREYS))
def test_no_shipped_model_reports_a_broken_facade_as_dressed(name, width, height, storey):
    case = sweep.run_case(_REGISTRY, name, round(width, 2), round(height, 2), storey)
    assert not case.bad, case


_REGISTRY = default_registry()
