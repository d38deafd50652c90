"""Bad relayout models found by fuzzing (benchmarks/fuzz_readers.py) give a ParseError, never a traceback."""
from __future__ import annotations

import pytest

from citygen.errors import ParseError
from citygen_relayout import load_model



def test_model_that_is_not_utf8_is_a_parse_error(tmp_path):
    (tmp_path / "m.relayout").write_bytes(b"model m\n# \xff\n")  # was: UnicodeDecodeError
    with pytest.raises(ParseError, match=r"m.relayout: model is not UTF-8 text \(byte 0xff at offset 10\)"):
        load_model(tmp_path / "m.relayout")


def test_layout_path_with_a_nul_byte_is_a_parse_error(tmp_path):
    (tmp_path / "m.relayout").write_text('model m\nlayout "f\x00.json"\n')  # was: ValueError embedded null byte
    with pytest.raises(ParseError) as info:
        load_model(tmp_path / "m.relayout")
    assert str(info.value.where) == f"{tmp_path / 'm.relayout'}:2:8" and "cannot read layout" in str(info.value)


def test_groups_and_sets_nested_past_the_bound_are_a_parse_error(tmp_path):
    """Was: RecursionError at 2000 nested groups; 32 levels is the bound."""
    from pathlib import Path
    model = (Path(__file__).resolve().parents[2] / "rulesets" / "townhouse.relayout").read_text()
    for line, deep, where in [("repeat Upper : Wall (Bay Wall)+",
                               "repeat Upper : Wall " + "(" * 2000 + "Bay Wall" + ")" * 2000 + "+", "group"),
                              ("repeat Ground : Pier ({Shop Entry} Pier)+",
                               "repeat Ground : Pier (" + "{" * 2000 + "Shop Entry" + "}" * 2000 + " Pier)+", "set")]:
        assert line in model
        (tmp_path / "deep.relayout").write_text(model.replace(line, deep))
        with pytest.raises(ParseError, match=f"{where} nested more than 32 levels deep"):
            load_model(tmp_path / "deep.relayout")
    (tmp_path / "ok.relayout").write_text(model.replace("repeat Upper : Wall (Bay Wall)+", "repeat Upper : Wall "
                                                        + "(" * 31 + "Bay Wall" + ")" * 31 + "+"))
    load_model(tmp_path / "ok.relayout")


def test_regression_a_huge_preview_is_refused_before_laying_out(capsys):
    """Was: ``citygen relayout townhouse.relayout --size 1000 1000`` took 950 MB and 50 s; now one error line."""
    from pathlib import Path

    from citygen.cli import main
    model = Path(__file__).resolve().parents[2] / "rulesets" / "townhouse.relayout"
    assert main(["relayout", str(model), "--size", "1000", "1000"]) == 2
    err = capsys.readouterr().err
    assert "terminals; a preview stops at 60,000 -- give a smaller --size" in err and "townhouse.relayout" in err
    assert main(["relayout", str(model), "--size", "20", "15"]) == 0
