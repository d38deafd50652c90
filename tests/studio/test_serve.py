"""Starting the studio: ``citygen studio`` answers through the ``citygen.early`` entry point before the plugins load,
on a session made in the background (:class:`PendingSession`)."""
from __future__ import annotations

import importlib.metadata
import json
import re
import subprocess
import sys
import urllib.request

from starlette.testclient import TestClient

from citygen.registry import default_registry
from citygen_studio.app import create_app
from citygen_studio.serve import PendingSession
from citygen_studio.session import Session
from tests.studio.test_api import URL, make_scene


def test_a_pending_session_answers_once_it_is_made(tmp_path):
    scene = make_scene(tmp_path)
    pending = PendingSession(lambda events: Session(default_registry(), scene, background=True, events=events))
    client = TestClient(create_app(pending), base_url=URL)
    assert client.get("/").status_code == 200
    assert client.get("/api/scene").json()["rulesets"] == ["../shared/apartment.grammar", "house.grammar"]
    assert len(client.get("/api/buildings").json()["buildings"]) == 2


def test_a_studio_that_cannot_start_says_so(capsys):
    def broken(events):
        raise ImportError("no module named 'pxr'")

    client = TestClient(create_app(PendingSession(broken)), base_url=URL)
    response = client.get("/api/scene")
    assert response.status_code == 500 and "could not start: ImportError" in response.json()["error"]["message"]
    assert client.get("/").status_code == 200  # (the page is served, and shows the error)


def test_citygen_studio_starts_early_and_serves_the_scene(tmp_path):
    assert "studio" in {e.name for e in importlib.metadata.entry_points(group="citygen.early")}
    scene = make_scene(tmp_path)
    proc = subprocess.Popen([sys.executable, "-m", "citygen.launch", "studio", str(scene), "--no-browser"],
                            stdout=subprocess.PIPE, text=True)
    try:
        url = re.search(r"http://127\.0\.0\.1:\d+/", proc.stdout.readline()).group(0)
        with urllib.request.urlopen(url, timeout=30) as page:
            assert "citygen studio" in page.read().decode()
        with urllib.request.urlopen(url + "api/scene", timeout=60) as answer:
            assert json.load(answer)["scene"] == "scene"
    finally:
        proc.terminate()
        proc.wait(10)
    bad = subprocess.run([sys.executable, "-m", "citygen.launch", "studio", "--port", "http"], capture_output=True,
                         text=True)
    assert bad.returncode == 2 and "a port is a whole number" in bad.stderr


def test_streams_and_downloads_wait_for_the_session_off_the_event_loop(tmp_path):
    scene = make_scene(tmp_path)
    client = TestClient(create_app(PendingSession(lambda events: Session(default_registry(), scene, background=True,
                                                                            events=events))), base_url=URL)
    with client.stream("GET", "/api/generate/events") as events:  # (no run yet: one state, not running)
        states = [json.loads(line[6:]) for line in events.iter_lines() if line.startswith("data: ")]
    assert states == [{"running": False, "done": 0, "total": 0, "error": None, "report": None, "output": None,
                       "edited": []}]
    assert client.get("/api/output", params={"name": "studio-out/scene.glb"}).status_code == 404


def test_loading_the_plugins_does_not_import_the_photo_analysis():
    """(~0.25 s of CPU of the studio's start: scipy.ndimage and the element library, for one constant.)"""
    code = ("import sys; from citygen.registry import default_registry; default_registry(); "
            "print('citygen_photo.photo' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout.strip() == "False"
