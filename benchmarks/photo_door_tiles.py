"""Which ground-floor tiles the door step changes (docs/photo.md, "Doors on the mirror axis", step 6).

    python benchmarks/photo_door_tiles.py [DATA_DIR] [--first 1 --last 20]

Each CMP photo (cropped to its annotated facade box) is analysed with the door step on and off (``axis_door``
finding nothing). Nothing above the ground floor may differ (column ``above``). A ground-floor tile of the run
without the door whose extent is also a ground-floor tile of the run with it is *untouched* by the door's tile
lines; it must have the same layout subtree (boxes, labels, elements; symbols aside, a contrast-test door being a
shop front where the axis door was found). Printed per photo: ground-floor tiles without the door, untouched ones,
untouched ones that differ (and why: the tile's group -- its members -- differs, or only the labels, else the
split sizes; "merged shop": the subtree is the same but the reported element boxes are not, door and shop
terminals side by side being one shop box with the door), and the share of the ground floor's width the door's
tiles (the door's own and those its lines cut or merge) take.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import citygen_photo.photo as photo
from citygen.layout import Region
from citygen_photo.photo import analyse, load_photo
from citygen_photo.score import cmp_boxes, facade_box

DEFAULT = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "cmp_facade" / "base"


def normalised(region: Region, geometry_only: bool = False) -> tuple:
    """A subtree without symbols, a door terminal counted as a shop front (``geometry_only``: boxes only)."""
    label = "shop" if region.label == "door" else region.label
    own = (round(region.x, 6), round(region.y, 6), round(region.w, 6), round(region.h, 6))
    if not geometry_only:
        own += (label,) if label == "shop" else (label, region.depth, region.material)
    return own + tuple(normalised(c, geometry_only) for c in region.children)


def ground_tiles(result) -> dict[tuple[float, float], Region]:
    """The ground floor's tiles by (x, w), rounded."""
    ground = result.layout.root.children[0]
    return {(round(t.x, 6), round(t.w, 6)): t for t in ground.children}


def elements(result, key: tuple[float, float]) -> list:
    """The element boxes (crop pixels) and labels, a door counted as a shop front, whose centre lies in the ground
    floor's tile ``key`` (metres)."""
    mpp = result.layout.meta["metres_per_pixel"]
    x0, x1, top = key[0] / mpp, (key[0] + key[1]) / mpp, result.floor_lines[-2]
    return [(box, "shop" if label == "door" else label) for box, label in result.elements
            if x0 <= (box[0] + box[2]) / 2 < x1 and (box[1] + box[3]) / 2 >= top]


def above_ground(result) -> tuple:
    """The floor and tile lines, the floors above the ground floor and the elements above its top line."""
    top = result.floor_lines[-2]
    return (result.floor_lines, result.tile_lines, result.layout.root.children[1:],
            [(box, label) for box, label in result.elements if (box[1] + box[3]) / 2 < top])


def untouched(on, off) -> tuple[list[tuple[float, float]], list[tuple[float, float]]]:
    """The ground-floor tiles of ``off`` that are also tiles of ``on`` (by extent), and the rest of ``on``'s."""
    a, b = ground_tiles(on), ground_tiles(off)
    kept = [k for k in b if k in a]
    return kept, [k for k in a if k not in b]


def run(image, door: bool, record: list):
    """``analyse`` with the door step on or off; the ground floor's tile groups (as sets of tile columns) are
    appended to ``record``."""
    cluster = photo.cluster_tiles

    def spy(work, floors, columns, regular, *args, **kwargs):
        groups = cluster(work, floors, columns, regular, *args, **kwargs)
        ground = floors.size - 2
        record.append([frozenset((int(columns[i][j]), int(columns[i][j + 1])) for i, j in g)
                       for g in groups if all(i == ground for i, _ in g)])
        return groups
    saved = photo.axis_door, photo.cluster_tiles
    photo.cluster_tiles = spy
    if not door:
        photo.axis_door = lambda *args, **kwargs: None
    try:
        return analyse(image)
    finally:
        photo.axis_door, photo.cluster_tiles = saved


