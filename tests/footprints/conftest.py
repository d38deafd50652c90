"""Shared paths and helpers for the footprint importer tests."""
from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import pytest

from citygen.errors import FootprintError
from citygen.footprints import ImportResult

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT / ".." / "shared" / "data"
HELSINKI = ROOT / "scenes" / "data" / "helsinki_buildings.geojson"
DELFT = ROOT / "scenes" / "data" / "delft_buildings.city.json"
BAD = ROOT / "tests" / "data" / "footprints" / "bad_footprints.geojson"


def assert_read_or_refused(read: Callable[[Path], ImportResult], path: Path) -> None:
    """A fuzzed file is refused with a FootprintError or read into footprints whose numbers are all finite."""
    try:
        result = read(path)
    except FootprintError:
        return
    for fp in result.footprints:
        assert all(abs(v) < float("inf") for v in (fp.height, fp.base, *fp.polygon.bounds)), fp.id


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
