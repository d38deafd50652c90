"""Write a city (or one building) as glTF 2.0 through trimesh: ``.glb`` (binary) or ``.gltf`` (JSON, buffer
embedded), atomically.

Layout (Y-up, metres)::

    Ground                        node + mesh (with [output] ground = true)
    <building>                    node at the building's pivot, extras: the citygen:* attributes
      <building>/<label>_<mat>    node + mesh of its own (facade meshes, mesh extras: label)
      <building>/Roof             node + mesh
      <building>/<k>              one node per instance, sharing its prototype's mesh

Every prototype (element or module) is one mesh with a primitive per material, shared by all the nodes that
instance it; materials are glTF PBR (metallic-roughness) with the USD stage's linear colours. Unlike the USD
writer this one holds the whole city in memory until :meth:`GltfWriter.close`.
"""
from __future__ import annotations

import os
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from trimesh.visual.material import PBRMaterial
from trimesh.visual.texture import TextureVisuals

from citygen import __version__
from citygen.errors import ExportError
from citygen.geometry.building import MeshData
from citygen.geometry.modules import ModuleKey
from citygen.geometry.prototypes import ProtoKey
from citygen.gltf import GLTF_SUFFIXES
from citygen.gltf.meshes import (Y_UP, Y_UP_QUATERNION, Primitive, PrototypeMeshes, quaternion_product,
                                 transform_points, triangles)
from citygen.usd.materials import Material, material
from citygen.usd.writer import BuildingRecord, StageStats

#: glTF buffer view targets (vertex data, index data).
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
#: Decimals of node translations in metres (0.01 mm); rotations and scales get two more.
DECIMALS = 5


def material_look(name: str, library: Mapping[str, Material] | None = None
                  ) -> tuple[tuple[float, float, float], float, float, float]:
    """Linear base colour, roughness, metallic and opacity of a material name (the scene's and rulesets'
    ``library`` first, as for the USD stage): what the stage's ``UsdPreviewSurface`` gets, so both files look
    alike."""
    found = material(name, library)
    return found.linear, found.roughness, found.metallic, found.opacity


@dataclass(frozen=True)
class _Placements:
    """A building's instances in its Y-up frame: prototype mesh names and rounded glTF transforms."""

    geometry: tuple[str, ...]
    translations: np.ndarray
    rotations: np.ndarray
    scales: np.ndarray


class _Material(PBRMaterial):
    """A PBR material told apart by its name too (trimesh merges materials of equal values)."""

    def __hash__(self) -> int:
        return hash((self.name, super().__hash__()))


def _translate(offset: np.ndarray) -> np.ndarray:
    out = np.eye(4)
    out[:3, 3] = offset
    return out


def _jsonable(value: Any) -> Any:
    return value.item() if isinstance(value, np.generic) else value


