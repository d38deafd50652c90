"""Stage validation: every registered ``pxr.UsdValidation`` validator plus mesh topology checks."""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from pxr import Tf, Usd, UsdGeom, UsdValidation


@dataclass(frozen=True)
class Finding:
    severity: str
    where: str
    message: str


def validate_stage(stage_or_path: Usd.Stage | str | Path) -> list[Finding]:
    """All findings for a stage; errors have ``severity == "error"``.

    Runs ``UsdValidation`` with all validators, then ``UsdGeom.Mesh.ValidateTopology`` on every mesh
    (including instance prototypes).
    """
    if isinstance(stage_or_path, Usd.Stage):
        stage = stage_or_path
    else:
        try:
            stage = Usd.Stage.Open(str(stage_or_path))
        except Tf.ErrorException as exc:
            return [Finding("error", str(stage_or_path), f"cannot open stage: {_usd_reason(exc)}")]
    findings = []
    context = UsdValidation.ValidationContext(UsdValidation.ValidationRegistry().GetOrLoadAllValidators())
    for error in context.Validate(stage):
        kind = error.GetType()
        severity = {UsdValidation.ValidationErrorType.Error: "error",
                    UsdValidation.ValidationErrorType.Warn: "warning"}.get(kind, "info")
        sites = ", ".join(map(_site, error.GetSites())) or "stage"
        findings.append(Finding(severity, sites, f"{error.GetValidator().GetMetadata().name}: {error.GetMessage()}"))
    for prim in stage.Traverse(Usd.TraverseInstanceProxies(Usd.PrimAllPrimsPredicate)):
        if prim.IsA(UsdGeom.Mesh):
            mesh = UsdGeom.Mesh(prim)
            ok, reason = UsdGeom.Mesh.ValidateTopology(mesh.GetFaceVertexIndicesAttr().Get(),
                                                       mesh.GetFaceVertexCountsAttr().Get(),
                                                       len(mesh.GetPointsAttr().Get()))
            if not ok:
                findings.append(Finding("error", str(prim.GetPath()), f"mesh topology: {reason}"))
    return findings


def _site(site: UsdValidation.ValidationErrorSite) -> str:
    """Where a finding is: a prim or property path, else its layer (a site may be a property only)."""
    if site.IsPrim():
        return str(site.GetPrim().GetPath())
    if site.IsProperty():
        return str(site.GetProperty().GetPath())
    layer = site.GetLayer()
    return str(layer.identifier) if layer else "stage"


def _usd_reason(exc: Exception) -> str:
    """The reason of a USD error without its source location ("Error in 'pxrInternal_...::Open' at line N in
    file stage.cpp : 'reason'" -> "reason")."""
    first = str(exc).strip().splitlines()[0]
    match = re.match(r"Error in '[^']*' at line \d+ in file \S+ : '(.*?)'?$", first)
    return match.group(1) if match else first
