"""Thin Sdf authoring helpers on one layer: prims, attributes, meshes with face normals and UVs, and materials.

Authoring goes through the Sdf API in change blocks (no composed stage while writing), which is what keeps a
100k-building city writable. Specs are authored one by one, never copied with ``Sdf.CopySpec``: the copy orders a
spec's fields by the addresses of their names' tokens, which vary with the process's history, and the .usdc bytes
with them (the text does not change): tiles written by different workers differed from run to run.
"""
from __future__ import annotations

import functools
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pxr import Gf, Sdf, Tf, Vt

from citygen.geometry.building import MeshData
from citygen.usd.materials import Material, material
from citygen.usd.normals import face_normals
from citygen.usd.uv import planar_st

T = Sdf.ValueTypeNames
_UNIFORM, _VARYING = Sdf.VariabilityUniform, Sdf.VariabilityVarying


@functools.lru_cache(maxsize=1024)  # (a mesh's binding names its material's look: every mesh asks)
def look_name(name: str) -> str:
    """The prim name of a material name (a scene may name one ``brick-red``)."""
    return Tf.MakeValidIdentifier(name)


@functools.lru_cache(maxsize=256)
def _schemas(names: tuple[str, ...]) -> Sdf.TokenListOp:
    """The ``apiSchemas`` list op prepending ``names`` (made once: a mesh's and a building's are all alike)."""
    return Sdf.TokenListOp.Create(prependedItems=list(names))


@functools.lru_cache(maxsize=4096)
def _reference(target: Sdf.Path, asset: str) -> Sdf.ReferenceListOp:
    """The list op prepending a reference to ``target`` in ``asset`` (this layer: "") (made once: every building
    references its prototypes and look set)."""
    return Sdf.ReferenceListOp.Create(prependedItems=[Sdf.Reference(asset, target)])


@functools.lru_cache(maxsize=1024)
def tokens(*values: str) -> Vt.TokenArray:
    """A token array value (made once per distinct one: labels and op orders repeat on every mesh and building)."""
    return Vt.TokenArray(list(values))


_POINTS, _INTS, _FLOAT3S, _NORMALS = T.Point3fArray, T.IntArray, T.Float3Array, T.Normal3fArray
_TOKEN, _TOKENS = T.Token, T.TokenArray
#: A mesh's ``apiSchemas`` by (bound to a material, labelled).
_MESH_SCHEMAS = {(True, True): _schemas(("MaterialBindingAPI", "SemanticsLabelsAPI:class")),
                 (True, False): _schemas(("MaterialBindingAPI",)), (False, True): _schemas(("SemanticsLabelsAPI:class",))}


def bound_value(bound: np.ndarray) -> Vt.Vec3fArray:
    return Vt.Vec3fArray.FromNumpy(np.asarray(bound, dtype=np.float32))


@dataclass(frozen=True)
class MeshArrays:
    """A non-empty mesh's attribute values as USD arrays, and its bound: what :meth:`Author.mesh` authors."""

    points: Vt.Vec3fArray
    counts: Vt.IntArray
    indices: Vt.IntArray
    extent: Vt.Vec3fArray
    bound: np.ndarray
    normals: Vt.Vec3fArray
    normal_indices: Vt.IntArray
    st: Vt.Vec2fArray | None  # face-varying texture coordinates in metres (of the points before ``offset``)


def mesh_arrays(meshes: Sequence[MeshData], normals: Sequence[tuple[np.ndarray, np.ndarray]],
                offset: np.ndarray | None = None, st: Sequence[bool] | None = None) -> list[MeshArrays]:
    """The :class:`MeshArrays` of non-empty ``meshes`` with their :func:`face_normals`, ``offset`` subtracted from
    their points (all points offset and bounded in one numpy pass); ``st``: which get texture coordinates."""
    if not meshes:
        return []
    sizes = [len(m.points) for m in meshes]
    pts = np.concatenate([m.points for m in meshes])
    if offset is not None:
        pts = np.asarray(pts, dtype=float) - offset
    pts = np.ascontiguousarray(pts, dtype=np.float32)
    ends = np.cumsum(sizes)
    starts = ends - sizes
    bounds = np.stack([np.minimum.reduceat(pts, starts), np.maximum.reduceat(pts, starts)], axis=1)  # float32
    out = []
    for k, (mesh, (values, index), start, end) in enumerate(zip(meshes, normals, starts.tolist(), ends.tolist())):
        bound = bounds[k]
        out.append(MeshArrays(
            Vt.Vec3fArray.FromNumpy(pts[start:end]), Vt.IntArray.FromNumpy(np.ascontiguousarray(mesh.counts)),
            Vt.IntArray.FromNumpy(np.ascontiguousarray(mesh.indices)), Vt.Vec3fArray.FromNumpy(bound), bound,
            Vt.Vec3fArray.FromNumpy(values), Vt.IntArray.FromNumpy(index),
            Vt.Vec2fArray.FromNumpy(planar_st(mesh.points, mesh.counts, mesh.indices)) if st and st[k] else None))
    return out


