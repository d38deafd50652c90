"""The studio in a real headless Chromium (Debian's ``chromium`` package, driven by Playwright): select a building,
edit its grammar, see the SVG and the 3D view change, break the grammar and see the marker. Screenshots go to the
test's temporary directory. Skipped where there is no Chromium (``CITYGEN_CHROMIUM`` names another binary)."""
from __future__ import annotations

import contextlib
import io
import os
import shutil
import threading
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from citygen.registry import default_registry
from tests.studio.test_api import make_scene

sync_api = pytest.importorskip("playwright.sync_api", reason="the browser tests need playwright (pip)")
CHROMIUM = os.environ.get("CITYGEN_CHROMIUM") or shutil.which("chromium") or "/usr/bin/chromium"
pytestmark = [pytest.mark.browser,
              pytest.mark.skipif(not Path(CHROMIUM).is_file(), reason="no chromium (apt-get install chromium)")]
#: WebGL without a GPU (SwiftShader); --no-sandbox: CI containers run as root.
FLAGS = ["--no-sandbox", "--use-gl=swiftshader", "--enable-unsafe-swiftshader"]


@pytest.fixture
def studio(tmp_path):
    """The studio on a two-house scene, served on a free loopback port from a thread."""
    import uvicorn
    from citygen_studio.app import create_app
    from citygen_studio.serve import listen
    from citygen_studio.session import Session

    scene = make_scene(tmp_path)
    sock = listen(0)
    server = uvicorn.Server(uvicorn.Config(create_app(Session(default_registry(), scene)), log_level="warning",
                                           lifespan="off"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{sock.getsockname()[1]}/", scene
    server.should_exit = True
    thread.join(10)


@contextlib.contextmanager
def opened(url: str, errors: list[str] | None = None):
    """A headless Chromium page on the studio at ``url``, once the studio says it is ready; page errors are
    appended to ``errors``."""
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        if errors is not None:
            page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(url)
        page.wait_for_selector("body[data-ready=true]", timeout=30_000)
        try:
            yield page
        finally:
            browser.close()


def canvas(page) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(page.locator("#view3d canvas").screenshot())).convert("RGB"), dtype=int)


def test_edit_a_grammar_live_on_a_building(studio, tmp_path):
    url, scene = studio
    errors: list[str] = []
    with opened(url, errors) as page:
        assert page.locator("#map path").count() == 2

        page.locator("#map path").first.click()
        page.wait_for_function("window.studio.builds >= 1 && document.getElementById('view3d').dataset.meshes",
                               timeout=30_000)
        page.wait_for_timeout(500)  # a few frames
        page.screenshot(path=tmp_path / "1-selected.png")
        before = canvas(page)
        background = np.array([0xDD, 0xE3, 0xEA])
        assert (np.abs(before - background).sum(axis=2) > 30).mean() > 0.05  # the building covers the view
        assert page.locator("#ruleset").input_value() == "house.grammar"
        assert page.locator("#facade rect[data-label=window]").count() > 0
        page.locator("#view3d canvas").click()  # the middle of the view: a face of the building
        page.wait_for_function("window.studio.picks >= 1", timeout=10_000)

        # an edit: every window gets shutters instead (the SVG preview follows), the walls brick (the 3D view does)
        previews, builds = page.evaluate("[window.studio.previews, window.studio.builds]")
        page.evaluate("""() => { const cm = document.querySelector('.CodeMirror').CodeMirror;
                                 cm.setValue(cm.getValue().replace('terminal(window', 'terminal(blind')
                                                         .replace('terminal(wall, material: render', 'terminal(wall, material: brick')); }""")
        page.wait_for_function(f"window.studio.builds > {builds}", timeout=30_000)
        page.wait_for_selector("#facade rect[data-label=blind]", timeout=10_000)
        assert page.locator("#facade rect[data-label=window]").count() == 0
        assert page.evaluate("window.studio.previews") > previews
        # the preview dressed the picked face under the building's own request (its floors, its entrance or not)
        page.wait_for_function("document.getElementById('face-mode').textContent.includes('floor lines')",
                               timeout=10_000)
        assert "as the city gets it" in page.locator("#face-mode").inner_text()
        page.wait_for_timeout(500)
        page.screenshot(path=tmp_path / "2-edited.png")
        assert (np.abs(canvas(page) - before).sum(axis=2) > 30).mean() > 0.05  # the 3D view changed

        # variations: the distinct layouts of the next seeds; picking one previews its seed
        page.locator("#vary").click()
        page.wait_for_selector("#variations figure", timeout=30_000)
        cells = page.locator("#variations figure")
        assert cells.count() >= 2
        previews = page.evaluate("window.studio.previews")
        cells.nth(1).click()
        page.wait_for_function(f"window.studio.previews > {previews}", timeout=10_000)
        assert page.locator("#seed").input_value() == cells.nth(1).get_attribute("data-seed")
        page.screenshot(path=tmp_path / "3-variation.png")

        # a syntax error typed at the end: a marker on its line, the message names file:line:column
        page.locator(".CodeMirror").click()
        page.keyboard.press("Control+End")
        page.keyboard.type("\nBroken --> split(")
        page.wait_for_selector(".CodeMirror-lint-marker-error", timeout=10_000)
        assert page.locator("#error").inner_text().startswith("house.grammar:")
        page.screenshot(path=tmp_path / "4-error.png")
        assert (scene.parent / "house.grammar").read_text() == (Path(__file__).parents[2] / "rulesets" /
                                                                "house.grammar").read_text()  # nothing saved
        assert errors == []


