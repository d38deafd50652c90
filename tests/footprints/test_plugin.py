"""The importers are found through the citygen entry point and chosen by suffix or content."""
from __future__ import annotations

from pathlib import Path

import pytest
from citygen.registry import load_registry

from .conftest import DELFT, HELSINKI


@pytest.fixture(scope="module")
def registry():
    return load_registry()


def test_importers_are_registered(registry):
    assert {"geojson", "cityjson"} <= set(registry.importers)
    assert registry.origins[("importers", "geojson")].plugin == "footprints"


@pytest.mark.parametrize("name, importer", [
    ("city.geojson", "geojson"), ("city.json", "geojson"), ("delft.city.json", "cityjson"),
    ("delft.cityjson", "cityjson"), ("CITY.GEOJSON", "geojson"), ("tile.city.jsonl", "cityjson"),
])
def test_importer_for_suffix(registry, name, importer):
    assert registry.importer_for(Path(name)).id == importer


def test_either_importer_reads_either_format(registry):
    # a CityJSON file named .json reaches the GeoJSON importer by suffix: it dispatches on the content
    assert len(registry.importers["geojson"].read(DELFT, {}).footprints) == 160
    assert len(registry.importers["cityjson"].read(HELSINKI, {}).footprints) == 480
