"""The studio's JSON API through Starlette's test client: the library's answers, and bad input as error data."""
from __future__ import annotations

import base64
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import trimesh
from starlette.testclient import TestClient

from citygen.registry import default_registry
from citygen_studio.app import MAX_BODY, create_app
from citygen_studio.session import MAX_TEXT, Session
from tests.mini_scene import LAT, LON, rect

REPO = Path(__file__).resolve().parents[2]
URL = "http://127.0.0.1"
SHARED = REPO.parent / "shared" / "data" / "cmp_facade" / "base"


def make_scene(tmp_path: Path) -> Path:
    """A scene folder ``city/`` with two houses, a grammar inside it and one beside it (``../shared/``)."""
    city, shared = tmp_path / "city", tmp_path / "shared"
    city.mkdir()
    shared.mkdir()
    shutil.copy(REPO / "rulesets" / "house.grammar", city / "house.grammar")
    shutil.copy(REPO / "rulesets" / "apartment.grammar", shared / "apartment.grammar")
    (tmp_path / "secret.grammar").write_text("not for the studio\n")
    features = [{"type": "Feature", "properties": {"id": k, "osm_type": "way", "building": kind, "building:levels": "4"},
                 "geometry": {"type": "Polygon", "coordinates": [rect(30.0 * k, 0.0, 16.0, 10.0)]}}
                for k, kind in enumerate(["house", "apartments"])]
    (city / "city.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": features}))
    (city / "scene.toml").write_text(
        '[scene]\nseed = 5\n[footprints]\npath = "city.geojson"\n'
        '[[assign]]\nwhen = { building = "house" }\nruleset = "house.grammar"\n'
        '[[assign]]\nruleset = "../shared/apartment.grammar"\n[output]\npath = "city.usdc"\n')
    return city / "scene.toml"


@pytest.fixture
def scene(tmp_path) -> Path:
    return make_scene(tmp_path)


@pytest.fixture
def client(scene) -> TestClient:
    return TestClient(create_app(Session(default_registry(), scene)), base_url=URL)


def test_scene_lists_its_rulesets_kinds_and_completions(client):
    info = client.get("/api/scene").json()
    assert info["error"] is None and info["buildings"] == 2
    assert info["rulesets"] == ["../shared/apartment.grammar", "house.grammar"]
    assert {"split", "layers", "relayout", "safe"} <= {k["id"] for k in info["kinds"]}
    assert "glass" in info["materials"] and "window" in info["labels"]


def test_buildings_carry_outline_attributes_and_assigned_ruleset(client):
    houses = client.get("/api/buildings").json()["buildings"]
    assert [h["id"] for h in houses] == ["way/0", "way/1"]
    assert houses[0]["rulesets"]["street"] == "house.grammar"
    assert houses[1]["rulesets"]["street"] == "../shared/apartment.grammar"
    assert houses[0]["attributes"]["building"] == "house" and len(houses[0]["rings"][0]) == 5


def test_build_gives_face_layouts_and_a_glb_of_the_building(client):
    built = client.post("/api/build", json={"index": 1}).json()
    assert built["skipped"] is None and built["attributes"]["sourceId"] == "way/1"
    dressed = [f for f in built["faces"] if f["layout"]]
    assert len(dressed) == 4 and any(r["label"] == "window" for r in dressed[0]["layout"]["leaves"])
    glb = trimesh.load(trimesh.util.wrap_as_stream(base64.b64decode(built["glb"])), file_type="glb", force="scene")
    assert len(glb.graph.nodes_geometry) > 10
    # face frames in the GLB's coordinates: Y-up, on the ground, the building's walls around its pivot
    (x0, y0, z0), (x1, y1, z1) = glb.bounds
    for face in built["faces"]:
        assert face["origin"][1] == pytest.approx(0.0) and face["u"][1] == face["normal"][1] == 0
        end = np.add(face["origin"], np.multiply(face["u"], face["width"]))
        for x, _, z in (face["origin"], end):
            assert x0 - 0.01 <= x <= x1 + 0.01 and z0 - 0.01 <= z <= z1 + 0.01


