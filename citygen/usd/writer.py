"""Write a city as one USD stage (``.usda``, ``.usdc`` or ``.usdz`` by extension), atomically.

Layout of the stage::

    /World                      Xform, kind=assembly (defaultPrim; rotated for upAxis Y), extentsHint
      Looks/ground, Ground      the ground quad (``[output] ground``)
      Tile_<i>_<j>              Xform, kind=group, extentsHint (with tile layers: a payload of the tile's layer)
        <building>              Xform, kind=component, translated to its pivot (footprint centroid, ground),
                                assetInfo, extentsHint, custom citygen:* attributes, primvars:citygen:variation
          Looks                 references its look set /Looks/<materials>: bindings resolve inside the building
          Roof                  Mesh
          variant set LOD       LOD0: Facade/<label>_<mat> meshes and Elements (PointInstancer, with extent)
                                LOD1: Walls (the mass)       -- or Render/Proxy scopes with lod = "purpose"
    /Materials                  class: UsdPreviewSurface definitions (linear colours from sRGB, once)
    /Looks                      class: a look set per combination of materials, its Materials referencing /Materials
    /Prototypes                 class: one prototype per element kind / module (meshes only: the building places a
                                module's elements, citygen.geometry.lift), each with its own Looks

A building is an asset: everything it binds and instances is under it or reached through internal references
(with tile layers, its elements through references into the element library beside its tile), so a reference to it
from another stage brings its looks and prototypes along.

With tile layers, each tile is a stage of its own (``<stem>_tiles/Tile_<i>_<j>.<digest>.usdc``: ``/World`` with the
tile, ``/Materials`` and the module ``/Prototypes`` it uses; its instances of elements reference the city's element
library ``<stem>_tiles/elements.usdc`` directly, :mod:`citygen.usd.library`), written as soon as the tile is complete
(memory stays bounded by one tile) and payloaded by the root's tile prim, so ``Usd.Stage.Open(root,
Usd.Stage.LoadNone)`` opens the city with its bounds only. The dask executor writes its tiles with the same code, so
every tile layer opens alone. The digest of its bytes names a tile so a run never overwrites a tile the current root
payloads (:mod:`citygen.usd.publish`).
"""
from __future__ import annotations

import functools
import hashlib
import os
import shutil
import tempfile
import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from pxr import Gf, Sdf, Tf, Usd, Vt

from citygen.errors import ExportError
from citygen.gcpause import cyclic_gc_paused
from citygen.geometry.building import BuildingGeometry, Instances, MeshData, ModuleProto
from citygen.geometry.lift import lift_module_elements
from citygen.geometry.modules import ModuleKey
from citygen.geometry.prototypes import ProtoKey
from citygen.temporaries import current_umask, remove_stale_temporaries, temp_prefix
from citygen.usd.author import Author, MeshArrays, T, bound_value, tokens
from citygen.usd.bounds import instances_bounds, points_bound, union
from citygen.usd.definitions import (
    PROTOTYPES,
    Definitions,
    Prototype,
    elements,
    meshes_bound,
    prepare_arrays,
    prepare_elements,
)
from citygen.usd.distinct import DistinctCount
from citygen.usd.element_bounds import element_bound
from citygen.usd.library import library_name, publish_library, settle_library, write_library
from citygen.usd.materials import Material
from citygen.usd.names import SUFFIXES, prim_name, tile_name
from citygen.usd.normals import face_normals
from citygen.usd.publish import PACKED_MTIME, publish_tile, remove_unlisted_tiles, write_layer

LOD_SET, LOD_FULL, LOD_MASS = "LOD", "LOD0", "LOD1"


@dataclass(frozen=True)
class BuildingRecord:
    """A building ready for the stage: its prim name, tile, geometry (city coordinates), ``citygen:`` attributes
    and pivot (the ground centroid of its footprint, where its transform puts its local origin)."""

    name: str
    tile: tuple[int, int]
    geometry: BuildingGeometry
    attributes: Mapping[str, Any]
    pivot: tuple[float, float, float] = (0.0, 0.0, 0.0)


#: Errors of the machine, not of a building: writing a layer that meets one stops with it (a full disk, no memory);
#: any other error writing a building is that building's (:meth:`StageWriter.add`, :func:`citygen.tiles.build_tile`).
ENVIRONMENT = (OSError, MemoryError, ExportError)


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
    extent: tuple[float, ...] | None = field(default=None)  # the world bound: min x, y, z, max x, y, z


