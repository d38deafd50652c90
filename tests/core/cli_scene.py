"""A small real scene (the shipped house grammar, four GeoJSON buildings) for tests that run ``citygen`` as a user
does: in process through ``citygen.cli.main`` or as a separate process."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from tests.mini_scene import rect

REPO = Path(__file__).resolve().parents[2]


def write_scene(folder: Path, buildings: int = 4, extra_output: str = "") -> Path:
    """``folder/city.toml`` over ``buildings`` 12 x 9 m houses in a row, written to ``out/city.usdc``."""
    features = [{"type": "Feature", "properties": {"id": k, "osm_type": "way", "building:levels": "2"},
                 "geometry": {"type": "Polygon", "coordinates": [rect(20.0 * (k % 50), 20.0 * (k // 50), 12, 9)]}}
                for k in range(buildings)]
    (folder / "city.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": features}))
    scene = folder / "city.toml"
    scene.write_text(f'[scene]\nseed = 1\n[footprints]\npath = "city.geojson"\n[[assign]]\n'
                     f'ruleset = "{(REPO / "rulesets" / "house.grammar").as_posix()}"\n'
                     f'[output]\npath = "out/city.usdc"\n{extra_output}')
    return scene


def citygen_process(*args: str, preexec=None, **kw) -> subprocess.Popen:
    """``python -m citygen.cli ARGS`` as its own process (stdout and stderr piped, text)."""
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.Popen([sys.executable, "-m", "citygen.cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env, cwd=REPO, preexec_fn=preexec, **kw)