def test_extract_a_grammar_from_a_dropped_layout(studio, tmp_path):
    url, _ = studio
    with opened(url) as page:
        page.locator("#inverse-panel summary").click()
        page.locator("#drop").set_input_files(str(Path(__file__).parents[2] / "rulesets" / "cmp_b0035.layout.json"))
        page.wait_for_selector("#facade rect[data-label=door]", timeout=30_000)
        page.locator("#method").select_option("greedy")
        previews = page.evaluate("window.studio.previews")
        page.locator("#extract").click()
        page.wait_for_function("document.getElementById('ruleset').value === 'cmp_b0035.layout.extracted.grammar'",
                               timeout=60_000)
        page.wait_for_function(f"window.studio.previews > {previews}", timeout=30_000)
        assert page.locator("#facade").get_attribute("data-ok") == "true"
        assert "size-independent" in page.locator(".CodeMirror").inner_text()  # the grammar for any face
        assert "Facade" in page.locator("#explain").inner_text() and "rules" in page.locator("#import-summary").inner_text()
        assert not page.locator("#save").is_disabled()  # not saved yet
        page.screenshot(path=tmp_path / "extracted.png")


def test_a_layer_stack_shows_its_account_and_alignment_columns(studio, tmp_path):
    url, scene = studio
    shutil.copy(Path(__file__).parents[2] / "rulesets" / "tenement.layers", scene.parent / "tenement.layers")
    with opened(url) as page:
        page.locator("#ruleset").select_option("tenement.layers")
        page.wait_for_selector("#facade line.column", state="attached", timeout=30_000)
        assert page.locator("#explain").inner_text().startswith("layers ruleset tenement")
        page.screenshot(path=tmp_path / "layers.png")


def test_generate_the_scene_and_see_the_report(studio, tmp_path):
    url, scene = studio
    with opened(url) as page:
        assert page.locator("#ruleset").input_value() == "../shared/apartment.grammar"
        page.evaluate("""() => { const cm = document.querySelector('.CodeMirror').CodeMirror;
                                 cm.setValue(cm.getValue().replace('terminal(window', 'terminal(blind')); }""")
        page.locator("#format").select_option(".glb")
        page.locator("#generate").click()
        page.wait_for_selector("#download:not([hidden])", timeout=120_000)
        report = page.locator("#report").inner_text()
        assert "written 2 buildings" in report and "unsaved edits of ../shared/apartment.grammar" in report
        assert page.locator("#download").get_attribute("href").endswith("studio-out%2Fscene.glb")
        page.screenshot(path=tmp_path / "generated.png")
    assert (scene.parent / "studio-out" / "scene.glb").is_file()
    shared = scene.parent.parent / "shared" / "apartment.grammar"
    assert shared.read_text() == (Path(__file__).parents[2] / "rulesets" / "apartment.grammar").read_text()


SHARED = Path(__file__).parents[2].parent / "shared" / "data" / "cmp_facade" / "base"


@pytest.mark.skipif(not (SHARED / "cmp_b0001.xml").is_file(), reason="needs the shared CMP facade data")
def test_import_options_cmp_tolerances_and_a_photo_crop(studio, tmp_path):
    url, _ = studio
    with opened(url) as page:
        page.locator("#inverse-panel summary").click()
        page.locator("#photo-width").fill("10")
        page.locator("#drop").set_input_files([str(SHARED / "cmp_b0001.xml"), str(SHARED / "cmp_b0001.png")])
        page.wait_for_function("document.getElementById('import-summary').textContent.includes('snap 0.01')",
                               timeout=30_000)
        page.locator("#snap").fill("0.05")
        page.locator("#element-caps").uncheck()
        page.locator("#reimport").click()
        page.wait_for_function("document.getElementById('import-summary').textContent.includes("
                               "'snap 0.05, align 0.025, equal sizes 0.03, no element caps')", timeout=30_000)

        page.locator("#parser").select_option("contrast")
        page.locator("#drop").set_input_files(str(SHARED / "cmp_b0001.jpg"))
        page.wait_for_function("document.getElementById('import-summary').textContent.includes('contrast parser)')",
                               timeout=60_000)
        box = page.locator("#photo").bounding_box()  # a drag across the middle of the photo sets the crop
        page.mouse.move(box["x"] + 0.2 * box["width"], box["y"] + 0.1 * box["height"])
        page.mouse.down()
        page.mouse.move(box["x"] + 0.8 * box["width"], box["y"] + 0.9 * box["height"], steps=5)
        page.mouse.up()
        page.wait_for_function(
            "document.getElementById('import-summary').textContent.includes('contrast parser, crop')", timeout=60_000)
        crop = [float(v) for v in page.locator("#crop").input_value().split()]
        natural = page.evaluate("[document.getElementById('photo').naturalWidth, "
                                "document.getElementById('photo').naturalHeight]")
        assert crop[0] == pytest.approx(0.2 * natural[0], abs=3) and crop[3] == pytest.approx(0.9 * natural[1], abs=3)
        page.screenshot(path=tmp_path / "crop.png")
