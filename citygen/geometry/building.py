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

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from citygen.geometry.prototypes import DEFAULT_DEPTH, INSTANCED, OPENINGS, QUANTUM, ProtoKey
from citygen.geometry.modules import CM, ModuleKey, Signatures
from citygen.geometry.quads import box_quads, merge_rects, to_world, weld
from citygen.layout import FacadeLayout, Region
from citygen.mass import Face, Mass

#: Depth of trim labels whose regions say 0 (metres along the normal).
TRIM_DEPTH = {"cornice": 0.3, "ledge": 0.12, "molding": 0.05, "deco": 0.04, "pillar": 0.1}
#: Material of a label when neither the region nor the building palette says otherwise.
LABEL_MATERIAL = {"window": "frame_white", "door": "door_wood", "shop": "frame_dark", "glass": "frame_dark",
                  "balcony": "railing_metal", "sill": "stone", "blind": "shutter_green", "cornice": "trim_white",
                  "ledge": "stone", "molding": "trim_white", "deco": "trim_white", "pillar": "stone",
                  "roof": "roof_dark"}


@dataclass(frozen=True)
class MeshData:
    """A polygon mesh: ``points (k, 3) float32``, ``counts (m,) int32`` and ``indices (sum(counts),) int32``."""

    points: np.ndarray
    counts: np.ndarray
    indices: np.ndarray

    @classmethod
    def from_quads(cls, quads: np.ndarray) -> MeshData:
        points, indices = weld(quads)
        return cls(points, np.full(len(quads), 4, np.int32), indices)


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
    meshes: Mapping[tuple[str, str], MeshData]
    instances: Instances
    modules: Mapping[ModuleKey, ModuleProto]
    roof: MeshData | None


class _Sink:
    """Collects facade quads per (label, material) and instance rows while a building is assembled."""

    def __init__(self) -> None:
        self.quads: dict[tuple[str, str], list[np.ndarray]] = {}
        self.keys: dict[ProtoKey | ModuleKey, int] = {}
        self.rows: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []

    def add_quads(self, key: tuple[str, str], quads: np.ndarray) -> None:
        if len(quads):
            self.quads.setdefault(key, []).append(quads)

    def add_instances(self, proto: np.ndarray, positions: np.ndarray, rotation: np.ndarray, scales: np.ndarray):
        self.rows.append((proto, positions, np.repeat(rotation[None, :], len(proto), axis=0), scales))

    def meshes(self) -> dict[tuple[str, str], MeshData]:
        return {k: MeshData.from_quads(np.concatenate(v)) for k, v in sorted(self.quads.items())}

    def instances(self) -> Instances:
        if not self.rows:
            return Instances(tuple(self.keys), np.zeros(0, np.int32), np.zeros((0, 3)), np.zeros((0, 4)),
                             np.zeros((0, 3), np.float32))
        proto, pos, rot, scale = (np.concatenate(c) for c in zip(*self.rows))
        return Instances(tuple(self.keys), proto.astype(np.int32), pos, rot, scale.astype(np.float32))


def _terminal_arrays(regions: Sequence[Region], wall_material: str, dx: float = 0.0, dy: float = 0.0,
                     sx: float = 1.0, sy: float = 1.0):
    """Visible terminals as arrays -- rects ``(n, 4)`` x0 y0 x1 y1 (shifted by ``-dx, -dy`` and scaled),
    depth, label and material -- with label defaults applied."""
    regions = [r for r in regions if r.label is not None and r.w > 1e-6 and r.h > 1e-6]
    rects = np.array([(r.x, r.y, r.x + r.w, r.y + r.h) for r in regions], dtype=float).reshape(-1, 4)
    rects = (rects - (dx, dy, dx, dy)) * (sx, sy, sx, sy)
    depth = np.array([r.depth for r in regions], dtype=float)
    labels = np.array([r.label for r in regions], dtype=object)
    materials = np.array([r.material or "" for r in regions], dtype=object)
    for label in set(labels):
        sel = labels == label
        depth[sel & (depth == 0.0)] = DEFAULT_DEPTH.get(label, TRIM_DEPTH.get(label, 0.0))
        material = wall_material if label == "wall" else LABEL_MATERIAL.get(label, wall_material)
        materials[sel & (materials == "")] = material
    return rects, depth, labels, materials


