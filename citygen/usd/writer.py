"""Write a city as one USD stage (``.usda``, ``.usdc`` or ``.usdz`` by extension), atomically.

Layout of the stage::

    /World                     Xform, kind=assembly (defaultPrim; rotated for upAxis Y)
      Looks/<material>         Material + UsdPreviewSurface
      Tile_<i>_<j>             Xform, kind=group
        <building>             Xform, kind=component, citygen:* attributes
          Facade/<label>_<mat> Mesh per label and material, UsdSemantics label
          Roof                 Mesh
          Elements             PointInstancer; Prototypes/<pN> reference /Prototypes/<name>
    /Prototypes                class: one prototype per element kind and quantised size

Authoring goes through the Sdf API inside one change block, which is what keeps a 100k-building city writable.
"""
from __future__ import annotations

import os
import tempfile
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from pxr import Gf, Sdf, Tf, Usd, UsdUtils, Vt

from citygen.errors import ExportError
from citygen.geometry.building import BuildingGeometry, Instances, MeshData, ModuleProto
from citygen.geometry.modules import ModuleKey
from citygen.geometry.prototypes import ProtoKey, build_prototype
from citygen.usd.materials import look

SUFFIXES = (".usda", ".usdc", ".usdz")
T = Sdf.ValueTypeNames


@dataclass(frozen=True)
class BuildingRecord:
    """A building ready for the stage: its prim name, tile, geometry and ``citygen:`` attributes."""

    name: str
    tile: tuple[int, int]
    geometry: BuildingGeometry
    attributes: Mapping[str, Any]


@dataclass(frozen=True)
class StageStats:
    path: Path
    buildings: int
    prims: int
    meshes: int
    instances: int
    prototypes: int
    polygons: int
    bytes: int


def prim_name(raw: str, taken: set[str]) -> str:
    """A valid, unique prim name for a stable id (``way/123`` -> ``way_123``; collisions get ``_2``, ``_3``)."""
    base = Tf.MakeValidIdentifier(raw) or "_"
    name, k = base, 2
    while name in taken:
        name, k = f"{base}_{k}", k + 1
    taken.add(name)
    return name


class _Author:
    """Thin Sdf authoring helpers on one layer."""

    def __init__(self, layer: Sdf.Layer) -> None:
        self.layer = layer
        self.prims = 0

    def prim(self, parent: Sdf.PrimSpec | Sdf.Layer, name: str, type_name: str = "",
             specifier=Sdf.SpecifierDef) -> Sdf.PrimSpec:
        self.prims += 1
        return Sdf.PrimSpec(parent, name, specifier, type_name)

    @staticmethod
    def attr(prim: Sdf.PrimSpec, name: str, vtype, value, uniform: bool = False) -> None:
        spec = Sdf.AttributeSpec(prim, name, vtype, Sdf.VariabilityUniform if uniform else Sdf.VariabilityVarying)
        spec.default = value

    @staticmethod
    def rel(prim: Sdf.PrimSpec, name: str, targets: Iterable[Sdf.Path]) -> None:
        spec = Sdf.RelationshipSpec(prim, name)
        for t in targets:
            spec.targetPathList.explicitItems.append(t)

    @staticmethod
    def api(prim: Sdf.PrimSpec, *schemas: str) -> None:
        prim.SetInfo("apiSchemas", Sdf.TokenListOp.Create(prependedItems=list(schemas)))

    def mesh(self, parent: Sdf.PrimSpec, name: str, mesh: MeshData, material: Sdf.Path | None,
             label: str | None) -> Sdf.PrimSpec | None:
        """A Mesh prim (none for an empty mesh)."""
        if not len(mesh.counts):
            return None
        prim = self.prim(parent, name, "Mesh")
        pts = np.ascontiguousarray(mesh.points, dtype=np.float32)
        self.attr(prim, "points", T.Point3fArray, Vt.Vec3fArray.FromNumpy(pts))
        self.attr(prim, "faceVertexCounts", T.IntArray, Vt.IntArray.FromNumpy(np.ascontiguousarray(mesh.counts)))
        self.attr(prim, "faceVertexIndices", T.IntArray, Vt.IntArray.FromNumpy(np.ascontiguousarray(mesh.indices)))
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        self.attr(prim, "extent", T.Float3Array, Vt.Vec3fArray([Gf.Vec3f(*map(float, lo)), Gf.Vec3f(*map(float, hi))]))
        self.attr(prim, "subdivisionScheme", T.Token, "none", uniform=True)
        schemas = []
        if material is not None:
            schemas.append("MaterialBindingAPI")
            self.rel(prim, "material:binding", [material])
        if label is not None:
            schemas.append("SemanticsLabelsAPI:class")
            self.attr(prim, "semantics:labels:class", T.TokenArray, Vt.TokenArray([label]), uniform=True)
        if schemas:
            self.api(prim, *schemas)
        return prim

    def material(self, parent: Sdf.PrimSpec, name: str) -> Sdf.Path:
        (r, g, b), roughness, metallic, opacity = look(name)
        mat = self.prim(parent, name, "Material")
        shader = self.prim(mat, "PreviewSurface", "Shader")
        self.attr(shader, "info:id", T.Token, "UsdPreviewSurface", uniform=True)
        self.attr(shader, "inputs:diffuseColor", T.Color3f, Gf.Vec3f(r, g, b))
        self.attr(shader, "inputs:roughness", T.Float, roughness)
        self.attr(shader, "inputs:metallic", T.Float, metallic)
        self.attr(shader, "inputs:opacity", T.Float, opacity)
        Sdf.AttributeSpec(shader, "outputs:surface", T.Token)
        out = Sdf.AttributeSpec(mat, "outputs:surface", T.Token)
        out.connectionPathList.explicitItems.append(shader.path.AppendProperty("outputs:surface"))
        return mat.path


