"""The inverse commands through ``citygen.cli.main``: import, extract (each method), cost, and bad input."""
import json
import re
from pathlib import Path

import pytest

import citygen_split
from citygen.cli import main
from citygen.layout import FacadeLayout, Region, check_partition

DATA = Path(__file__).resolve().parents[1] / "data" / "inverse"
XML = DATA / "cmp_b0009.xml"


@pytest.fixture(scope="module")
def layout_json(tmp_path_factory):
    out = tmp_path_factory.mktemp("cli") / "b0009.json"
    assert main(["layout", "import-cmp", str(XML), "--width", "14", "--png", str(DATA / "cmp_b0009.png"),
                 "-o", str(out)]) == 0
    return out


def test_import_cmp_with_width_and_png(layout_json, capsys):
    layout = FacadeLayout.loads(layout_json.read_text())
    assert check_partition(layout) == []
    assert layout.width == pytest.approx(14.0, abs=1e-3)
    assert layout.meta["scale_from"] == "width 14.0 m"
    assert layout.meta["label_map_agreement"] > 0.5


def test_import_cmp_to_stdout(capsys):
    assert main(["layout", "import-cmp", str(XML), "--floor-height", "3.2"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["width"] > 0 and "terminals" in err


@pytest.mark.parametrize("method", ["greedy", "is", "adp", "exact"])
def test_extract_each_method(layout_json, tmp_path, capsys, method):
    out = tmp_path / f"{method}.grammar"
    assert main(["grammar", "extract", str(layout_json), "--method", method, "--iterations", "15", "--seed", "3",
                 "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "exact: re-derived" in err
    cost = float(err.split()[1])
    assert main(["grammar", "cost", str(out)]) == 0
    assert float(capsys.readouterr().out.split()[1]) == pytest.approx(cost, abs=0.005)
    assert f"method {method}" in out.read_text()
    if method == "exact":  # (the integer program ends on this facade: its grammar is proven optimal)
        assert "optimal over the candidate rules" in err and "# integer program: optimal" in out.read_text()


def test_extract_time_limit_is_checked(layout_json, capsys):
    assert main(["grammar", "extract", str(layout_json), "--time-limit", "0"]) == 2
    assert "--time-limit must be a number of seconds > 0" in capsys.readouterr().err
    assert main(["grammar", "extract", str(layout_json), "--method", "exact", "--iterations", "5",
                 "--time-limit", "30"]) == 0
    out, err = capsys.readouterr()
    assert out.startswith("# extracted by citygen grammar extract (wu2014), method exact") and "optimal" in err


def test_extract_size_independent(layout_json, tmp_path, capsys):
    out = tmp_path / "si.grammar"
    assert main(["grammar", "extract", str(layout_json), "--method", "greedy", "--size-independent",
                 "-o", str(out)]) == 0
    text = out.read_text()
    assert "floors {" in text and "case entrance" in text and "made by: citygen grammar extract" in text
    assert str(tmp_path) not in text  # no absolute paths in a file meant to be committed
    cost = float(capsys.readouterr().err.split()[1])
    assert citygen_split.grammar_cost(citygen_split.parse(text, "si")) == pytest.approx(cost, abs=0.005)
    assert main(["facade", str(out), "--size", "20", "12", "--json"]) == 0


def test_cost_of_a_hand_written_grammar(tmp_path, capsys):
    g = tmp_path / "hand.grammar"
    g.write_text("F1 --> split(x) { 1: A | 2: B | 1: A }\nF2 --> repeat(x) { 1: A | 2: B }\n"
                 "A --> terminal(wall)\nB --> terminal(window)\n")
    assert main(["grammar", "cost", str(g)]) == 0
    assert capsys.readouterr().out.split()[:4] == ["cost", "5.60", "rules", "2"]  # wu2014 §3.2: 3.1 + 2.5
    assert main(["grammar", "cost", str(g), "--split-cost", "0", "--repeat-cost", "0"]) == 0
    assert capsys.readouterr().out.split()[1] == "5.00"


def _fails(capsys, argv, *needles):
    assert main(argv) != 0
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.startswith("error: ")
    for needle in needles:
        assert needle in err, err
    return err


def _object(tmp_path, name, body):
    path = tmp_path / name
    path.write_text(body)
    (tmp_path / "label_names.txt").write_text((DATA / "label_names.txt").read_text())
    return str(path)


BOX = "<object><points><x>{}</x><x>{}</x><y>{}</y><y>{}</y></points><label>{}</label></object>"


def test_malformed_xml(tmp_path, capsys):
    path = _object(tmp_path, "bad.xml", "<object><points><x>0.1</x></points>")
    _fails(capsys, ["layout", "import-cmp", path], "bad.xml:1:", "malformed CMP annotation")


def test_unknown_label_id(tmp_path, capsys):
    path = _object(tmp_path, "unknown.xml", BOX.format(0, 1, 0, 1, 2) + BOX.format(0.1, 0.2, 0.1, 0.2, 42))
    _fails(capsys, ["layout", "import-cmp", path], "unknown.xml", "object 1", "label 42")


def test_zero_size_box_is_refused_unless_dropped(tmp_path, capsys):
    path = _object(tmp_path, "zero.xml", BOX.format(0, 1, 0, 1, 2) + BOX.format(0.5, 0.5, 0.2, 0.3, 3))
    _fails(capsys, ["layout", "import-cmp", path], "zero.xml", "object 1 (window)", "zero-size",
           "--drop-degenerate")
    out = tmp_path / "zero.json"
    assert main(["layout", "import-cmp", path, "--drop-degenerate", "-o", str(out)]) == 0
    assert FacadeLayout.loads(out.read_text()).meta["dropped_boxes"] == 1


def test_import_cmp_regularisation_options(tmp_path, capsys):
    """The tolerances are options: none gives the annotation back pixel for pixel, the summary says how much of
    it the import kept, and a share outside [0, 0.5) is refused naming the option."""
    xml = DATA / "cmp_b0045.xml"
    raw, default = tmp_path / "raw.json", tmp_path / "default.json"
    assert main(["layout", "import-cmp", str(xml), "--snap", "0", "--align", "0", "--equal-sizes", "0",
                 "-o", str(raw)]) == 0
    assert "100 % of the annotated element pixels kept" in capsys.readouterr().err
    assert main(["layout", "import-cmp", str(xml), "-o", str(default)]) == 0
    assert "% of the annotated element pixels kept" in capsys.readouterr().err
    raw_layout, default_layout = (FacadeLayout.loads(p.read_text()) for p in (raw, default))
    assert raw_layout.meta["annotation_agreement"]["element_pixels"] == 1.0
    assert len(default_layout.terminals()) < len(raw_layout.terminals())
    assert main(["layout", "import-cmp", str(xml), "--no-element-caps", "-o", str(tmp_path / "u.json")]) == 0
    capsys.readouterr()
    uncapped = FacadeLayout.loads((tmp_path / "u.json").read_text())
    assert uncapped.meta["tolerances_px"]["y"][0] > default_layout.meta["tolerances_px"]["y"][0]
    _fails(capsys, ["layout", "import-cmp", str(xml), "--align", "0.7"], "cmp_b0045.xml", "--align", "[0, 0.5)")


@pytest.mark.parametrize("argv,name", [
    (["layout", "import-cmp", "{}/missing.xml"], "missing.xml"),
    (["grammar", "extract", "{}/missing.json"], "missing.json"),
    (["grammar", "cost", "{}/missing.grammar"], "missing.grammar"),
])
def test_missing_files(tmp_path, capsys, argv, name):
    _fails(capsys, [a.format(tmp_path) for a in argv], name)


def test_bad_layout_and_grammar_files(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text('{"width": 3')
    _fails(capsys, ["grammar", "extract", str(bad)], "bad.json:1:")
    overlap = tmp_path / "overlap.json"
    overlap.write_text(FacadeLayout(2, 1, Region(0, 0, 2, 1, "F", children=(
        Region(0, 0, 1.5, 1, "A", "wall"), Region(1, 0, 1, 1, "B", "window")))).dumps())
    _fails(capsys, ["grammar", "extract", str(overlap), "--method", "greedy"], "overlap.json", "not a partition")
    _fails(capsys, ["grammar", "extract", str(overlap), "--size-independent"], "overlap.json", "not a partition")
    g = tmp_path / "bad.grammar"
    g.write_text("Facade --> split(x) { 1: A | B\n")
    _fails(capsys, ["grammar", "cost", str(g)], "bad.grammar:2:1")


def test_regression_files_that_are_not_utf8_are_refused(tmp_path, capsys):
    """A layout or annotation with a byte that is not UTF-8 ended in a UnicodeDecodeError traceback."""
    bad = tmp_path / "latin1.json"
    bad.write_bytes(b'{"width": 3, "name": "fa\xe7ade"}')
    _fails(capsys, ["grammar", "extract", str(bad)], "latin1.json", "not UTF-8")
    xml = tmp_path / "latin1.xml"
    xml.write_bytes((DATA / "cmp_b0012.xml").read_bytes().replace(b"window", b"w\xefndow", 1))
    _fails(capsys, ["layout", "import-cmp", str(xml)], "latin1.xml", "not UTF-8")
    _fails(capsys, ["layout", "import-cmp", str(xml), "--drop-degenerate"], "latin1.xml", "not UTF-8")


def test_size_independent_takes_one_layout(layout_json, capsys):
    _fails(capsys, ["grammar", "extract", str(layout_json), str(layout_json), "--size-independent"],
           "one layout")


def test_extract_refuses_a_grammar_that_does_not_regenerate_its_layout(layout_json, tmp_path, capsys, monkeypatch):
    """The CLI re-derives every exact grammar; a mismatch (an extractor bug) is an error naming the layout and the
    first terminals missing, and no grammar file is written."""
    import dataclasses

    import citygen_inverse.extract as extract_module
    real = extract_module.extract_grammar

    def broken(*args, **kwargs):
        result = real(*args, **kwargs)
        return dataclasses.replace(result, text=result.text.replace("terminal(window", "terminal(wall"))
    monkeypatch.setattr(extract_module, "extract_grammar", broken)
    out = tmp_path / "broken.grammar"
    assert main(["grammar", "extract", str(layout_json), "--method", "greedy", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "does not regenerate the layout" in err and str(layout_json) in err and "is not derived" in err
    assert not out.exists()


def test_joint_grammars_are_re_derived_facade_by_facade(layout_json, tmp_path, capsys, monkeypatch):
    """A joint grammar (wu2014 §6.1) was written without a check; each layout is now derived from its own facade
    symbol, and the cost and rule count printed are those of the written file (with the axiom's choice rule)."""
    import dataclasses

    import citygen_inverse.extract as extract_module
    other = tmp_path / "b0005.json"
    assert main(["layout", "import-cmp", str(DATA / "cmp_b0005.xml"), "-o", str(other)]) == 0
    out = tmp_path / "joint.grammar"
    assert main(["grammar", "extract", str(layout_json), str(other), "--method", "greedy", "-o", str(out)]) == 0
    assert "exact: all 2 facades re-derived" in capsys.readouterr().err
    extracted = out.read_text().splitlines()[1]
    assert main(["grammar", "cost", str(out)]) == 0
    cost, _, rules = capsys.readouterr().out.split()[1:4]
    assert f"cost {cost[:-1]}" in extracted and f"{rules} rules" in extracted
    real = extract_module.extract_grammar

    def broken(*args, **kwargs):  # every part of the second facade's first split comes out as a wall
        result = real(*args, **kwargs)
        lines = [re.sub(r": \w+", ": Wall", line) if line.startswith("Facade2 -->") else line
                 for line in result.text.splitlines()]
        return dataclasses.replace(result, text="\n".join(lines))
    monkeypatch.setattr(extract_module, "extract_grammar", broken)
    assert main(["grammar", "extract", str(layout_json), str(other), "--method", "greedy", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "does not regenerate the layout" in err and str(other) in err and str(layout_json) not in err


def test_mismatches_names_what_is_not_derived(layout_json):
    from citygen_inverse.extract import extract_grammar
    from citygen_inverse.verify import mismatches
    layout = FacadeLayout.loads(layout_json.read_text())
    text = extract_grammar(layout, "greedy").text
    assert mismatches(text, layout) == []
    other = FacadeLayout(layout.width, layout.height,
                         Region(0.0, 0.0, layout.width, layout.height, "Facade",
                                children=(Region(0.0, 0.0, layout.width, layout.height, "Wall", "wall"),)))
    problems = mismatches(text, other)
    assert problems[0].endswith("derived") and "1 terminals in the layout" in problems[0]


def test_out_of_range_options_are_refused_naming_the_option(layout_json, tmp_path, capsys):
    """Regressions: ``--iterations 0`` ran one iteration silently, negative or NaN costs were used as given, and
    ``--floor-height 0`` ended in a ZeroDivisionError traceback."""
    _fails(capsys, ["grammar", "extract", str(layout_json), "--iterations", "0"], "b0009.json",
           "--iterations must be at least 1")
    _fails(capsys, ["grammar", "extract", str(layout_json), "--split-cost", "-1", "--repeat-cost", "nan"],
           "--split-cost must be a finite number >= 0", "--repeat-cost")
    grammar = tmp_path / "g.grammar"
    assert main(["grammar", "extract", str(layout_json), "--method", "greedy", "--iterations", "0",
                 "-o", str(grammar)]) == 0  # (greedy builds one grammar whatever --iterations says)
    capsys.readouterr()
    _fails(capsys, ["grammar", "cost", str(grammar), "--repeat-cost", "inf"], "g.grammar", "--repeat-cost")
    for option in (["--floor-height", "0"], ["--width", "-3"]):
        _fails(capsys, ["layout", "import-cmp", str(XML), *option], "cmp_b0009.xml", "must be a positive number")


def test_the_api_refuses_what_the_cli_refuses(layout_json):
    from citygen_inverse.actions import CostModel
    from citygen_inverse.cmp import import_cmp
    from citygen_inverse.extract import extract_grammar
    layout = FacadeLayout.loads(layout_json.read_text())
    with pytest.raises(ValueError, match="split must be a finite number >= 0"):
        CostModel(split=-0.1)
    with pytest.raises(ValueError, match="adp needs at least 1 iteration"):
        extract_grammar(layout, "adp", 0)
    assert extract_grammar(layout, "greedy", 0).iterations == 1
    with pytest.raises(Exception, match="floor_height must be a positive number"):
        import_cmp(XML, floor_height=0.0)


def test_output_goes_into_a_new_directory(layout_json, tmp_path, capsys):
    """Regression: ``-o new/dir/file`` ended in a FileNotFoundError traceback (``citygen generate`` creates the
    stage's directory; the layout and grammar writers now do too)."""
    out = tmp_path / "new" / "dir" / "b0045.json"
    assert main(["layout", "import-cmp", str(DATA / "cmp_b0045.xml"), "-o", str(out)]) == 0
    grammar = tmp_path / "other" / "g.grammar"
    assert main(["grammar", "extract", str(out), "--method", "greedy", "-o", str(grammar)]) == 0
    assert FacadeLayout.loads(out.read_text()).width > 0 and grammar.read_text().strip()
