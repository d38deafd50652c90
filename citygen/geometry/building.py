"""One building's geometry: facade meshes per (label, material), instanced elements, and the roof.

Terminal regions are classified by label:

* instanced elements (:data:`prototypes.INSTANCED`: windows, doors, shop fronts, balconies, sills, blinds) become
  PointInstancer instances of a prototype; openings carry their reveal inside the prototype, attachments get a
  wall quad behind them in the facade mesh;
* every other label is a box from the wall plane to its depth (a flat quad at depth 0) in the facade mesh of its
  label and material (walls, pillars, cornices, ledges, mouldings, ...);
* ``label is None`` is transparent and produces nothing.

All per-region work is numpy over the regions of a face; Python loops run per face, not per region.
"""
from __future__ import annotations

import math
import operator
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from citygen.geometry.backs import balcony_backs, balcony_doors
from citygen.geometry.prototypes import DEFAULT_DEPTH, INSTANCED, OPENINGS, QUANTUM, ProtoKey
from citygen.geometry.modules import CM, ModuleKey, Signatures
from citygen.geometry.quads import box_quads, box_quads_grouped, merge_rects_grouped, to_world, weld, weld_many
from citygen.layout import FacadeLayout, Region
from citygen.mass import Face, Mass
from citygen.usd.materials import COLOUR_PREFIX

#: A ruleset's material for the building's own plaster render: painted in the building's wall material (its
#: palette pick, or the OSM ``building:colour``, which paints every wall), so rulesets shared by a street still give
#: each house its colour.
BUILDING_RENDER = "render"
#: Openings that, standing on a balcony, are its door (they reach down behind the railing).
DOORS_ONTO = ("window", "door")
#: Depth of trim labels whose regions say 0 (metres along the normal).
TRIM_DEPTH = {"cornice": 0.3, "ledge": 0.12, "molding": 0.05, "deco": 0.04, "pillar": 0.1}
#: A face is vertical (a wall, e.g. a roof's gable) when its unit normal's z is at most this (0.06 degrees).
VERTICAL_TOL = 1e-3
#: Material of a label when neither the region nor the building palette says otherwise.
LABEL_MATERIAL = {"window": "frame_white", "door": "door_wood", "shop": "frame_dark", "glass": "frame_dark",
                  "balcony": "railing_metal", "sill": "stone", "blind": "shutter_green", "cornice": "trim_white",
                  "ledge": "stone", "molding": "trim_white", "deco": "trim_white", "pillar": "stone",
                  "roof": "roof_dark"}


def _proper(idx: np.ndarray) -> np.ndarray:
    """Which welded quads ``(m, 4)`` keep four distinct corners."""
    return ((idx[:, 0] != idx[:, 1]) & (idx[:, 1] != idx[:, 2]) & (idx[:, 2] != idx[:, 3]) & (idx[:, 3] != idx[:, 0])
            & (idx[:, 0] != idx[:, 2]) & (idx[:, 1] != idx[:, 3]))