@functools.lru_cache(maxsize=4096)  # (every building has the same dozen keys)
def attribute_name(key: str) -> str:
    """``citygen:<key>``, each ``:``-separated part of ``key`` a valid identifier (a kept tag ``ref:bag-id``
    becomes ``citygen:tag:ref:bag_id``)."""
    return ":".join(["citygen", *(Tf.MakeValidIdentifier(part) for part in key.split(":"))])


def variation(name: str) -> float:
    """A building's stable value in [0, 1) for shader variation (``primvars:citygen:variation``)."""
    return int.from_bytes(hashlib.blake2b(name.encode("utf-8"), digest_size=4).digest(), "big") / 2 ** 32


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


def _model_bound(prim: Sdf.PrimSpec, bound: np.ndarray | None) -> None:
    """``extentsHint`` (GeomModelAPI) of a model prim: its bound for the default purpose."""
    if bound is not None:
        Author.attr(prim, "extentsHint", T.Float3Array, bound_value(bound))


class StageWriter:
    """Streams buildings into a stage: :meth:`add` them in tile order, then :meth:`close` writes the files.

    With ``tile_layers`` every tile is written by a :class:`StageWriter` of its own into a staging folder (a
    complete stage, the same a dask worker writes), published into ``<stem>_tiles/`` under its content name and
    payloaded from the root; without, everything goes into the root layer. Nothing at ``path`` changes until
    :meth:`close` succeeds, and an old root keeps its tiles until the new root replaces it. ``uvs``: every mesh gets
    ``primvars:st`` (meshes of textured materials always do); ``lod``: ``variants`` (set ``LOD``), ``purpose``
    (render/proxy scopes) or ``none``; ``materials``: the scene's and rulesets' material library.
    """

    def __init__(self, path: str | Path, *, up_axis: str = "Z", layer_data: Mapping[str, Any] | None = None,
                 tile_layers: bool = False, uvs: bool = False, lod: str = "variants",
                 materials: Mapping[str, Material] | None = None, element_library: str | None = None) -> None:
        self.path = Path(path)
        suffix = self.path.suffix.lower()
        if suffix not in SUFFIXES:
            raise ExportError(f"unsupported stage extension {self.path.suffix!r}", where=str(self.path),
                              hint=f"use one of {', '.join(SUFFIXES)}")
        self.up_axis = up_axis
        self.uvs, self.lod, self.library = uvs, lod, dict(materials or {})
        self.layer_data = dict(layer_data or {})
        self.tile_suffix = ".usdc" if suffix == ".usdz" else suffix
        self.tiles_dir = self.path.with_name(f"{self.path.stem}_tiles") if tile_layers else None
        self.staging: Path | None = None
        self.started = time.time()  # (tiles older than this that the new root does not list are removed)
        remove_stale_temporaries(self.path.parent)
        # (in the data of the format written: Export copies a layer into crate data first, ~2x cheaper from crate data)
        self.layer = Sdf.Layer.CreateAnonymous(self.tile_suffix)
        self.author = Author(self.layer, uvs, self.library, self.path.parent)
        self.counts = {"buildings": 0, "meshes": 0, "instances": 0, "polygons": 0}
        self.definitions = Definitions(self.author)
        self.element_library = f"./{element_library}" if element_library else ""
        self.prototypes: dict[ProtoKey | ModuleKey, tuple[str, Sdf.Path]] = {}  # the layer and path instances reference
        self.bounds: dict[ProtoKey | ModuleKey, np.ndarray | None] = {}
        self.queued: list[BuildingRecord] = []  # the open tile's buildings, authored when it is finished
        self.tile: tuple[tuple[int, int], Sdf.PrimSpec | StageWriter] | None = None
        self.tile_bound: np.ndarray | None = None
        self.world_bounds: list[np.ndarray | None] = []
        self.seen_tiles: set[tuple[int, int]] = set()
        self.sublayers: list[tuple[Sdf.PrimSpec, str]] = []  # tile prims and their staged layers' names
        self.failed: list[tuple[BuildingRecord, Exception]] = []  # (buildings left out: see _write_queued)
        self.tile_prototypes: set[ProtoKey] = set()  # (the tile layers' element kinds: the element library's)
        self.tile_modules = DistinctCount()  # (the tile layers' module prototypes, counted only)
        self.elements = elements(self.library, uvs)
        with Sdf.ChangeBlock():
            self.layer.customLayerData = {"citygen": _dictionary(self.layer_data)}
            self.world = _world(self.author, self.layer, up_axis)

    def __enter__(self) -> StageWriter:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        """On an error, remove the staged tile layers (the files at ``path`` were never touched)."""
        if exc_type is not None and self.staging is not None:
            shutil.rmtree(self.staging, ignore_errors=True)

    def define(self, names: Iterable[str]) -> None:
        """``/Materials/<name>`` of each name not yet defined in this layer."""
        self.definitions.define(names)

    def ground(self, mesh: MeshData) -> None:
        """``/World/Ground``: the ground under the city (:func:`citygen.ground.ground_mesh`; material and semantic
        label ``ground``)."""
        with Sdf.ChangeBlock():
            self.define(["ground"])
            looks = self.author.looks(self.world, ["ground"])
            self.author.mesh(self.world, "Ground", mesh, looks, "ground", "ground")
        self.world_bounds.append(points_bound(mesh.points))
        self.counts["meshes"] += 1
        self.counts["polygons"] += len(mesh.counts)

    def prototypes_of(self, keys: Iterable[ProtoKey | ModuleKey], modules: Mapping[ModuleKey, ModuleProto]) -> None:
        """Give each of ``keys`` its ``/Prototypes`` path (:attr:`prototypes`: in this layer, or for an element kind of
        a layer with an element library, in the library) and its bound; the geometry of element prototypes new to
        the process is prepared in one batch (a layer with an element library takes only their bounds, from their
        keys: :func:`~citygen.usd.element_bounds.element_bound`), the prims this layer holds authored with its other
        new prototypes when the tile is finished (:class:`~citygen.usd.definitions.Definitions`).

        Instances reference a library's element directly, not through a prim of this layer: the instances of an
        element in every tile then share one USD prototype, and Blender's importer makes one material per material
        of each prototype it imports (with its default ``MAKE_UNIQUE``: 9,648 materials and 2.35 GB for the
        demo's tiles through per-tile prims, 6,119 and 1.82 GB so; docs/performance.md)."""
        fresh = [k for k in keys if k not in self.prototypes]
        if not fresh:
            return
        if not self.element_library:  # (a tile layer needs only the bounds of its library's elements)
            prepare_elements([k for k in fresh if not isinstance(k, ModuleKey)], self.elements, self.library)
        for key in fresh:
            path = PROTOTYPES.AppendChild(Tf.MakeValidIdentifier(key.name))
            if isinstance(key, ModuleKey):  # its meshes; the building places its elements (citygen.geometry.lift)
                # (a module's key leaves sub-millimetre details open: a layer takes its first building's module, so
                # a tile's bytes never depend on the tiles its process wrote before)
                names: set[str] = set()
                meshes = [(prim_name(f"{label}_{mat}", names), mat, label, mesh)
                          for (label, mat), mesh in modules[key].meshes.items() if len(mesh.counts)]
                proto = Prototype(key.label, meshes, meshes_bound([m for *_, m in meshes]))
            elif self.element_library:
                self.prototypes[key], self.bounds[key] = (self.element_library, path), element_bound(key)
                continue
            else:
                proto = self.elements[key]
            self.definitions.pending.append((path, proto))
            self.prototypes[key], self.bounds[key] = ("", path), proto.bound

    def add(self, record: BuildingRecord) -> None:
        """Add one building (authored with the rest of its tile when the tile is finished, :meth:`_write_queued`);
        records must come grouped by tile (a tile cannot be reopened). A building whose writing raises is left out
        and listed in :attr:`failed` with the error, once its tile is finished (by a later ``add`` or
        :meth:`close`)."""
        target = self._tile(record.tile)
        if isinstance(target, StageWriter):
            target.add(record)
            return
        self.queued.append(record)

    # (many short-lived spec handles, freed by reference counting: the cyclic collections they set off cost each
    # demo tile worker ~0.01-0.08 s of its ~3 s of writing)
    @cyclic_gc_paused()
    def _write_queued(self, target: Sdf.PrimSpec) -> None:
        """Author the open tile's buildings, in the order added: their face normals and their instancers' bounds
        each in one batch. When that raises (not :data:`ENVIRONMENT`), what it authored of them is taken back and
        each is authored alone; one that raises alone is taken back and listed in :attr:`failed` (the materials and
        prototypes it defined stay, unused)."""
        queued, self.queued = self.queued, []
        mark = self._mark()
        try:
            self._author(target, queued)
        except ENVIRONMENT:
            raise
        except Exception:
            self._take_back(target, queued, mark)
            for record in queued:
                mark = self._mark()
                try:
                    self._author(target, [record])
                except ENVIRONMENT:
                    raise
                except Exception as exc:
                    self._take_back(target, [record], mark)
                    self.failed.append((record, exc))

    def _author(self, target: Sdf.PrimSpec, records: list[BuildingRecord]) -> None:
        batches = [_mesh_batch(record.geometry, self.lod) for record in records]
        normals = iter(face_normals([mesh for batch in batches for mesh in batch]))
        placed = self._placed(records)
        with Sdf.ChangeBlock():
            for record, batch, (inst, inst_bound) in zip(records, batches, placed):
                bound = _write_building(self, target, record, batch, [next(normals) for _ in batch], inst, inst_bound)
                if bound is not None:
                    self.tile_bound = union([self.tile_bound, bound + np.asarray(record.pivot)])

    def _mark(self) -> tuple[dict[str, int], int, np.ndarray | None]:
        """What :meth:`_take_back` restores: the counts, the prims authored, the open tile's bound."""
        return dict(self.counts), self.author.prims, self.tile_bound

    def _take_back(self, target: Sdf.PrimSpec, records: list[BuildingRecord],
                   mark: tuple[dict[str, int], int, np.ndarray | None]) -> None:
        """Remove the prims of ``records`` under ``target`` and restore the figures of ``mark``."""
        for record in records:
            child = target.nameChildren.get(record.name)
            if child is not None:
                target.RemoveNameChild(child)
        self.counts, self.author.prims, self.tile_bound = dict(mark[0]), mark[1], mark[2]

    def _placed(self, records: list[BuildingRecord]) -> list[tuple[Instances, np.ndarray | None]]:
        """Each building's instances with its modules' elements lifted (:func:`lift_module_elements`), placed from
        its pivot, and their bound; their prototypes get their paths in this layer in order of first use
        (:meth:`prototypes_of`). The bounds of all the buildings come from one numpy pass."""
        placed = []
        for record in records:
            geo = record.geometry
            inst = lift_module_elements(geo.instances, geo.modules)
            if len(inst.proto_indices):
                self.prototypes_of(inst.protos, geo.modules)
            placed.append(Instances(inst.protos, inst.proto_indices,
                                    np.asarray(inst.positions, dtype=float) - np.asarray(record.pivot, dtype=float),
                                    inst.orientations, inst.scales))
        keys = list(dict.fromkeys(k for inst in placed for k in inst.protos))
        number = {k: n for n, k in enumerate(keys)}
        rows = [np.array([number[k] for k in inst.protos], dtype=np.int64)[inst.proto_indices] if len(inst.protos)
                else np.zeros(0, np.int64) for inst in placed]
        bounds = instances_bounds([self.bounds[k] for k in keys], np.concatenate([np.zeros(0, np.int64), *rows]),
                                  _rows([inst.positions for inst in placed], 3),
                                  _rows([inst.orientations for inst in placed], 4),
                                  _rows([inst.scales for inst in placed], 3), [len(r) for r in rows])
        return list(zip(placed, bounds))

    def _tile(self, tile: tuple[int, int]) -> Sdf.PrimSpec | StageWriter:
        """The open tile's prim (or, with tile layers, its writer), opening ``tile`` after closing the last."""
        if self.tile is not None and self.tile[0] == tile:
            return self.tile[1]
        if tile in self.seen_tiles:
            raise ExportError(f"tile {tile} was already written", where=str(self.path),
                              hint="add buildings sorted by tile")
        self._flush_tile()
        self.seen_tiles.add(tile)
        name = tile_name(tile)
        if self.tiles_dir is not None:
            sub = type(self)(self.staging_folder() / f"{name}{self.tile_suffix}", up_axis=self.up_axis,
                              layer_data={**self.layer_data, "tile": name}, uvs=self.uvs, lod=self.lod,
                              materials=self.library, element_library=library_name(self.tile_suffix))
            self.tile = (tile, sub)
            return sub
        prim = self.author.prim(self.world, name, "Xform")
        prim.SetInfo("kind", "group")
        self.author.api(prim, "GeomModelAPI")
        self.tile = (tile, prim)
        return prim

    def _flush_tile(self) -> None:
        """Finish the open tile: its bound, or with tile layers, write its layer and payload it."""
        if self.tile is None:
            return
        (_, target), self.tile = self.tile, None
        if isinstance(target, StageWriter):
            stats = target.close()
            self.failed += target.failed
            self.add_tile_layer(stats.path.name, stats, target.prototypes)
            return
        self._write_queued(target)
        self.definitions.author_pending()
        with Sdf.ChangeBlock():
            _model_bound(target, self.tile_bound)
        self.world_bounds.append(self.tile_bound)
        self.tile_bound = None

    def staging_folder(self) -> Path:
        """The hidden folder beside ``path`` that tile layers are written to until :meth:`close` publishes them
        (named by :func:`~citygen.temporaries.temp_prefix`, so a later run removes it if this one is killed)."""
        if self.tiles_dir is None:
            raise ExportError("this stage has no tile layers", where=str(self.path), hint="pass tile_layers=True")
        if self.staging is None:
            try:
                self.tiles_dir.parent.mkdir(parents=True, exist_ok=True)
                self.staging = Path(tempfile.mkdtemp(prefix=temp_prefix(self.tiles_dir.name),
                                                     dir=self.tiles_dir.parent))
                os.chmod(self.staging, 0o777 & ~current_umask())  # (shared with dask workers)
            except OSError as exc:
                raise ExportError(f"cannot write the tile layers: {exc.strerror or exc}", where=str(self.tiles_dir),
                                  hint="check free disk space and permissions") from None
        return self.staging

    def add_tile_layer(self, name: str, stats: StageStats, prototypes: Iterable[ProtoKey | ModuleKey]) -> None:
        """Payload a tile layer written into :meth:`staging_folder` as file ``name`` (a complete stage of its own,
        by a tile's writer here or on a dask worker, see :mod:`citygen.distributed`); tiles come in tile order."""
        if self.tile is not None and isinstance(self.tile[1], Sdf.PrimSpec):
            self._flush_tile()
        if not (self.staging_folder() / name).is_file():
            raise ExportError(f"tile layer {name} is missing from the staging folder", where=str(self.staging),
                              hint="the output folder must be shared with every worker, at the same path")
        assert self.tiles_dir is not None
        tile = Path(name).stem
        with Sdf.ChangeBlock():
            prim = self.author.prim(self.world, tile, "Xform")
            prim.SetInfo("kind", "group")
            self.author.api(prim, "GeomModelAPI")
            bound = None if stats.extent is None else np.reshape(stats.extent, (2, 3))
            _model_bound(prim, bound)
        self.world_bounds.append(bound)
        self.sublayers.append((prim, name))  # (payloaded once published under its content name, see close)
        self.author.prims += stats.prims
        for key in ("buildings", "meshes", "instances", "polygons"):
            self.counts[key] += getattr(stats, key)
        self.take_prototypes(prototypes)

    def take_prototypes(self, keys: Iterable[ProtoKey | ModuleKey]) -> None:
        """Note the prototypes a tile layer uses (:meth:`add_tile_layer`'s, or taken as its task's result comes in:
        the main process then holds no tile's keys): the element kinds, for the element library, and the module
        prototypes, only counted (a city's are ~1.8 a building). The element kinds new to the run are prepared for
        the library now (:func:`prepare_elements`, :func:`prepare_arrays`: built, welded, their normals and USD
        arrays), while the workers still build: the library's writing at the end only authors them."""
        modules, kinds = [], []
        for key in keys:
            if isinstance(key, ProtoKey):
                kinds.append(key)
            else:
                modules.append(key)
        self.tile_modules.update(modules)
        fresh = [k for k in dict.fromkeys(kinds) if k not in self.tile_prototypes]
        prepare_elements(fresh, self.elements, self.library)
        prepare_arrays([self.elements[k] for k in fresh], self.author)
        self.tile_prototypes.update(fresh)

    @cyclic_gc_paused()
    def close(self) -> StageStats:
        """Write the last tile, publish the tiles under their content names and the element library (both runs'
        elements while the old root may use it), switch the root to them (one rename), then settle the library and
        remove the tiles no root lists any more (:mod:`citygen.usd.publish`, :mod:`citygen.usd.library`); return
        the figures."""
        self._flush_tile()
        self.definitions.author_pending()
        bound = union(self.world_bounds)
        with Sdf.ChangeBlock():
            _model_bound(self.world, bound)
        packed = self.path.suffix.lower() == ".usdz"
        if self.tiles_dir is not None:
            library = self._stage_library()
            names, own = self._publish_tiles(library, packed)
            with Sdf.ChangeBlock():
                for (prim, _), name in zip(self.sublayers, names):
                    prim.payloadList.prependedItems.append(
                        Sdf.Payload(f"./{self.tiles_dir.name}/{name}", Sdf.Path("/World").AppendChild(prim.name)))
            files = [*names, *([library] if library else [])]
            if packed:
                for name in files:
                    os.utime(self.tiles_dir / name, (PACKED_MTIME, PACKED_MTIME))
        size = write_layer(self.layer, self.path)
        if self.tiles_dir is not None:
            if packed:  # the package holds the tile layers and the library
                shutil.rmtree(self.tiles_dir)
            else:
                if own is not None and library:
                    settle_library(own, self.tiles_dir / library)
                size += sum((self.tiles_dir / name).stat().st_size for name in files)
                remove_unlisted_tiles(self.tiles_dir, files, self.started)
        extent = None if bound is None else tuple(float(v) for v in bound.reshape(-1))
        return StageStats(path=self.path, buildings=self.counts["buildings"], prims=self.author.prims,
                          meshes=self.counts["meshes"], instances=self.counts["instances"],
                          prototypes=len(self.prototypes) + len(self.tile_prototypes) + len(self.tile_modules),
                          polygons=self.counts["polygons"],
                          bytes=size, extent=extent)

    def _stage_library(self) -> str | None:
        """Write the element library of the tiles' element prototypes into the staging folder; its name, or None
        when the tiles use no elements."""
        keys = list(self.tile_prototypes)
        if not keys:
            return None
        name = library_name(self.tile_suffix)
        self.author.prims += write_library(self.staging_folder() / name, keys, self.library, self.uvs, self.up_axis)
        return name

    def _publish_tiles(self, library: str | None, packed: bool) -> tuple[list[str], Path | None]:
        """Move the staged tiles into the tile folder under their content names (none the current root lists is
        touched) and the element ``library`` (:func:`~citygen.usd.library.publish_library`; a package's alone);
        return the tiles' names, in tile order, and the run's own library if it waits to be settled."""
        assert self.tiles_dir is not None
        staging, own = self.staging_folder(), None
        try:
            self.tiles_dir.mkdir(parents=True, exist_ok=True)
            names = [publish_tile(staging / name, self.tiles_dir) for _, name in self.sublayers]
            if library and packed:
                os.replace(staging / library, self.tiles_dir / library)
            elif library:
                own = publish_library(staging / library, self.tiles_dir)
        except OSError as exc:
            raise ExportError(f"cannot publish the tile layers: {exc.strerror or exc}", where=str(self.tiles_dir),
                              hint="check free disk space and permissions") from None
        shutil.rmtree(staging, ignore_errors=True)
        self.staging = None
        return names, own


