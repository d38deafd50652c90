"""Start-up cost (issue 24): loading the plugins does not import what only some rulesets need, so a run (and each
of its worker processes) pays only for the kinds it uses."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

RULESET = Path(__file__).resolve().parents[2] / "rulesets" / "residential_house.layers"
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