class GltfScene:
    """A city assembled as a trimesh scene: :meth:`ground`, :meth:`add` buildings, then :meth:`export`."""

    def __init__(self, layer_data: Mapping[str, Any] | None = None,
                 materials: Mapping[str, Material] | None = None) -> None:
        self.library = dict(materials or {})
        self.scene = trimesh.Scene(base_frame="world")
        if layer_data:
            self.scene.metadata["citygen"] = dict(layer_data)
        self.materials: dict[str, _Material] = {}
        self.prototypes: dict[ProtoKey | ModuleKey, str] = {}
        self.parts: dict[str, str] = {}  # geometry name of a prototype's 2nd, 3rd... primitive -> the prototype's
        self.meshes = PrototypeMeshes()
        self.counts = {"buildings": 0, "meshes": 0, "instances": 0, "polygons": 0}
        self.trs: dict[str, dict[str, list[float]]] = {}  # node name -> glTF translation / rotation / scale
        self.placements: dict[str, _Placements] = {}  # building node -> its instances' nodes, added on export

    def _material(self, name: str) -> _Material:
        if name not in self.materials:
            (r, g, b), roughness, metallic, opacity = material_look(name, self.library)
            self.materials[name] = _Material(name=name, baseColorFactor=[r, g, b, opacity], roughnessFactor=roughness,
                                             metallicFactor=metallic, alphaMode="BLEND" if opacity < 1 else "OPAQUE")
        return self.materials[name]

    def _geometry(self, name: str, primitive: Primitive, extras: Mapping[str, Any]) -> None:
        self.scene.geometry[name] = trimesh.Trimesh(
            vertices=primitive.points, faces=primitive.triangles, process=False, validate=False,
            visual=TextureVisuals(material=self._material(primitive.material)), metadata=dict(extras))

    def _node(self, name: str, parent: str, matrix: np.ndarray, geometry: str | None = None,
              extras: Mapping[str, Any] | None = None) -> None:
        kwargs: dict[str, Any] = {"geometry": geometry} if geometry else {}
        if extras:
            kwargs["metadata"] = dict(extras)
        self.scene.graph.update(frame_to=name, frame_from=parent, matrix=matrix, **kwargs)

    def _mesh_node(self, name: str, parent: str, mesh: MeshData, matrix: np.ndarray, material: str,
                   label: str) -> None:
        """A node with a mesh of its own: ``mesh`` mapped by ``matrix``."""
        if not len(mesh.counts):
            return
        self._geometry(name, Primitive(material, transform_points(matrix, mesh.points), triangles(mesh)),
                       {"label": label})
        self._node(name, parent, np.eye(4), name)
        self.counts["meshes"] += 1
        self.counts["polygons"] += len(mesh.counts)

    def _prototype(self, key: ProtoKey | ModuleKey, modules) -> str:
        """The geometry name of a prototype's mesh (its first primitive), added on first use."""
        if key not in self.prototypes:
            name = self.prototypes[key] = key.name
            label = key.label if isinstance(key, ProtoKey) else "module"
            for k, primitive in enumerate(self.meshes(key, modules)):
                part = name if k == 0 else f"{name}.{k}"
                self._geometry(part, primitive, {"label": label})
                if k:
                    self.parts[part] = name
        return self.prototypes[key]

    def ground(self, mesh: MeshData) -> None:
        """The ``Ground`` under the city (:func:`citygen.ground.ground_mesh`; material ``ground``)."""
        self._mesh_node("Ground", "world", mesh, Y_UP, "ground", "ground")

    def add(self, record: BuildingRecord, placed: bool = True) -> None:
        """One building: a node at its pivot (at the origin unless ``placed``) with its meshes and instances."""
        geo = record.geometry
        origin = np.asarray(record.pivot, dtype=float)  # (the USD stage's pivot: the footprint's ground centroid)
        local = Y_UP @ _translate(-origin)
        name = record.name
        extras = {f"citygen:{k}": _jsonable(v) for k, v in sorted(record.attributes.items())}
        offset = Y_UP[:3, :3] @ origin if placed else np.zeros(3)
        self._node(name, "world", _translate(offset), extras=extras)
        self.trs[name] = {"translation": np.round(offset, DECIMALS).tolist()}
        for (label, look), mesh in geo.meshes.items():
            self._mesh_node(f"{name}/{label}_{look}", name, mesh, local, look, label)
        if geo.roof is not None:
            self._mesh_node(f"{name}/Roof", name, geo.roof, local, geo.roof_material, "roof")
        inst = geo.instances
        if len(inst.proto_indices):
            self.placements[name] = _Placements(
                tuple(self._prototype(inst.protos[k], geo.modules) for k in inst.proto_indices.tolist()),
                np.round((inst.positions - origin) @ Y_UP[:3, :3].T, DECIMALS),
                np.round(quaternion_product(Y_UP_QUATERNION, inst.orientations), DECIMALS + 2),
                np.round(inst.scales.astype(float), DECIMALS + 2))
        self.counts["instances"] += len(inst.proto_indices)
        self.counts["buildings"] += 1

    def _postprocess(self, tree: dict[str, Any]) -> None:
        """Prototype primitives joined into one mesh each; node transforms as translation, rotation and scale
        (shorter than trimesh's matrices); the instance nodes (kept out of trimesh's scene graph, where 100k nodes
        cost seconds and memory); buffer view targets; materials' exact linear colours (trimesh keeps 8 bits)."""
        tree["asset"]["generator"] = f"citygen {__version__} (trimesh {trimesh.__version__})"
        meshes, renumber, by_name = [], {}, {}
        for k, mesh in enumerate(tree.get("meshes", [])):
            owner = self.parts.get(mesh["name"])
            if owner is None:
                renumber[k] = by_name[mesh["name"]] = len(meshes)
                meshes.append(mesh)
            else:
                meshes[by_name[owner]]["primitives"] += mesh["primitives"]
        if meshes:
            tree["meshes"] = meshes
        nodes = tree.setdefault("nodes", [])
        for node in nodes:
            if "mesh" in node:
                node["mesh"] = renumber[node["mesh"]]
            trs = self.trs.get(node["name"])
            if trs is not None:
                node.pop("matrix", None)
                node.update(trs)
        for parent in [node for node in nodes if node["name"] in self.placements]:
            rows = self.placements[parent["name"]]
            children = parent.setdefault("children", [])
            for k, (geometry, t, r, scale) in enumerate(zip(rows.geometry, rows.translations.tolist(),
                                                            rows.rotations.tolist(), rows.scales.tolist())):
                children.append(len(nodes))
                nodes.append({"name": f"{parent['name']}/{k}", "mesh": by_name[geometry], "translation": t,
                              "rotation": r, "scale": scale})
        views = tree.get("bufferViews")  # (a GLB's are in place here; a .gltf's come after)
        if views:
            for mesh in meshes:
                for primitive in mesh["primitives"]:
                    views[tree["accessors"][primitive["indices"]]["bufferView"]]["target"] = ELEMENT_ARRAY_BUFFER
                    views[tree["accessors"][primitive["attributes"]["POSITION"]]["bufferView"]]["target"] = ARRAY_BUFFER
        for entry in tree.get("materials", []):
            (r, g, b), roughness, metallic, opacity = material_look(entry["name"], self.library)
            entry["pbrMetallicRoughness"] = {"baseColorFactor": [r, g, b, opacity], "metallicFactor": metallic,
                                                "roughnessFactor": roughness}

    def export(self, binary: bool = True) -> bytes:
        """The scene as GLB bytes, or (``binary=False``) as one glTF JSON document with its buffer embedded."""
        if binary:
            return trimesh.exchange.gltf.export_glb(self.scene, include_normals=False,
                                                    tree_postprocessor=self._postprocess)
        files = trimesh.exchange.gltf.export_gltf(self.scene, include_normals=False, merge_buffers=True,
                                                  embed_buffers=True, tree_postprocessor=self._postprocess)
        return files["model.gltf"]

    def stats(self, path: Path, size: int) -> StageStats:
        return StageStats(path=path, buildings=self.counts["buildings"],
                          prims=len(self.scene.graph.nodes) + self.counts["instances"],
                          meshes=self.counts["meshes"], instances=self.counts["instances"],
                          prototypes=len(self.prototypes), polygons=self.counts["polygons"], bytes=size)


