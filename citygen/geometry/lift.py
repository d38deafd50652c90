"""Module elements lifted into the building's own instances, for the stage: a module prototype keeps its meshes (the
walls and mouldings of a bay) and the building's PointInstancer places the bay's windows, doors and balconies
itself, instead of a PointInstancer nested in every module prototype.

Nested instancers cost every importer a set of prototypes per module: Blender makes each a collection holding its
own copies of the element prototypes (Helsinki demo: 17.6k collections, 2.0 GB), and the writer authors an
instancer, a prototype scope and references per module (about a third of the stage's specs). Lifted, a building
holds each element prototype once.

An element placed in its module's frame at ``t`` with rotation ``r`` and scale ``s``, in a module placed at ``T``
with rotation ``R`` and scale ``S`` (USD's order: scale, rotate, translate), lands at ``T + R (S * t)`` with rotation
``R r`` and scale ``S * s``. That is exact when ``r`` is the identity, as it is for every module element (they lie
in the module's face frame), or when ``S`` is uniform.
"""
from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from citygen.geometry.building import Instances, ModuleProto
from citygen.geometry.modules import ModuleKey
from citygen.geometry.prototypes import ProtoKey
from citygen.gltf.meshes import quaternion_product

_NEXT, _LAST = [1, 2, 0], [2, 0, 1]


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise ``a x b`` of ``(n, 3)`` arrays (``np.cross`` is slow on many small calls)."""
    return a[:, _NEXT] * b[:, _LAST] - a[:, _LAST] * b[:, _NEXT]


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``(n, 3)`` vectors ``v`` rotated by the unit quaternions ``q`` ``(n, 4)``."""
    u, w = q[:, :3], q[:, 3:]
    t = 2.0 * _cross(u, v)
    return v + w * t + _cross(u, t)


def has_meshes(module: ModuleProto) -> bool:
    """Whether a module keeps a prototype once its elements are lifted out."""
    return any(len(m.counts) for m in module.meshes.values())


def lift_module_elements(inst: Instances, modules: Mapping[ModuleKey, ModuleProto]) -> Instances:
    """``inst`` with the elements of every module instance as instances of their own, after the building's rows
    (module by module in ``inst.protos`` order, each module's rows in order); a module with no meshes of its own
    leaves no instance (and no prototype). Element prototypes new to the building follow its own, in order of
    first use. One numpy pass over all module rows."""
    keys: list[ProtoKey | ModuleKey] = []
    index: dict[ProtoKey | ModuleKey, int] = {}
    for key in inst.protos:
        if not isinstance(key, ModuleKey) or has_meshes(modules[key]):
            index[key] = len(keys)
            keys.append(key)
    positions = np.asarray(inst.positions, float).reshape(-1, 3)
    orientations = np.asarray(inst.orientations, float).reshape(-1, 4)
    scales = np.asarray(inst.scales, float).reshape(-1, 3)
    own = np.array([index.get(k, -1) for k in inst.protos], dtype=np.int64)[inst.proto_indices]
    kept = own >= 0
    # every module's elements, concatenated in protos order: their building prototype index and transforms
    size = np.zeros(len(inst.protos), np.int64)
    parts: list[tuple[np.ndarray, Instances]] = []
    for k, key in enumerate(inst.protos):
        if isinstance(key, ModuleKey) and len(elements := modules[key].elements.proto_indices):
            for e in modules[key].elements.protos:
                if e not in index:
                    index[e] = len(keys)
                    keys.append(e)
            size[k] = len(elements)
            parts.append((np.array([index[e] for e in modules[key].elements.protos])[elements],
                          modules[key].elements))
    if not parts:
        return Instances(tuple(keys), own[kept].astype(np.int32), positions[kept], orientations[kept],
                         scales[kept].astype(np.float32))
    start = np.cumsum(size) - size
    row = np.flatnonzero(size[inst.proto_indices])
    row = row[np.argsort(inst.proto_indices[row], kind="stable")]  # module by module, each in row order
    count = size[inst.proto_indices[row]]
    placed = np.repeat(row, count)
    element = np.repeat(start[inst.proto_indices[row]] - np.cumsum(count) + count, count) + np.arange(count.sum())
    proto = np.concatenate([p for p, _ in parts])[element]
    offset = np.concatenate([e.positions for _, e in parts]).astype(float)[element]
    turn, scale = orientations[placed], scales[placed]
    return Instances(
        tuple(keys), np.concatenate([own[kept], proto]).astype(np.int32),
        np.concatenate([positions[kept], positions[placed] + _rotate(turn, scale * offset)]),
        np.concatenate([orientations[kept],
                        quaternion_product(turn, np.concatenate([e.orientations for _, e in parts])[element])]),
        np.concatenate([scales[kept], scale * np.concatenate([e.scales for _, e in parts])[element]]).astype(np.float32))