def compare(image) -> dict:
    groups_on: list = []
    groups_off: list = []
    on, off = run(image, True, groups_on), run(image, False, groups_off)
    if on.layout.meta["door_edge"] is None:
        return {"door": False}
    above = above_ground(on) != above_ground(off)
    kept, rebuilt = untouched(on, off)
    a, b = ground_tiles(on), ground_tiles(off)
    reasons: dict[str, int] = {}
    for k in kept:
        if normalised(a[k]) == normalised(b[k]):
            if elements(on, k) != elements(off, k):  # pieces a door / shop apart without the door, one shop with it
                reasons["merged shop"] = reasons.get("merged shop", 0) + 1
            continue
        if normalised(a[k], True) == normalised(b[k], True):
            reason = "labels"
        elif _members(groups_on[0], k, on) != _members(groups_off[0], k, off):
            reason = "group"
        else:
            reason = "sizes"
        reasons[reason] = reasons.get(reason, 0) + 1
    width = sum(w for _, w in rebuilt) / on.layout.root.children[0].w
    differ = sum(n for reason, n in reasons.items() if reason != "merged shop")
    return {"door": True, "above": int(above), "tiles": len(b), "kept": len(kept), "differ": differ,
            "reasons": reasons, "merged": reasons.get("merged shop", 0), "rebuilt": len(rebuilt), "share": width}


def _members(groups: list[frozenset], key: tuple[float, float], result) -> frozenset:
    """The tiles (metres) grouped with the tile ``key`` in ``groups`` (working-pixel columns)."""
    ground = result.layout.root.children[0]
    scale = ground.w / (max(c1 for g in groups for _, c1 in g) - min(c0 for g in groups for c0, _ in g)) \
        if groups else 1.0
    x0 = min(c0 for g in groups for c0, _ in g) if groups else 0

    def metres(c: tuple[int, int]) -> tuple[float, float]:
        return round(ground.x + (c[0] - x0) * scale, 6), round((c[1] - c[0]) * scale, 6)
    for g in groups:
        tiles = {metres(c) for c in g}
        if _near(key, tiles):
            return frozenset(tiles)
    return frozenset()


def _near(key: tuple[float, float], keys: set) -> bool:
    return any(abs(key[0] - k[0]) < 1e-4 and abs(key[1] - k[1]) < 1e-4 for k in keys)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", default=str(DEFAULT))
    parser.add_argument("--first", type=int, default=1)
    parser.add_argument("--last", type=int, default=20)
    args = parser.parse_args(argv)
    from PIL import Image
    total: dict[str, float] = {}
    print(f"{'photo':10} {'above':>5} {'tiles':>5} {'kept':>4} {'differ':>6} {'rebuilt':>7} {'share':>5}  reasons")
    for i in range(args.first, args.last + 1):
        jpg = Path(args.data) / f"cmp_b{i:04d}.jpg"
        if not jpg.is_file():
            continue
        with Image.open(jpg) as im:
            size = im.size
        crop = tuple(round(v) for v in facade_box(cmp_boxes(jpg.with_suffix(".xml"), size)))
        r = compare(load_photo(jpg, crop))
        if not r["door"]:
            print(f"{jpg.stem:10} no axis door")
            continue
        print(f"{jpg.stem:10} {'differs' if r['above'] else 'same':>5} {r['tiles']:5d} {r['kept']:4d} "
              f"{r['differ']:6d} {r['rebuilt']:7d} {r['share']:5.2f}  {r['reasons']}")
        for k in ("above", "tiles", "kept", "differ", "merged", "rebuilt", "share"):
            total[k] = total.get(k, 0) + r[k]
        total["photos"] = total.get("photos", 0) + 1
    if total:
        print(f"\nphotos with an axis door {int(total['photos'])}, differing above the ground floor "
              f"{int(total['above'])}: ground-floor tiles {int(total['tiles'])}, untouched "
              f"by the door's lines {int(total['kept'])}, of them differing {int(total['differ'])} (and with "
              f"merged shop boxes only {int(total['merged'])}); the door's tiles "
              f"take {total['share'] / total['photos']:.2f} of the ground floor's width on average")
    return 0


if __name__ == "__main__":
    sys.exit(main())