def test_build_with_an_edited_ruleset_uses_the_edit(client, scene):
    text = (scene.parent / "house.grammar").read_text()
    plain = client.post("/api/build", json={"index": 0}).json()
    edited = text.replace("terminal(window", "terminal(blind")  # (a plausible edit: shutters for windows)
    changed = client.post("/api/build", json={"index": 0, "rulesets": {"house.grammar": edited}}).json()
    labels = {r["label"] for f in changed["faces"] if f["layout"] for r in f["layout"]["leaves"]}
    assert "blind" in labels and changed["glb"] != plain["glb"]
    assert (scene.parent / "house.grammar").read_text() == text  # nothing saved


def test_preview_of_a_ruleset_text(client, scene):
    text = (scene.parent / "house.grammar").read_text()
    body = {"ruleset": "house.grammar", "text": text, "width": 12, "height": 9, "floor_height": 3, "seed": 1}
    preview = client.post("/api/preview", json=body).json()
    assert preview["ok"] and preview["kind"] == "split" and preview["problems"] == []
    layout = preview["layout"]
    assert (layout["width"], layout["height"]) == (12, 9) and layout["floor_lines"][-1] == 9
    assert preview["explain"]


def test_variations_of_a_relayout_model_are_distinct_layouts(client, scene):
    for name in ("cmp_b0035.relayout", "cmp_b0035.layout.json"):
        shutil.copy(REPO / "rulesets" / name, scene.parent / name)
    text = (scene.parent / "cmp_b0035.relayout").read_text()
    body = {"ruleset": "cmp_b0035.relayout", "text": text, "width": 14, "height": 12, "floor_height": 3, "count": 4}
    result = client.post("/api/variations", json=body).json()
    layouts = [v["layout"] for v in result["variations"]]
    assert result["ok"] and 1 < len(layouts) <= 4
    assert len({json.dumps(layout["leaves"]) for layout in layouts}) == len(layouts)
    assert [v["seed"] for v in result["variations"]] == sorted(v["seed"] for v in result["variations"])
    assert client.post("/api/variations", json={**body, "count": 1000}).status_code == 400


def test_malformed_ruleset_is_an_error_with_its_position(client):
    body = {"ruleset": "house.grammar", "text": "Facade --> split(y) { 1: Floor\n", "width": 10, "height": 9}
    preview = client.post("/api/preview", json=body)
    assert preview.status_code == 200
    error = preview.json()["error"]
    assert error["file"] == "house.grammar" and error["line"] >= 1 and error["column"] >= 1 and error["message"]
    check = client.post("/api/check", json={"ruleset": "house.grammar", "text": "Facade --> ???"}).json()
    assert not check["ok"] and check["error"]["file"] == "house.grammar"


@pytest.mark.parametrize("width, height", [(1e9, 10), (10, 0), (-5, 10), ("wide", 10), (None, 10)])
def test_huge_or_bad_sizes_are_refused(client, scene, width, height):
    body = {"ruleset": "house.grammar", "text": (scene.parent / "house.grammar").read_text(), "width": width,
            "height": height}
    response = client.post("/api/preview", json=body)
    assert response.status_code == 400
    assert response.json()["error"]["message"].startswith("width" if width != 10 else "height")


def test_huge_bodies_are_refused(client):
    text = "# " + "x" * MAX_BODY
    response = client.post("/api/check", json={"ruleset": "house.grammar", "text": text})
    assert response.status_code == 413
    response = client.post("/api/check", json={"ruleset": "house.grammar", "text": "x" * (MAX_TEXT + 1)})
    assert response.status_code == 413


@pytest.mark.parametrize("name", ["../secret.grammar", "../../secret.grammar", "/etc/passwd", "sub/../../secret.grammar",
                                  "../shared/../secret.grammar"])
def test_paths_outside_the_scene_folder_are_refused(client, tmp_path, name):
    assert client.get("/api/ruleset", params={"name": name}).status_code in (400, 403)
    response = client.post("/api/ruleset", json={"name": name, "text": "overwritten"})
    assert response.status_code in (400, 403) and response.json()["error"]["message"]
    assert (tmp_path / "secret.grammar").read_text() == "not for the studio\n"


