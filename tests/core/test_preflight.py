"""What ``generate`` checks before it builds anything (issue 23): every ruleset the scene names loads, the output
and report paths can be written. A failure is one error line and leaves nothing behind."""
from __future__ import annotations

import pytest

from citygen.errors import CitygenError, SceneError
from citygen.pipeline import generate_city
from citygen.scene import load_scene
from tests.core.test_pipeline_smoke import _picky


def _add_rule(scene_path, rule: str) -> None:
    text = scene_path.read_text()
    scene_path.write_text(text.replace("[[assign]]\n", rule + "\n[[assign]]\n", 1))


def test_a_ruleset_with_a_syntax_error_stops_the_run_before_any_building(small_scene, test_registry):
    """Was: rulesets parsed when first used, so every building using it was skipped and the run exited 0."""
    (small_scene.parent / "broken.grammar").write_text("@start Facade\nFacade --> split(x) { 1: A | \n")
    _add_rule(small_scene, '[[assign]]\nwhen = { building = "house" }\nruleset = "broken.grammar"\n')
    scene = load_scene(small_scene)
    with pytest.raises(SceneError) as info:
        generate_city(scene, registry=test_registry)
    message = str(info.value)
    assert f"{small_scene}:11: [[assign]] #1: ruleset broken.grammar does not load: " in message
    assert f"{small_scene.parent / 'broken.grammar'}:3:1: expected a size" in message  # the ruleset's own file:line:column
    assert not (small_scene.parent / "out").exists()


def test_a_ruleset_read_by_the_wrong_kind_stops_the_run(small_scene, test_registry):
    _add_rule(small_scene, '[[assign]]\nwhen = { building = "house" }\nruleset = "bays.testgrid"\nkind = "split"\n')
    with pytest.raises(SceneError, match=r"ruleset bays.testgrid does not load: .*bays.testgrid:1:1"):
        generate_city(load_scene(small_scene), registry=test_registry)


def test_a_ruleset_kind_crashing_on_load_is_a_clear_error(small_scene, test_registry):
    """The test kind reads JSON with json.loads: a JSONDecodeError is the kind's bug, still one clear error."""
    (small_scene.parent / "bays.testgrid").write_text("{not json")
    with pytest.raises(SceneError, match=r"does not load: internal error JSONDecodeError.*\[plugin testgrid\]"):
        generate_city(load_scene(small_scene), registry=test_registry)


def test_a_broken_fallback_is_found_before_generating_too(small_scene, test_registry):
    (small_scene.parent / "broken.grammar").write_text("nonsense\n")
    small_scene.write_text(small_scene.read_text().replace('ruleset = "bays.testgrid"\n',
                                                           'ruleset = "bays.testgrid"\nfallback = "broken.grammar"\n'))
    with pytest.raises(CitygenError, match="ruleset broken.grammar does not load"):
        generate_city(load_scene(small_scene), registry=test_registry)


def test_the_fallback_dresses_faces_whose_ruleset_raised_any_error(small_scene, test_registry, monkeypatch):
    """docs/scene.md: a ruleset that raises gets the fallback. Was: only a CitygenError did; any other exception
    skipped the whole building as an internal error."""
    from tests.core.fakes import GridKind
    original = GridKind.generate

    def crashing(self, ruleset, request):
        if ruleset["bay"] == 3.0 and request.width < 13:
            raise ZeroDivisionError("a ruleset kind bug")
        return original(self, ruleset, request)

    monkeypatch.setattr(GridKind, "generate", crashing)
    (small_scene.parent / "wide.testgrid").write_text('{"bay": 2.0, "window": 1.0}')
    small_scene.write_text(small_scene.read_text().replace('ruleset = "bays.testgrid"\n',
                                                           'ruleset = "bays.testgrid"\nfallback = "wide.testgrid"\n'))
    report = generate_city(load_scene(small_scene), registry=test_registry)
    assert report.written == 3 and [s.id for s in report.skipped] == ["way/bad"]
    assert not [w for w in report.warnings if "fell back to plain walls" in w]


def test_without_a_fallback_a_ruleset_bug_still_skips_its_building_as_an_internal_error(small_scene, test_registry,
                                                                                         monkeypatch):
    from tests.core.fakes import GridKind

    def crashing(self, ruleset, request):
        raise ZeroDivisionError("a ruleset kind bug")

    monkeypatch.setattr(GridKind, "generate", crashing)
    report = generate_city(load_scene(small_scene), registry=test_registry)
    assert report.written == 0
    assert all(s.reason.startswith("internal error ZeroDivisionError") for s in report.skipped if s.id != "way/bad")


def test_a_ruleset_kind_calling_sys_exit_skips_its_building_not_the_run(small_scene, test_registry, monkeypatch):
    """Was: a plugin raising SystemExit ended the whole run silently."""
    import sys

    from tests.core.fakes import GridKind
    original = GridKind.generate

    def exits(self, ruleset, request):
        if request.context.building_id == "way/2":
            sys.exit(4)
        return original(self, ruleset, request)

    monkeypatch.setattr(GridKind, "generate", exits)
    report = generate_city(load_scene(small_scene), registry=test_registry)
    assert report.written == 2
    assert ("way/2", "internal error SystemExit: 4") in [(s.id, s.reason) for s in report.skipped]
