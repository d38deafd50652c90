"""Roof benchmark: every footprint of a file roofed with one shape (default: the Helsinki data, all hipped).

    python benchmarks/roofs_hipped.py [--shape hipped] [--repeat 3] [--party] [FILE ...]

Per roof the median CPU time (process_time) over the repeats; prints the median, p99 and worst roof, the slowest
footprints with their vertex counts, the roofs that failed (the pipeline would build those flat), the builders'
warnings and a sha256 digest of every roof mesh (it must not change when the roof code only gets faster).
``--party``: roof with the party walls the pipeline finds (neighbours up to the eave)."""
from __future__ import annotations

import argparse
import hashlib
import statistics
import time
import warnings
from pathlib import Path

import numpy as np
from shapely.geometry import MultiPolygon

from citygen.coordinator import party_walls
from citygen.mass import build_mass, neighbour_cover
from citygen.registry import default_registry
from citygen.roof import roof_spec
from citygen_footprints.plugin import read_footprints

REPO = Path(__file__).resolve().parents[1]
DEFAULT_FILES = [REPO / "scenes" / "data" / "helsinki_buildings.geojson"]


def _vertices(outline) -> int:
    parts = outline.geoms if isinstance(outline, MultiPolygon) else [outline]
    return sum(len(r.coords) - 1 for p in parts for r in (p.exterior, *p.interiors))


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("files", nargs="*", type=Path)
    parser.add_argument("--shape", default="hipped")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--party", action="store_true", help="pass the party walls found between the footprints")
    args = parser.parse_args()
    builder = default_registry().roof_builders[args.shape]
    for path in args.files or DEFAULT_FILES:
        masses = [build_mass(fp) for fp in read_footprints(path, {}).footprints]
        covers = neighbour_cover(masses) if args.party else [np.zeros(len(m.faces)) for m in masses]
        times, failures, attached, ignored = [], [], 0, []
        digest = hashlib.sha256()
        for mass, cover in zip(masses, covers):
            party = tuple(int(k) for k in np.flatnonzero(party_walls(cover, [f.width for f in mass.faces],
                                                                        mass.height)))
            attached += bool(party)
            spec = roof_spec({"roof:shape": args.shape}, mass.height, party=party)
            runs = []
            for _ in range(args.repeat):
                t0 = time.process_time()
                try:
                    with warnings.catch_warnings(record=True) as caught:
                        warnings.simplefilter("always")
                        mesh = builder.build(mass.outline, mass.base + mass.height, spec)
                except Exception as exc:
                    failures.append(f"{type(exc).__name__}: {exc}")
                    break
                runs.append(time.process_time() - t0)
            ignored += [str(w.message) for w in caught] if runs else []
            if runs:
                for array in (mesh.points, mesh.counts, mesh.indices):
                    digest.update(np.ascontiguousarray(array).tobytes())
            times.append(statistics.median(runs) if runs else float("nan"))
        ms = np.array(times) * 1000
        ok = ms[~np.isnan(ms)]
        print(f"{path.name}: {len(masses)} roofs ({args.shape}, {attached} with party walls), {len(failures)} failed "
              f"(flat fallback); "
              f"CPU per roof median {np.median(ok):.2f} ms, p99 {np.percentile(ok, 99):.1f} ms, "
              f"max {ok.max():.0f} ms, total {ok.sum() / 1000:.2f} s")
        print(f"  digest {digest.hexdigest()}")
        for k in np.argsort(-np.nan_to_num(ms))[:3]:
            print(f"  slow: {ms[k]:.0f} ms, {_vertices(masses[k].outline)} vertices")
        for failure in failures:
            print(f"  failed: {failure}")
        for message in sorted(set(ignored)):
            print(f"  {ignored.count(message)} roofs: {message}")


if __name__ == "__main__":
    main()
