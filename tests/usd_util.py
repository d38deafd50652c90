"""Helpers for tests that read back written stages."""
from __future__ import annotations

from pxr import Kind, Usd, UsdGeom, UsdSemantics


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
