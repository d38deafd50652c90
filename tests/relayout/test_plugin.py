"""Plugin registration and the ``citygen relayout`` command."""
from __future__ import annotations

import argparse
import json

from citygen.layout import FacadeLayout
from citygen.registry import load_registry
from citygen.request import FacadeRequest

from .conftest import RULESETS


def run_command(argv):
    registry = load_registry()
    command = registry.commands["relayout"]
    parser = argparse.ArgumentParser()
    command.configure(parser)
    return command.run(parser.parse_args(argv), registry)


def test_kind_is_registered_by_suffix():
    registry = load_registry()
    kind = registry.kind_for_path(RULESETS / "townhouse.relayout")
    assert kind.id == "relayout"
    model = kind.load(RULESETS / "townhouse.relayout")
    text = kind.explain(model, FacadeRequest.preview(12.0, 9.6))
    assert "townhouse" in text and "solved" in text


def test_command_prints_json_variations(capsys):
    assert run_command([str(RULESETS / "fig7_walkthrough.relayout"), "--size", "18", "15", "--count", "3",
                        "--seed", "4", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    layouts = [FacadeLayout.from_json(d) for d in data]
    assert len(layouts) == 3 and all(lay.width == 18.0 for lay in layouts)


def test_command_draws_a_contact_sheet(tmp_path):
    from PIL import Image
    out = tmp_path / "sheet.png"
    assert run_command([str(RULESETS / "cmp_b0035.relayout"), "--size", "20", "12", "--count", "5",
                        "--png", str(out)]) == 0
    assert Image.open(out).size[0] > 600


def test_command_reports_a_bad_model(tmp_path, capsys):
    bad = tmp_path / "bad.relayout"
    bad.write_text("root F 1 1\nsplit F q A:1\n")
    assert run_command([str(bad), "--size", "5", "5"]) == 2
    assert "bad.relayout:2:9" in capsys.readouterr().err


def test_infeasible_size_exits_non_zero(capsys):
    assert run_command([str(RULESETS / "fig7_walkthrough.relayout"), "--size", "25", "5"]) == 1
    assert "height must lie in" in capsys.readouterr().err
