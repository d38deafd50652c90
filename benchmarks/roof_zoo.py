"""Roof zoo: a seeded sweep of the pitched roofs over random and degenerate outlines, counting what goes wrong.

    python benchmarks/roof_zoo.py [--per-kind 40] [--seed 0] [--save out/roof_zoo_failures.jsonl]
    python benchmarks/roof_zoo.py --replay out/roof_zoo_failures.jsonl
    python benchmarks/roof_zoo.py --kinds star --builders hipped --per-kind 3000  # one kind, one builder, more

Per kind of outline (random star polygons, and ones with a few repeated radii and angles; axis-aligned L, U, T,
H, courtyard, staircase and grid-union shapes, the hard case for the weighted skeleton with their many parallel
edges; the same rotated or moved ~1 km out like a city frame; near-degenerate ones: nearly collinear vertices,
1-5 cm edges, thin slivers, courtyards nearly touching the walls) every skeleton builder, ``sawtooth`` and
``butterfly`` roof each outline twice, free and with a random proper subset of party walls, each with a random
``roof:orientation`` (none, along, across); ``saltbox``, ``side_hipped`` and ``crosspitched`` (rectangle-like parts
only) roof the ``quad`` kind instead, rectangle-like quadrilaterals. Outcomes: ``ok`` (closed, party walls kept),
``fallback`` (built other than asked, with a note: a party-wall roof built as free, a gabled roof instead),
``RoofError`` (the pipeline would build it flat), ``cracked`` (the mesh's open boundary is not exactly the outline
at the wall top) and ``exception`` (any other error). Prints a table per kind and one per builder, the failure
messages grouped and the slowest roof (CPU time); failing cases (WKT, exact coordinates, party walls, builder,
orientation) go to ``--save`` as JSON lines for ``--replay``."""
from __future__ import annotations

import argparse
import json
import re
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np
from shapely import affinity, wkt
from shapely.geometry import Polygon, box
from shapely.geometry.polygon import orient
from shapely.ops import unary_union

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from citygen.mass import clean_outline  # noqa: E402
from citygen.roof import RoofSpec, roof_notes  # noqa: E402
from citygen.roof import rectangle_like  # noqa: E402
from citygen_roofs.osm_shapes import (ButterflyRoof, CrosspitchedRoof, SaltboxRoof, SawtoothRoof,  # noqa: E402
                                      SideHippedRoof)
from citygen_roofs.pitched import (DomeRoof, GabledRoof, GambrelRoof, HalfHippedRoof, HippedRoof,  # noqa: E402
                                   MansardRoof, RoofError, RoundRoof)
from tests.roofs.test_builders import _plumb_to_rounding, _open_edges, _outline_edges, _same_edges  # noqa: E402

SKELETON = (HippedRoof(), GabledRoof(), HalfHippedRoof(), MansardRoof(), GambrelRoof(), DomeRoof(), RoundRoof())
#: the roofs of planar pieces (citygen_roofs.osm_shapes); their party walls and orientations are drawn from a
#: second random stream, so the skeleton roofs' cases are those of the sweep before they were added
PLANES = (SawtoothRoof(), ButterflyRoof(), SaltboxRoof(), SideHippedRoof(), CrosspitchedRoof())
BUILDERS = {b.id: b for b in (*SKELETON, *PLANES)}
#: rectangle-like parts only (elsewhere the gabled roof, with a note): swept over the ``quad`` kind alone, which the
#: other roofs skip
RECTANGULAR = {"saltbox", "side_hipped", "crosspitched"}
ORIENTATIONS = (None, "along", "across")
OUTCOMES = ("ok", "fallback", "RoofError", "cracked", "exception")
TOP = 12.0


def _u(rng, lo, hi) -> float:
    return float(rng.uniform(lo, hi))


def star(rng) -> Polygon:
    n = int(rng.integers(3, 15))
    angles = np.cumsum(rng.uniform(0.3, 1.0, n))
    angles = 2 * np.pi * angles / angles[-1]
    r = rng.uniform(5.0, 25.0, n)
    return Polygon(np.column_stack([r * np.cos(angles), r * np.sin(angles)]))