def test_saving_writes_inside_the_scene_folder_and_named_rulesets(client, scene):
    text = (scene.parent / "house.grammar").read_text() + "\n# edited\n"
    assert client.post("/api/ruleset", json={"name": "house.grammar", "text": text}).json()["saved"]
    assert client.get("/api/ruleset", params={"name": "house.grammar"}).json()["text"] == text
    assert client.post("/api/ruleset", json={"name": "../shared/apartment.grammar", "text": text}).status_code == 200
    assert sorted(p.name for p in scene.parent.iterdir()) == ["city.geojson", "house.grammar", "scene.toml"]


def test_unknown_ruleset_kind_is_an_error(client):
    response = client.post("/api/check", json={"ruleset": "notes.txt", "text": "hello"})
    assert response.status_code == 400 and ".txt" in json.dumps(response.json()["error"])


def test_a_scene_loading_in_the_background_is_waited_for(scene):
    session = Session(default_registry(), scene, background=True)
    client = TestClient(create_app(session), base_url=URL)
    assert client.get("/api/scene").json()["rulesets"] and session.scene_ready.is_set()  # (maybe before the masses)
    assert client.get("/api/ruleset", params={"name": "../shared/apartment.grammar"}).status_code == 200
    assert len(client.get("/api/buildings").json()["buildings"]) == 2 and session.loaded.is_set()
    assert client.get("/api/scene").json()["buildings"] == 2


def test_a_scene_that_fails_to_load_is_reported_as_data(tmp_path):
    (tmp_path / "broken.toml").write_text("[scene\nseed = 1\n")
    client = TestClient(create_app(Session(default_registry(), tmp_path / "broken.toml")), base_url=URL)
    info = client.get("/api/scene").json()
    assert info["error"]["file"] == "broken.toml" and info["error"]["line"] == 1
    response = client.post("/api/build", json={"index": 0})
    assert response.status_code == 409 and "scene" in response.json()["error"]["message"]


def test_generate_runs_the_scene_with_progress_report_and_download(client, scene):
    started = client.post("/api/generate", json={"format": ".glb"}).json()
    assert started["output"] == "studio-out/scene.glb"
    assert client.post("/api/generate", json={"format": ".glb"}).status_code in (200, 409)  # (409 while running)
    with client.stream("GET", "/api/generate/events") as events:
        assert events.headers["content-type"].startswith("text/event-stream")
        states = [json.loads(line[len("data: "):]) for line in events.iter_lines() if line.startswith("data: ")]
    state = states[-1]
    assert not state["running"] and all(s["running"] for s in states[:-1])
    assert state["error"] is None and state["done"] == state["total"] == 2
    assert state["report"]["written"] == 2 and "written 2 buildings" in state["report"]["summary"]
    download = client.get("/api/output", params={"name": state["output"]})
    assert download.status_code == 200 and download.content[:4] == b"glTF"
    assert client.get("/api/output", params={"name": "scene.toml"}).status_code == 404
    assert client.get("/api/output", params={"name": "../secret.grammar"}).status_code == 403
    assert client.post("/api/generate", json={"format": ".obj"}).status_code == 400


def test_a_dropped_layout_gives_a_grammar_that_parses(client):
    data = base64.b64encode((REPO / "rulesets" / "cmp_b0035.layout.json").read_bytes()).decode()
    imported = client.post("/api/import", json={"name": "cmp_b0035.layout.json", "data": data}).json()
    assert imported["drawing"]["leaves"] and imported["summary"].startswith("cmp_b0035.layout.json:")
    grammar = client.post("/api/extract", json={"layout": imported["layout"], "method": "greedy",
                                                "iterations": 1}).json()
    assert grammar["rules"] > 0
    for text in (grammar["text"], grammar["size_independent"]):
        assert client.post("/api/check", json={"ruleset": "new.grammar", "text": text}).json()["ok"]
    body = {"ruleset": "new.grammar", "text": grammar["size_independent"], "width": 20, "height": 15}
    assert client.post("/api/preview", json=body).json()["ok"]


@pytest.mark.skipif(not (SHARED / "cmp_b0001.jpg").is_file(), reason="needs the shared CMP facade photos")
def test_a_dropped_photo_becomes_a_layout(client):
    data = base64.b64encode((SHARED / "cmp_b0001.jpg").read_bytes()).decode()
    imported = client.post("/api/import", json={"name": "cmp_b0001.jpg", "data": data, "width": 12}).json()
    assert imported["drawing"]["width"] == pytest.approx(12)
    assert any(r["label"] == "window" for r in imported["drawing"]["leaves"])


