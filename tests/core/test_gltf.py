"""glTF output: the same city as the USD stage, as shared meshes, PBR materials and node extras (Y-up)."""
from __future__ import annotations

import json
import struct
import subprocess
import sys
from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import trimesh
from pxr import Usd, UsdGeom, UsdShade

from citygen.errors import CitygenError
from citygen.geometry.building import Instances, MeshData
from citygen.gltf.meshes import Y_UP, Y_UP_QUATERNION, instance_matrices, quaternion_product, triangles
from citygen.pipeline import generate_city
from citygen.scene import load_scene
from tests.mini_scene import generate_mini_scene
from tests.usd_util import buildings

REPO = Path(__file__).resolve().parents[2]
#: Three rows of houses dressed by the shipped apartment grammar (modules of bays with windows and sills).
HOUSES = [(k, (30.0 * (k % 3), 25.0 * (k // 3), 18.0, 11.0), 4 + k % 2) for k in range(6)]


def instance_nodes(doc: dict) -> list[dict]:
    """Nodes placing a prototype: their mesh is a prototype's (named by its key, no ``building/`` prefix)."""
    return [n for n in doc["nodes"] if "mesh" in n and "/" not in doc["meshes"][n["mesh"]]["name"]
            and n["name"] != "Ground"]


def glb_json(path: Path) -> dict:
    """The JSON chunk of a GLB file."""
    data = path.read_bytes()
    magic, version, length = struct.unpack("<4sII", data[:12])
    assert (magic, version, length) == (b"glTF", 2, len(data))
    size, kind = struct.unpack("<I4s", data[12:20])
    assert kind == b"JSON"
    return json.loads(data[20:20 + size])


@pytest.fixture(scope="module")
def city(tmp_path_factory) -> tuple[Path, Path, int]:
    """The mini city as a USD stage and as a GLB, and the GLB's count of instances."""
    tmp = tmp_path_factory.mktemp("gltf")
    report, usda = generate_mini_scene(tmp, HOUSES, REPO / "rulesets" / "apartment.grammar", seed=7)
    assert report.written == len(HOUSES) and not report.skipped
    glb = tmp / "mini.glb"
    report = generate_city(load_scene(tmp / "mini.toml"), out=glb)
    assert report.written == len(HOUSES) and report.stats.path == glb
    return usda, glb, report.stats.instances


def test_round_trip_through_trimesh_counts_buildings_instances_and_materials(city):
    usda, glb, glb_instances = city
    stage = Usd.Stage.Open(str(usda))
    loaded = trimesh.load(glb, force="scene")
    graph = loaded.graph
    extras = {node: graph.transforms.edge_data[(graph.transforms.parents[node], node)].get("metadata", {})
              for node in graph.nodes if node in graph.transforms.parents}
    houses = sorted(e["citygen:sourceId"] for e in extras.values() if "citygen:sourceId" in e)
    assert houses == sorted(p.GetAttribute("citygen:sourceId").Get() for p in buildings(stage))
    # every instance is one node sharing its prototype's mesh (a mesh of several primitives loads as one geometry
    # per primitive, each under the instance's node); a module's elements are baked into its mesh, where the stage
    # places them with the building's own instancer (citygen.geometry.lift), so the stage has more rows
    doc = glb_json(glb)
    users = Counter(node["mesh"] for node in instance_nodes(doc))
    instanced = sum(users.values())
    stage_instances = sum(len(UsdGeom.PointInstancer(p).GetProtoIndicesAttr().Get())
                          for p in stage.Traverse() if p.IsA(UsdGeom.PointInstancer))
    assert instanced == glb_instances > 20 and stage_instances > instanced
    assert any(name.startswith("module_") for name in (doc["meshes"][m]["name"] for m in users))
    assert max(users.values()) > 10 and len(users) < instanced / 3  # prototypes' meshes are shared
    shared = [g for g, n in Counter(graph[node][1] for node in graph.nodes_geometry).items() if n > 1]
    assert len(shared) >= len([m for m, n in users.items() if n > 1])
    # the same materials, with the stage's linear colours
    looks = {p.GetName(): UsdShade.Material(p) for p in stage.GetPrimAtPath("/Materials").GetAllChildren()}
    assert sorted(m["name"] for m in doc["materials"]) == sorted(looks)
    for material in doc["materials"]:
        shader = looks[material["name"]].ComputeSurfaceSource()[0]
        colour = shader.GetInput("diffuseColor").Get()
        assert material["pbrMetallicRoughness"]["baseColorFactor"][:3] == pytest.approx(list(colour), abs=1e-6)
    assert {g.visual.material.name for g in loaded.geometry.values()} == set(looks)


def test_gltf_is_the_stage_turned_y_up(city):
    """World bounds of the GLB (instances placed, Y-up) are the stage's bounds with (x, y, z) -> (x, z, -y)."""
    usda, glb, _ = city
    stage = Usd.Stage.Open(str(usda))
    box = UsdGeom.BBoxCache(Usd.TimeCode.Default(), ["default"]).ComputeWorldBound(stage.GetPseudoRoot()).ComputeAlignedRange()
    lo, hi = np.array(box.GetMin()), np.array(box.GetMax())
    expected = np.array([[lo[0], lo[2], -hi[1]], [hi[0], hi[2], -lo[1]]])
    assert trimesh.load(glb, force="scene").bounds == pytest.approx(expected, abs=1e-3)


def test_building_nodes_sit_at_their_pivot_with_local_geometry(city):
    _, glb, _ = city
    doc = glb_json(glb)
    houses = [n for n in doc["nodes"] if "citygen:sourceId" in n.get("extras", {})]
    for node in houses:
        x, y, z = node["translation"]
        assert y == pytest.approx(node["extras"]["citygen:base"])
        assert (x, z) != (0.0, 0.0) and "matrix" not in node


def test_same_seed_same_bytes(tmp_path, city):
    _, glb, _ = city
    scene = load_scene(glb.parent / "mini.toml")
    generate_city(scene, out=tmp_path / "again.glb")
    assert (tmp_path / "again.glb").read_bytes() == glb.read_bytes()


def test_gltf_json_has_its_buffer_embedded(tmp_path, city):
    _, glb, _ = city
    out = tmp_path / "city.gltf"
    report = generate_city(load_scene(glb.parent / "mini.toml"), out=out)
    doc = json.loads(out.read_text())
    assert doc["buffers"][0]["uri"].startswith("data:application/octet-stream;base64,")
    assert report.stats.bytes == out.stat().st_size
    assert len(trimesh.load(out, force="scene").geometry) == len(trimesh.load(glb, force="scene").geometry)
    assert [p.name for p in tmp_path.iterdir()] == ["city.gltf"]  # no temporary file left behind


def test_one_building_glb_is_centred_on_its_pivot(city):
    from citygen.builder import Builder
    from citygen.gltf.writer import building_glb
    from citygen.mass import build_mass, neighbour_cover
    from citygen.pipeline import import_footprints

    _, glb, _ = city
    scene = load_scene(glb.parent / "mini.toml")
    footprint = import_footprints(scene).footprints[0]
    mass = build_mass(footprint)
    outcome = Builder(scene, scene.seed).build(footprint, mass, neighbour_cover([mass])[0], "house", (0, 0))
    loaded = trimesh.load(trimesh.util.wrap_as_stream(building_glb(outcome.record)), file_type="glb", force="scene")
    (x0, y0, z0), (x1, y1, z1) = loaded.bounds
    assert y0 == pytest.approx(0.0, abs=1e-4) and y1 > 10
    assert abs(x0 + x1) < 2.0 and abs(z0 + z1) < 2.0  # within the balconies' reach of the centre


def test_glb_with_dask_executor_is_an_error(small_scene):
    with pytest.raises(CitygenError, match="dask executor writes USD"):
        generate_city(load_scene(small_scene), out=small_scene.parent / "city.glb", executor="dask")
    assert not (small_scene.parent / "city.glb").exists()


def test_usd_only_output_options_are_reported_as_ignored(tmp_path, city):
    _, glb, _ = city
    scene = load_scene(glb.parent / "mini.toml")
    scene = replace(scene, output=replace(scene.output, lod=True))
    report = generate_city(scene, out=tmp_path / "lod.glb")
    assert "lod.glb: glTF output ignores [output] lod" in report.warnings


def test_writing_usd_never_imports_trimesh(city):
    usda, _, _ = city
    code = ("import sys; from citygen.pipeline import generate_city; from citygen.scene import load_scene; "
            f"r = generate_city(load_scene({str(usda.parent / 'mini.toml')!r}), out={str(usda.parent / 'c.usda')!r}); "
            "print(r.written, 'trimesh' in sys.modules)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == f"{len(HOUSES)} False"


def test_fan_triangles_keep_the_winding():
    mesh = MeshData(np.zeros((7, 3), np.float32), np.array([4, 3], np.int32), np.array([0, 1, 2, 3, 4, 5, 6]))
    assert triangles(mesh).tolist() == [[0, 1, 2], [0, 2, 3], [4, 5, 6]]


def test_instance_trs_matches_the_instance_matrix():
    rng = np.random.default_rng(1)
    q = rng.normal(size=(5, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    inst = Instances((), np.zeros(5, np.int32), rng.normal(size=(5, 3)), q, rng.uniform(0.5, 2, size=(5, 3)))
    y_up = Instances((), inst.proto_indices, inst.positions @ Y_UP[:3, :3].T,
                     quaternion_product(Y_UP_QUATERNION, q), inst.scales)
    assert instance_matrices(y_up) == pytest.approx(Y_UP @ instance_matrices(inst))
