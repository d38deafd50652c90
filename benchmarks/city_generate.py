"""End-to-end city generation benchmark: buildings/s, peak memory, prims, instances and file size.

    python benchmarks/city_generate.py [SCENE ...] [--jobs N] [--suffix .usdc]

Default scene: scenes/helsinki.toml (486 OSM buildings). Target on a 2-core machine: < 10 s, < 1 GB.
"""
from __future__ import annotations

import argparse
import resource
import sys
import tempfile
import time
from pathlib import Path

from citygen.pipeline import generate_city
from citygen.scene import load_scene

REPO = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("scenes", nargs="*", default=[str(REPO / "scenes" / "helsinki.toml")])
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--suffix", default=".usdc")
    args = parser.parse_args()
    for scene_path in args.scenes:
        scene = load_scene(scene_path)
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / f"city{args.suffix}"
            t0 = time.perf_counter()
            report = generate_city(scene, out=out, jobs=args.jobs)
            elapsed = time.perf_counter() - t0
            s = report.stats
            peak = max(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss,
                       resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss) / 1024
            print(f"{Path(scene_path).name}: {report.written} buildings ({len(report.skipped)} skipped) in "
                  f"{elapsed:.2f} s = {report.written / elapsed:.0f} buildings/s, jobs {args.jobs}")
            print("  stages: " + ", ".join(f"{k} {v:.2f}s" for k, v in report.timings.items()))
            print(f"  peak RSS {peak:.0f} MB; {args.suffix} {s.bytes / 1e6:.2f} MB; {s.prims} prims, {s.meshes} "
                  f"meshes, {s.polygons} polygons, {s.instances} instances of {s.prototypes} prototypes; "
                  f"warnings {len(report.warnings)}")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
