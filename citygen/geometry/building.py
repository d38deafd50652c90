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
from citygen.geometry.quads import box_quads, merge_rects, to_world, weld
from citygen.layout import FacadeLayout
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
    """Instances of prototypes: one row per element."""

    protos: tuple[ProtoKey, ...]
    proto_indices: np.ndarray
    positions: np.ndarray
    orientations: np.ndarray  # (n, 4) quaternions, scalar last (x, y, z, w)
    scales: np.ndarray
    labels: tuple[str, ...]


@dataclass(frozen=True)
class BuildingGeometry:
    meshes: Mapping[tuple[str, str], MeshData]
    instances: Instances
    roof: MeshData | None


def _face_arrays(layout: FacadeLayout, wall_material: str):
    """Visible terminals of a layout as arrays: rects ``(n, 4)`` x0 y0 x1 y1, depth, label and material."""
    regions = [r for r in layout.root.terminals() if r.label is not None and r.w > 1e-6 and r.h > 1e-6]
    rects = np.array([(r.x, r.y, r.x + r.w, r.y + r.h) for r in regions], dtype=float).reshape(-1, 4)
    depth = np.array([r.depth for r in regions], dtype=float)
    labels = np.array([r.label for r in regions], dtype=object)
    materials = np.array([r.material or "" for r in regions], dtype=object)
    for label in set(labels):
        sel = labels == label
        default_depth = DEFAULT_DEPTH.get(label, TRIM_DEPTH.get(label, 0.0))
        depth[sel & (depth == 0.0)] = default_depth
        material = wall_material if label == "wall" else LABEL_MATERIAL.get(label, wall_material)
        materials[sel & (materials == "")] = material
    return rects, depth, labels, materials


def _instance_keys(labels: np.ndarray, materials: np.ndarray, size: np.ndarray, depth: np.ndarray,
                   keys: dict[ProtoKey, int]) -> np.ndarray:
    """Prototype index per instance; new prototypes are added to ``keys`` (one Python step per prototype)."""
    q = np.column_stack([np.maximum(1, np.rint(size / QUANTUM)), np.rint(depth * 100)]).astype(np.int64)
    names = np.char.add(np.char.add(labels.astype(str), "\x1f"), materials.astype(str))
    uniq_names, name_code = np.unique(names, return_inverse=True)
    combos, inverse = np.unique(np.column_stack([name_code, q]), axis=0, return_inverse=True)
    index = np.empty(len(combos), np.int32)
    for k, (code, qw, qh, qd) in enumerate(combos):
        label, material = uniq_names[code].split("\x1f")
        index[k] = keys.setdefault(ProtoKey(label, material, int(qw), int(qh), int(qd)), len(keys))
    return index[inverse.ravel()]


def build_geometry(mass: Mass, layouts: Sequence[tuple[Face, FacadeLayout | None]], wall_material: str,
                   roof: MeshData | None) -> BuildingGeometry:
    """Geometry of one building from its faces and their layouts (``None``: a plain wall face)."""
    quads: dict[tuple[str, str], list[np.ndarray]] = {}
    keys: dict[ProtoKey, int] = {}
    inst_proto, inst_pos, inst_rot, inst_scale, inst_label = [], [], [], [], []
    for face, layout in layouts:
        m = face.matrix()
        if layout is None:
            quads.setdefault(("wall", wall_material), []).append(
                to_world(box_quads(np.array([[0.0, 0.0, face.width, face.height]]), np.zeros(1)), m))
            continue
        rects, depth, labels, materials = _face_arrays(layout, wall_material)
        if not len(rects):
            continue
        instanced = np.isin(labels, list(INSTANCED))
        panel = ~instanced
        for label, material in sorted({(str(a), str(b)) for a, b in zip(labels[panel], materials[panel])}):
            sel = panel & (labels == label) & (materials == material)
            for d in np.unique(depth[sel]):
                flat = merge_rects(rects[sel & (depth == d)])
                quads.setdefault((label, material), []).append(to_world(box_quads(flat, np.full(len(flat), d)), m))
        behind = instanced & ~np.isin(labels, list(OPENINGS))
        if behind.any():
            quads.setdefault(("wall", wall_material), []).append(
                to_world(box_quads(rects[behind], np.zeros(int(behind.sum()))), m))
        if instanced.any():
            r = rects[instanced]
            size = np.column_stack([r[:, 2] - r[:, 0], r[:, 3] - r[:, 1]])
            proto = _instance_keys(labels[instanced], materials[instanced], size, depth[instanced], keys)
            quantised = np.array([k.size[:2] for k in keys])[proto]
            inst_proto.append(proto)
            inst_scale.append(np.column_stack([size / quantised, np.ones(len(r))]))
            inst_pos.append(to_world(np.column_stack([r[:, 0], r[:, 1], np.zeros(len(r))]), m))
            inst_rot.append(np.repeat(Rotation.from_matrix(m[:3, :3].T).as_quat()[None, :], len(r), axis=0))
            inst_label.extend(labels[instanced])
    meshes = {k: MeshData.from_quads(np.concatenate(v)) for k, v in sorted(quads.items())}
    n = len(inst_proto)
    instances = Instances(
        protos=tuple(keys), proto_indices=np.concatenate(inst_proto) if n else np.zeros(0, np.int32),
        positions=np.concatenate(inst_pos) if n else np.zeros((0, 3)),
        orientations=np.concatenate(inst_rot) if n else np.zeros((0, 4)),
        scales=np.concatenate(inst_scale).astype(np.float32) if n else np.zeros((0, 3), np.float32),
        labels=tuple(inst_label))
    return BuildingGeometry(meshes=meshes, instances=instances, roof=roof)
