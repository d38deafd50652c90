"""Scaling benchmark: a synthetic city of N blocks of row houses, to see how generation grows with city size.

    python benchmarks/city_scale.py [N ...] [--jobs 2] [--one-file] [--masses] [--executor dask [--scheduler ADDRESS]]

Footprints are rectangles in EPSG:3067 (Finnish TM) around Helsinki, 8-40 m wide, 3-8 storeys, in blocks that
share party walls, dressed with the shipped split grammars. Prints buildings/s, wall and CPU time (main process, and
main plus its finished children: the workers and the child that imports the footprints and plans the masses), peak memory (main process, largest worker, and the whole process
tree: the sums of the RSS -- which counts pages a forked worker shares with the main process twice -- and of the
PSS -- which shares them out -- of the main process and its children, sampled every second by a thread whose own
CPU is left out of the main process's: reading a process's smaps costs ~4 ms, so sampling three processes five
times a second took ~70 s of the main process's CPU in a 20-minute run) and stage size per N. The
scene leaves ``tile_layers`` unset (tile layers above 1,000 buildings, the default); ``--one-file`` forces one
layer; ``--masses`` makes a mass-only (LOD1) city.
``--executor dask`` runs one task per tile on a local dask cluster of ``--jobs`` workers (or on ``--scheduler``;
then the workers' CPU and memory are not seen here). Run one N per invocation for a clean peak (ru_maxrss never
goes down).
"""
from __future__ import annotations

import argparse
import contextlib
import json
import resource
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import psutil

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
    parser.add_argument("--one-file", action="store_true", help="tile_layers = false: the whole city in one layer")
    parser.add_argument("--masses", action="store_true", help="masses = true: a mass-only (LOD1) city")
    parser.add_argument("--executor", choices=("local", "dask"), default="local")
    parser.add_argument("--scheduler", help="with --executor dask: a running scheduler's address")
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
                + ("tile_layers = false\n" if args.one_file else "") + ("masses = true\n" if args.masses else ""))
            t0, c0, k0 = time.perf_counter(), time.process_time(), _children_cpu()
            with TreePeak() as tree:
                report = generate_city(load_scene(tmp / "scene.toml"), jobs=args.jobs, executor=args.executor,
                                       scheduler=args.scheduler)
            elapsed, cpu, children = time.perf_counter() - t0, time.process_time() - c0 - tree.cpu, _children_cpu() - k0
            main_peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
            worker_peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
            s = report.stats
            print(f"N={n} [{args.executor}, {args.jobs} jobs{', one file' if args.one_file else ''}"
                  f"{', masses only' if args.masses else ''}]: "
                  f"{report.written} buildings in {elapsed:.1f} s = {report.written / elapsed:.0f} buildings/s; "
                  f"CPU main {cpu:.1f} s, main+workers {cpu + children:.1f} s; "
                  f"peak RSS main {main_peak:.0f} MB, worker {worker_peak:.0f} MB, process tree {tree.peak:.0f} MB "
                  f"(PSS {tree.pss:.0f} MB); "
                  f"{s.bytes / 1e6:.1f} MB .usdc "
                  f"({s.bytes / max(report.written, 1) / 1e3:.0f} kB/building); {s.instances} instances of "
                  f"{s.prototypes} prototypes")


class TreePeak(threading.Thread):
    """The peaks, in MB, of the summed RSS and PSS of this process and all its descendants, sampled every second;
    ``cpu``: the CPU seconds the sampling took (this thread's)."""

    def __init__(self) -> None:
        super().__init__(daemon=True)
        self.peak = self.pss = self.cpu = 0.0
        self.done = threading.Event()

    def __enter__(self) -> TreePeak:
        self.start()
        return self

    def __exit__(self, *exc) -> None:
        self.done.set()
        self.join()

    def run(self) -> None:
        me = psutil.Process()
        while not self.done.wait(1.0):
            rss = pss = 0
            for proc in [me, *me.children(recursive=True)]:
                with contextlib.suppress(psutil.Error):
                    info = proc.memory_full_info()
                    rss, pss = rss + info.rss, pss + info.pss
            self.peak, self.pss = max(self.peak, rss / 2 ** 20), max(self.pss, pss / 2 ** 20)
            self.cpu = time.thread_time()


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


if __name__ == "__main__":
    main()