def symmetric_star(rng) -> Polygon:
    """A star polygon with radii and gaps from a few values: repeated angles and lengths, so events coincide
    (reflex vertices meeting each other, several edges vanishing at once)."""
    n = int(rng.integers(3, 13))
    angles = np.cumsum(rng.choice([0.3, 0.5, 1.0], n))
    angles = 2 * np.pi * angles / angles[-1]
    r = rng.choice([5.0, 15.0, 25.0], n)
    return Polygon(np.column_stack([r * np.cos(angles), r * np.sin(angles)]))


def _union(boxes) -> Polygon:
    shape = unary_union(boxes)
    return Polygon(shape.exterior, shape.interiors) if shape.geom_type == "Polygon" else None


def l_shape(rng) -> Polygon:
    w, d, a, h = _u(rng, 8, 40), _u(rng, 4, 15), _u(rng, 3, 12), _u(rng, 3, 25)
    return _union([box(0, 0, w, d), box(0, d - 1, a, d + h)])


def u_shape(rng) -> Polygon:
    w, d, a, h = _u(rng, 8, 40), _u(rng, 4, 15), _u(rng, 3, 12), _u(rng, 3, 25)
    return _union([box(0, 0, w + 2 * a, d), box(0, d - 1, a, d + h), box(w + a, d - 1, w + 2 * a, d + _u(rng, 3, 25))])


def t_shape(rng) -> Polygon:
    w, d, s, h = _u(rng, 10, 40), _u(rng, 4, 12), _u(rng, 3, 10), _u(rng, 3, 25)
    x = _u(rng, 0, w - s)
    return _union([box(0, 0, w, d), box(x, d - 1, x + s, d + h)])


def h_shape(rng) -> Polygon:
    a, b, h = _u(rng, 3, 10), _u(rng, 3, 10), _u(rng, 10, 40)
    s = _u(rng, 3, min(12.0, h - 1))
    gap = _u(rng, 4, 25)
    y = _u(rng, 0, h - s)
    return _union([box(0, 0, a, h), box(a + gap, _u(rng, -5, 5), a + gap + b, h + _u(rng, -5, 5)),
                   box(a - 1, y, a + gap + 1, y + s)])


def courtyard(rng) -> Polygon:
    w, d = _u(rng, 12, 60), _u(rng, 12, 60)
    x0, y0 = _u(rng, 2, w / 2 - 2), _u(rng, 2, d / 2 - 2)
    return box(0, 0, w, d).difference(box(x0, y0, _u(rng, w / 2 + 2, w - 2), _u(rng, d / 2 + 2, d - 2)))


def staircase(rng) -> Polygon:
    steps, w, d = int(rng.integers(2, 7)), _u(rng, 2, 8), _u(rng, 2, 8)
    depth = _u(rng, 5, 15)
    return _union([box(k * w, k * d, (k + 1) * w + (depth if k == steps - 1 else 1.0), k * d + depth)
                   for k in range(steps)])


def grid(rng) -> Polygon:
    """A union of random cells of a random rectilinear grid: many parallel edges, sometimes equal spacings."""
    for _ in range(20):
        xs = np.cumsum(np.r_[0, rng.choice([3.0, 4.0, 5.0, 6.0], 5) if rng.random() < 0.5 else rng.uniform(2, 8, 5)])
        ys = np.cumsum(np.r_[0, rng.choice([3.0, 4.0, 5.0, 6.0], 5) if rng.random() < 0.5 else rng.uniform(2, 8, 5)])
        cells = rng.random((5, 5)) < 0.6
        shape = _union([box(xs[i], ys[j], xs[i + 1], ys[j + 1]) for i in range(5) for j in range(5) if cells[i, j]])
        if shape is not None and shape.area > 0:
            return shape
    return box(0, 0, 10, 10)


RECTILINEAR = (l_shape, u_shape, t_shape, h_shape, courtyard, staircase, grid)


def any_shape(rng) -> Polygon:
    """A rectilinear shape (70 %) or a star polygon."""
    shape = None
    while shape is None:
        shape = RECTILINEAR[rng.integers(len(RECTILINEAR))](rng) if rng.random() < 0.7 else star(rng)
    return shape


def rotated(rng) -> Polygon:
    return affinity.rotate(any_shape(rng), _u(rng, 0, 360), origin=(0, 0))