def write_stage(path: str | Path, buildings: Iterable[BuildingRecord], *, up_axis: str = "Z",
                layer_data: Mapping[str, Any] | None = None, tile_layers: bool = False) -> StageStats:
    """Author the city (records sorted by tile) and write it to ``path``; see :class:`StageWriter`."""
    with StageWriter(path, up_axis=up_axis, layer_data=layer_data, tile_layers=tile_layers) as writer:
        for record in buildings:
            writer.add(record)
        return writer.close()


def _world(author: Author, layer: Sdf.Layer, up_axis: str) -> Sdf.PrimSpec:
    """Stage metadata and ``/World`` (the default prim), the same in a root and in a tile layer."""
    layer.defaultPrim = "World"
    layer.pseudoRoot.SetInfo("metersPerUnit", 1.0)
    layer.pseudoRoot.SetInfo("upAxis", up_axis)
    world = author.prim(layer, "World", "Xform")
    world.SetInfo("kind", "assembly")
    author.api(world, "GeomModelAPI")
    if up_axis == "Y":
        author.attr(world, "xformOp:rotateX", T.Float, -90.0)
        author.attr(world, "xformOpOrder", T.TokenArray, Vt.TokenArray(["xformOp:rotateX"]), uniform=True)
    return world


def _mesh_batch(geo: BuildingGeometry, lod: str) -> list[MeshData]:
    """A building's meshes in the order :func:`_write_building` takes their normals: facades, roof, walls."""
    walls = geo.walls if lod != "none" else None
    return [*geo.meshes.values(), *([geo.roof] if geo.roof is not None else []),
            *([walls] if walls is not None else [])]


