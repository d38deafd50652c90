"""Shared fixtures: a registry with the test plugins and a small city of local-metric footprints."""
from __future__ import annotations

import json
from pathlib import Path

import os

import pytest
from hypothesis import settings

from citygen.registry import load_registry

# CI runs the same examples every time (a red build must be reproducible); locally hypothesis explores.
settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
settings.register_profile("dev", deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else os.environ.get("HYPOTHESIS_PROFILE", "dev"))

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data"


@pytest.fixture(scope="session")
def test_registry():
    from tests.core.fakes import FakePlugin
    return load_registry(extra_plugins=[FakePlugin()])


SMALL_CITY = [
    {"id": "way/1", "coordinates": [[[0, 0], [20, 0], [20, 12], [0, 12], [0, 0]]], "height": 15.0, "levels": 5},
    # shares its west wall with way/1 (party wall), has a courtyard
    {"id": "way/2", "coordinates": [[[20, 0], [50, 0], [50, 30], [20, 30], [20, 0]],
                                    [[28, 8], [42, 8], [42, 22], [28, 22], [28, 8]]], "height": 18.0,
     "tags": {"building": "apartments"}},
    # nearly collinear vertex and a 10 cm jog that must merge away
    {"id": "way/3", "coordinates": [[[0, 40], [8, 40.03], [16, 40], [16, 50], [8.05, 50], [8, 50.1], [0, 50], [0, 40]]],
     "height": 7.0, "tags": {"building": "house"}},
    {"id": "way/bad", "coordinates": [[[0, 60], [10, 70], [10, 60], [0, 70], [0, 60]]], "height": 9.0},
]


@pytest.fixture
def small_scene(tmp_path: Path) -> Path:
    (tmp_path / "city.local.json").write_text(json.dumps(SMALL_CITY))
    (tmp_path / "bays.testgrid").write_text(json.dumps({"bay": 3.0, "window": 1.3}))
    (tmp_path / "scene.toml").write_text(
        '[scene]\nname = "small"\nseed = 3\n\n[footprints]\npath = "city.local.json"\n\n'
        '[defaults]\nfloor_height = 3.0\n\n[[assign]]\nruleset = "bays.testgrid"\n\n'
        '[output]\npath = "out/small.usda"\n')
    return tmp_path / "scene.toml"
