"""What ``generate`` says about a run that went wrong quietly (issue 23, smaller findings): ``when`` tests that
can match nothing, an empty footprint file, and why ``--strict`` failed."""
from __future__ import annotations

import json

from citygen.cli import main
from citygen.pipeline import generate_city
from citygen.scene import load_scene
from tests.core.cli_scene import write_scene


def test_a_misspelt_when_attribute_is_a_warning_naming_the_rule_and_the_near_names(small_scene, test_registry):
    small_scene.write_text(small_scene.read_text().replace('[[assign]]\nruleset = "bays.testgrid"\n',
                                                           '[[assign]]\nwhen = { bulding = "house" }\n'
                                                           'ruleset = "bays.testgrid"\n[[assign]]\n'
                                                           'ruleset = "bays.testgrid"\n'))
    report = generate_city(load_scene(small_scene), registry=test_registry)
    assert "scene.toml:11: [[assign]] #1: no footprint has attribute 'bulding', so the rule matches none (did you " \
           "mean 'building'?)" in report.warnings


def test_text_compared_with_a_numeric_attribute_is_a_warning(small_scene, test_registry):
    small_scene.write_text(small_scene.read_text().replace('[[assign]]\nruleset = "bays.testgrid"\n',
                                                           '[[assign]]\nwhen = { height = "tall" }\n'
                                                           'ruleset = "bays.testgrid"\n[[assign]]\n'
                                                           'ruleset = "bays.testgrid"\n'))
    report = generate_city(load_scene(small_scene), registry=test_registry)
    assert "scene.toml:11: [[assign]] #1: when height = ['tall'] compares text with height, a number on every " \
           "footprint: it never matches" in report.warnings


def test_an_empty_footprint_file_warns_and_fails_strict_saying_why(tmp_path, capsys):
    """Was: an empty FeatureCollection wrote an empty stage with exit 0 even with --strict, and --strict exited 1
    without saying why."""
    scene = write_scene(tmp_path, buildings=0)
    assert main(["generate", str(scene), "-q"]) == 0
    assert "city.geojson: no footprint to build; the stage is empty" in capsys.readouterr().out
    assert main(["generate", str(scene), "-q", "--strict"]) == 1
    assert capsys.readouterr().err == "citygen: --strict: no building written (exit status 1)\n"


def test_strict_says_how_many_buildings_were_skipped(tmp_path, capsys):
    scene = write_scene(tmp_path, buildings=2)
    data = json.loads((tmp_path / "city.geojson").read_text())
    data["features"][1]["geometry"]["coordinates"] = [[[24.94, 60.17], [24.94, 60.17], [24.94, 60.17],
                                                        [24.94, 60.17]]]
    (tmp_path / "city.geojson").write_text(json.dumps(data))
    assert main(["generate", str(scene), "-q", "--strict"]) == 1
    assert capsys.readouterr().err == "citygen: --strict: 1 buildings skipped (exit status 1)\n"


def test_an_importer_option_error_names_the_scene_file_and_line(tmp_path):
    """Was: ``[footprints]: [footprints] min_area = -1 is invalid``, with no file or line."""
    import pytest

    from citygen.errors import SceneError
    scene = write_scene(tmp_path, buildings=1)
    scene.write_text(scene.read_text().replace('path = "city.geojson"\n', 'path = "city.geojson"\nmin_area = -1\n'))
    with pytest.raises(SceneError) as info:
        generate_city(load_scene(scene))
    assert str(info.value).startswith(f"{scene}:5: [footprints] min_area = -1 is invalid")
