"""Scaling benchmark: a synthetic city of N blocks of row houses, to see how generation grows with city size.

    python benchmarks/city_scale.py [N ...] [--jobs 2] [--tile-layers]

Footprints are rectangles in EPSG:3067 (Finnish TM) around Helsinki, 8-40 m wide, 3-8 storeys, in blocks that
share party walls, dressed with the shipped split grammars. Prints buildings/s, peak memory (main process and
largest worker) and stage size per N. Run one N per invocation for a clean peak (ru_maxrss never goes down).
"""
from __future__ import annotations

import argparse
import json
import resource
import tempfile
import time
from pathlib import Path

import numpy as np

from citygen.pipeline import generate_city
from citygen.scene import load_scene

REPO = Path(__file__).resolve().parents[1]


def synthetic_city(n: int, seed: int = 1) -> dict:
    rng = np.random.default_rng(seed)
    features, x0, y0 = [], 385000.0, 6672000.0
    per_row = max(1, int(np.sqrt(n)))
    for i in range(n):
        row, col = divmod(i, per_row)
        w, d = rng.uniform(8, 40), rng.uniform(10, 18)
        x, y = x0 + col * 42.0, y0 + row * 30.0
        ring = [[x, y], [x + w, y], [x + w, y + d], [x, y + d], [x, y]]
        features.append({"type": "Feature", "properties": {"id": i, "osm_type": "way",
                                                           "building:levels": str(int(rng.integers(3, 9)))},
                         "geometry": {"type": "Polygon", "coordinates": [ring]}})
    return {"type": "FeatureCollection", "features": features}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("sizes", nargs="*", type=int, default=[500, 2000])
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--tile-layers", action="store_true", help="stream each 250 m tile into its own layer")
    args = parser.parse_args()
    for n in args.sizes:
        with tempfile.TemporaryDirectory() as tmp:
            tmp = Path(tmp)
            (tmp / "city.geojson").write_text(json.dumps(synthetic_city(n)))
            rulesets = ", ".join(f'"{(REPO / "rulesets" / g).as_posix()}"'
                                 for g in ("apartment.grammar", "office.grammar", "historic.grammar"))
            (tmp / "scene.toml").write_text(
                f'[scene]\nseed = 1\n[footprints]\npath = "city.geojson"\ncrs = "EPSG:3067"\n'
                f'[[assign]]\nruleset = [{rulesets}]\n[output]\npath = "city.usdc"\n'
                f'tile_layers = {str(args.tile_layers).lower()}\n')
            t0 = time.perf_counter()
            report = generate_city(load_scene(tmp / "scene.toml"), jobs=args.jobs)
            elapsed = time.perf_counter() - t0
            main_peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
            worker_peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
            s = report.stats
            print(f"N={n}: {report.written} buildings in {elapsed:.1f} s = {report.written / elapsed:.0f} buildings/s;"
                  f" peak RSS main {main_peak:.0f} MB, worker {worker_peak:.0f} MB; {s.bytes / 1e6:.1f} MB .usdc ({s.bytes / max(report.written, 1) / 1e3:.0f}"
                  f" kB/building); {s.instances} instances of {s.prototypes} prototypes")


if __name__ == "__main__":
    main()
