"""Shared paths and helpers for the footprint importer tests."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT / ".." / "shared" / "data"
HELSINKI = ROOT / "scenes" / "data" / "helsinki_buildings.geojson"
DELFT = ROOT / "scenes" / "data" / "delft_buildings.city.json"
BAD = ROOT / "tests" / "data" / "footprints" / "bad_footprints.geojson"


def write_json(path: Path, doc: object) -> Path:
    path.write_text(json.dumps(doc))
    return path


@pytest.fixture(scope="session")
def helsinki():
    from citygen_footprints.plugin import read_footprints
    return read_footprints(HELSINKI, {})


@pytest.fixture(scope="session")
def delft():
    from citygen_footprints.plugin import read_footprints
    return read_footprints(DELFT, {})