def offset_1km(rng) -> Polygon:
    shape = any_shape(rng)
    if rng.random() < 0.5:
        shape = affinity.rotate(shape, _u(rng, 0, 360), origin=(0, 0))
    return affinity.translate(shape, _u(rng, -1500, 1500), _u(rng, -1500, 1500))


def _insert(ring: np.ndarray, k: int, point: np.ndarray) -> np.ndarray:
    return np.insert(ring, k + 1, point, axis=0)


def _map_exterior(rng, fn) -> Polygon:
    """A random shape with its exterior ring changed by ``fn(ring) -> ring``."""
    shape = any_shape(rng)
    if rng.random() < 0.3:
        shape = affinity.rotate(shape, _u(rng, 0, 360), origin=(0, 0))
    ring = np.asarray(shape.exterior.coords)[:-1]
    return Polygon(fn(ring), [r.coords for r in shape.interiors])


def collinear(rng) -> Polygon:
    """Vertices inserted mid-edge, off the line by 0-5 mm."""
    def fn(ring):
        for _ in range(int(rng.integers(1, 4))):
            k = int(rng.integers(len(ring)))
            a, b = ring[k], ring[(k + 1) % len(ring)]
            d = b - a
            n = np.array([-d[1], d[0]]) / np.hypot(*d)
            ring = _insert(ring, k, a + _u(rng, 0.2, 0.8) * d + rng.choice([0.0, _u(rng, -5e-3, 5e-3)]) * n)
        return ring
    return _map_exterior(rng, fn)


def short_edges(rng) -> Polygon:
    """A vertex 1-5 cm from a corner, on the edge or just off it (a tiny jog)."""
    def fn(ring):
        for _ in range(int(rng.integers(1, 3))):
            k = int(rng.integers(len(ring)))
            a, b = ring[k], ring[(k + 1) % len(ring)]
            d = (b - a) / np.hypot(*(b - a))
            n = np.array([-d[1], d[0]])
            ring = _insert(ring, k, a + _u(rng, 0.01, 0.05) * d + _u(rng, -0.03, 0.03) * n)
        return ring
    return _map_exterior(rng, fn)


def sliver(rng) -> Polygon:
    """Thin outlines: a long thin rectangle or triangle, or a shape with a thin spike or slot."""
    kind = rng.integers(4)
    length, width = _u(rng, 5, 40), _u(rng, 0.05, 0.6)
    if kind == 0:
        return affinity.rotate(box(0, 0, length, width), _u(rng, 0, 360))
    if kind == 1:
        return Polygon([(0, 0), (length, _u(rng, -1, 1) * width), (_u(rng, 0.2, 0.8) * length, width)])
    base = box(0, 0, _u(rng, 8, 30), _u(rng, 8, 30))
    x = _u(rng, 2, base.bounds[2] - 2)
    if kind == 2:  # a thin spike out of the top wall
        return _union([base, box(x, base.bounds[3] - 1, x + width, base.bounds[3] + length)])
    shape = base.difference(box(x, _u(rng, 1, 4), x + width, base.bounds[3] + 1))  # a thin slot
    return shape if shape.geom_type == "Polygon" else base


def near_touch(rng) -> Polygon:
    """A courtyard 1-10 cm from a wall (or two)."""
    w, d = _u(rng, 12, 50), _u(rng, 12, 50)
    gap = _u(rng, 0.01, 0.1)
    x0 = gap if rng.random() < 0.5 else _u(rng, 2, w / 2 - 2)
    y0 = _u(rng, 0.01, 0.1) if rng.random() < 0.5 else _u(rng, 2, d / 2 - 2)
    x1, y1 = _u(rng, w / 2 + 2, w - 2), _u(rng, d / 2 + 2, d - 2)
    hole = box(x0, y0, x1, y1) if rng.random() < 0.7 else Polygon(
        [(x0, y0), (x1, _u(rng, y0, y1)), (_u(rng, x0, x1), y1)])
    shape = box(0, 0, w, d).difference(hole)
    return affinity.rotate(shape, _u(rng, 0, 360)) if rng.random() < 0.3 else shape


