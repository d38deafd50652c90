"""Start-up cost (issue 24): loading the plugins does not import what only some rulesets need, so a run (and each
of its worker processes) pays only for the kinds it uses."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

RULESET = Path(__file__).resolve().parents[2] / "rulesets" / "residential_house.layers"
SCENE = Path(__file__).resolve().parents[2] / "scenes" / "helsinki.toml"
#: Modules a city without layer stacks or SAFE rulesets never needs (solvers and what they import).
LAZY = ["citygen_layers.solver", "citygen_layers.sizing", "citygen_safe.generate", "citygen_safe.optimise",
        "citygen_photo.photo", "scipy.spatial", "scipy.ndimage"]


def _loaded_after(code: str) -> set[str]:
    out = subprocess.run([sys.executable, "-c", f"import sys, json\n{code}\nprint(json.dumps(sorted(sys.modules)))"],
                         capture_output=True, text=True, check=True).stdout
    return set(json.loads(out.splitlines()[-1]))


def test_loading_the_registry_and_the_command_line_imports_no_solver_of_an_unused_kind():
    loaded = _loaded_after("from citygen.cli import build_parser\nfrom citygen.registry import default_registry\n"
                           "build_parser(default_registry())")
    assert {"citygen_layers.plugin", "citygen_safe.plugin"} <= loaded
    assert not loaded & set(LAZY)


def test_a_kind_imports_its_solver_on_first_use():
    loaded = _loaded_after(
        "from citygen.registry import default_registry\n"
        "from citygen.request import FacadeRequest\n"
        "kind = default_registry().ruleset_kind('layers')\n"
        f"ruleset = kind.load(__import__('pathlib').Path({str(RULESET)!r}))\n"
        "kind.generate(ruleset, FacadeRequest.preview(10.0, 9.0, 3.0))")
    assert {"citygen_layers.solver", "citygen_layers.sizing"} <= loaded


def test_the_command_line_and_the_footprints_planning_import_no_usd():
    """The planning child is forked before the stage writer is imported (citygen.pipeline._generate), so that the
    main process imports USD while the child plans: neither the command line, the registry, the scene nor the
    planning may import ``pxr`` (prim names are made without it: citygen.usd.names)."""
    loaded = _loaded_after(
        "from pathlib import Path\nfrom citygen.cli import build_parser\n"
        "from citygen.registry import default_registry\nfrom citygen.scene import load_scene\n"
        "from citygen import pipeline\nfrom citygen.tilework import Spill\nimport tempfile\n"
        "registry = default_registry()\nbuild_parser(registry)\n"
        f"scene = load_scene(Path({str(SCENE)!r}), registry.roof_builders, registry.ruleset_kinds)\n"
        "with tempfile.TemporaryDirectory() as tmp:\n"
        "    planned = pipeline._plan(scene, registry, registry.roof_builders, Spill(Path(tmp) / 'spill'))\n"
        "    assert sum(map(len, planned.works)) > 400")
    assert not {m for m in loaded if m == "pxr" or m.startswith("pxr.")}
