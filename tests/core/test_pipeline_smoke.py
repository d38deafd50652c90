import pytest

from citygen.pipeline import generate_city
from citygen.scene import load_scene
from citygen.usd.validate import validate_stage


def test_small_city_is_written_and_valid(small_scene, test_registry):
    report = generate_city(load_scene(small_scene), registry=test_registry)
    assert report.written == 3
    assert [s.id for s in report.skipped] == ["way/bad"]
    errors = [f for f in validate_stage(report.stats.path) if f.severity == "error"]
    assert errors == []


def test_a_face_the_ruleset_cannot_dress_becomes_plain_wall(small_scene, test_registry, monkeypatch):
    _picky(monkeypatch, {3.0})
    report = generate_city(load_scene(small_scene), registry=test_registry)
    assert report.written == 3
    assert any("testgrid fell back to plain walls: the ruleset failed" in w for w in report.warnings)
    errors = [f for f in validate_stage(report.stats.path) if f.severity == "error"]
    assert errors == []


def test_a_bug_building_one_mass_skips_that_building_as_an_internal_error(small_scene, test_registry, monkeypatch):
    """A mass builder that raises something other than a CitygenError is a bug: the building is skipped with a
    reason saying so (as a facade or roof bug is), which the fuzz harness looks for; the rest is written."""
    import citygen.pipeline as pipeline
    original = pipeline.mass_plan
    scene = load_scene(small_scene)
    first = pipeline.import_footprints(scene, test_registry).footprints[0].id

    def broken(footprint, scene, roofs):  # (called where the city is planned: maybe a forked child process)
        if footprint.id == first:
            raise ZeroDivisionError("float division by zero")
        return original(footprint, scene, roofs)

    monkeypatch.setattr(pipeline, "mass_plan", broken)
    report = generate_city(scene, registry=test_registry)
    assert report.written == 2
    (skip,) = [s for s in report.skipped if s.id == first]
    assert skip.reason == "internal error ZeroDivisionError building its mass: float division by zero"


def _picky(monkeypatch, bays):
    """GridKind fails on faces narrower than 13 m with the rulesets whose bay (m) is in the set ``bays``."""
    from citygen.errors import RulesetError
    from tests.core.fakes import GridKind

    original = GridKind.generate

    def picky(self, ruleset, request):
        if request.width < 13 and ruleset["bay"] in bays:
            raise RulesetError("face too narrow for this test ruleset")
        return original(self, ruleset, request)

    monkeypatch.setattr(GridKind, "generate", picky)


def _openings(stage_path):
    from pxr import Usd
    stage = Usd.Stage.Open(str(stage_path))
    return sum(1 for p in stage.Traverse() if p.IsInstance())


def test_a_fallback_ruleset_dresses_the_faces_the_assigned_one_cannot(small_scene, test_registry, monkeypatch):
    """``[[assign]] fallback``: the faces the assigned ruleset leaves plain get the fallback ruleset instead (same
    floor lines; one warning naming them and why); the building's ruleset attribute names them."""
    from pxr import Usd
    failing = {3.0, 2.0}
    _picky(monkeypatch, failing)
    (small_scene.parent / "wide.testgrid").write_text('{"bay": 2.0, "window": 1.0}')
    small_scene.write_text(small_scene.read_text().replace('ruleset = "bays.testgrid"\n',
                                                           'ruleset = "bays.testgrid"\nfallback = "wide.testgrid"\n'))
    plain = generate_city(load_scene(small_scene), out=small_scene.parent / "plain.usda", registry=test_registry)
    failing.discard(2.0)  # now the fallback can dress them
    dressed = generate_city(load_scene(small_scene), out=small_scene.parent / "dressed.usda", registry=test_registry)
    assert dressed.written == 3 and not [w for w in dressed.warnings if "fell back to plain walls" in w]
    assert [w for w in plain.warnings if "fell back to plain walls" in w]  # the fallback fails too: plain, reported
    assert _openings(dressed.stats.path) > _openings(plain.stats.path)
    stage = Usd.Stage.Open(str(dressed.stats.path))
    rulesets = [p.GetAttribute("citygen:ruleset").Get() for p in stage.Traverse() if p.HasAttribute("citygen:ruleset")]
    assert any("testgrid:wide.testgrid (fallback on faces" in r for r in rulesets)


def test_masses_only_builds_walls_and_roofs_without_generating_a_facade(small_scene, test_registry, monkeypatch):
    """``[output] masses = true`` (``citygen generate --masses``): no ruleset is loaded, no face generated."""
    from citygen.builder import Builder
    monkeypatch.setattr(Builder, "ruleset", lambda *a: pytest.fail("a ruleset was loaded in masses-only mode"))
    small_scene.write_text(small_scene.read_text().replace("[output]\n", "[output]\nmasses = true\n"))
    report = generate_city(load_scene(small_scene), registry=test_registry)
    assert report.written == 3 and not report.faces and report.stats.instances == 0