def component(author: Author, parent: Sdf.PrimSpec, name: str, pivot: np.ndarray,
              attributes: Mapping[str, Any]) -> Sdf.PrimSpec:
    """A building's prim ``name``: a component (``assetInfo``, GeomModelAPI) translated to ``pivot``, with its
    custom ``citygen:*`` ``attributes`` and ``primvars:citygen:variation``; its geometry goes under it."""
    prim = author.prim(parent, name, "Xform")
    prim.SetInfo("kind", "component")
    prim.SetInfo("assetInfo", {"name": name})
    author.api(prim, "GeomModelAPI")
    author.attr(prim, "xformOp:translate", T.Double3, Gf.Vec3d(*map(float, pivot)))
    author.attr(prim, "xformOpOrder", T.TokenArray, tokens("xformOp:translate"), uniform=True)
    for key, value in sorted(attributes.items()):
        vtype, v = _value(value)
        author.attr(prim, attribute_name(key), vtype, v, custom=True)
    tint = author.attr(prim, "primvars:citygen:variation", T.Float, variation(name))
    tint.SetInfo("interpolation", "constant")
    return prim


def _write_building(writer: StageWriter, parent: Sdf.PrimSpec, record: BuildingRecord, batch: list[MeshData],
                    normals: list[tuple[np.ndarray, np.ndarray]], local: Instances,
                    local_bound: np.ndarray | None) -> np.ndarray | None:
    """One building prim at its pivot, its geometry in local coordinates; returns its local bound. Its level of
    detail follows ``writer.lod``: the facades and elements (``LOD0``) and the plain walls of its mass (``LOD1``)
    as variants or as a render/proxy pair; the roof is shared by both. ``batch``: its :func:`_mesh_batch`,
    ``normals`` their :func:`face_normals`; ``local``: its instances placed from its pivot, of bound ``local_bound``
    (:meth:`StageWriter._placed`)."""
    author, counts, geo = writer.author, writer.counts, record.geometry
    pivot = np.asarray(record.pivot, dtype=float)
    prim = component(author, parent, record.name, pivot, record.attributes)
    walls = geo.walls if writer.lod != "none" else None
    wall = next((mat for label, mat in geo.meshes if label == "wall"), "concrete")
    used = sorted({mat for _, mat in geo.meshes} | ({geo.roof_material} if geo.roof is not None else set())
                  | ({wall} if walls is not None else set()))
    writer.define(used)
    looks = author.looks(prim, used)
    mats = [*(mat for _, mat in geo.meshes), *([geo.roof_material] if geo.roof is not None else []),
            *([wall] if walls is not None else [])]
    kept = [k for k, mesh in enumerate(batch) if len(mesh.counts)]
    arrays: list[MeshArrays | MeshData] = list(batch)  # (an empty mesh stays MeshData: Author.mesh skips it)
    for k, a in zip(kept, author.arrays([(batch[k], mats[k]) for k in kept], [normals[k] for k in kept], pivot)):
        arrays[k] = a
    body = mass = prim
    if walls is not None and writer.lod == "variants":
        lods = Sdf.VariantSetSpec(prim, LOD_SET)
        body, mass = Sdf.VariantSpec(lods, LOD_FULL).primSpec, Sdf.VariantSpec(lods, LOD_MASS).primSpec
        prim.variantSetNameList.prependedItems.append(LOD_SET)
        prim.variantSelections[LOD_SET] = LOD_FULL
    elif walls is not None:
        body, mass = author.prim(prim, "Render", "Scope"), author.prim(prim, "Proxy", "Scope")
        author.attr(body, "purpose", T.Token, "render", uniform=True)
        author.attr(mass, "purpose", T.Token, "proxy", uniform=True)
    bounds = []  # local
    if walls is not None:
        bounds.append(author.mesh(mass, "Walls", arrays[-1], looks, wall, "wall"))
        counts["meshes"] += 1
        counts["polygons"] += len(walls.counts)
    if geo.meshes:
        facade = author.prim(body, "Facade", "Scope")
        names: set[str] = set()
        for ((label, mat), mesh), prepared in zip(geo.meshes.items(), arrays):
            bounds.append(author.mesh(facade, prim_name(f"{label}_{mat}", names), prepared, looks, mat, label))
            counts["meshes"] += bounds[-1] is not None
            counts["polygons"] += len(mesh.counts)
    if geo.roof is not None:
        bounds.append(author.mesh(prim, "Roof", arrays[len(geo.meshes)], looks, geo.roof_material, "roof"))
        counts["meshes"] += 1
        counts["polygons"] += len(geo.roof.counts)
    if len(local.proto_indices):
        bounds.append(local_bound)
        _instancer(author, body, local, writer.prototypes, local_bound)
        counts["instances"] += len(local.proto_indices)
    counts["buildings"] += 1
    building = union(bounds)
    _model_bound(prim, building)
    return building


