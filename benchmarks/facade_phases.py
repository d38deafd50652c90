"""CPU per phase of the buildings of a scene (default: the Helsinki demo), built one by one in this process.

    python benchmarks/facade_phases.py [SCENE] [--limit N] [--profile FILE]

Builds every building as ``citygen generate --jobs 1`` does (no stage is written) and prints the CPU seconds
(this thread's) spent inside each phase, inclusive of what it calls: the whole build, the split-grammar
derivations, the plausibility / partition / request checks, the relayout search, the roofs and the geometry.
Phases nest (checks run inside the split and relayout kinds), so the rows do not add up. ``--profile`` writes a
cProfile of the builds to FILE.
"""
from __future__ import annotations

import argparse
import cProfile
import functools
import importlib
import inspect
import math
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def _phases() -> dict[str, tuple[object, str]]:
    """Phase name -> (owner of the function, its attribute name)."""
    import citygen.builder
    import citygen.entrance
    import citygen.layout
    import citygen.plausible
    import citygen.request
    import citygen.roofmesh
    import citygen_relayout.api
    import citygen_split.alternatives
    derive = importlib.import_module("citygen_split.derive")  # (the package's ``derive`` is the function)
    return {
        "build (all)": (citygen.builder.Builder, "build"),
        "split: derive_plausible": (citygen_split.alternatives, "derive_plausible"),
        "split: derivations": (derive._Derivation, "run"),
        "relayout": (citygen_relayout.api, "relayout"),
        "check_plausible": (citygen.plausible, "_findings"),
        "check_partition": (citygen.layout, "check_partition"),
        "check_request": (citygen.request, "_problems"),
        "builder: _held": (citygen.builder.Builder, "_held"),
        "builder: _checked": (citygen.builder.Builder, "_checked"),
        "builder: _defined": (citygen.builder.Builder, "_defined"),
        "hidden_behind": (citygen.builder, "hidden_behind"),
        "enforce_entrance": (citygen.entrance, "enforce_entrance"),
        "roof": (citygen.roofmesh, "build_roof"),
        "build_geometry": (citygen.builder, "build_geometry"),
    }


def _instrument(phases: dict[str, tuple[object, str]]) -> tuple[dict[str, float], dict[str, int]]:
    """Wrap each phase's function (everywhere it was imported by name) to add its inclusive CPU to the totals;
    a phase re-entered within itself counts once."""
    cpu = dict.fromkeys(phases, 0.0)
    calls = dict.fromkeys(phases, 0)
    for name, (owner, attr) in phases.items():
        original = getattr(owner, attr)
        depth = [0]

        def timed(*args, _f=original, _name=name, _depth=depth, **kwargs):
            calls[_name] += 1
            if _depth[0]:
                return _f(*args, **kwargs)
            _depth[0] += 1
            start = time.thread_time()
            try:
                return _f(*args, **kwargs)
            finally:
                cpu[_name] += time.thread_time() - start
                _depth[0] -= 1

        wrapper = functools.wraps(original)(timed)
        for module in list(sys.modules.values()):
            if getattr(module, "__name__", "").startswith(("citygen", "citygen_")) and \
                    getattr(module, attr, None) is original:
                setattr(module, attr, wrapper)
        static = isinstance(inspect.getattr_static(owner, attr), staticmethod)
        setattr(owner, attr, staticmethod(wrapper) if static else wrapper)
    return cpu, calls


def _work(scene_path: Path) -> tuple[object, list[tuple]]:
    """The scene and its buildings' build arguments, in the pipeline's order."""
    from citygen.builder import load_rulesets
    from citygen.errors import CitygenError
    from citygen.mass import neighbour_cover
    from citygen.pipeline import import_footprints
    from citygen.registry import default_registry
    from citygen.roofplan import plan_mass
    from citygen.scene import load_scene
    from citygen.usd.names import prim_name

    scene = load_scene(scene_path)
    registry = default_registry()
    rulesets = load_rulesets(scene, registry)
    footprints, masses = [], []
    for fp in import_footprints(scene, registry).footprints:
        try:
            masses.append(plan_mass(fp, scene, registry.roof_builders)[0])
        except CitygenError:  # (the pipeline skips it too)
            continue
        footprints.append(fp)
    cover = neighbour_cover(masses)
    taken: set[str] = set()
    names = [prim_name(fp.id, taken) for fp in footprints]
    size = scene.output.tile_size
    tiles = [(math.floor(m.outline.centroid.x / size), math.floor(m.outline.centroid.y / size)) for m in masses]
    work = sorted(zip(footprints, masses, cover, names, tiles), key=lambda w: (w[4], w[3]))
    return (scene, registry, rulesets), work


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(REPO / "scenes" / "helsinki.toml"))
    parser.add_argument("--limit", type=int, default=0, help="build only the first N buildings")
    parser.add_argument("--profile", help="write a cProfile of the builds to this file")
    args = parser.parse_args()
    from citygen.builder import Builder

    (scene, registry, rulesets), work = _work(Path(args.scene))
    if args.limit:
        work = work[: args.limit]
    cpu, calls = _instrument(_phases())
    builder = Builder(scene, scene.seed, registry, rulesets)
    profile = cProfile.Profile() if args.profile else None
    start = time.thread_time()
    if profile:
        profile.enable()
    skipped = sum(builder.build(*item).record is None for item in work)
    if profile:
        profile.disable()
        profile.dump_stats(args.profile)
    total = time.thread_time() - start
    print(f"{Path(args.scene).name}: {len(work)} buildings ({skipped} skipped), {total:.2f} s CPU, "
          f"{1e3 * total / max(len(work), 1):.1f} ms per building")
    print(f"{'phase':<26} {'CPU s':>8} {'ms/bldg':>8} {'calls':>8}")
    for name in cpu:
        print(f"{name:<26} {cpu[name]:>8.2f} {1e3 * cpu[name] / max(len(work), 1):>8.1f} {calls[name]:>8}")


if __name__ == "__main__":
    main()
