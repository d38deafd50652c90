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

With tile layers, each ``Tile_<i>_<j>`` lives in its own layer ``<stem>_tiles/Tile_<i>_<j>.<digest>.usdc`` (a
sublayer of the root, with the prototypes first used in that tile; the digest of its bytes names it so a run never
overwrites a tile the current root lists, :mod:`citygen.usd.publish`), written as soon as the tile is complete, so
memory stays bounded by one tile. Authoring goes through
the Sdf API in change blocks, which is what keeps a 100k-building city writable.
"""
from __future__ import annotations

import os
import re
import shutil
import tempfile
import time
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
from citygen.usd.normals import face_normals
from citygen.usd.publish import publish_tile, remove_stale_temporaries, remove_unlisted_tiles, temp_prefix
from citygen.usd.uv import planar_st

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


def tile_name(tile: tuple[int, int]) -> str:
    """The prim (and layer file) name of a tile: ``Tile_<i>_<j>``, ``m`` for a minus sign."""
    return f"Tile_{tile[0]}_{tile[1]}".replace("-", "m")


class _Author:
    """Thin Sdf authoring helpers on one layer. Meshes get indexed face normals (``primvars:normals``, uniform,
    :mod:`citygen.usd.normals`); ``uvs``: also ``primvars:st`` (:mod:`citygen.usd.uv`)."""

    def __init__(self, layer: Sdf.Layer, uvs: bool = False) -> None:
        self.layer = layer
        self.uvs = uvs
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
             label: str | None, normals: tuple[np.ndarray, np.ndarray] | None = None) -> Sdf.PrimSpec | None:
        """A Mesh prim (none for an empty mesh); ``normals``: its :func:`face_normals` when already computed in a
        batch with other meshes."""
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
        values, index = normals or face_normals([mesh])[0]
        spec = Sdf.AttributeSpec(prim, "primvars:normals", T.Normal3fArray, Sdf.VariabilityVarying)
        spec.default = Vt.Vec3fArray.FromNumpy(values)
        spec.SetInfo("interpolation", "uniform")
        self.attr(prim, "primvars:normals:indices", T.IntArray, Vt.IntArray.FromNumpy(index))
        if self.uvs:
            st = Sdf.AttributeSpec(prim, "primvars:st", T.TexCoord2fArray, Sdf.VariabilityVarying)
            st.default = Vt.Vec2fArray.FromNumpy(planar_st(pts, mesh.counts, mesh.indices))
            st.SetInfo("interpolation", "faceVarying")
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


class StageWriter:
    """Streams buildings into a stage: :meth:`add` them in tile order, then :meth:`close` writes the files.

    With ``tile_layers`` every tile is its own layer (``<stem>_tiles/Tile_i_j.<digest><suffix>``) holding its buildings and
    the ``/Prototypes`` first used there; it is exported and dropped from memory as soon as the next tile starts,
    so memory stays bounded by one tile whatever the city's size. The root layer holds ``/World`` and its materials
    and lists the tile layers as sublayers: internal references and material bindings compose as in one file (the
    tile layers are a streaming device, not independently loadable assets). Without it everything goes into the
    root layer. Nothing at ``path`` changes until :meth:`close` succeeds. With ``uvs`` every mesh gets
    face-varying ``primvars:st`` in metres (:mod:`citygen.usd.uv`; about doubles the file); with ``lod`` every
    building a ``lod`` variant set (``full``: facades and elements; ``mass``: plain walls).
    """

    def __init__(self, path: str | Path, *, up_axis: str = "Z", layer_data: Mapping[str, Any] | None = None,
                 tile_layers: bool = False, uvs: bool = False, lod: bool = False) -> None:
        self.path = Path(path)
        suffix = self.path.suffix.lower()
        if suffix not in SUFFIXES:
            raise ExportError(f"unsupported stage extension {self.path.suffix!r}", where=str(self.path),
                              hint=f"use one of {', '.join(SUFFIXES)}")
        self.up_axis = up_axis
        self.tile_suffix = ".usdc" if suffix == ".usdz" else suffix
        self.tiles_dir = self.path.with_name(f"{self.path.stem}_tiles") if tile_layers else None
        self.staging: Path | None = None
        self.started = time.time()  # (tiles older than this that the new root does not list are removed)
        remove_stale_temporaries(self.path.parent)
        self.layer = Sdf.Layer.CreateAnonymous(".usda")
        self.author = _Author(self.layer, uvs)
        self.lod = lod
        self.counts = {"buildings": 0, "meshes": 0, "instances": 0, "polygons": 0}
        self.materials: dict[str, Sdf.Path] = {}
        self.material_names: set[str] = set()
        self.prototypes: dict[ProtoKey | ModuleKey, Sdf.Path] = {}
        self.sublayers: list[str] = []
        self.tile: tuple[tuple[int, int], Sdf.Layer | None, Sdf.PrimSpec] | None = None
        self.seen_tiles: set[tuple[int, int]] = set()
        with Sdf.ChangeBlock():
            self.layer.defaultPrim = "World"
            self.layer.pseudoRoot.SetInfo("metersPerUnit", 1.0)
            self.layer.pseudoRoot.SetInfo("upAxis", up_axis)
            self.layer.customLayerData = {"citygen": _dictionary(layer_data or {})}
            self.world = self.author.prim(self.layer, "World", "Xform")
            self.world.SetInfo("kind", "assembly")
            if up_axis == "Y":
                self.author.attr(self.world, "xformOp:rotateX", T.Float, -90.0)
                self.author.attr(self.world, "xformOpOrder", T.TokenArray, Vt.TokenArray(["xformOp:rotateX"]),
                                 uniform=True)
            self.looks = self.author.prim(self.world, "Looks", "Scope")
        self.protos_root: Sdf.PrimSpec | None = None

    def __enter__(self) -> StageWriter:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        """On an error, remove the staged tile layers (the files at ``path`` were never touched)."""
        if exc_type is not None and self.staging is not None:
            shutil.rmtree(self.staging, ignore_errors=True)

    def material(self, name: str) -> Sdf.Path:
        if name not in self.materials:
            with Sdf.ChangeBlock():
                self.materials[name] = self.author.material(self.looks, prim_name(name, self.material_names))
        return self.materials[name]

    def ground(self, x0: float, y0: float, x1: float, y1: float, z: float) -> None:
        """``/World/Ground``: one flat quad (material and semantic label ``ground``) under the city at height ``z``."""
        quad = MeshData(np.array([[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]], dtype=np.float32),
                        np.array([4], dtype=np.int32), np.arange(4, dtype=np.int32))
        with Sdf.ChangeBlock():
            self.author.mesh(self.world, "Ground", quad, self.material("ground"), "ground")
        self.counts["meshes"] += 1
        self.counts["polygons"] += 1

    def prototype(self, key: ProtoKey | ModuleKey, modules: Mapping[ModuleKey, ModuleProto]) -> Sdf.Path:
        """The ``/Prototypes`` prim of an element kind or module, authored on first use."""
        if key in self.prototypes:
            return self.prototypes[key]
        author = self.author
        if self.protos_root is None:
            layer = self.layer if self.tile is None or self.tile[1] is None else self.tile[1]
            self.protos_root = author.prim(layer, "Prototypes", "", Sdf.SpecifierClass)
        proto = author.prim(self.protos_root, Tf.MakeValidIdentifier(key.name), "Xform")
        author.api(proto, "SemanticsLabelsAPI:class")
        author.attr(proto, "semantics:labels:class", T.TokenArray, Vt.TokenArray([key.label]), uniform=True)
        if isinstance(key, ModuleKey):
            module = modules[key]
            names: set[str] = set()
            for ((label, mat), mesh), normals in zip(module.meshes.items(), face_normals(module.meshes.values())):
                author.mesh(proto, prim_name(f"{label}_{mat}", names), mesh, self.material(mat), label, normals)
            if len(module.elements.proto_indices):
                _instancer(author, proto, module.elements, lambda k: self.prototype(k, modules))
        else:
            parts = [(part, MeshData.from_quads(part.quads)) for part in build_prototype(key) if len(part.quads)]
            for (part, mesh), normals in zip(parts, face_normals([mesh for _, mesh in parts])):
                author.mesh(proto, part.name, mesh, self.material(part.material), None, normals)
        self.prototypes[key] = proto.path
        return proto.path

    def add(self, record: BuildingRecord) -> None:
        """Author one building; records must come grouped by tile (a tile cannot be reopened)."""
        with Sdf.ChangeBlock():
            _write_building(self.author, self._tile_prim(record.tile), record, self.material, self.prototype,
                            self.counts, self.lod)

    def _tile_prim(self, tile: tuple[int, int]) -> Sdf.PrimSpec:
        if self.tile is not None and self.tile[0] == tile:
            return self.tile[2]
        if tile in self.seen_tiles:
            raise ExportError(f"tile {tile} was already written", where=str(self.path),
                              hint="add buildings sorted by tile")
        self._flush_tile()
        self.seen_tiles.add(tile)
        name = tile_name(tile)
        if self.tiles_dir is None:
            layer, parent = None, self.world
        else:
            layer = Sdf.Layer.CreateAnonymous(self.tile_suffix)
            layer.pseudoRoot.SetInfo("metersPerUnit", 1.0)
            layer.pseudoRoot.SetInfo("upAxis", self.up_axis)
            parent = Sdf.PrimSpec(layer, "World", Sdf.SpecifierOver)
        prim = self.author.prim(parent, name, "Xform")
        prim.SetInfo("kind", "group")
        self.tile = (tile, layer, prim)
        return prim

    def _flush_tile(self) -> None:
        """Export the open tile layer into the staging folder and let it go."""
        if self.tile is None or self.tile[1] is None:
            return
        name = self.tile[2].name + self.tile_suffix
        _export(self.tile[1], self.staging_folder() / name)
        self.sublayers.append(name)
        self.tile, self.protos_root = None, None

    def staging_folder(self) -> Path:
        """The hidden folder beside ``path`` that tile layers are written to until :meth:`close` publishes them
        (named by :func:`~citygen.usd.publish.temp_prefix`, so a later run removes it if this one is killed)."""
        if self.tiles_dir is None:
            raise ExportError("this stage has no tile layers", where=str(self.path), hint="pass tile_layers=True")
        if self.staging is None:
            try:
                self.tiles_dir.parent.mkdir(parents=True, exist_ok=True)
                self.staging = Path(tempfile.mkdtemp(prefix=temp_prefix(self.tiles_dir.name),
                                                     dir=self.tiles_dir.parent))
                os.chmod(self.staging, 0o777 & ~_umask())  # (shared with dask workers)
            except OSError as exc:
                raise ExportError(f"cannot write the tile layers: {exc.strerror or exc}", where=str(self.tiles_dir),
                                  hint="check free disk space and permissions") from None
        return self.staging

    def add_tile_layer(self, name: str, stats: StageStats, prototypes: Iterable[ProtoKey | ModuleKey]) -> None:
        """List a tile layer that another process wrote into :meth:`staging_folder` as file ``name`` (a complete
        stage of its own, see :mod:`citygen.distributed`); tiles come in tile order, like :meth:`add`."""
        self._flush_tile()
        if not (self.staging_folder() / name).is_file():
            raise ExportError(f"tile layer {name} is missing from the staging folder", where=str(self.staging),
                              hint="the output folder must be shared with every worker, at the same path")
        self.sublayers.append(name)
        self.author.prims += stats.prims
        for key in ("buildings", "meshes", "instances", "polygons"):
            self.counts[key] += getattr(stats, key)
        for key in prototypes:
            self.prototypes.setdefault(key, Sdf.Path("/Prototypes").AppendChild(Tf.MakeValidIdentifier(key.name)))

    def close(self) -> StageStats:
        """Write the last tile, publish the tiles under their content names, switch the root to them (one
        rename), then remove the tiles no root lists any more (:mod:`citygen.usd.publish`); return the figures."""
        self._flush_tile()
        names: list[str] = []
        if self.tiles_dir is not None:
            names = self._publish_tiles()
            self.layer.subLayerPaths = [f"{self.tiles_dir.name}/{name}" for name in names]
        size = _finish(self.layer, self.path)
        if self.tiles_dir is not None:
            if self.path.suffix.lower() == ".usdz":  # the package holds the tile layers
                shutil.rmtree(self.tiles_dir)
            else:
                size += sum((self.tiles_dir / name).stat().st_size for name in names)
                remove_unlisted_tiles(self.tiles_dir, names, self.started)
        return StageStats(path=self.path, buildings=self.counts["buildings"], prims=self.author.prims,
                          meshes=self.counts["meshes"], instances=self.counts["instances"],
                          prototypes=len(self.prototypes), polygons=self.counts["polygons"], bytes=size)

    def _publish_tiles(self) -> list[str]:
        """Move the staged tiles into the tile folder under their content names (none the current root lists is
        touched); return those names, in tile order."""
        assert self.tiles_dir is not None
        try:
            self.tiles_dir.mkdir(parents=True, exist_ok=True)
            names = [publish_tile(self.staging / name, self.tiles_dir) for name in self.sublayers]
        except OSError as exc:
            raise ExportError(f"cannot publish the tile layers: {exc.strerror or exc}", where=str(self.tiles_dir),
                              hint="check free disk space and permissions") from None
        if self.staging is not None:
            shutil.rmtree(self.staging, ignore_errors=True)
            self.staging = None
        return names


def write_stage(path: str | Path, buildings: Iterable[BuildingRecord], *, up_axis: str = "Z",
                layer_data: Mapping[str, Any] | None = None, tile_layers: bool = False) -> StageStats:
    """Author the city (records sorted by tile) and write it to ``path``; see :class:`StageWriter`."""
    with StageWriter(path, up_axis=up_axis, layer_data=layer_data, tile_layers=tile_layers) as writer:
        for record in buildings:
            writer.add(record)
        return writer.close()


def _write_building(author: _Author, parent: Sdf.PrimSpec, record: BuildingRecord, material, prototype,
                    counts: dict[str, int], lod: bool = False) -> None:
    """One building prim; with ``lod`` its facades and elements are the ``full`` variant of a ``lod`` variant set
    whose ``mass`` variant is the plain walls (the roof is shared by both)."""
    geo = record.geometry
    prim = author.prim(parent, record.name, "Xform")
    prim.SetInfo("kind", "component")
    for key, value in sorted(record.attributes.items()):
        vtype, v = _value(value)
        author.attr(prim, f"citygen:{key}", vtype, v)
    body = prim
    walls = geo.walls if lod else None
    batch = [*geo.meshes.values(), *([geo.roof] if geo.roof is not None else []), *([walls] if walls is not None else [])]
    normals = face_normals(batch)  # one batch per building, in this order
    if lod:
        lods = Sdf.VariantSetSpec(prim, "lod")
        body, mass = Sdf.VariantSpec(lods, "full").primSpec, Sdf.VariantSpec(lods, "mass").primSpec
        prim.variantSetNameList.prependedItems.append("lod")
        prim.variantSelections["lod"] = "full"
        wall = next((mat for label, mat in geo.meshes if label == "wall"), "concrete")
        if walls is not None and author.mesh(mass, "Walls", walls, material(wall), "wall", normals[-1]) is not None:
            counts["meshes"] += 1
            counts["polygons"] += len(walls.counts)
    if geo.meshes:
        facade = author.prim(body, "Facade", "Scope")
        names: set[str] = set()
        for ((label, mat), mesh), mesh_normals in zip(geo.meshes.items(), normals):
            counts["meshes"] += author.mesh(facade, prim_name(f"{label}_{mat}", names), mesh, material(mat),
                                            label, mesh_normals) is not None
            counts["polygons"] += len(mesh.counts)
    if geo.roof is not None:
        author.mesh(prim, "Roof", geo.roof, material(geo.roof_material), "roof", normals[len(geo.meshes)])
        counts["meshes"] += 1
        counts["polygons"] += len(geo.roof.counts)
    inst = geo.instances
    if len(inst.proto_indices):
        _instancer(author, body, inst, lambda key: prototype(key, geo.modules))
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
        targets.append(ref.path.StripAllVariantSelections())  # (inside a lod variant: a composed path)
    author.rel(pi, "prototypes", targets)
    author.attr(pi, "protoIndices", T.IntArray, Vt.IntArray.FromNumpy(inst.proto_indices.astype(np.int32)))
    author.attr(pi, "positions", T.Point3fArray, Vt.Vec3fArray.FromNumpy(inst.positions.astype(np.float32)))
    author.attr(pi, "orientations", T.QuathArray, Vt.QuathArray.FromNumpy(inst.orientations.astype(np.float16)))
    author.attr(pi, "scales", T.Float3Array, Vt.Vec3fArray.FromNumpy(inst.scales.astype(np.float32)))


def _finish(layer: Sdf.Layer, path: Path) -> int:
    """Export ``layer`` to ``path`` through a temporary file in the same folder; return the file size. On any
    failure (an :class:`ExportError`) the file at ``path`` is unchanged and the temporary one removed."""
    suffix = path.suffix.lower()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp_name = tempfile.mkstemp(prefix=temp_prefix(path.stem), suffix=suffix, dir=path.parent)
    except OSError as exc:
        raise ExportError(f"cannot write the stage: {exc.strerror or exc}", where=str(path),
                          hint="check free disk space and permissions") from None
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
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; a stage is an ordinary file
        os.replace(tmp, path)
    except OSError as exc:
        raise ExportError(f"cannot write the stage: {exc.strerror or exc}", where=str(path),
                          hint="check free disk space and permissions") from None
    except ExportError as exc:  # named by the stage's path, not the temporary file's
        raise ExportError(exc.message, where=str(path), hint=exc.hint) from None
    finally:
        tmp.unlink(missing_ok=True)
    return path.stat().st_size


def _umask() -> int:
    umask = os.umask(0)
    os.umask(umask)
    return umask


def _export(layer: Sdf.Layer, target: Path) -> None:
    """``layer.Export`` whose failures (False, a ``Tf.ErrorException`` such as a full disk, an OSError) are one
    :class:`ExportError` naming the file and USD's first reason."""
    try:
        if layer.Export(str(target)):
            return
        reason = ""
    except Tf.ErrorException as exc:
        reason = _usd_reason(exc)
    except OSError as exc:
        reason = exc.strerror or str(exc)
    raise ExportError(f"USD export failed{': ' + reason if reason else ''}", where=str(target),
                      hint="check free disk space and permissions")


def _usd_reason(exc: Tf.ErrorException) -> str:
    """The commentary of the first error inside a ``Tf.ErrorException`` (its text lists every error, with C++
    function names and source lines)."""
    text = "\n".join(str(a) for a in exc.args) or str(exc)
    match = re.search(r" : '([^\n]*)'", text)
    return match[1] if match else text.strip().splitlines()[0] if text.strip() else ""


def open_stage(path: str | Path) -> Usd.Stage:
    stage = Usd.Stage.Open(str(path))
    if stage is None:
        raise ExportError("cannot open stage", where=str(path))
    return stage