def _instancer(author: Author, parent: Sdf.PrimSpec, inst: Instances,
               prototypes: Mapping[Any, tuple[str, Sdf.Path]], bound: np.ndarray | None) -> None:
    """A PointInstancer ``Elements`` under ``parent`` whose prototypes, ``Prototypes/p<k>``, are instanceable Xforms
    referencing the shared ``/Prototypes`` (one prototype per element kind: DCCs load it once) of this layer or
    of the element library (``prototypes``: the layer and path of each).

    Authored spec by spec, never with ``Sdf.CopySpec`` from a template: that copy orders each spec's fields by the
    addresses of their names' tokens in the process, so the .usdc bytes (not the text) would depend on the process's
    history (see :mod:`citygen.usd.author`)."""
    names = _ref_names(len(inst.protos))
    pi = author.prim(parent, "Elements", "PointInstancer")
    holder = author.prim(pi, "Prototypes", "Scope")
    for name, key in zip(names, inst.protos):
        ref = author.prim(holder, name, "Xform")
        asset, path = prototypes[key]
        author.reference(ref, path, asset)
        ref.SetInfo("instanceable", True)
    base = holder.path.StripAllVariantSelections()  # (inside a LOD variant: the targets are composed paths)
    author.rel(pi, "prototypes", [base.AppendChild(name) for name in names])
    author.attr(pi, "protoIndices", T.IntArray, Vt.IntArray.FromNumpy(inst.proto_indices.astype(np.int32)))
    author.attr(pi, "positions", T.Point3fArray, Vt.Vec3fArray.FromNumpy(np.asarray(inst.positions, np.float32)))
    author.attr(pi, "orientations", T.QuathArray, Vt.QuathArray.FromNumpy(inst.orientations.astype(np.float16)))
    author.attr(pi, "scales", T.Float3Array, Vt.Vec3fArray.FromNumpy(inst.scales.astype(np.float32)))
    if bound is not None:
        author.attr(pi, "extent", T.Float3Array, bound_value(bound))


def _rows(arrays: list[np.ndarray], width: int) -> np.ndarray:
    """``arrays`` of ``width`` columns one after the other (none: no rows)."""
    return np.concatenate([np.zeros((0, width)), *(np.asarray(a, dtype=float).reshape(-1, width) for a in arrays)])


@functools.lru_cache(maxsize=64)
def _ref_names(n: int) -> tuple[str, ...]:
    """The prim names of a PointInstancer's ``n`` prototype references: ``p0``, ``p1``, ..."""
    return tuple(f"p{k}" for k in range(n))


def open_stage(path: str | Path) -> Usd.Stage:
    stage = Usd.Stage.Open(str(path))
    if stage is None:
        raise ExportError("cannot open stage", where=str(path))
    return stage