class GltfWriter(GltfScene):
    """A :class:`GltfScene` written to ``path`` (``.glb`` or ``.gltf``) by :meth:`close`, through a temporary file
    in the same folder, so nothing at ``path`` changes unless the write succeeds. Same interface as the USD
    ``StageWriter``'s ``ground``, ``add`` and ``close``."""

    def __init__(self, path: str | Path, *, layer_data: Mapping[str, Any] | None = None,
                 materials: Mapping[str, Material] | None = None) -> None:
        self.path = Path(path)
        if self.path.suffix.lower() not in GLTF_SUFFIXES:
            raise ExportError(f"unsupported glTF extension {self.path.suffix!r}", where=str(self.path),
                              hint=f"use one of {', '.join(GLTF_SUFFIXES)}")
        super().__init__(layer_data, materials)
        self.failed: list[tuple[Any, Exception]] = []  # (the USD writer's buildings left out: this one leaves none)

    def __enter__(self) -> GltfWriter:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        return None

    def close(self) -> StageStats:
        data = self.export(binary=self.path.suffix.lower() == ".glb")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{self.path.stem}.", suffix=self.path.suffix, dir=self.path.parent)
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(data)
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)
            os.replace(tmp, self.path)
        finally:
            Path(tmp).unlink(missing_ok=True)
        return self.stats(self.path, len(data))


def building_glb(record: BuildingRecord, materials: Mapping[str, Material] | None = None) -> bytes:
    """One building alone as GLB bytes, its pivot (footprint centre at its base) at the origin."""
    scene = GltfScene(materials=materials)
    scene.add(record, placed=False)
    return scene.export()