@dataclass(frozen=True)
class MeshData:
    """A polygon mesh: ``points (k, 3) float32``, ``counts (m,) int32`` and ``indices (sum(counts),) int32``."""

    points: np.ndarray
    counts: np.ndarray
    indices: np.ndarray

    @classmethod
    def from_quads(cls, quads: np.ndarray) -> MeshData:
        """Welded quads; quads that collapse under welding (sub-millimetre slivers) are dropped, since a face
        repeating a vertex is invalid in DCC importers."""
        points, indices = weld(quads)
        idx = indices.reshape(-1, 4)
        ok = _proper(idx)
        return cls(points, np.full(int(ok.sum()), 4, np.int32), idx[ok].reshape(-1))

    @classmethod
    def many_from_quads(cls, quads: Sequence[np.ndarray], parts: Sequence[int] | None = None) -> list[MeshData]:
        """:meth:`from_quads` of each ``(m, 4, 3)`` array (with ``parts``: of each run of ``parts[k]`` arrays
        joined), welded in one batch."""
        points, indices, pb, ib = weld_many(list(quads), parts=parts)
        idx = indices.reshape(-1, 4)
        ok = _proper(idx)
        kept = np.concatenate([[0], np.cumsum(ok)])[ib // 4].tolist()
        idx = idx[ok].reshape(-1)
        pb = pb.tolist()
        return [cls(points[pb[k]:pb[k + 1]], np.full(kept[k + 1] - kept[k], 4, np.int32),
                    idx[4 * kept[k]:4 * kept[k + 1]]) for k in range(len(pb) - 1)]

    @classmethod
    def concat(cls, meshes: Sequence[MeshData]) -> MeshData:
        """One mesh of ``meshes`` (points not welded)."""
        offsets = np.cumsum([0, *(len(m.points) for m in meshes[:-1])])
        return cls(np.concatenate([m.points for m in meshes]).astype(np.float32),
                   np.concatenate([m.counts for m in meshes]).astype(np.int32),
                   np.concatenate([m.indices + o for m, o in zip(meshes, offsets)]).astype(np.int32))

    def subset(self, faces: np.ndarray) -> MeshData:
        """The faces selected by the boolean mask ``faces``, with only the points they use."""
        picked = self.indices[np.repeat(faces, self.counts)]
        kept = np.zeros(len(self.points), dtype=bool)
        kept[picked] = True
        number = np.cumsum(kept) - 1  # (each kept point's number among them, in point order)
        return MeshData(self.points[kept], self.counts[faces], number[picked].astype(np.int32))

    def split_vertical(self, tol: float = VERTICAL_TOL) -> tuple[MeshData | None, MeshData | None]:
        """(the faces that are not vertical, the vertical ones): the gables and steps of a roof are walls.

        A face is vertical when its unit normal's z is within ``tol`` of 0 (one of no area is not). Either part is
        None when empty."""
        from citygen.usd.normals import polygon_normals  # (the stage's normals: that module imports this one)
        vertical = np.abs(polygon_normals(self.points, self.counts, self.indices)[:, 2]) <= tol
        return (self.subset(~vertical) if not vertical.all() else None,
                self.subset(vertical) if vertical.any() else None)


@dataclass(frozen=True)
class Instances:
    """Instances of prototypes (elements and modules): one row per placement."""

    protos: tuple[ProtoKey | ModuleKey, ...]
    proto_indices: np.ndarray
    positions: np.ndarray
    orientations: np.ndarray  # (n, 4) quaternions, scalar last (x, y, z, w)
    scales: np.ndarray


@dataclass(frozen=True)
class ModuleProto:
    """A module's geometry in its own frame (origin bottom-left, size ``key.size``): meshes and elements."""

    meshes: Mapping[tuple[str, str], MeshData]
    elements: Instances


@dataclass(frozen=True)
class BuildingGeometry:
    """A building's facade meshes, element and module instances, roof, and ``walls``: its mass as plain wall
    quads (the light level of detail a stage may offer instead of the facades; None unless asked for)."""

    meshes: Mapping[tuple[str, str], MeshData]
    instances: Instances
    modules: Mapping[ModuleKey, ModuleProto]
    roof: MeshData | None
    walls: MeshData | None = None
    roof_material: str = "roof_dark"


class _Sink:
    """Collects facade quads per (label, material) and instance rows while a building is assembled."""

    def __init__(self) -> None:
        self.quads: dict[tuple[str, str], list[np.ndarray]] = {}
        self.keys: dict[ProtoKey | ModuleKey, int] = {}
        #: per call of :meth:`add_instances`: prototype indices, positions, one rotation, scales ``(n, 2)``
        self.rows: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []

    def add_quads(self, key: tuple[str, str], quads: np.ndarray) -> None:
        if len(quads):
            self.quads.setdefault(key, []).append(quads)

    def add_instances(self, proto: np.ndarray, positions: np.ndarray, rotation: np.ndarray, scales: np.ndarray):
        """Rows of instances; ``scales`` is ``(n, 2)`` (x, y) -- instances never scale along the normal."""
        self.rows.append((proto, positions, rotation, scales))

    def take(self, emitted: _Emitted) -> None:
        """A unit's quads and element instances (its prototypes registered in the order it lists them)."""
        for key, quads in emitted.quads:
            self.add_quads(key, quads)
        if emitted.kinds is not None:
            index = np.array([self.keys.setdefault(p, len(self.keys)) for p in emitted.protos], np.int64)
            self.add_instances(index[emitted.kinds], emitted.positions, emitted.rotation, emitted.scales)

    def instances(self) -> Instances:
        """The rows as one table: each call's rotation repeated over its rows, scale 1 along the normal."""
        if not self.rows:
            return Instances(tuple(self.keys), np.zeros(0, np.int32), np.zeros((0, 3)), np.zeros((0, 4)),
                             np.zeros((0, 3), np.float32))
        proto, pos, rot, scale = zip(*self.rows)
        proto, scale = np.concatenate(proto), np.concatenate(scale)
        rot = np.repeat(np.array(rot), [len(p) for p in pos], axis=0)
        return Instances(tuple(self.keys), proto.astype(np.int32), np.concatenate(pos), rot,
                         np.column_stack([scale, np.ones(len(scale))]).astype(np.float32))


@dataclass(frozen=True)
class _Unit:
    """Terminals emitted together through one transform: a face's loose terminals, or a module prototype's
    (shifted by ``-dx, -dy``, then scaled by ``sx, sy`` into its own frame), as positions among ``layout``'s
    terminals (:attr:`FacadeLayout.leaf_rects`, :attr:`FacadeLayout.leaf_sources`)."""

    layout: FacadeLayout
    leaves: np.ndarray
    matrix: np.ndarray
    dx: float = 0.0
    dy: float = 0.0
    sx: float = 1.0
    sy: float = 1.0


@dataclass(frozen=True)
class _Terminals:
    """Visible terminals of some units as arrays: rects ``(n, 4)`` x0 y0 x1 y1 (in their unit's frame), depth, the
    unit of each, and a style code indexing ``styles`` (label, material) -- label defaults for depth and material
    already applied. ``local`` numbers each unit's styles in the order they first occur in it."""

    rects: np.ndarray
    depth: np.ndarray
    codes: np.ndarray
    units: np.ndarray
    local: np.ndarray
    styles: tuple[tuple[str, str], ...]


_LOOK = operator.attrgetter("label", "material", "depth")


def _terminal_arrays(units: Sequence[_Unit], wall_material: str) -> _Terminals:
    """Terminal arrays of every unit, read from its layout's terminal arrays (the style and depth of each distinct
    (label, material, depth) are worked out once, in the order the terminals first show them). The layouts'
    arrays are joined once and every unit's terminals gathered from them in one step."""
    looks: dict[tuple[str, str | None, float], int] = {}
    offsets: dict[int, int] = {}  # id(layout) -> where its terminals start in the joined arrays
    rect_parts, look_parts, picks = [], [], []
    joined = 0
    for unit in units:
        layout = unit.layout
        offset = offsets.get(id(layout))
        if offset is None:
            sources, source_of = layout.leaf_sources
            keys = list(map(_LOOK, sources))
            ids = {key: looks.setdefault(key, len(looks)) if key[0] is not None else -1 for key in dict.fromkeys(keys)}
            look_of = np.fromiter(map(ids.__getitem__, keys), np.intp, len(keys))
            offset = offsets[id(layout)] = joined
            joined += len(layout.leaf_rects)
            rect_parts.append(layout.leaf_rects)
            look_parts.append(look_of[source_of])
        picks.append(unit.leaves + offset if offset else unit.leaves)
    if picks:
        picked = np.concatenate(picks)
        rects, look = np.concatenate(rect_parts)[picked], np.concatenate(look_parts)[picked]
        keep = (look >= 0) & ~(rects[:, 2] <= 1e-6) & ~(rects[:, 3] <= 1e-6)
        xywh, look = rects[keep], look[keep]
        unit_of = np.repeat(np.arange(len(units)), [len(p) for p in picks])[keep]
    else:
        xywh, look, unit_of = np.zeros((0, 4)), np.zeros(0, np.intp), np.zeros(0, np.intp)
    rows = list(looks)
    seen, first = np.unique(look, return_index=True)
    styles: dict[tuple[str, str], int] = {}
    depth_of, code_of = np.zeros(len(rows)), np.zeros(len(rows), np.int64)
    for k in seen[np.argsort(first)].tolist():  # (styles numbered in the order the terminals first show them)
        depth_of[k], code_of[k] = _look(*rows[k], wall_material, styles)
    frame = np.array([(u.dx, u.dy, u.sx, u.sy) for u in units], dtype=float).reshape(-1, 4)[unit_of]
    table = np.column_stack([xywh[:, 0], xywh[:, 1], xywh[:, 0] + xywh[:, 2], xywh[:, 1] + xywh[:, 3]])
    rects = (table - frame[:, [0, 1, 0, 1]]) * frame[:, [2, 3, 2, 3]]
    codes = code_of[look]
    return _Terminals(rects, depth_of[look], codes, unit_of, _local_codes(unit_of, codes, len(styles)),
                      tuple(styles))


def _local_codes(units: np.ndarray, codes: np.ndarray, n_styles: int) -> np.ndarray:
    """Per terminal the rank of its style among its unit's styles, in the order they first occur in the unit."""
    pairs, first, inverse = np.unique(units * max(n_styles, 1) + codes, return_index=True, return_inverse=True)
    unit = pairs // max(n_styles, 1)
    order = np.lexsort((first, unit))
    rank = np.empty(len(pairs), np.int64)
    rank[order] = np.arange(len(pairs)) - np.searchsorted(unit[order], unit[order])
    return rank[inverse.ravel()]


def _look(label: str, material: str | None, depth: float, wall_material: str,
          styles: dict[tuple[str, str], int]) -> tuple[float, int]:
    """The depth and style code (registered in ``styles``) of a terminal: label defaults for depth and material,
    and the building's wall material where the terminal asks for it."""
    material = material or (wall_material if label == "wall" else LABEL_MATERIAL.get(label, wall_material))
    if material == BUILDING_RENDER or (label == "wall" and wall_material.startswith(COLOUR_PREFIX)):
        material = wall_material  # the building's colour; a colour from the data paints every wall
    depth = depth or DEFAULT_DEPTH.get(label) or TRIM_DEPTH.get(label, 0.0)
    return depth, styles.setdefault((label, material), len(styles))


def _meshes(sinks: Sequence[_Sink]) -> list[dict[tuple[str, str], MeshData]]:
    """Every sink's facade meshes (per (label, material), sorted), welded in one batch."""
    keys = [sorted(sink.quads) for sink in sinks]
    lists = [sink.quads[k] for sink, ks in zip(sinks, keys) for k in ks]
    welded = iter(MeshData.many_from_quads([q for quads in lists for q in quads], [len(quads) for quads in lists]))
    return [{k: next(welded) for k in ks} for ks in keys]


def face_quaternion(matrix: np.ndarray) -> np.ndarray:
    """Quaternion ``(x, y, z, w)`` of the rotation in a row-vector 4x4 transform (Shepperd's method)."""
    m = matrix[:3, :3].T.tolist()  # (Python floats: the same IEEE arithmetic without numpy's per-scalar cost)
    trace = m[0][0] + m[1][1] + m[2][2]
    if trace > 0:
        t = 2.0 * math.sqrt(1.0 + trace)
        q = ((m[2][1] - m[1][2]) / t, (m[0][2] - m[2][0]) / t, (m[1][0] - m[0][1]) / t, 0.25 * t)
    else:
        diagonal = (m[0][0], m[1][1], m[2][2])
        i = diagonal.index(max(diagonal))
        j, k = (i + 1) % 3, (i + 2) % 3
        t = 2.0 * math.sqrt(1.0 + m[i][i] - m[j][j] - m[k][k])
        q = [0.0, 0.0, 0.0, (m[k][j] - m[j][k]) / t]
        q[i], q[j], q[k] = 0.25 * t, (m[j][i] + m[i][j]) / t, (m[k][i] + m[i][k]) / t
    return np.asarray(q, dtype=float)


def _runs(*keys: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stable sort by ``keys`` (the last one primary): ``(order, start of each run of equal keys in it, run of
    each element)`` -- a run's first element is the first occurrence of its keys."""
    order = np.lexsort(keys)
    change = np.zeros(len(order), dtype=bool)
    change[:1] = True
    for key in keys:
        sorted_key = key[order]
        change[1:] |= sorted_key[1:] != sorted_key[:-1]
    run = np.empty(len(order), np.int64)
    run[order] = np.cumsum(change) - 1
    return order, np.flatnonzero(change), run


#: Panel-group key of the flat wall quads behind attachments: after the unit's other groups.
_BEHIND = 1 << 50


@dataclass
class _Emitted:
    """One unit's output, for its sink to take in order: facade quads per (label, material), in groups, and
    element instances (``kinds`` index ``protos``; ``scales`` ``(n, 2)``)."""

    quads: list[tuple[tuple[str, str], np.ndarray]] = field(default_factory=list)
    protos: list[ProtoKey] = field(default_factory=list)
    kinds: np.ndarray | None = None
    positions: np.ndarray | None = None
    rotation: np.ndarray | None = None
    scales: np.ndarray | None = None


def _emit(units: Sequence[_Unit], t: _Terminals, wall_material: str) -> list[_Emitted]:
    """Facade quads and element instances of every unit's terminals, transformed by the unit's matrix; all units
    in one batch. An opening standing on a balcony is its door (:mod:`citygen.geometry.backs`)."""
    out = [_Emitted() for _ in units]
    if not len(t.rects):
        return out
    labels = np.array([label for label, _ in t.styles])
    style_instanced = np.isin(labels, list(INSTANCED))
    style_behind = style_instanced & ~np.isin(labels, list(OPENINGS))
    instanced = style_instanced[t.codes]
    doors, under = balcony_doors(t.rects, t.units, (labels == "balcony")[t.codes],
                                 np.isin(labels, list(DOORS_ONTO))[t.codes])
    rects, backs, back_units = balcony_backs(t.rects, t.units, style_behind[t.codes], doors, under)
    t = replace(t, rects=rects)
    _emit_panels(out, units, t, ~instanced, backs, back_units, wall_material)
    if instanced.any():
        _emit_elements(out, units, t, instanced)
    return out


def _emit_panels(out: list[_Emitted], units: Sequence[_Unit], t: _Terminals, panel: np.ndarray,
                 backs: np.ndarray, back_units: np.ndarray, wall_material: str) -> None:
    """Boxes of the ``panel`` terminals, merged per (unit, style, depth in mm) at the group's first depth, then
    the flat wall quads ``backs`` behind attachments (``back_units``: their units): every group merged and boxed in
    one batch, each unit's quads transformed by its matrix and listed per group (its styles in first-occurrence
    order, then by depth)."""
    depth_mm = np.rint(t.depth[panel] * 1000).astype(np.int64)
    n_behind = len(backs)
    keys = np.concatenate([(t.local[panel] << 32) | (depth_mm & 0xFFFFFFFF), np.full(n_behind, _BEHIND)])
    unit_of = np.concatenate([t.units[panel], back_units])
    order, first, groups = _runs(keys, unit_of)
    head = order[first]
    code = np.concatenate([t.codes[panel], np.full(n_behind, -1)])[head]
    depths = np.concatenate([t.depth[panel], np.zeros(n_behind)])[head]
    group_unit = unit_of[head]
    flat, flat_groups = merge_rects_grouped(np.concatenate([t.rects[panel], backs]), groups)
    quads, quad_groups = box_quads_grouped(flat, depths[flat_groups], flat_groups)
    unit_bounds = np.searchsorted(group_unit[quad_groups], np.arange(len(units) + 1)).tolist()
    for u in np.unique(group_unit).tolist():
        lo, hi = unit_bounds[u], unit_bounds[u + 1]
        quads[lo:hi] = to_world(quads[lo:hi], units[u].matrix)
    bounds = np.searchsorted(quad_groups, np.arange(len(head) + 1)).tolist()
    wall = ("wall", wall_material)
    for g, (c, u) in enumerate(zip(code.tolist(), group_unit.tolist())):
        out[u].quads.append((t.styles[c] if c >= 0 else wall, quads[bounds[g]:bounds[g + 1]]))


def _emit_elements(out: list[_Emitted], units: Sequence[_Unit], t: _Terminals, instanced: np.ndarray) -> None:
    """Instances of the ``instanced`` terminals: one prototype per (style, size in quanta, depth in cm), listed per
    unit in the order of its (style rank, size, depth)."""
    r, local, depth, unit_of = t.rects[instanced], t.local[instanced], t.depth[instanced], t.units[instanced]
    codes = t.codes[instanced]
    size = np.column_stack([r[:, 2] - r[:, 0], r[:, 3] - r[:, 1]])
    q = np.maximum(1, np.rint(size / QUANTUM)).astype(np.int64)
    qd = np.rint(depth * 100).astype(np.int64)
    key = (local << 48) | (q[:, 0] << 32) | (q[:, 1] << 16) | (qd & 0xFFFF)
    order, first, kind = _runs(key, unit_of)
    head = order[first]
    kind_unit = unit_of[head]
    for u, c, k in zip(kind_unit.tolist(), codes[head].tolist(), key[head].tolist()):
        label, material = t.styles[c]
        out[u].protos.append(ProtoKey(label, material, (k >> 32) & 0xFFFF, (k >> 16) & 0xFFFF,
                                      ((k & 0xFFFF) ^ 0x8000) - 0x8000))
    kind -= np.searchsorted(kind_unit, unit_of)  # (a unit's kinds count from 0)
    scales = size / (q * QUANTUM)
    bounds = np.searchsorted(unit_of, np.arange(len(units) + 1)).tolist()
    for u in np.unique(unit_of).tolist():
        lo, hi = bounds[u], bounds[u + 1]
        m = units[u].matrix
        e = out[u]
        e.kinds, e.scales, e.rotation = kind[lo:hi], scales[lo:hi], face_quaternion(m)
        e.positions = to_world(np.column_stack([r[lo:hi, 0], r[lo:hi, 1], np.zeros(hi - lo)]), m)


_IDENTITY = np.eye(4)
_MODULE_CACHE = threading.local()
_MODULE_CACHE_SIZE = 4096


def _module_cache() -> dict[ModuleKey, ModuleProto]:
    """The calling thread's module prototypes by key: buildings dressed by one ruleset share most modules.

    Stages stay deterministic: the writer keeps the first prototype of a key in stage order, and that building,
    being the first with the key in its worker too, built it itself (the pipeline clears the cache per building,
    the dask executor per tile). Per thread, so tiles built by concurrent threads of one process never share it.
    """
    cache = getattr(_MODULE_CACHE, "modules", None)
    if cache is None:
        cache = _MODULE_CACHE.modules = {}
    return cache


def clear_module_cache() -> None:
    """Forget the calling thread's module prototypes."""
    _module_cache().clear()


def _plain_quads(faces: Sequence[tuple[Face, ...]]) -> np.ndarray:
    """``(n, 4, 3)``: each face's rectangle as one flat quad in the face's frame."""
    return box_quads(np.array([(0.0, 0.0, face.width, face.height) for face, *_ in faces]).reshape(-1, 4),
                     np.zeros(len(faces)))


class _ModuleKeys(dict):
    """A building's module keys by (signature, w, h) in centimetres: one :class:`ModuleKey` per module, however
    many faces place it (a dict lookup instead of a frozen dataclass made per placement)."""

    def __init__(self, wall: str) -> None:
        super().__init__()
        self.wall = wall

    def __call__(self, signature: int, w: int, h: int) -> ModuleKey:
        key = self.get((signature, w, h))
        if key is None:
            key = self[signature, w, h] = ModuleKey(signature, w, h, self.wall)
        return key


def build_geometry(mass: Mass, layouts: Sequence[tuple[Face, FacadeLayout | None]], wall_material: str,
                   roof: MeshData | None, modules: bool = True, roof_material: str = "roof_dark",
                   walls: bool = False) -> BuildingGeometry:
    """Geometry of one building from its faces and their layouts (``None``: a plain wall face).

    With ``modules``, repeated subtrees become module instances (:mod:`citygen.geometry.modules`); the remaining
    terminals become facade quads and element instances. With ``walls``, the mass is also kept as plain walls
    (the ``mass`` level of detail). The roof's vertical faces (gables, steps between roof pieces) are wall: they
    join the ``("wall", wall_material)`` mesh (and the plain walls), the roof keeps the rest.
    """
    signatures = Signatures(layout.root for _, layout in layouts if layout is not None and modules)
    cache = _module_cache()
    protos: dict[ModuleKey, ModuleProto | None] = {}  # (None: built below, with the faces' terminals)
    module_key = _ModuleKeys(wall_material)
    units: list[_Unit] = []
    built: list[tuple[ModuleKey, int]] = []  # modules to build, with their unit
    faces: list[tuple[Face, np.ndarray, int | None, list[tuple[ModuleKey, Region]]]] = []  # + unit, modules
    for face, layout in layouts:
        m = face.matrix()
        if layout is None:
            faces.append((face, m, None, []))
            continue
        if modules:
            placed, loose = signatures.split(layout.root)
        else:
            placed, loose = [], range(len(layout.leaf_rects))
        keyed = [(module_key(signatures.signature(r), max(1, round(r.w * CM)), max(1, round(r.h * CM))), r)
                 for r, _, _ in placed]
        faces.append((face, m, len(units), keyed))
        units.append(_Unit(layout, np.asarray(loose, np.intp), m))
        for (key, r), (_, at, n) in zip(keyed, placed):
            if key not in protos:
                protos[key] = cache.get(key)
                if protos[key] is None:
                    qw, qh = key.size
                    built.append((key, len(units)))
                    units.append(_Unit(layout, np.arange(at, at + n), _IDENTITY, r.x, r.y, qw / r.w, qh / r.h))
    emitted = _emit(units, _terminal_arrays(units, wall_material), wall_material)
    sinks = [_Sink() for _ in built]
    for own, (_, unit) in zip(sinks, built):
        own.take(emitted[unit])
    sink = _Sink()
    flat = _plain_quads(faces) if walls or any(unit is None for _, _, unit, _ in faces) else None
    plain = [to_world(q[None], m) for q, (_, m, _, _) in zip(flat, faces)] if walls else None
    for k, (face, m, unit, keyed) in enumerate(faces):
        if unit is None:
            sink.add_quads(("wall", wall_material), plain[k] if plain is not None else to_world(flat[k][None], m))
            continue
        sink.take(emitted[unit])
        if keyed:
            sink.add_instances(np.asarray([sink.keys.setdefault(key, len(sink.keys)) for key, _ in keyed]),
                               to_world(np.asarray([(r.x, r.y, 0.0) for _, r in keyed], dtype=float), m),
                               face_quaternion(m), np.asarray([(r.w / key.size[0], r.h / key.size[1])
                                                               for key, r in keyed]))
    *module_meshes, meshes = _meshes([*sinks, sink])
    for (key, _), own, own_meshes in zip(built, sinks, module_meshes):
        if len(cache) >= _MODULE_CACHE_SIZE:
            cache.clear()
        protos[key] = cache[key] = ModuleProto(own_meshes, own.instances())
    mass_walls = MeshData.from_quads(np.concatenate(plain)) if plain else None
    roof, gables = roof.split_vertical() if roof is not None else (None, None)
    if gables is not None:  # the roof's vertical faces are wall: in the walls of both levels of detail
        key = ("wall", wall_material)
        joined = MeshData.concat([meshes[key], gables]) if key in meshes else gables
        meshes = dict(sorted({**meshes, key: joined}.items()))
        mass_walls = MeshData.concat([mass_walls, gables]) if mass_walls is not None else None
    return BuildingGeometry(meshes=meshes, instances=sink.instances(), modules=protos, roof=roof,
                            walls=mass_walls, roof_material=roof_material)