class Author:
    """Authoring on one layer. Meshes get indexed face normals (``primvars:normals``, uniform,
    :mod:`citygen.usd.normals`) and, with ``uvs`` or where their material has a texture, face-varying
    ``primvars:st`` in metres (:mod:`citygen.usd.uv`). ``library``: the scene's and rulesets' materials;
    ``layer_dir``: the folder the layer is published to (texture paths are written relative to it)."""

    def __init__(self, layer: Sdf.Layer, uvs: bool = False, library: Mapping[str, Material] | None = None,
                 layer_dir: Path | None = None) -> None:
        self.layer = layer
        self.uvs = uvs
        self.library = library or {}
        self.layer_dir = layer_dir
        self.prims = 0
        self.look_sets: dict[str, Sdf.Path] = {}
        self.look_root: Sdf.PrimSpec | None = None
        self._textured: dict[str, bool] = {}

    def prim(self, parent: Sdf.PrimSpec | Sdf.Layer, name: str, type_name: str = "",
             specifier=Sdf.SpecifierDef) -> Sdf.PrimSpec:
        self.prims += 1
        return Sdf.PrimSpec(parent, name, specifier, type_name)

    @staticmethod
    def attr(prim: Sdf.PrimSpec, name: str, vtype, value, uniform: bool = False,
             custom: bool = False) -> Sdf.AttributeSpec:
        spec = Sdf.AttributeSpec(prim, name, vtype, _UNIFORM if uniform else _VARYING, custom)
        spec.default = value
        return spec

    @staticmethod
    def _primvar(prim: Sdf.PrimSpec, name: str, vtype, interpolation: str, value) -> None:
        spec = Sdf.AttributeSpec(prim, name, vtype)
        spec.SetInfo("interpolation", interpolation)
        spec.default = value

    @staticmethod
    def rel(prim: Sdf.PrimSpec, name: str, targets: Iterable[Sdf.Path]) -> None:
        Sdf.RelationshipSpec(prim, name).targetPathList.explicitItems = list(targets)

    @staticmethod
    def reference(prim: Sdf.PrimSpec, target: Sdf.Path, asset: str = "") -> None:
        """A reference to ``target`` in the layer ``asset`` (default: an internal reference), prepended."""
        prim.SetInfo("references", _reference(target, asset))

    @staticmethod
    def api(prim: Sdf.PrimSpec, *schemas: str) -> None:
        prim.SetInfo("apiSchemas", _schemas(schemas))

    @staticmethod
    def connect(prim: Sdf.PrimSpec, name: str, vtype, source: Sdf.Path) -> None:
        spec = Sdf.AttributeSpec(prim, name, vtype)
        spec.connectionPathList.explicitItems.append(source)

    def textured(self, name: str) -> bool:
        found = self._textured.get(name)
        if found is None:
            found = self._textured[name] = material(name, self.library).texture is not None
        return found

    def arrays(self, meshes: Sequence[tuple[MeshData, str | None]],
               normals: Sequence[tuple[np.ndarray, np.ndarray]] | None = None,
               offset: np.ndarray | None = None) -> list[MeshArrays]:
        """The attribute values of non-empty ``meshes`` (each with its material; ``offset`` subtracted from their
        points), for :meth:`mesh`; ``normals``: their :func:`face_normals` if computed in a batch before."""
        meshes = list(meshes)
        st = [self.uvs or (mat is not None and self.textured(mat)) for _, mat in meshes]
        return mesh_arrays([m for m, _ in meshes], normals or face_normals([m for m, _ in meshes]), offset, st)

    def mesh(self, parent: Sdf.PrimSpec, name: str, mesh: MeshData | MeshArrays, looks: Sdf.Path | None,
             mat: str | None, label: str | None, normals: tuple[np.ndarray, np.ndarray] | None = None,
             offset: np.ndarray | None = None) -> np.ndarray | None:
        """A Mesh prim bound to ``looks/<mat>``, none for an empty mesh; returns its bound (its ``extent``).
        ``mesh``: its data, or its :meth:`arrays` prepared before (a prototype's, once for every layer using it);
        ``normals``: its :func:`face_normals` when already computed in a batch with other meshes; ``offset`` is
        subtracted from its points (the building's pivot)."""
        if isinstance(mesh, MeshData):
            if not len(mesh.counts):
                return None
            mesh = self.arrays([(mesh, mat)], normals and [normals], offset)[0]
        self.prims += 1
        attribute = Sdf.AttributeSpec  # (the specs in the order of the stage's bytes: see the module's docstring)
        prim = Sdf.PrimSpec(parent, name, Sdf.SpecifierDef, "Mesh")
        attribute(prim, "points", _POINTS).default = mesh.points
        attribute(prim, "faceVertexCounts", _INTS).default = mesh.counts
        attribute(prim, "faceVertexIndices", _INTS).default = mesh.indices
        attribute(prim, "extent", _FLOAT3S).default = mesh.extent
        attribute(prim, "subdivisionScheme", _TOKEN, _UNIFORM, False).default = "none"
        normals = attribute(prim, "primvars:normals", _NORMALS)
        normals.SetInfo("interpolation", "uniform")
        normals.default = mesh.normals
        attribute(prim, "primvars:normals:indices", _INTS).default = mesh.normal_indices
        if mesh.st is not None:
            self._primvar(prim, "primvars:st", T.TexCoord2fArray, "faceVarying", mesh.st)
        bound = looks is not None and mat is not None
        if bound:
            Sdf.RelationshipSpec(prim, "material:binding").targetPathList.explicitItems = [
                looks.AppendChild(look_name(mat))]
        if label is not None:
            attribute(prim, "semantics:labels:class", _TOKENS, _UNIFORM, False).default = tokens(label)
        if bound or label is not None:
            prim.SetInfo("apiSchemas", _MESH_SCHEMAS[bound, label is not None])
        return mesh.bound

    def looks(self, parent: Sdf.PrimSpec, names: Iterable[str]) -> Sdf.Path:
        """``parent/Looks``: one Material per name, so the bindings of everything under ``parent`` resolve inside it
        (a reference to ``parent`` brings them along). ``Looks`` is one prim referencing the layer's look set of
        these names (``/Looks/<name>__<name>...``, a class of Materials each referencing ``/Materials/<name>``,
        authored once per combination), so a building or prototype costs one spec for its looks, not one per
        material. Typeless, not a Scope: Blender's importer makes an empty object of every Scope (Delft: 278 of
        2,503 objects), while it reaches materials through the bindings."""
        scope = self.prim(parent, "Looks", "")
        names = list(names)
        if names:
            self.reference(scope, self._look_set(names))
        return scope.path

    def _look_set(self, names: Iterable[str]) -> Sdf.Path:
        """``/Looks/<set>`` of the material ``names``, authored on first use."""
        looks = [look_name(name) for name in names]
        key = "__".join(looks)
        path = self.look_sets.get(key)
        if path is None:
            if self.look_root is None:
                self.look_root = self.prim(self.layer, "Looks", "", Sdf.SpecifierClass)
            spec = self.prim(self.look_root, key, "")
            for name in looks:
                look = self.prim(spec, name, "Material")
                self.reference(look, Sdf.Path("/Materials").AppendChild(name))
            path = self.look_sets[key] = spec.path
        return path

    def material(self, parent: Sdf.PrimSpec, name: str) -> None:
        """A ``UsdPreviewSurface`` Material ``parent/name`` of the library material ``name`` (linear colour; a
        texture through a ``UsdTransform2d`` that scales ``st`` metres to repeats)."""
        look = material(name, self.library)
        mat = self.prim(parent, look_name(name), "Material")
        shader = self.prim(mat, "PreviewSurface", "Shader")
        self.attr(shader, "info:id", T.Token, "UsdPreviewSurface", uniform=True)
        if look.texture is None:
            self.attr(shader, "inputs:diffuseColor", T.Color3f, Gf.Vec3f(*look.linear))
        else:
            self._texture(mat, shader, look)
        self.attr(shader, "inputs:roughness", T.Float, look.roughness)
        self.attr(shader, "inputs:metallic", T.Float, look.metallic)
        self.attr(shader, "inputs:opacity", T.Float, look.opacity)
        Sdf.AttributeSpec(shader, "outputs:surface", T.Token)
        self.connect(mat, "outputs:surface", T.Token, shader.path.AppendProperty("outputs:surface"))

    def _texture(self, mat: Sdf.PrimSpec, shader: Sdf.PrimSpec, look: Material) -> None:
        reader = self.prim(mat, "ST", "Shader")
        self.attr(reader, "info:id", T.Token, "UsdPrimvarReader_float2", uniform=True)
        self.attr(reader, "inputs:varname", T.String, "st")
        Sdf.AttributeSpec(reader, "outputs:result", T.Float2)
        scale = self.prim(mat, "Tiling", "Shader")
        self.attr(scale, "info:id", T.Token, "UsdTransform2d", uniform=True)
        self.connect(scale, "inputs:in", T.Float2, reader.path.AppendProperty("outputs:result"))
        self.attr(scale, "inputs:scale", T.Float2, Gf.Vec2f(1 / look.texture_size[0], 1 / look.texture_size[1]))
        Sdf.AttributeSpec(scale, "outputs:result", T.Float2)
        tex = self.prim(mat, "Texture", "Shader")
        self.attr(tex, "info:id", T.Token, "UsdUVTexture", uniform=True)
        assert look.texture is not None
        where = os.path.relpath(look.texture, self.layer_dir) if self.layer_dir else str(look.texture)
        self.attr(tex, "inputs:file", T.Asset, Sdf.AssetPath(where.replace(os.sep, "/")))
        self.attr(tex, "inputs:sourceColorSpace", T.Token, "sRGB")
        self.attr(tex, "inputs:wrapS", T.Token, "repeat")
        self.attr(tex, "inputs:wrapT", T.Token, "repeat")
        self.connect(tex, "inputs:st", T.Float2, scale.path.AppendProperty("outputs:result"))
        Sdf.AttributeSpec(tex, "outputs:rgb", T.Float3)
        self.connect(shader, "inputs:diffuseColor", T.Color3f, tex.path.AppendProperty("outputs:rgb"))
