"""The studio's keystroke-to-redraw budget: facade preview round trips, one building's build + GLB, start to first
paint.

Run: ``python benchmarks/studio_latency.py [SCENE] [--repeat N] [--browser]``. Prints the median wall and CPU
milliseconds of ``POST /api/preview`` for every shipped ruleset at 20 x 15 m and of ``POST /api/build`` (layouts +
GLB) for the scene's first buildings, through Starlette's test client (HTTP handling in process, no network): *edit*
is a text the studio has not seen (a keystroke: a comment line with a new number appended, so nothing is remembered
but the kinds' own per-process caches), *same* the text again (the studio answers from memory: a size toggled back, a
building reselected). CPU is the process's (every thread's) time: the machine is shared, so wall times vary with its
load. With ``--browser``, also the time from starting ``citygen studio`` to the page's first paint, its editor ready
and the map drawn in headless Chromium.
"""
from __future__ import annotations

import argparse
import re
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

from citygen_studio.app import create_app
from citygen_studio.session import Session
from starlette.testclient import TestClient

from citygen.registry import default_registry

REPO = Path(__file__).resolve().parents[1]


def timed(call, repeat: int) -> tuple[float, float]:
    """Median wall and CPU milliseconds of ``call(k)`` for ``k`` in ``range(repeat)``."""
    walls, cpus = [], []
    for k in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        call(k)
        walls.append(1000 * (time.perf_counter() - t0))
        cpus.append(1000 * (time.process_time() - c0))
    return statistics.median(walls), statistics.median(cpus)


def first_paint(scene: Path) -> dict[str, float]:
    """Seconds from starting ``citygen studio`` (headless Chromium already running, as a user's browser is) to: its
    URL printed, the page's first paint, the editor showing a ruleset, the map drawn."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path="/usr/bin/chromium",
                                    args=["--no-sandbox", "--use-gl=swiftshader", "--enable-unsafe-swiftshader"])
        page = browser.new_page()
        t0 = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "citygen.launch", "studio", str(scene), "--no-browser"],
                                stdout=subprocess.PIPE, text=True)
        try:
            url = re.search(r"http://\S+", proc.stdout.readline()).group(0)
            times = {"url": time.perf_counter() - t0}
            page.goto(url, wait_until="commit")
            page.wait_for_function("performance.getEntriesByName('first-paint').length > 0", timeout=60_000)
            times["first paint"] = time.perf_counter() - t0
            page.wait_for_function("document.querySelector('.CodeMirror') && "
                                   "document.querySelector('.CodeMirror').CodeMirror.getValue().length > 0",
                                   timeout=60_000)
            times["editor"] = time.perf_counter() - t0
            page.wait_for_selector("#map path", timeout=60_000)
            times["map"] = time.perf_counter() - t0
        finally:
            proc.terminate()
            proc.wait()
            browser.close()
    return times


def print_paint(scene: Path) -> None:
    c0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    times = first_paint(scene)
    c1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = c1.ru_utime + c1.ru_stime - c0.ru_utime - c0.ru_stime
    print("start to " + ", ".join(f"{what} {seconds:.2f} s" for what, seconds in times.items())
          + f" (studio process CPU {cpu:.2f} s until stopped)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(REPO / "scenes" / "helsinki.toml"))
    parser.add_argument("--repeat", type=int, default=9)
    parser.add_argument("--buildings", type=int, default=5)
    parser.add_argument("--browser", action="store_true", help="also measure start to first paint in Chromium")
    parser.add_argument("--paint-only", action="store_true", help="only measure start to first paint")
    args = parser.parse_args()
    scene = Path(args.scene).resolve()
    if args.paint_only:
        print_paint(scene)
        return
    t0 = time.perf_counter()
    session = Session(default_registry(), scene)
    print(f"scene loaded in {time.perf_counter() - t0:.2f} s ({len(session.footprints)} buildings)")
    client = TestClient(create_app(session), base_url="http://127.0.0.1")
    print(f"{'preview 20 x 15 m':<30} {'edit wall':>9} {'edit CPU':>9} {'same wall':>9} {'same CPU':>9}  (ms)")
    for path in sorted((REPO / "rulesets").iterdir()):
        if not any(path.name.endswith(s) for k in session.registry.ruleset_kinds.values() for s in k.suffixes):
            continue
        name = session.confinement.show(str(path))
        if not session.confinement.named or path.resolve() not in session.confinement.named:
            session.confinement.named.add(path.resolve())  # (the benchmark previews every shipped ruleset)
        text = path.read_text()
        body = {"ruleset": name, "text": text, "width": 20, "height": 15, "floor_height": 3.3}
        assert client.post("/api/preview", json=body).json()["ok"], name
        edit = timed(lambda k: client.post("/api/preview", json={**body, "text": f"{text}\n# edit {k}\n"}),
                     args.repeat)
        same = timed(lambda k: client.post("/api/preview", json=body), args.repeat)
        print(f"{path.name:<30} {edit[0]:>9.1f} {edit[1]:>9.1f} {same[0]:>9.1f} {same[1]:>9.1f}")
    print(f"{'build + GLB':<30} {'edit wall':>9} {'edit CPU':>9} {'same wall':>9} {'same CPU':>9} {'GLB kB':>7}")
    buildings = client.get("/api/buildings").json()["buildings"]
    for index in range(min(args.buildings, len(session.footprints))):
        built = client.post("/api/build", json={"index": index}).json()
        size = len(built.get("glb", "")) * 3 / 4 / 1000
        ruleset = buildings[index]["rulesets"]["street"]
        text = client.get("/api/ruleset", params={"name": ruleset}).json()["text"] if ruleset else None
        repeat = max(3, args.repeat // 3)
        edit = timed(lambda k: client.post("/api/build", json={
            "index": index, "rulesets": {ruleset: f"{text}\n# edit {k}\n"} if ruleset else {}}), repeat)
        same = timed(lambda k: client.post("/api/build", json={"index": index}), repeat)
        print(f"{buildings[index]['id']:<30} {edit[0]:>9.1f} {edit[1]:>9.1f} {same[0]:>9.1f} {same[1]:>9.1f} "
              f"{size:>7.0f}")
    if args.browser:
        print_paint(scene)


if __name__ == "__main__":
    main()