def _value(value: Any):
    if isinstance(value, bool):
        return T.Bool, value
    if isinstance(value, int):
        return T.Int, value
    if isinstance(value, float):
        return T.Double, value
    return T.String, str(value)


def _dictionary(data: Mapping[str, Any]) -> dict[str, Any]:
    """Layer metadata values USD can store: nested dicts, scalars, strings, and numeric lists as double arrays."""
    out: dict[str, Any] = {}
    for key, value in data.items():
        if isinstance(value, Mapping):
            out[key] = _dictionary(value)
        elif isinstance(value, (list, tuple)):
            out[key] = Vt.DoubleArray([float(v) for v in value])
        else:
            out[key] = value
    return out


def write_stage(path: str | Path, buildings: Iterable[BuildingRecord], *, up_axis: str = "Z",
                layer_data: Mapping[str, Any] | None = None) -> StageStats:
    """Author the city and write it to ``path`` atomically (temporary file + rename)."""
    path = Path(path)
    if path.suffix.lower() not in SUFFIXES:
        raise ExportError(f"unsupported stage extension {path.suffix!r}", where=str(path),
                          hint=f"use one of {', '.join(SUFFIXES)}")
    layer = Sdf.Layer.CreateAnonymous(".usda")
    author = _Author(layer)
    counts = {"buildings": 0, "meshes": 0, "instances": 0, "polygons": 0}
    with Sdf.ChangeBlock():
        layer.defaultPrim = "World"
        layer.pseudoRoot.SetInfo("metersPerUnit", 1.0)
        layer.pseudoRoot.SetInfo("upAxis", up_axis)
        layer.customLayerData = {"citygen": _dictionary(layer_data or {})}
        world = author.prim(layer, "World", "Xform")
        world.SetInfo("kind", "assembly")
        if up_axis == "Y":
            author.attr(world, "xformOp:rotateX", T.Float, -90.0)
            author.attr(world, "xformOpOrder", T.TokenArray, Vt.TokenArray(["xformOp:rotateX"]), uniform=True)
        looks = author.prim(world, "Looks", "Scope")
        protos_root = author.prim(layer, "Prototypes", "", Sdf.SpecifierClass)
        materials: dict[str, Sdf.Path] = {}
        material_names: set[str] = set()
        prototypes: dict[ProtoKey, Sdf.Path] = {}

        def material(name: str) -> Sdf.Path:
            if name not in materials:
                materials[name] = author.material(looks, prim_name(name, material_names))
            return materials[name]

        def prototype(key: ProtoKey | ModuleKey, modules: Mapping[ModuleKey, ModuleProto]) -> Sdf.Path:
            if key not in prototypes:
                proto = author.prim(protos_root, Tf.MakeValidIdentifier(key.name), "Xform")
                author.api(proto, "SemanticsLabelsAPI:class")
                author.attr(proto, "semantics:labels:class", T.TokenArray, Vt.TokenArray([key.label]), uniform=True)
                if isinstance(key, ModuleKey):
                    module = modules[key]
                    names: set[str] = set()
                    for (label, mat), mesh in module.meshes.items():
                        author.mesh(proto, prim_name(f"{label}_{mat}", names), mesh, material(mat), label)
                    if len(module.elements.proto_indices):
                        _instancer(author, proto, module.elements, lambda k: prototype(k, modules))
                else:
                    for part in build_prototype(key):
                        if len(part.quads):
                            author.mesh(proto, part.name, MeshData.from_quads(part.quads), material(part.material),
                                        None)
                prototypes[key] = proto.path
            return prototypes[key]

        tiles: dict[tuple[int, int], Sdf.PrimSpec] = {}
        for record in buildings:
            if record.tile not in tiles:
                i, j = record.tile
                tile = author.prim(world, f"Tile_{i}_{j}".replace("-", "m"), "Xform")
                tile.SetInfo("kind", "group")
                tiles[record.tile] = tile
            _write_building(author, tiles[record.tile], record, material, prototype, counts)
    stage_layer = _finish(layer, path)
    return StageStats(path=path, buildings=counts["buildings"], prims=author.prims, meshes=counts["meshes"],
                      instances=counts["instances"], prototypes=len(prototypes), polygons=counts["polygons"],
                      bytes=stage_layer)


