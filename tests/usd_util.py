"""Helpers for tests that read back written stages."""
from __future__ import annotations

from pxr import Kind, Usd, UsdGeom, UsdSemantics, UsdShade


def buildings(stage: Usd.Stage) -> list[Usd.Prim]:
    return [p for p in stage.Traverse() if Usd.ModelAPI(p).GetKind() == Kind.Tokens.component]


def element_labels(stage: Usd.Stage, instancer: Usd.Prim) -> list[str]:
    """Semantic labels of every element an instancer places, modules flattened (nested instancers)."""
    if not instancer:
        return []
    pi = UsdGeom.PointInstancer(instancer)
    protos = [stage.GetPrimAtPath(t) for t in pi.GetPrototypesRel().GetTargets()]
    labels = []
    for i in pi.GetProtoIndicesAttr().Get():
        proto = protos[i]
        label = UsdSemantics.LabelsAPI(proto, "class").GetLabelsAttr().Get()[0]
        labels += element_labels(stage, proto.GetChild("Elements")) if label == "module" else [label]
    return labels


def assert_resolves(stage: Usd.Stage, root: str = "/") -> None:
    """Every mesh under ``root`` (instance proxies included) binds a Material whose surface is a connected
    UsdPreviewSurface, and every PointInstancer's prototypes exist and hold meshes."""
    meshes = 0
    for prim in Usd.PrimRange(stage.GetPrimAtPath(root), Usd.TraverseInstanceProxies(Usd.PrimDefaultPredicate)):
        if prim.IsA(UsdGeom.Mesh):
            meshes += 1
            material, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
            assert material, f"{prim.GetPath()} binds no material that resolves"
            source = material.GetSurfaceOutput().GetConnectedSources()[0]
            assert source and source[0].source.GetPrim().GetAttribute("info:id").Get() == "UsdPreviewSurface"
        elif prim.IsA(UsdGeom.PointInstancer):
            targets = UsdGeom.PointInstancer(prim).GetPrototypesRel().GetForwardedTargets()
            assert targets, prim.GetPath()
            for target in targets:
                proto = stage.GetPrimAtPath(target)
                assert proto and any(p.IsA(UsdGeom.Mesh) for p in Usd.PrimRange(
                    proto, Usd.TraverseInstanceProxies(Usd.PrimDefaultPredicate))), f"{target} holds no mesh"
    assert meshes, f"no mesh under {root}"


def world_points(mesh: Usd.Prim):
    """A mesh's points in world coordinates (``(n, 3)`` array)."""
    import numpy as np
    matrix = np.array(UsdGeom.Xformable(mesh).ComputeLocalToWorldTransform(Usd.TimeCode.Default()))
    points = np.array(UsdGeom.Mesh(mesh).GetPointsAttr().Get(), dtype=float)
    return points @ matrix[:3, :3] + matrix[3, :3]