def _cmp_b0001_request() -> dict:
    """The import request of CMP annotation cmp_b0001 with its label map, 10 m wide."""
    def encoded(name: str) -> str:
        return base64.b64encode((SHARED / name).read_bytes()).decode()

    return {"name": "cmp_b0001.xml", "data": encoded("cmp_b0001.xml"), "label_map": encoded("cmp_b0001.png"),
            "width": 10}

@pytest.mark.skipif(not (SHARED / "cmp_b0001.xml").is_file(), reason="needs the shared CMP annotations")
def test_a_dropped_cmp_annotation_becomes_a_layout(client):
    body = _cmp_b0001_request()
    imported = client.post("/api/import", json=body).json()
    assert imported["drawing"]["width"] == pytest.approx(10) and "no label map" not in imported["summary"]
    assert any(r["label"] == "window" for r in imported["drawing"]["leaves"])
    alone = client.post("/api/import", json={**body, "label_map": None}).json()
    assert "no label map" in alone["summary"]
    broken = {"name": "cmp_b0001.xml", "data": base64.b64encode(b"<object><name>").decode()}
    error = client.post("/api/import", json=broken).json()["error"]
    assert error["message"].startswith("cmp_b0001.xml:1:")


def test_bad_drops_are_errors_naming_the_file(client):
    bad = base64.b64encode(b"not an image").decode()
    response = client.post("/api/import", json={"name": "facade.jpg", "data": bad})
    assert response.status_code == 400 and response.json()["error"]["message"].startswith("facade.jpg: ")
    assert client.post("/api/import", json={"name": "facade.jpg", "data": "%%%"}).status_code == 400
    response = client.post("/api/import", json={"name": "broken.json", "data": base64.b64encode(b"{").decode()})
    assert response.status_code == 400 and "broken.json" in json.dumps(response.json()["error"])
    assert client.post("/api/extract", json={"layout": {}, "method": "magic", "iterations": 1}).status_code == 400
    assert client.post("/api/extract", json={"layout": {}, "method": "adp", "iterations": 10**6}).status_code == 400


def test_bad_requests_are_errors_as_data(client):
    assert client.post("/api/build", json={"index": 7}).status_code == 404
    assert client.post("/api/build", json={"index": "one"}).status_code == 400
    assert client.post("/api/build", content=b"{not json", headers={"content-type": "application/json"}).status_code == 400
    assert client.post("/api/build", content=b"index=1",
                       headers={"content-type": "application/x-www-form-urlencoded"}).status_code == 415
    assert client.post("/api/build", json=[1, 2]).status_code == 400


def test_other_sites_and_hosts_are_refused(client):
    response = client.post("/api/ruleset", json={"name": "house.grammar", "text": "x"},
                           headers={"origin": "http://evil.example"})
    assert response.status_code == 403
    assert TestClient(client.app, base_url="http://evil.example").get("/api/scene").status_code == 400


def test_slow_requests_time_out(scene):
    client = TestClient(create_app(Session(default_registry(), scene), time_limit=0.001), base_url=URL)
    response = client.post("/api/build", json={"index": 1})
    assert response.status_code == 504 and "longer than" in response.json()["error"]["message"]


def test_the_page_and_its_libraries_are_served(client):
    page = client.get("/")
    assert page.status_code == 200 and "citygen studio" in page.text
    assert client.get("/vendor/three/build/three.module.js").status_code == 200
    assert client.get("/vendor/codemirror/lib/codemirror.js").status_code == 200


def test_generate_reads_unsaved_edits_without_writing_them(client, scene):
    house = scene.parent / "house.grammar"
    saved = house.read_text()
    edited = saved.replace("terminal(window", "terminal(blind")
    started = client.post("/api/generate", json={"format": ".usda", "rulesets": {"house.grammar": edited}}).json()
    assert started["edited"] == ["house.grammar"]
    with client.stream("GET", "/api/generate/events") as events:
        state = [json.loads(line[6:]) for line in events.iter_lines() if line.startswith("data: ")][-1]
    assert state["error"] is None and state["report"]["written"] == 2 and state["edited"] == ["house.grammar"]
    stage = (scene.parent / "studio-out" / "scene.usda").read_text()
    assert "blind" in stage  # the edit's labels are in the city
    assert house.read_text() == saved  # and the file is as it was
    assert sorted(p.name for p in scene.parent.iterdir()) == ["city.geojson", "house.grammar", "scene.toml",
                                                               "studio-out"]


