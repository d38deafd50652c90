"""Triangle meshes and node transforms for glTF from the geometry the USD writer consumes (numpy only).

glTF can share a *mesh* between nodes but not a subtree of nodes, so every prototype the USD stage instances
becomes one mesh with a primitive per material: an element (:class:`ProtoKey`) from its parts, a module
(:class:`ModuleKey`) from its own meshes plus its elements baked in place. A building's instances are then one
node each, whatever they hold.

Data is Z-up (GIS, USD stage default); glTF is Y-up: :data:`Y_UP` rotates ``(x, y, z)`` to ``(x, z, -y)``.
Matrices here act on column vectors (``p' = M @ p``), as glTF's do.
"""
from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from citygen.geometry.building import Instances, MeshData, ModuleProto
from citygen.geometry.modules import ModuleKey
from citygen.geometry.prototypes import ProtoKey, build_prototype

#: Z-up to Y-up: ``(x, y, z) -> (x, z, -y)`` (a rotation of -90 degrees about x; windings are kept).
Y_UP = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, -1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


@dataclass(frozen=True)
class Primitive:
    """Triangles of one material: ``points (k, 3) float32``, ``triangles (t, 3) int32``."""

    material: str
    points: np.ndarray
    triangles: np.ndarray


def triangles(mesh: MeshData) -> np.ndarray:
    """``(t, 3)`` fan triangles of a polygon mesh (citygen's polygons are convex: quads and triangles)."""
    counts = np.asarray(mesh.counts, dtype=np.int64)
    fans = np.maximum(counts - 2, 0)
    owner = np.repeat(np.arange(len(counts)), fans)
    corner = np.arange(int(fans.sum())) - np.repeat(np.cumsum(fans) - fans, fans)
    first = (np.cumsum(counts) - counts)[owner]
    idx = np.asarray(mesh.indices, dtype=np.int64)
    return np.column_stack([idx[first], idx[first + corner + 1], idx[first + corner + 2]]).astype(np.int32)


def transform_points(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``points (k, 3)`` mapped by a 4x4 column-vector matrix, as float32."""
    pts = np.asarray(points, dtype=float)
    return (pts @ matrix[:3, :3].T + matrix[:3, 3]).astype(np.float32)


def instance_matrices(inst: Instances) -> np.ndarray:
    """``(n, 4, 4)`` matrices ``translate @ rotate @ scale`` of instance rows (quaternions ``x, y, z, w``)."""
    x, y, z, w = np.asarray(inst.orientations, dtype=float).T
    rot = np.stack([np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
                    np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
                    np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1)], 1)
    out = np.zeros((len(x), 4, 4))
    out[:, :3, :3] = rot * np.asarray(inst.scales, dtype=float)[:, None, :]
    out[:, :3, 3] = inst.positions
    out[:, 3, 3] = 1.0
    return out


#: :data:`Y_UP` as a quaternion ``(x, y, z, w)``.
Y_UP_QUATERNION = np.array([-np.sqrt(0.5), 0.0, 0.0, np.sqrt(0.5)])


def quaternion_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton products ``a * b`` of quaternions ``(..., 4)`` stored ``x, y, z, w`` (rotation ``b``, then ``a``)."""
    ax, ay, az, aw = np.moveaxis(np.asarray(a, dtype=float), -1, 0)
    bx, by, bz, bw = np.moveaxis(np.asarray(b, dtype=float), -1, 0)
    return np.stack([aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz], -1)


def _merged(pieces: Iterable[tuple[str, np.ndarray, np.ndarray]]) -> tuple[Primitive, ...]:
    """Pieces ``(material, points, triangles)`` merged per material, materials in order of first appearance."""
    groups: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    for material, points, tris in pieces:
        if len(tris):
            groups.setdefault(material, []).append((points, tris))
    out = []
    for material, parts in groups.items():
        offsets = np.cumsum([0] + [len(p) for p, _ in parts[:-1]])
        out.append(Primitive(material, np.concatenate([p for p, _ in parts]).astype(np.float32),
                             np.concatenate([t + o for (_, t), o in zip(parts, offsets)]).astype(np.int32)))
    return tuple(out)


class PrototypeMeshes:
    """The primitives of every prototype a city instances, built once per key."""

    def __init__(self) -> None:
        self._cache: dict[ProtoKey | ModuleKey, tuple[Primitive, ...]] = {}

    def __call__(self, key: ProtoKey | ModuleKey, modules: Mapping[ModuleKey, ModuleProto]) -> tuple[Primitive, ...]:
        if key not in self._cache:
            self._cache[key] = self._module(modules[key]) if isinstance(key, ModuleKey) else self._element(key)
        return self._cache[key]

    @staticmethod
    def _element(key: ProtoKey) -> tuple[Primitive, ...]:
        meshes = [(part.material, MeshData.from_quads(part.quads)) for part in build_prototype(key) if len(part.quads)]
        return _merged((material, mesh.points, triangles(mesh)) for material, mesh in meshes)

    def _module(self, module: ModuleProto) -> tuple[Primitive, ...]:
        """A module's meshes and, baked in at their placements, its elements' primitives (one batch per element
        kind and material)."""
        pieces = [(material, mesh.points, triangles(mesh)) for (_, material), mesh in module.meshes.items()]
        elements = module.elements
        matrices = instance_matrices(elements)
        for k in np.unique(elements.proto_indices).tolist():
            placed = matrices[elements.proto_indices == k]
            for p in self(elements.protos[k], {}):
                points = np.einsum("nij,kj->nki", placed[:, :3, :3], p.points) + placed[:, None, :3, 3]
                offsets = np.arange(len(placed))[:, None, None] * len(p.points)
                pieces.append((p.material, points.reshape(-1, 3), (p.triangles[None] + offsets).reshape(-1, 3)))
        return _merged(pieces)