def quad(rng) -> Polygon | None:
    """A rectangle-like quadrilateral: a rectangle with its corners moved by up to 4 % of its width, rotated, a
    third of them ~1 km out; None when it does not fill 90 % of its minimum rotated rectangle."""
    w, d = _u(rng, 4, 40), _u(rng, 4, 40)
    corners = np.array([(0, 0), (w, 0), (w, d), (0, d)]) + rng.uniform(-0.04, 0.04, (4, 2)) * min(w, d)
    shape = affinity.rotate(Polygon(corners), _u(rng, 0, 360), origin=(0, 0))
    if rng.random() < 0.3:
        shape = affinity.translate(shape, _u(rng, -1500, 1500), _u(rng, -1500, 1500))
    return shape if rectangle_like(shape) else None


#: kinds the pipeline's outline cleaning (``clean_outline``: no edge under 0.8 m, no vertex within 0.1 m of its
#: neighbours' line) would smooth away: these reach the builders as they are, only oriented
RAW = {"collinear", "short edges", "sliver", "near-touch"}
KINDS = {"star": star, "symmetric star": symmetric_star, "L": l_shape, "U": u_shape, "T": t_shape, "H": h_shape,
         "courtyard": courtyard, "staircase": staircase, "grid": grid, "rotated": rotated, "offset 1 km": offset_1km,
         "collinear": collinear, "short edges": short_edges, "sliver": sliver, "near-touch": near_touch,
         "quad": quad}


def _n_edges(outline: Polygon) -> int:
    return sum(len(r.coords) - 1 for r in (outline.exterior, *outline.interiors))


def _pinched(outline: Polygon) -> bool:
    """Whether rings touch at a vertex (a valid polygon: e.g. a courtyard touching the outer wall at a corner)."""
    pts = [tuple(p) for r in (outline.exterior, *outline.interiors) for p in np.asarray(r.coords)[:-1]]
    return len(set(pts)) < len(pts)


def _closed(mesh, outline: Polygon) -> bool:
    """The mesh's open boundary is exactly the outline at the wall top, its triangles' projections cover the
    outline once and none faces down. Where rings touch (a pinch) the walls meeting there share a vertical edge
    twice each way: the boundary is then the edges used more often one way than the other."""
    p = mesh.points.astype(float)
    tris = mesh.indices.reshape(-1, 3)
    n = np.cross(p[tris[:, 1]] - p[tris[:, 0]], p[tris[:, 2]] - p[tris[:, 0]])
    ulp = 4 * float(np.spacing(np.abs(mesh.points).max()))  # float32 rounding of the points, a few units
    longest = np.max([np.linalg.norm(p[tris[:, k]] - p[tris[:, k - 1]], axis=1) for k in range(3)], axis=0)
    down = (n[:, 2] < -ulp * longest) & ~_plumb_to_rounding(mesh, n)
    if np.any(down) or abs(n[:, 2].sum() / 2 - outline.area) > ulp * outline.length:
        return False
    try:
        edges, z = _open_edges(mesh)
    except AssertionError:
        if not _pinched(outline):
            return False
        directed = Counter((int(a), int(b)) for t in tris for a, b in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0])))
        loose = [(a, b) for (a, b), k in directed.items() if k > directed.get((b, a), 0)]
        edges = np.array([np.r_[p[a, :2], p[b, :2]] for a, b in loose])
        z = np.array([p[[a, b], 2] for a, b in loose])
    return len(edges) > 0 and _same_edges(edges, _outline_edges(outline)) and np.allclose(z, TOP, atol=1e-3)


def roof(outline: Polygon, builder: str, party: tuple[int, ...], orientation: str | None
         ) -> tuple[str, str, float]:
    """Build one roof: (outcome, message, CPU seconds)."""
    spec = RoofSpec(builder, 30.0, party=party, orientation=orientation)
    t0 = time.process_time()
    try:
        with roof_notes() as notes:
            mesh = BUILDERS[builder].build(outline, TOP, spec)
    except RoofError as exc:
        return "RoofError", str(exc), time.process_time() - t0
    except Exception as exc:  # noqa: BLE001 - counted: any other error is a bug
        return "exception", f"{type(exc).__name__}: {exc}", time.process_time() - t0
    seconds = time.process_time() - t0
    if not _closed(mesh, outline):
        return "cracked", "open boundary is not the outline", seconds
    if notes:
        return "fallback", notes[0], seconds
    return "ok", "", seconds


