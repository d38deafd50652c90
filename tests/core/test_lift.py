"""Module elements lifted into the building's instances (citygen.geometry.lift): the same placements as the nested
module instancers composed, and no prototype for a module left without meshes."""
from __future__ import annotations

import numpy as np

from citygen.geometry.building import Instances, MeshData, ModuleProto, face_quaternion
from citygen.geometry.lift import lift_module_elements
from citygen.geometry.modules import ModuleKey
from citygen.geometry.prototypes import ProtoKey
from citygen.gltf.meshes import instance_matrices

WINDOW, SILL, DOOR = ProtoKey("window", "glass", 11, 15, -25), ProtoKey("sill", "stone", 13, 1, 8), \
    ProtoKey("door", "door_wood", 10, 22, -20)
WALL = MeshData(np.array([[0, 0, 0], [3, 0, 0], [3, 3, 0], [0, 3, 0]], np.float32), np.array([4], np.int32),
                np.arange(4, dtype=np.int32))
EMPTY = MeshData(np.zeros((0, 3), np.float32), np.zeros(0, np.int32), np.zeros(0, np.int32))


def _elements(*rows) -> Instances:
    protos = tuple(dict.fromkeys(key for key, _, _ in rows))
    return Instances(protos, np.array([protos.index(key) for key, _, _ in rows], np.int32),
                     np.array([p for _, p, _ in rows], float), np.tile([0.0, 0.0, 0.0, 1.0], (len(rows), 1)),
                     np.array([s for _, _, s in rows], np.float32))


def _turned(angle: float) -> np.ndarray:
    """The quaternion of a face turned ``angle`` radians about z (its frame: u along the wall, v up, w out)."""
    c, s = np.cos(angle), np.sin(angle)
    return face_quaternion(np.array([[c, s, 0, 0], [0, 0, 1, 0], [s, -c, 0, 0], [0, 0, 0, 1.0]]))


def test_lifted_elements_land_where_the_nested_instancers_put_them():
    bay = ModuleKey(1, 300, 300, "brick")
    modules = {bay: ModuleProto({("wall", "brick"): WALL},
                                _elements((WINDOW, (0.9, 1.0, 0.0), (1.1, 0.9, 1.0)), (SILL, (0.8, 0.9, 0.0), (1.0, 1.0, 1.0))))}
    building = Instances((DOOR, bay), np.array([1, 0, 1], np.int32),
                         np.array([[10.0, 5.0, 0.0], [2.0, 0.0, 0.0], [-4.0, 7.0, 3.0]]),
                         np.stack([_turned(0.7), _turned(0.0), _turned(-2.1)]),
                         np.array([[0.93, 1.2, 1.0], [1.0, 1.0, 1.0], [1.07, 0.6, 1.0]], np.float32))
    lifted = lift_module_elements(building, modules)
    assert lifted.protos == (DOOR, bay, WINDOW, SILL)
    assert lifted.proto_indices.tolist() == [1, 0, 1, 2, 3, 2, 3]  # the building's rows, then each bay's elements
    got = instance_matrices(lifted)
    nested = instance_matrices(building)[[0, 0, 2, 2]] @ instance_matrices(modules[bay].elements)[[0, 1, 0, 1]]
    np.testing.assert_allclose(got[3:], nested, atol=1e-9)
    np.testing.assert_allclose(got[:3], instance_matrices(building), atol=1e-12)


def test_a_module_without_meshes_leaves_only_its_elements():
    bare = ModuleKey(2, 200, 300, "brick")
    modules = {bare: ModuleProto({("wall", "brick"): EMPTY}, _elements((WINDOW, (0.5, 1.0, 0.0), (1.0, 1.0, 1.0))))}
    building = Instances((bare, DOOR), np.array([0, 1, 0], np.int32), np.array([[0.0, 0, 0], [5, 0, 0], [9, 0, 0]]),
                         np.tile([0.0, 0.0, 0.0, 1.0], (3, 1)), np.ones((3, 3), np.float32))
    lifted = lift_module_elements(building, modules)
    assert lifted.protos == (DOOR, WINDOW)
    assert lifted.proto_indices.tolist() == [0, 1, 1]
    np.testing.assert_allclose(lifted.positions, [[5, 0, 0], [0.5, 1, 0], [9.5, 1, 0]])
