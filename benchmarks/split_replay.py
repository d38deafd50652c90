"""CPU of the split kind's derivations and the builder's layout checks on a scene's own faces, and a digest of the
layouts (to show that a change keeps them bit for bit).

    python benchmarks/split_replay.py [SCENE] [--repeat N]

Builds every building of the scene once (as ``citygen generate --jobs 1``) to collect the faces the split kind
is asked for, then derives them again ``--repeat`` times in this process with the cyclic collector paused (as the
builder does; a building's faces share their subtrees): ``derive_plausible`` (derivations and their plausibility
and request checks), then the builder's ``_checked`` checks (partition, entrance, request). Prints the least CPU
seconds of each part over the repeats and a sha256 of every layout's regions (coordinates, fields and which regions
share a module key; the rulesets' paths enter it, so compare runs of one checkout).
"""
from __future__ import annotations

import argparse
import gc
import hashlib
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from facade_phases import REPO, _work  # noqa: E402  (the scene's buildings, in the pipeline's order)


def _faces(scene_path: Path) -> list[tuple[object, object, object]]:
    """The (grammar, request, the building's shared subtrees) the split kind derives while the scene's buildings are
    built."""
    import citygen_split.plugin as plugin
    from citygen.builder import Builder

    (scene, registry, rulesets), work = _work(scene_path)
    faces = []
    original = plugin.derive_plausible

    def noted(grammar, request, *args, **kwargs):
        faces.append((grammar, request, kwargs.get("subtrees")))  # (the building's shared subtrees, if any)
        return original(grammar, request, *args, **kwargs)

    plugin.derive_plausible = noted
    try:
        builder = Builder(scene, scene.seed, registry, rulesets)
        for item in work:
            builder.build(*item)
    finally:
        plugin.derive_plausible = original
    return faces


def _digest(layouts: list) -> str:
    """sha256 of every region of ``layouts`` in tree order; module keys (hashes salted per process) enter as the
    order in which each key was first met."""
    digest, keys = hashlib.sha256(), {}
    for layout in layouts:
        stack = [layout.root]
        rows = [(layout.width, layout.height, sorted(layout.meta.items(), key=str))]
        while stack:
            r = stack.pop()
            key = None if r.key is None else keys.setdefault(r.key, len(keys))
            rows.append((r.x, r.y, r.w, r.h, r.symbol, r.label, r.depth, r.material, r.asset, r.layer, key,
                         len(r.children)))
            stack.extend(reversed(r.children))
        digest.update(repr(rows).encode())
    return digest.hexdigest()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(REPO / "scenes" / "helsinki.toml"))
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    from citygen.builder import Builder
    from citygen_split.alternatives import derive_plausible
    from citygen_split.derive import Subtrees

    faces = _faces(Path(args.scene))
    best = [float("inf"), float("inf")]
    layouts: list = []
    for _ in range(args.repeat):
        layouts, derive_cpu, check_cpu = [], 0.0, 0.0
        gc.disable()
        try:
            building = subtrees = None
            for grammar, request, shared in faces:
                start = time.process_time()
                if shared is not building:  # (a new building: its faces share subtrees as in the build)
                    building, subtrees = shared, None if shared is None else Subtrees(grammar)
                layout = derive_plausible(grammar, request, subtrees=subtrees).layout
                derived = time.process_time()
                layouts.append(Builder._checked(layout, request, "split", []))
                check_cpu += time.process_time() - derived
                derive_cpu += derived - start
        finally:
            gc.enable()
        best = [min(best[0], derive_cpu), min(best[1], check_cpu)]
    print(f"{Path(args.scene).name}: {len(faces)} split faces; least CPU of {args.repeat}: derive_plausible "
          f"{best[0]:.2f} s, builder checks {best[1]:.2f} s, together {sum(best):.2f} s")
    print(f"layouts sha256 {_digest(layouts)}")


if __name__ == "__main__":
    main()
