"""Author.mesh copies a per-kind template spec and sets its values: the result must be exactly the mesh authored
spec by spec (same properties, order, metadata and values), for every kind of mesh."""
from __future__ import annotations

import itertools

import numpy as np
import pytest
from pxr import Sdf, Vt

from citygen.geometry.building import MeshData
from citygen.usd.author import Author, T
from citygen.usd.normals import face_normals
from citygen.usd.uv import planar_st


def _box_side() -> MeshData:
    pts = np.array([[0, 0, 0], [2, 0, 0], [2, 0, 3], [0, 0, 3], [2, 1, 0], [2, 1, 3]], dtype=np.float32)
    return MeshData(pts, np.array([4, 4], np.int32), np.array([0, 1, 2, 3, 1, 4, 5, 2], np.int32))


def _spec_by_spec(layer: Sdf.Layer, mesh: MeshData, st: bool, looks: Sdf.Path | None, mat: str | None,
                  label: str | None) -> None:
    """The mesh as the writer authored it before templates: one Sdf call per spec."""
    (normals, index), = face_normals([mesh])
    prim = Sdf.PrimSpec(layer.GetPrimAtPath("/R"), "M", Sdf.SpecifierDef, "Mesh")

    def attr(name, vtype, value, uniform=False):
        spec = Sdf.AttributeSpec(prim, name, vtype, Sdf.VariabilityUniform if uniform else Sdf.VariabilityVarying)
        spec.default = value
        return spec

    attr("points", T.Point3fArray, Vt.Vec3fArray.FromNumpy(mesh.points))
    attr("faceVertexCounts", T.IntArray, Vt.IntArray.FromNumpy(mesh.counts))
    attr("faceVertexIndices", T.IntArray, Vt.IntArray.FromNumpy(mesh.indices))
    attr("extent", T.Float3Array, Vt.Vec3fArray.FromNumpy(np.array([mesh.points.min(0), mesh.points.max(0)])))
    attr("subdivisionScheme", T.Token, "none", True)
    attr("primvars:normals", T.Normal3fArray, Vt.Vec3fArray.FromNumpy(normals)).SetInfo("interpolation", "uniform")
    attr("primvars:normals:indices", T.IntArray, Vt.IntArray.FromNumpy(index))
    if st:
        attr("primvars:st", T.TexCoord2fArray, Vt.Vec2fArray.FromNumpy(
            planar_st(mesh.points, mesh.counts, mesh.indices))).SetInfo("interpolation", "faceVarying")
    schemas = []
    if looks is not None and mat is not None:
        schemas.append("MaterialBindingAPI")
        Sdf.RelationshipSpec(prim, "material:binding").targetPathList.explicitItems = [looks.AppendChild(mat)]
    if label is not None:
        schemas.append("SemanticsLabelsAPI:class")
        attr("semantics:labels:class", T.TokenArray, Vt.TokenArray([label]), True)
    if schemas:
        prim.SetInfo("apiSchemas", Sdf.TokenListOp.Create(prependedItems=schemas))


def _layer() -> Sdf.Layer:
    layer = Sdf.Layer.CreateAnonymous(".usda")
    Sdf.PrimSpec(layer, "R", Sdf.SpecifierDef, "Xform")
    return layer


@pytest.mark.parametrize("st, bound, label", list(itertools.product([False, True], [False, True], [None, "window"])))
def test_a_mesh_copied_from_its_template_equals_the_mesh_authored_spec_by_spec(st, bound, label):
    mesh = _box_side()
    looks = Sdf.Path("/R/Looks") if bound else None
    expected = _layer()
    _spec_by_spec(expected, mesh, st, looks, "brick", label)
    got = _layer()
    author = Author(got, uvs=st)
    returned = author.mesh(got.GetPrimAtPath("/R"), "M", mesh, looks, "brick", label)
    assert got.ExportToString() == expected.ExportToString()
    assert np.array_equal(returned, [mesh.points.min(0), mesh.points.max(0)])
    assert author.prims == 1


def test_meshes_of_one_template_keep_their_own_values():
    """Two meshes copied from the same template: the second's values do not leak into the first's."""
    small, big = _box_side(), _box_side()
    big = MeshData(big.points * 10, big.counts, big.indices)
    layer = _layer()
    author = Author(layer)
    root = layer.GetPrimAtPath("/R")
    author.mesh(root, "A", small, Sdf.Path("/R/Looks"), "brick", "wall")
    author.mesh(root, "B", big, Sdf.Path("/R/Looks"), "glass", "wall")
    a, b = layer.GetPrimAtPath("/R/A"), layer.GetPrimAtPath("/R/B")
    assert np.array_equal(np.array(a.attributes["points"].default), small.points)
    assert np.array_equal(np.array(b.attributes["points"].default), big.points)
    assert list(a.relationships["material:binding"].targetPathList.explicitItems) == [Sdf.Path("/R/Looks/brick")]
    assert list(b.relationships["material:binding"].targetPathList.explicitItems) == [Sdf.Path("/R/Looks/glass")]