def test_generate_refuses_edits_that_do_not_parse_or_need_workers(client, scene):
    broken = client.post("/api/generate", json={"format": ".glb", "rulesets": {"house.grammar": "Facade --> ???"}})
    assert broken.status_code == 400 and broken.json()["error"]["file"] == "house.grammar"
    assert broken.json()["error"]["line"] == 1
    text = (scene.parent / "house.grammar").read_text()
    more = client.post("/api/generate", json={"format": ".glb", "jobs": 2, "rulesets": {"house.grammar": text}})
    assert more.status_code == 400 and "jobs must be 1" in more.json()["error"]["message"]
    outside = client.post("/api/generate", json={"format": ".glb", "rulesets": {"../secret.grammar": "x"}})
    assert outside.status_code == 403
    assert client.get("/api/generate").json()["running"] is False  # (nothing started)


def test_a_face_preview_is_the_face_the_city_gets(client, scene):
    built = client.post("/api/build", json={"index": 1}).json()
    text = (scene.parent.parent / "shared" / "apartment.grammar").read_text()
    body = {"ruleset": "../shared/apartment.grammar", "text": text, "building": 1, "width": 1, "height": 1}
    dressed = [f for f in built["faces"] if f["layout"]]
    for face in dressed:
        preview = client.post("/api/preview", json={**body, "face": face["index"]}).json()
        assert preview["ok"] and preview["layout"]["leaves"] == face["layout"]["leaves"]  # (not 1 x 1 m)
        assert preview["request"] == face["request"]
        assert preview["request"]["floor_lines"] == preview["layout"]["floor_lines"]
    assert sum(client.post("/api/preview", json={**body, "face": f["index"]}).json()["request"]["entrance"]
               for f in dressed) == 1  # the building's one entrance
    edited = client.post("/api/preview", json={**body, "face": dressed[0]["index"],
                                               "text": text.replace("terminal(window", "terminal(blind")}).json()
    assert "blind" in {r["label"] for r in edited["layout"]["leaves"]}


def test_a_face_preview_of_a_missing_building_or_face_is_an_error(client, scene):
    body = {"ruleset": "house.grammar", "text": (scene.parent / "house.grammar").read_text(), "face": 0}
    assert client.post("/api/preview", json={**body, "building": 9}).status_code == 404
    response = client.post("/api/preview", json={**body, "building": 0, "face": 99})
    assert response.status_code == 404 and "dressed faces" in response.json()["error"]["hint"]
    assert client.post("/api/preview", json={**body, "building": 0, "face": "front"}).status_code == 400


def test_a_face_preview_of_a_kind_that_couples_faces_matches_the_build(tmp_path):
    scene = make_scene(tmp_path)
    for name in ("townhouse.relayout", "cmp_b0035.relayout", "cmp_b0035.layout.json"):
        shutil.copy(REPO / "rulesets" / name, scene.parent / name)
    text = scene.read_text()
    scene.write_text(text[:text.index("[[assign]]")] + '[[assign]]\nruleset = "townhouse.relayout"\n'
                     + text[text.index("[output]"):])
    client = TestClient(create_app(Session(default_registry(), scene)), base_url=URL)
    built = client.post("/api/build", json={"index": 1}).json()
    body = {"ruleset": "townhouse.relayout", "text": (scene.parent / "townhouse.relayout").read_text(), "building": 1}
    same = 0
    for face in (f for f in built["faces"] if f["layout"]):
        preview = client.post("/api/preview", json={**body, "face": face["index"]}).json()
        if not preview["problems"]:
            assert preview["layout"]["leaves"] == face["layout"]["leaves"]
            same += 1
    assert same >= 2


