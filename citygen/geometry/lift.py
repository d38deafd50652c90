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
    first use."""
    keys: list[ProtoKey | ModuleKey] = []
    index: dict[ProtoKey | ModuleKey, int] = {}
    for key in inst.protos:
        if not isinstance(key, ModuleKey) or has_meshes(modules[key]):
            index[key] = len(keys)
            keys.append(key)
    remap = np.array([index.get(k, -1) for k in inst.protos], dtype=np.int64)
    own = remap[inst.proto_indices] if len(inst.proto_indices) else np.zeros(0, np.int64)
    kept = own >= 0
    rows = [(own[kept], np.asarray(inst.positions, float)[kept], np.asarray(inst.orientations, float)[kept],
             np.asarray(inst.scales, float)[kept])]
    for k, key in enumerate(inst.protos):
        if not isinstance(key, ModuleKey):
            continue
        elements = modules[key].elements
        placed = np.flatnonzero(inst.proto_indices == k)
        if not len(elements.proto_indices) or not len(placed):
            continue
        for e in elements.protos:
            if e not in index:
                index[e] = len(keys)
                keys.append(e)
        local = np.array([index[e] for e in elements.protos], dtype=np.int64)
        n, m = len(placed), len(elements.proto_indices)
        position = np.asarray(inst.positions, float)[placed]
        rotation = np.asarray(inst.orientations, float)[placed]
        scale = np.asarray(inst.scales, float)[placed]
        offset = (scale[:, None, :] * np.asarray(elements.positions, float)[None]).reshape(-1, 3)
        turn = np.repeat(rotation, m, axis=0)
        rows.append((np.tile(local[elements.proto_indices], n),
                     np.repeat(position, m, axis=0) + _rotate(turn, offset),
                     quaternion_product(turn, np.tile(np.asarray(elements.orientations, float), (n, 1))),
                     (scale[:, None, :] * np.asarray(elements.scales, float)[None]).reshape(-1, 3)))
    proto, positions, orientations, scales = (np.concatenate(c) for c in zip(*rows))
    return Instances(tuple(keys), proto.astype(np.int32), positions, orientations, scales.astype(np.float32))
