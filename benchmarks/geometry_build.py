"""Geometry benchmark: CPU per building of ``build_geometry`` on a scene's real layouts (default: the Helsinki demo).

    python benchmarks/geometry_build.py [SCENE] [--repeat 3] [--cache FILE] [--profile]

The scene is derived once (one job, nothing written) while every ``build_geometry`` call's arguments are recorded;
``--cache FILE`` pickles them so later runs skip the derivation. Then the recorded calls are replayed ``--repeat``
times and the script prints the median and best CPU (process_time) per building and a sha256 digest of every
output array (meshes, instances, module prototypes, roof, walls): the digest must not change when the geometry code
only gets faster.
``--profile`` replays once under pyinstrument instead (installed with the ``bench`` extra).
"""
from __future__ import annotations

import argparse
import contextlib
import gc
import hashlib
import pickle
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

import citygen.builder
import citygen.pipeline
from citygen.gcpause import cyclic_gc_paused
from citygen.geometry.building import BuildingGeometry, MeshData, build_geometry, clear_module_cache
from citygen.scene import load_scene

REPO = Path(__file__).resolve().parents[1]


class _NoStage:
    """A stage writer that writes nothing (the benchmark only wants the builds)."""

    def ground(self, *args) -> None:
        pass

    def add(self, record) -> None:
        pass

    def close(self) -> None:
        return None


def record_calls(scene_path: Path) -> list[tuple[tuple, dict]]:
    """The arguments of every ``build_geometry`` call of the scene's one-job run (nothing is written)."""
    calls: list[tuple[tuple, dict]] = []

    def recording(*args, **kwargs):
        calls.append((args, kwargs))
        return build_geometry(*args, **kwargs)

    scene = load_scene(scene_path)
    original_build, original_writer = citygen.builder.build_geometry, citygen.pipeline._writer
    citygen.builder.build_geometry = recording
    citygen.pipeline._writer = lambda *args: contextlib.nullcontext(_NoStage())
    try:  # (in a scratch folder: a scene with tile layers still writes them)
        with tempfile.TemporaryDirectory() as scratch:
            citygen.pipeline.generate_city(scene, out=Path(scratch) / "unwritten.usdc", jobs=1)
    finally:
        citygen.builder.build_geometry, citygen.pipeline._writer = original_build, original_writer
    return calls


def _digest_mesh(h, mesh: MeshData | None) -> None:
    if mesh is not None:
        for array in (mesh.points, mesh.counts, mesh.indices):
            h.update(np.ascontiguousarray(array).tobytes())


def digest(geometries: list[BuildingGeometry]) -> str:
    """sha256 over every array and key of the geometries, in order."""
    h = hashlib.sha256()
    for g in geometries:
        for key, mesh in g.meshes.items():
            h.update(repr(key).encode())
            _digest_mesh(h, mesh)
        for instances in (g.instances, *(p.elements for p in g.modules.values())):
            h.update(repr(instances.protos).encode())
            for array in (instances.proto_indices, instances.positions, instances.orientations, instances.scales):
                h.update(np.ascontiguousarray(array).tobytes())
        for key, proto in g.modules.items():
            h.update(repr(key).encode())
            for name, mesh in proto.meshes.items():
                h.update(repr(name).encode())
                _digest_mesh(h, mesh)
        _digest_mesh(h, g.roof)
        _digest_mesh(h, g.walls)
        h.update(g.roof_material.encode())
    return h.hexdigest()


def replay(calls: list[tuple[tuple, dict]]) -> tuple[float, list[BuildingGeometry]]:
    """CPU seconds of building every recorded call (the module cache cleared and the cyclic garbage collector paused
    per building, as the builder does)."""
    out = []
    t0 = time.process_time()
    for args, kwargs in calls:
        clear_module_cache()
        with cyclic_gc_paused():
            out.append(build_geometry(*args, **kwargs))
    return time.process_time() - t0, out


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("scene", nargs="?", type=Path, default=REPO / "scenes" / "helsinki.toml")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--cache", type=Path, help="pickle of the recorded calls (written when missing)")
    parser.add_argument("--profile", action="store_true")
    args = parser.parse_args()
    if args.cache and args.cache.exists():
        calls = pickle.loads(args.cache.read_bytes())
    else:
        calls = record_calls(args.scene)
        if args.cache:
            args.cache.write_bytes(pickle.dumps(calls, protocol=pickle.HIGHEST_PROTOCOL))
    gc.freeze()  # (the recorded layouts stay out of the collector's passes, which would blur a comparison)
    if args.profile:
        from pyinstrument import Profiler
        with Profiler(interval=0.0005) as profiler:
            replay(calls)
        print(profiler.output_text(unicode=False, color=False, show_all=False))
        return
    runs, geometries = [], []
    for _ in range(args.repeat):
        cpu, geometries = replay(calls)
        runs.append(cpu)
    cpu = statistics.median(runs)
    print(f"{args.scene.name}: {len(calls)} buildings, build_geometry CPU median {cpu:.2f} s, best {min(runs):.2f} s "
          f"({1000 * cpu / len(calls):.1f} / {1000 * min(runs) / len(calls):.1f} ms per building; "
          f"runs {', '.join(f'{r:.2f}' for r in runs)})")
    print(f"  digest {digest(geometries)}")


if __name__ == "__main__":
    main()