def cases(per_kind: int, seed: int, kinds=tuple(KINDS), builders=tuple(BUILDERS)):
    """(kind, outline, builder, party, orientation) for every kind, outline and builder that applies to it, free
    and with party walls."""
    rng, second = np.random.default_rng(seed), np.random.default_rng([seed, 1])
    for kind in kinds:
        make = KINDS[kind]
        made = 0
        while made < per_kind:
            outline = make(rng)
            if outline is not None and outline.geom_type == "Polygon" and outline.is_valid:
                outline = orient(outline, sign=1.0) if kind in RAW else clean_outline(outline)
            if outline is None or outline.geom_type != "Polygon" or not outline.is_valid or outline.area < 1.0:
                continue
            made += 1
            n = _n_edges(outline)
            for builder in builders:
                if (builder in RECTANGULAR) != (kind == "quad") and builder not in ("sawtooth", "butterfly"):
                    continue
                draw = rng if builder in (b.id for b in SKELETON) else second
                k = int(draw.integers(1, n))
                party = tuple(sorted(int(e) for e in draw.choice(n, size=k, replace=False)))
                for walls in ((), party):
                    yield kind, outline, builder, walls, ORIENTATIONS[draw.integers(3)]


def _generic(message: str) -> str:
    return re.sub(r"-?\d+(\.\d+)?(e-?\d+)?", "N", message)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--per-kind", type=int, default=40,
                        help="outlines per kind (each roofed twice by every builder that applies)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--save", type=Path, default=Path("out/roof_zoo_failures.jsonl"))
    parser.add_argument("--replay", type=Path, help="rebuild the cases of a saved failures file")
    parser.add_argument("--kinds", nargs="+", choices=list(KINDS), default=list(KINDS))
    parser.add_argument("--builders", nargs="+", choices=list(BUILDERS), default=list(BUILDERS))
    args = parser.parse_args()
    if args.replay:
        for line in args.replay.read_text().splitlines():
            case = json.loads(line)
            outline = Polygon(case["rings"][0], case["rings"][1:]) if "rings" in case else wkt.loads(case["wkt"])
            outcome, message, _ = roof(outline, case["builder"], tuple(case["party"]), case["orientation"])
            print(f"{case['kind']}/{case['builder']}: was {case['outcome']}, now {outcome} {message}")
        return
    counts: Counter = Counter()
    by_builder: Counter = Counter()
    messages: Counter = Counter()
    failures, worst = [], (0.0, "")
    t0 = time.process_time()
    for kind, outline, builder, party, orientation in cases(args.per_kind, args.seed, args.kinds, args.builders):
        outcome, message, seconds = roof(outline, builder, party, orientation)
        counts[kind, outcome] += 1
        by_builder[builder, outcome] += 1
        if seconds > worst[0]:
            worst = (seconds, f"{kind}/{builder}, {_n_edges(outline)} edges")
        if outcome != "ok":
            messages[outcome, _generic(message)] += 1
            failures.append({"kind": kind, "builder": builder, "party": list(party), "orientation": orientation,
                             "outcome": outcome, "message": message, "wkt": outline.wkt,
                             "rings": [np.asarray(r.coords)[:-1].tolist()  # exact: WKT rounds the last digit
                                       for r in (outline.exterior, *outline.interiors)]})
    print(f"{'kind':<15}" + "".join(f"{o:>11}" for o in OUTCOMES))
    for kind in [*args.kinds, "total"]:
        row = [sum(v for (k, o), v in counts.items() if o == out and kind in (k, "total")) for out in OUTCOMES]
        print(f"{kind:<15}" + "".join(f"{v:>11}" for v in row))
    print(f"{'builder':<15}" + "".join(f"{o:>11}" for o in OUTCOMES))
    for builder in args.builders:
        print(f"{builder:<15}" + "".join(f"{by_builder[builder, out]:>11}" for out in OUTCOMES))
    for (outcome, message), count in messages.most_common():
        print(f"  {count:5d} {outcome}: {message}")
    print(f"worst roof {worst[0] * 1000:.0f} ms ({worst[1]}); total CPU {time.process_time() - t0:.1f} s")
    if failures:
        args.save.parent.mkdir(parents=True, exist_ok=True)
        args.save.write_text("".join(json.dumps(f) + "\n" for f in failures))
        print(f"{len(failures)} failing cases saved to {args.save}")


if __name__ == "__main__":
    main()
