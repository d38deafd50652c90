"""Footprint import benchmark: median time to read the shipped Helsinki (GeoJSON) and Delft (CityJSON) data.

    python benchmarks/footprints_import.py [--repeat N] [FILE ...]

Prints per file: footprints, skipped, warnings, median / min ms over N runs, footprints per second.
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from citygen_footprints.plugin import read_footprints

REPO = Path(__file__).resolve().parents[1]
DEFAULT_FILES = [REPO / "scenes" / "data" / "helsinki_buildings.geojson",
                 REPO / "scenes" / "data" / "delft_buildings.city.json"]
FULL_DELFT = REPO / ".." / "shared" / "data" / "cityjson_delft" / "delft.json"


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("files", nargs="*", type=Path)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    files = args.files or DEFAULT_FILES + ([FULL_DELFT] if FULL_DELFT.exists() else [])
    for path in files:
        read_footprints(path, {})  # warm up imports and PROJ's database
        times = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            result = read_footprints(path, {})
            times.append(time.perf_counter() - t0)
        median = statistics.median(times)
        print(f"{path.name}: {len(result.footprints)} footprints, {len(result.skipped)} skipped, "
              f"{len(result.warnings)} warnings; median {median * 1000:.0f} ms, min {min(times) * 1000:.0f} ms "
              f"({len(result.footprints) / median:.0f} footprints/s, {args.repeat} runs)")


if __name__ == "__main__":
    main()
