"""The writer's PointInstancer copies its prototype prims from a template spec (``_instancer_template``) and gives
each its reference: the result must be exactly the instancer authored prim by prim, at the top of a building and
inside a LOD variant (whose relationship targets are composed paths, without the variant selection)."""
from __future__ import annotations

import numpy as np
import pytest
from pxr import Sdf, Usd, Vt

from citygen.geometry.building import Instances
from citygen.usd.author import Author, T
from citygen.usd.writer import _instancer


def _instances(n: int) -> Instances:
    rows = np.arange(2 * n) % n
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (2 * n, 1))
    return Instances(tuple(f"k{i}" for i in range(n)), rows.astype(np.int32), np.arange(6 * n, dtype=float)
                     .reshape(-1, 3), quat, np.ones((2 * n, 3), np.float32))


def _prim_by_prim(author: Author, parent: Sdf.PrimSpec, inst: Instances, prototypes: dict) -> None:
    """The instancer as the writer authored it before the template: one Sdf call per prim and field."""
    pi = author.prim(parent, "Elements", "PointInstancer")
    holder = author.prim(pi, "Prototypes", "Scope")
    names = [f"p{k}" for k in range(len(inst.protos))]
    for name, key in zip(names, inst.protos):
        ref = author.prim(holder, name, "Xform")
        author.reference(ref, prototypes[key])
        ref.SetInfo("instanceable", True)
    base = holder.path.StripAllVariantSelections()
    author.rel(pi, "prototypes", [base.AppendChild(name) for name in names])
    author.attr(pi, "protoIndices", T.IntArray, Vt.IntArray.FromNumpy(inst.proto_indices.astype(np.int32)))
    author.attr(pi, "positions", T.Point3fArray, Vt.Vec3fArray.FromNumpy(np.asarray(inst.positions, np.float32)))
    author.attr(pi, "orientations", T.QuathArray, Vt.QuathArray.FromNumpy(inst.orientations.astype(np.float16)))
    author.attr(pi, "scales", T.Float3Array, Vt.Vec3fArray.FromNumpy(inst.scales.astype(np.float32)))
    author.attr(pi, "extent", T.Float3Array, Vt.Vec3fArray([(0, 0, 0), (1, 1, 1)]))


def _building(variant: bool) -> tuple[Sdf.Layer, Sdf.PrimSpec]:
    layer = Sdf.Layer.CreateAnonymous(".usda")
    prim = Sdf.PrimSpec(layer, "B", Sdf.SpecifierDef, "Xform")
    if not variant:
        return layer, prim
    lods = Sdf.VariantSetSpec(prim, "LOD")
    prim.variantSetNameList.prependedItems.append("LOD")
    prim.variantSelections["LOD"] = "LOD0"
    return layer, Sdf.VariantSpec(lods, "LOD0").primSpec


@pytest.mark.parametrize("variant", [False, True])
@pytest.mark.parametrize("n", [1, 3, 12])
def test_an_instancer_copied_from_its_template_equals_the_one_authored_prim_by_prim(variant, n):
    inst = _instances(n)
    prototypes = {key: Sdf.Path(f"/Prototypes/{key}_proto") for key in inst.protos}
    expected, parent = _building(variant)
    old = Author(expected)
    _prim_by_prim(old, parent, inst, prototypes)
    got, parent = _building(variant)
    new = Author(got)
    _instancer(new, parent, inst, prototypes, np.array([[0, 0, 0], [1, 1, 1]]))
    assert got.ExportToString() == expected.ExportToString()
    assert new.prims == old.prims == n + 2


def test_instancers_of_one_template_keep_their_own_references():
    """Two buildings' instancers of the same size: each references its own prototypes, and the composed
    instancer's prototypes are its own instanceable prims."""
    layer = Sdf.Layer.CreateAnonymous(".usda")
    author = Author(layer)
    for name, target in (("A", "/Prototypes/window"), ("B", "/Prototypes/door")):
        parent = Sdf.PrimSpec(layer, name, Sdf.SpecifierDef, "Xform")
        _instancer(author, parent, _instances(1), {"k0": Sdf.Path(target)}, None)
    protos = Sdf.PrimSpec(layer, "Prototypes", Sdf.SpecifierClass)
    for target in ("window", "door"):
        Sdf.PrimSpec(protos, target, Sdf.SpecifierDef, "Xform")
    stage = Usd.Stage.Open(layer)
    for name, target in (("A", "window"), ("B", "door")):
        proto = stage.GetPrimAtPath(f"/{name}/Elements/Prototypes/p0")
        assert proto.IsInstance()
        refs = layer.GetPrimAtPath(f"/{name}/Elements/Prototypes/p0").referenceList.prependedItems
        assert [r.primPath for r in refs] == [Sdf.Path(f"/Prototypes/{target}")]
        rel = stage.GetPrimAtPath(f"/{name}/Elements").GetRelationship("prototypes")
        assert rel.GetTargets() == [Sdf.Path(f"/{name}/Elements/Prototypes/p0")]