def _instance_keys(labels: np.ndarray, materials: np.ndarray, size: np.ndarray, depth: np.ndarray,
                   keys: dict) -> np.ndarray:
    """Prototype index per element; new prototypes are added to ``keys`` (one Python step per prototype)."""
    q = np.column_stack([np.maximum(1, np.rint(size / QUANTUM)), np.rint(depth * 100)]).astype(np.int64)
    names = np.char.add(np.char.add(labels.astype(str), "\x1f"), materials.astype(str))
    uniq_names, name_code = np.unique(names, return_inverse=True)
    combos, inverse = np.unique(np.column_stack([name_code.ravel(), q]), axis=0, return_inverse=True)
    index = np.empty(len(combos), np.int32)
    for k, (code, qw, qh, qd) in enumerate(combos):
        label, material = uniq_names[code].split("\x1f")
        index[k] = keys.setdefault(ProtoKey(label, material, int(qw), int(qh), int(qd)), len(keys))
    return index[inverse.ravel()]


def _emit(sink: _Sink, arrays, matrix: np.ndarray, wall_material: str) -> None:
    """Facade quads and element instances of terminal arrays, transformed by a face (or identity) matrix."""
    rects, depth, labels, materials = arrays
    if not len(rects):
        return
    instanced = np.isin(labels, list(INSTANCED))
    panel = ~instanced
    for label, material in sorted({(str(a), str(b)) for a, b in zip(labels[panel], materials[panel])}):
        sel = panel & (labels == label) & (materials == material)
        for d in np.unique(depth[sel]):
            flat = merge_rects(rects[sel & (depth == d)])
            sink.add_quads((label, material), to_world(box_quads(flat, np.full(len(flat), d)), matrix))
    behind = instanced & ~np.isin(labels, list(OPENINGS))
    if behind.any():
        flat = merge_rects(rects[behind])
        sink.add_quads(("wall", wall_material), to_world(box_quads(flat, np.zeros(len(flat))), matrix))
    if instanced.any():
        r = rects[instanced]
        size = np.column_stack([r[:, 2] - r[:, 0], r[:, 3] - r[:, 1]])
        proto = _instance_keys(labels[instanced], materials[instanced], size, depth[instanced], sink.keys)
        keys = list(sink.keys)
        quantised = np.array([keys[i].size[:2] for i in range(len(keys))])[proto]
        sink.add_instances(proto, to_world(np.column_stack([r[:, 0], r[:, 1], np.zeros(len(r))]), matrix),
                           Rotation.from_matrix(matrix[:3, :3].T).as_quat(),
                           np.column_stack([size / quantised, np.ones(len(r))]))


def _module_proto(key: ModuleKey, region: Region) -> ModuleProto:
    qw, qh = key.size
    sink = _Sink()
    _emit(sink, _terminal_arrays(list(region.terminals()), key.wall, region.x, region.y, qw / region.w,
                                 qh / region.h), np.eye(4), key.wall)
    return ModuleProto(sink.meshes(), sink.instances())


def build_geometry(mass: Mass, layouts: Sequence[tuple[Face, FacadeLayout | None]], wall_material: str,
                   roof: MeshData | None) -> BuildingGeometry:
    """Geometry of one building from its faces and their layouts (``None``: a plain wall face).

    Repeated subtrees become module instances (:mod:`citygen.geometry.modules`); the remaining terminals become
    facade quads and element instances.
    """
    sink = _Sink()
    modules: dict[ModuleKey, ModuleProto] = {}
    signatures = Signatures(layout.root for _, layout in layouts if layout is not None)
    for face, layout in layouts:
        m = face.matrix()
        if layout is None:
            sink.add_quads(("wall", wall_material),
                           to_world(box_quads(np.array([[0.0, 0.0, face.width, face.height]]), np.zeros(1)), m))
            continue
        placed, loose = signatures.split(layout.root)
        _emit(sink, _terminal_arrays(loose, wall_material), m, wall_material)
        if not placed:
            continue
        proto, pos, scale = [], [], []
        for r in placed:
            key = ModuleKey(signatures.sig[id(r)], max(1, round(r.w * CM)), max(1, round(r.h * CM)), wall_material)
            if key not in modules:
                modules[key] = _module_proto(key, r)
            proto.append(sink.keys.setdefault(key, len(sink.keys)))
            qw, qh = key.size
            pos.append((r.x, r.y, 0.0))
            scale.append((r.w / qw, r.h / qh, 1.0))
        sink.add_instances(np.asarray(proto), to_world(np.asarray(pos, dtype=float), m),
                           Rotation.from_matrix(m[:3, :3].T).as_quat(), np.asarray(scale))
    return BuildingGeometry(meshes=sink.meshes(), instances=sink.instances(), modules=modules, roof=roof)
