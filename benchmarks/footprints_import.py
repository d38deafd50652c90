"""Footprint import benchmark: median time to read the shipped Helsinki (GeoJSON, OpenStreetMap) and Delft
(CityJSON) data.

    python benchmarks/footprints_import.py [--repeat N] [FILE ...]

Prints per file: footprints, skipped, warnings, median / min ms over N runs, footprints per second. With pyosmium
and no FILE also the Helsinki extract as Overpass writes it -- ways and relations before their nodes, as XML and
as OSM JSON -- which is read from a sorted copy, and whether its footprints equal the extract's.
"""
from __future__ import annotations

import argparse
import importlib.util
import statistics
import sys
import tempfile
import time
from pathlib import Path

from citygen_footprints.plugin import OSMImporter, read_footprints

REPO = Path(__file__).resolve().parents[1]
DEFAULT_FILES = [REPO / "scenes" / "data" / "helsinki_buildings.geojson",
                 REPO / "scenes" / "data" / "delft_buildings.city.json"]
FULL_DELFT = REPO / ".." / "shared" / "data" / "cityjson_delft" / "delft.json"
HELSINKI_PBF = REPO / "scenes" / "data" / "helsinki.osm.pbf"


def read(path: Path):
    return OSMImporter().read(path, {}) if path.suffix in (".osm", ".pbf") else read_footprints(path, {})


def overpass_copies(directory: Path) -> list[Path]:
    """The Helsinki extract in the Overpass API's order (ways and relations, then nodes): as OSM XML and as OSM
    JSON (``tests.mutate.write_osm``)."""
    import osmium
    from citygen_footprints.osm_sorted import plain
    sys.path.insert(0, str(REPO))
    from tests.mutate import osm_model, write_osm
    elements = list(plain(osmium.FileProcessor(str(HELSINKI_PBF), osmium.osm.NODE | osmium.osm.WAY |
                                               osmium.osm.RELATION)))
    model = osm_model({i: (a, b) for kind, i, a, b in elements if kind == "n" and a is not None},
                      [e[1:] for e in elements if e[0] == "w"], [e[1:] for e in elements if e[0] == "r"])
    paths = [directory / "helsinki_overpass.osm", directory / "helsinki_overpass.json"]
    for path in paths:
        write_osm(model, path)
    return paths


def measure(path: Path, repeat: int):
    read(path)  # warm up imports and PROJ's database
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = read(path)
        times.append(time.perf_counter() - t0)
    median = statistics.median(times)
    print(f"{path.name}: {len(result.footprints)} footprints, {len(result.skipped)} skipped, "
          f"{len(result.warnings)} warnings; median {median * 1000:.0f} ms, min {min(times) * 1000:.0f} ms "
          f"({len(result.footprints) / median:.0f} footprints/s, {repeat} runs)")
    return result


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("files", nargs="*", type=Path)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    files = args.files or DEFAULT_FILES + ([FULL_DELFT] if FULL_DELFT.exists() else [])
    for path in files:
        measure(path, args.repeat)
    if not args.files and importlib.util.find_spec("osmium"):
        reference = measure(HELSINKI_PBF, args.repeat)
        with tempfile.TemporaryDirectory() as tmp:
            for path in overpass_copies(Path(tmp)):
                result = measure(path, args.repeat)
                same = [(f.id, f.polygon.wkb, f.height) for f in result.footprints] == \
                    [(f.id, f.polygon.wkb, f.height) for f in reference.footprints]
                print(f"  the same footprints as {HELSINKI_PBF.name}: {same}")


if __name__ == "__main__":
    main()