def test_a_face_preview_of_a_curved_wall_is_its_stretch_of_the_walls_facade(tmp_path):
    """A round house's faces are one run (citygen.runs): each face's preview is the stretch the city cuts from the
    run's facade, judged as the city judges it (the run's facade), not a facade of its own."""
    scene = make_scene(tmp_path)
    mx, my = (np.array(rect(0.0, 0.0, 1.0, 1.0)[2]) - rect(0.0, 0.0, 1.0, 1.0)[0]).tolist()  # (degrees a metre)
    ring = [[LON + 5.0 * mx * np.cos(2 * np.pi * k / 24), LAT + 5.0 * my * np.sin(2 * np.pi * k / 24)]
            for k in range(25)]
    ring[-1] = ring[0]
    feature = {"type": "Feature", "properties": {"id": 0, "osm_type": "way", "building": "house",
                                                  "building:levels": "1"},
               "geometry": {"type": "Polygon", "coordinates": [ring]}}
    (scene.parent / "city.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": [feature]}))
    client = TestClient(create_app(Session(default_registry(), scene)), base_url=URL)
    built = client.post("/api/build", json={"index": 0}).json()
    body = {"ruleset": "house.grammar", "text": (scene.parent / "house.grammar").read_text(), "building": 0}
    faces = [f for f in built["faces"] if f["layout"]]
    assert len(faces) == 24
    windows = 0
    for face in faces:
        preview = client.post("/api/preview", json={**body, "face": face["index"]}).json()
        assert preview["ok"] and preview["problems"] == [], (face["index"], preview)
        assert preview["layout"]["leaves"] == face["layout"]["leaves"]
        windows += sum(r["label"] == "window" for r in preview["layout"]["leaves"])
    assert windows >= 8


@pytest.mark.skipif(not (SHARED / "cmp_b0001.xml").is_file(), reason="needs the shared CMP annotations")
def test_cmp_import_takes_the_command_lines_tolerances(client):
    body = _cmp_b0001_request()
    default = client.post("/api/import", json=body).json()
    loose = client.post("/api/import", json={**body, "options": {"snap": 0.05, "align": 0.1, "equal_sizes": 0.2,
                                                                  "element_caps": False}}).json()
    assert "snap 0.05, align 0.1, equal sizes 0.2, no element caps" in loose["summary"]
    assert loose["layout"] != default["layout"]  # (coarser tolerances merge more edges)
    for options in ({"snap": 0.5}, {"align": -0.1}, {"element_caps": "yes"}, {"tolerance": 1}, [0.01]):
        response = client.post("/api/import", json={**body, "options": options})
        assert response.status_code == 400 and response.json()["error"]["message"]


@pytest.mark.skipif(not (SHARED / "cmp_b0001.jpg").is_file(), reason="needs the shared CMP facade photos")
def test_photo_import_takes_a_crop_box_and_a_parser(client):
    data = base64.b64encode((SHARED / "cmp_b0001.jpg").read_bytes()).decode()
    body = {"name": "cmp_b0001.jpg", "data": data, "width": 8}
    cropped = client.post("/api/import", json={**body, "options": {"crop": [20, 10, 300, 400],
                                                                    "parser": "contrast"}}).json()
    assert "contrast parser, crop 20 10 300 400" in cropped["summary"]
    assert cropped["drawing"]["width"] == pytest.approx(8)
    assert cropped["drawing"]["height"] == pytest.approx(8 * 390 / 280, rel=0.02)  # (the crop's proportions)
    outside = client.post("/api/import", json={**body, "options": {"crop": [0, 0, 99999, 10]}})
    assert outside.status_code == 400 and outside.json()["error"]["message"].startswith("cmp_b0001.jpg: ")
    assert client.post("/api/import", json={**body, "options": {"parser": "magic"}}).status_code == 400
    assert client.post("/api/import", json={**body, "options": {"crop": [1, 2, 3]}}).status_code == 400


@pytest.mark.skipif(not (SHARED / "cmp_b0284.xml").is_file(), reason="needs the shared CMP annotations")
def test_cmp_import_refuses_or_drops_zero_size_boxes(client):
    body = {"name": "cmp_b0284.xml", "data": base64.b64encode((SHARED / "cmp_b0284.xml").read_bytes()).decode()}
    refused = client.post("/api/import", json=body)
    assert refused.status_code == 400 and "zero-size box" in refused.json()["error"]["message"]
    assert refused.json()["error"]["message"].startswith("cmp_b0284.xml: ")
    assert client.post("/api/import", json={**body, "options": {"drop_degenerate": True}}).status_code == 200
