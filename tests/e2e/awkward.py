"""Seeded cities of awkward footprints (jagged stars, slivers, courtyards, L shapes, near-collinear edges, tiny
boxes, near-touching pairs) with random tags (heights up to 400 m, levels, roof shapes and orientations, lifted
bases), written as GeoJSON near Helsinki: the pipeline's fuzz input."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
from shapely import affinity
from shapely.geometry import MultiPolygon, Polygon, mapping

KINDS = ("yes", "apartments", "retail", "school", "church", "house", "office", "kiosk", "hotel", "residential")
ROOFS = ("hipped", "gabled", "pyramidal", "skillion", "round", "half-hipped", "dome", "flat", "onion", "saltbox",
         "side_hipped", "crosspitched", "butterfly", "sawtooth", None)


def _shape(rng: np.random.Generator, cx: float, cy: float) -> Polygon | MultiPolygon:
    kind = int(rng.integers(0, 7))
    if kind == 0:  # star-shaped, jagged
        n = int(rng.integers(5, 25))
        a, r = np.sort(rng.uniform(0, 2 * math.pi, n)), rng.uniform(3, 25, n)
        return Polygon(np.c_[cx + r * np.cos(a), cy + r * np.sin(a)])
    if kind == 1:  # a long sliver, rotated
        w, h = rng.uniform(0.5, 3), rng.uniform(5, 60)
        return affinity.rotate(Polygon([(cx, cy), (cx + w, cy), (cx + w, cy + h), (cx, cy + h)]), rng.uniform(0, 180))
    if kind == 2:  # a courtyard block, rotated
        w, h, d = rng.uniform(20, 70), rng.uniform(20, 70), rng.uniform(5, 9)
        hole = [(cx + d, cy + d), (cx + d, cy + h - d), (cx + w - d, cy + h - d), (cx + w - d, cy + d)]
        return affinity.rotate(Polygon([(cx, cy), (cx + w, cy), (cx + w, cy + h), (cx, cy + h)], [hole]),
                               rng.uniform(0, 90))
    if kind == 3:  # an L
        w, h, d = rng.uniform(10, 40), rng.uniform(10, 40), rng.uniform(3, 9)
        return Polygon([(cx, cy), (cx + w, cy), (cx + w, cy + d), (cx + d, cy + d), (cx + d, cy + h), (cx, cy + h)])
    if kind == 4:  # many nearly collinear points on one side
        xs = np.linspace(0, rng.uniform(10, 40), int(rng.integers(3, 30)))
        top = [(cx + x, cy + 10 + rng.uniform(-0.05, 0.05)) for x in xs[::-1]]
        return Polygon([(cx, cy), (cx + xs[-1], cy), *top])
    if kind == 5:  # tiny
        s = rng.uniform(0.3, 2.5)
        return Polygon([(cx, cy), (cx + s, cy), (cx + s, cy + s), (cx, cy + s)])
    a = Polygon([(cx, cy), (cx + 8, cy), (cx + 8, cy + 8), (cx, cy + 8)])  # two boxes nearly touching
    b = affinity.translate(a, 8.0 + rng.uniform(-0.01, 0.2), rng.uniform(-3, 3))
    return MultiPolygon([a, b]) if a.disjoint(b) else a.union(b)


def write_awkward_city(path: Path, seed: int, count: int, max_height: float = 400.0) -> Path:
    """``count`` awkward buildings on a 12-wide grid of 90 m cells, as a GeoJSON FeatureCollection at ``path``."""
    rng = np.random.default_rng(seed)
    metres = (1 / (111_320 * math.cos(math.radians(60.17))), 1 / 110_540)
    features = []
    for k in range(count):
        shape = _shape(rng, (k % 12) * 90.0 + rng.uniform(-30, 30), (k // 12) * 90.0 + rng.uniform(-30, 30))
        shape = affinity.translate(affinity.scale(shape, *metres, origin=(0, 0)), 24.94, 60.17)
        props: dict = {"id": k, "building": str(rng.choice(KINDS))}
        r = rng.random()
        if r < 0.5:
            props["height"] = float(rng.choice([rng.uniform(2, max_height), 0.5, max_height]))
        elif r < 0.8:
            props["building:levels"] = int(rng.integers(1, 30))
        roof = ROOFS[int(rng.integers(len(ROOFS)))]
        if roof:
            props["roof:shape"] = roof
        if rng.random() < 0.2:
            props["min_height"] = float(rng.uniform(0, 10))
        if rng.random() < 0.2:
            props["roof:orientation"] = str(rng.choice(["along", "across"]))
        features.append({"type": "Feature", "properties": props, "geometry": mapping(shape)})
    path.write_text(json.dumps({"type": "FeatureCollection", "features": features}))
    return path