def _write_building(author: _Author, parent: Sdf.PrimSpec, record: BuildingRecord, material, prototype,
                    counts: dict[str, int]) -> None:
    geo = record.geometry
    prim = author.prim(parent, record.name, "Xform")
    prim.SetInfo("kind", "component")
    for key, value in sorted(record.attributes.items()):
        vtype, v = _value(value)
        author.attr(prim, f"citygen:{key}", vtype, v)
    if geo.meshes:
        facade = author.prim(prim, "Facade", "Scope")
        names: set[str] = set()
        for (label, mat), mesh in geo.meshes.items():
            counts["meshes"] += author.mesh(facade, prim_name(f"{label}_{mat}", names), mesh, material(mat),
                                            label) is not None
            counts["polygons"] += len(mesh.counts)
    if geo.roof is not None:
        author.mesh(prim, "Roof", geo.roof, material("roof_dark"), "roof")
        counts["meshes"] += 1
        counts["polygons"] += len(geo.roof.counts)
    inst = geo.instances
    if len(inst.proto_indices):
        _instancer(author, prim, inst, lambda key: prototype(key, geo.modules))
        counts["instances"] += len(inst.proto_indices)
    counts["buildings"] += 1


def _instancer(author: _Author, parent: Sdf.PrimSpec, inst: Instances, prototype) -> None:
    """A PointInstancer ``Elements`` under ``parent`` whose prototypes reference the shared ``/Prototypes``."""
    pi = author.prim(parent, "Elements", "PointInstancer")
    holder = author.prim(pi, "Prototypes", "Scope")
    targets = []
    for k, key in enumerate(inst.protos):
        ref = author.prim(holder, f"p{k}", "Xform")
        ref.referenceList.prependedItems.append(Sdf.Reference(primPath=prototype(key)))
        ref.SetInfo("instanceable", True)  # one shared prototype per element kind: DCCs load it once
        targets.append(ref.path)
    author.rel(pi, "prototypes", targets)
    author.attr(pi, "protoIndices", T.IntArray, Vt.IntArray.FromNumpy(inst.proto_indices.astype(np.int32)))
    author.attr(pi, "positions", T.Point3fArray, Vt.Vec3fArray.FromNumpy(inst.positions.astype(np.float32)))
    author.attr(pi, "orientations", T.QuathArray, Vt.QuathArray.FromNumpy(inst.orientations.astype(np.float16)))
    author.attr(pi, "scales", T.Float3Array, Vt.Vec3fArray.FromNumpy(inst.scales.astype(np.float32)))


def _finish(layer: Sdf.Layer, path: Path) -> int:
    """Export ``layer`` to ``path`` through a temporary file in the same folder; return the file size."""
    path.parent.mkdir(parents=True, exist_ok=True)
    suffix = path.suffix.lower()
    fd, tmp_name = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=suffix, dir=path.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        if suffix == ".usdz":
            inner = tmp.with_suffix(".usdc")
            _export(layer, inner)
            try:
                if not UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(str(inner)), str(tmp)):
                    raise ExportError("usdz packaging failed", where=str(path))
            finally:
                inner.unlink(missing_ok=True)
        else:
            _export(layer, tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; a stage is an ordinary file
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path.stat().st_size


def _export(layer: Sdf.Layer, target: Path) -> None:
    if not layer.Export(str(target)):
        raise ExportError("USD export failed", where=str(target), hint="check free disk space and permissions")


def open_stage(path: str | Path) -> Usd.Stage:
    stage = Usd.Stage.Open(str(path))
    if stage is None:
        raise ExportError("cannot open stage", where=str(path))
    return stage
