"""Face normals: one per polygon (uniform, indexed), following the winding, on every written mesh."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pxr import Usd, UsdGeom

from citygen.pipeline import generate_city
from citygen.scene import load_scene
from citygen.geometry.building import MeshData
from citygen.usd.normals import STEP, face_normals, polygon_normals

SQUARE = np.array([[0, 0, 0], [2, 0, 1], [2, 1, 1], [0, 1, 0]], dtype=float)  # a quad rising towards +x


def test_quad_and_triangle_normals_follow_the_winding():
    up = np.array([-1, 0, 2]) / np.sqrt(5)
    assert polygon_normals(SQUARE, [4], np.arange(4)) == pytest.approx(up[None])
    assert polygon_normals(SQUARE, [4], np.arange(4)[::-1]) == pytest.approx(-up[None])
    assert polygon_normals(SQUARE, [3], [0, 1, 2]) == pytest.approx(up[None])


def test_mixed_polygons_use_newell_and_agree_with_the_quad_path():
    pentagon = np.array([[0, 0, 0], [2, 0, 0], [3, 1, 0], [1, 2, 0], [-1, 1, 0]], dtype=float)
    points = np.vstack([SQUARE, pentagon])
    normals = polygon_normals(points, [4, 5, 3], np.r_[0:4, 4:9, 0:3])
    assert normals[0] == pytest.approx(polygon_normals(SQUARE, [4], np.arange(4))[0])
    assert normals[1] == pytest.approx([0, 0, 1]) and normals[2] == pytest.approx(normals[0])


def test_a_polygon_of_no_area_faces_up():
    line = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], dtype=float)
    assert polygon_normals(line, [4], np.arange(4)).tolist() == [[0, 0, 1]]
    assert polygon_normals(line, [3, 3], [0, 1, 2, 1, 2, 3]).tolist() == [[0, 0, 1]] * 2


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)), min_size=1, max_size=40),
       st.floats(-1e3, 1e3))
def test_indexed_normals_are_unit_and_within_the_grid_step_of_each_face(directions, offset):
    """Quads of random orientation, each drawn twice at another place in its plane (float32 points)."""
    quads = []
    for d in directions:
        n = np.array(d) if np.linalg.norm(d) > 1e-3 else np.array([0.0, 0.0, 1.0])
        n /= np.linalg.norm(n)
        u = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
        u /= np.linalg.norm(u)
        v = np.cross(n, u)
        for shift in (0.0, 3.0):
            corner = offset + shift * u
            quads.append([corner, corner + 2 * u, corner + 2 * u + v, corner + v])
    points = np.array(quads, dtype=np.float32).reshape(-1, 3)
    mesh = MeshData(points, np.full(len(quads), 4, np.int32), np.arange(len(points), dtype=np.int32))
    (values, index), = face_normals([mesh])
    assert values.dtype == np.float32 and index.dtype == np.int32 and len(index) == len(quads)
    assert np.allclose(np.linalg.norm(values, axis=1), 1.0, atol=1e-6)
    assert len(values) == len(np.unique(values, axis=0))
    exact = polygon_normals(points, np.full(len(quads), 4), np.arange(len(points)))
    assert np.all(np.einsum("ij,ij->i", values[index], exact) > np.cos(2 * STEP))


def test_the_faces_of_a_box_share_six_normals():
    box = np.array([[x, y, z] for x in (0, 4) for y in (0, 3) for z in (0, 2)], dtype=np.float32) + 500
    faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    halves = [[f[0], f[1], f[2]] for f in faces] + [[f[0], f[2], f[3]] for f in faces]
    mesh = MeshData(box, np.full(12, 3, np.int32), np.array(halves, dtype=np.int32).ravel())
    (values, index), = face_normals([mesh])
    assert len(values) == 6 and np.array_equal(index[:6], index[6:])
    assert sorted(map(tuple, values.astype(int).tolist())) == sorted(
        [(-1, 0, 0), (1, 0, 0), (0, -1, 0), (0, 1, 0), (0, 0, -1), (0, 0, 1)])


def test_a_batch_gives_each_mesh_its_own_normals_as_alone():
    """A building's meshes are done in one batch; each gets exactly what it would get alone."""
    rng = np.random.default_rng(5)
    meshes = [MeshData(rng.normal(size=(12, 3)).astype(np.float32), np.array(c, np.int32),
                       rng.integers(0, 12, sum(c)).astype(np.int32)) for c in ([4, 4, 3], [5], [], [3, 3, 4, 6])]
    for (values, index), mesh in zip(face_normals(meshes), meshes):
        (alone, alone_index), = face_normals([mesh])
        assert np.array_equal(values, alone) and np.array_equal(index, alone_index)
        assert len(index) == len(mesh.counts) and len(values) == len(np.unique(index))
        if len(mesh.counts):
            assert np.allclose(values[index], polygon_normals(mesh.points, mesh.counts, mesh.indices), atol=STEP)


def test_every_written_mesh_has_outward_face_normals(small_scene, test_registry, tmp_path):
    report = generate_city(load_scene(small_scene), registry=test_registry, out=tmp_path / "city.usda")
    stage = Usd.Stage.Open(str(report.stats.path))
    meshes = [UsdGeom.Mesh(p) for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    assert meshes and any(m.GetPrim().GetName() == "Roof" for m in meshes)
    for mesh in meshes:
        normals = UsdGeom.PrimvarsAPI(mesh).GetPrimvar("normals")
        assert normals.GetInterpolation() == UsdGeom.Tokens.uniform and normals.IsIndexed()
        counts = np.array(mesh.GetFaceVertexCountsAttr().Get())
        points, indices = np.array(mesh.GetPointsAttr().Get()), np.array(mesh.GetFaceVertexIndicesAttr().Get())
        per_face = np.array(normals.ComputeFlattened())
        assert len(per_face) == len(counts)
        start = np.cumsum(counts) - counts
        for k, (s, c) in enumerate(zip(start, counts)):  # the face's own normal, by Newell's method
            p = points[indices[s:s + c]]
            q = np.roll(p, -1, axis=0)
            n = np.array([np.sum((p[:, 1] - q[:, 1]) * (p[:, 2] + q[:, 2])),
                          np.sum((p[:, 2] - q[:, 2]) * (p[:, 0] + q[:, 0])),
                          np.sum((p[:, 0] - q[:, 0]) * (p[:, 1] + q[:, 1]))])
            if np.linalg.norm(n) > 1e-6:
                assert per_face[k] @ n / np.linalg.norm(n) > 0.9999
        if mesh.GetPrim().GetName() == "Roof":
            assert np.all(per_face[:, 2] > -1e-6)  # roofs face up (flat here) or out, never down


def test_a_batch_with_other_polygons_gives_each_polygon_its_own_normal():
    """Triangles and quads take the diagonals' normal and other polygons Newell's, polygon by polygon: a batch of
    many meshes (a whole tile's) with one pentagon gets the normals each polygon has alone."""
    rng = np.random.default_rng(1)
    points = rng.random((40, 3))
    counts = np.array([4, 3, 5, 4, 6, 3, 4])
    indices = rng.integers(0, 40, counts.sum())
    ends = np.cumsum(counts)
    alone = np.concatenate([polygon_normals(points, counts[k:k + 1], indices[ends[k] - counts[k]:ends[k]])
                            for k in range(len(counts))])
    np.testing.assert_array_equal(polygon_normals(points, counts, indices), alone)
