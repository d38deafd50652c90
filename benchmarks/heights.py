"""Heights and roofs of a written city: the tallest building, how many roofs are tall, and the tagged buildings'
tops against their data (``python benchmarks/heights.py out.usdc [--source-id way/122595241]``).

Per building (component prim): its top (highest mesh point), its roof's height (the ``Roof`` mesh's z range) and
its walls' (from its base to the roof's eave). Prints the figures docs/performance.md records.
"""
from __future__ import annotations

import argparse

import numpy as np
from pxr import Usd, UsdGeom


def building_heights(stage: Usd.Stage) -> list[dict]:
    """One row per building: id, base, top, roof and wall heights (metres)."""
    rows = []
    for prim in stage.Traverse():
        if Usd.ModelAPI(prim).GetKind() != "component":
            continue
        base = prim.GetAttribute("citygen:base").Get() or 0.0
        top, roof = -np.inf, None
        for child in Usd.PrimRange(prim):
            if not child.IsA(UsdGeom.Mesh):
                continue
            points = np.asarray(UsdGeom.Mesh(child).GetPointsAttr().Get(), dtype=float)
            if not len(points):
                continue
            top = max(top, float(points[:, 2].max()))
            if child.GetName() == "Roof":
                roof = (float(points[:, 2].min()), float(points[:, 2].max()))
        eave = roof[0] if roof else top
        rows.append({"id": prim.GetAttribute("citygen:sourceId").Get(), "base": base, "top": top,
                     "roof": (roof[1] - roof[0]) if roof else 0.0, "walls": eave - base})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("stage")
    parser.add_argument("--source-id", action="append", default=[], help="print this building's row")
    args = parser.parse_args()
    rows = building_heights(Usd.Stage.Open(args.stage))
    tallest = max(rows, key=lambda r: r["top"] - r["base"])
    roofs = [r for r in rows if r["roof"] > 0]
    print(f"buildings {len(rows)}, with a pitched roof {len(roofs)}")
    print(f"tallest {tallest['id']}: {tallest['top'] - tallest['base']:.2f} m")
    print(f"roofs >= 8 m: {sum(r['roof'] >= 8 for r in roofs)}; roofs >= half their walls: "
          f"{sum(r['roof'] >= 0.5 * r['walls'] for r in roofs)}; tallest roof {max(r['roof'] for r in roofs):.2f} m")
    for r in rows:
        if r["id"] in args.source_id:
            print(f"{r['id']}: base {r['base']:.2f}, top {r['top']:.2f}, walls {r['walls']:.2f}, roof {r['roof']:.2f}")


if __name__ == "__main__":
    main()
