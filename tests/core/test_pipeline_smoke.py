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
    from citygen.errors import RulesetError
    from tests.core.fakes import GridKind

    original = GridKind.generate

    def picky(self, ruleset, request):
        if request.width < 13:  # fails on the narrow faces only
            raise RulesetError("face too narrow for this test ruleset")
        return original(self, ruleset, request)

    monkeypatch.setattr(GridKind, "generate", picky)
    report = generate_city(load_scene(small_scene), registry=test_registry)
    assert report.written == 3
    assert any("plain wall, the ruleset failed" in w for w in report.warnings)
    errors = [f for f in validate_stage(report.stats.path) if f.severity == "error"]
    assert errors == []
