from citygen.pipeline import generate_city
from citygen.scene import load_scene
from citygen.usd.validate import validate_stage


def test_small_city_is_written_and_valid(small_scene, test_registry):
    report = generate_city(load_scene(small_scene), registry=test_registry)
    assert report.written == 3
    assert [s.id for s in report.skipped] == ["way/bad"]
    errors = [f for f in validate_stage(report.stats.path) if f.severity == "error"]
    assert errors == []
