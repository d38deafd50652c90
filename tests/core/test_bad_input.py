"""Bad layout JSON and scene files found by fuzzing (benchmarks/fuzz_readers.py) give a LayoutError or
SceneError naming the file and what is wrong, not a traceback."""
from __future__ import annotations

import json
import random
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from citygen.errors import CitygenError, LayoutError, SceneError
from citygen.layout import FacadeLayout
from citygen.scene import load_scene

from ..mutate import mutate, scratch_rulesets

REPO = Path(__file__).resolve().parents[2]
LAYOUTS = sorted((REPO / "rulesets").glob("*.layout.json"))
SCENES = sorted((REPO / "scenes").glob("*.toml"))
REGION = {"x": 0, "y": 0, "w": 2, "h": 1, "symbol": "Wall", "label": "wall"}


def layout_text(**region) -> str:
    return json.dumps({"schema_version": 1, "width": 2, "height": 1, "root": {**REGION, **region}})


@pytest.mark.parametrize("text, words", [
    ("[1, 2]", "a layout is a JSON object, not list"),                        # was: AttributeError
    ('{"schema_version": 1, "width": 2, "height": 1}', "layout has no root region"),  # was: KeyError 'root'
    ('{"schema_version": 1, "width": 1e400, "height": 1, "root": {}}', "finite positive width and height"),
    ('{"schema_version": 1, "width": 2, "height": 1, "meta": 3, "root": {}}', "meta must be a JSON object"),
    (layout_text(h=10 ** 400), "region root has h = 1000"),                 # was: OverflowError
    (layout_text(depth=float("inf")), "region root has depth = inf, not a finite number"),
    (layout_text(depth=1e308), "region root has depth = 1e+308 m, beyond +-100 m"),  # was: OverflowError (modules)
    (layout_text(w=float("nan")), "region root has w = nan"),
    (layout_text(w=-1), "region root has a negative size"),
    (layout_text(label={}), "region root has label = {}, not a string"),  # was: TypeError unhashable in safe
    (layout_text(children=[5]), "region root.children[0] is int, not a JSON object"),
    (layout_text(children={"x": 1}), "region root has children = {'x': 1}, not a list"),
])
def test_malformed_layout_json_is_a_layout_error_naming_file_and_region(text, words):
    with pytest.raises(LayoutError) as info:
        FacadeLayout.loads(text, "f.layout.json")
    assert str(info.value).startswith("f.layout.json: ") and words in str(info.value)


def test_scene_ruleset_path_too_long_for_the_file_system_is_a_scene_error(tmp_path):
    # was: OSError [Errno 36] File name too long from Path.exists()
    scene = tmp_path / "s.toml"
    scene.write_text(f'[footprints]\npath = "c.geojson"\n\n[[assign]]\nruleset = "{"x" * 5000}.grammar"\n')
    with pytest.raises(SceneError) as info:
        load_scene(scene)
    assert str(info.value.where) == f"{scene}:4" and "does not exist" in str(info.value)
    assert len(str(info.value)) < 600


def test_scene_that_is_not_utf8_is_a_scene_error(tmp_path):
    (tmp_path / "s.toml").write_bytes(b'[scene]\nname = "caf\xe9"\n')  # was: UnicodeDecodeError
    with pytest.raises(SceneError, match=r"s.toml: scene is not UTF-8 text \(byte 0xe9 at offset 19\)"):
        load_scene(tmp_path / "s.toml")


@settings(max_examples=60, deadline=None)
@given(path=st.sampled_from(LAYOUTS), seed=st.integers(0, 2 ** 32 - 1))
def test_mutated_layout_json_raises_only_layout_errors(path, seed):
    text = mutate(path.read_text(), "json", random.Random(seed))
    try:
        FacadeLayout.loads(text, path.name)
    except LayoutError:
        pass


@pytest.fixture(scope="module")
def scratch(tmp_path_factory):
    root = tmp_path_factory.mktemp("fuzz")
    scratch_rulesets(root)
    (root / "scenes").mkdir()
    return root / "scenes"


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(path=st.sampled_from(SCENES), seed=st.integers(0, 2 ** 32 - 1))
def test_mutated_shipped_scenes_raise_only_citygen_errors(scratch, path, seed):
    target = scratch / "fuzz.toml"
    target.write_text(mutate(path.read_text(), "toml", random.Random(seed)), encoding="utf-8")
    try:
        load_scene(target)
    except CitygenError:
        pass


@pytest.mark.parametrize(("nesting", "message"), [
    (40, r"scene.toml:1: \[footprints\] nests arrays or tables more than 32 levels deep"),
    (5000, r"scene.toml: arrays or tables nested more than 32 levels deep")])
def test_deeply_nested_scene_values_are_a_scene_error(tmp_path, nesting, message):
    """Was: RecursionError from tomllib (about 1000 levels), or from code walking the parsed values."""
    (tmp_path / "scene.toml").write_text(f'[footprints]\npath = "a.geojson"\nx = {"[" * nesting}{"]" * nesting}\n')
    with pytest.raises(SceneError, match=message):
        load_scene(tmp_path / "scene.toml")


@pytest.mark.parametrize(("text", "line"), [
    ('[footprints]\npath = "a.geojson"\n[output]\npath = 3\n', 4),
    ('[footprints]\npath = "a.geojson"\nfloor_height = 3\n[defaults]\nfloor_height = -1\n', 5),
    ('[footprints]\npath = "a.geojson"\nuvs = 1\n[output]\nuvs = 2\n', 5)])
def test_an_error_about_a_key_in_two_tables_names_the_right_line(tmp_path, text, line):
    """Was: the first line with the key anywhere in the file (here in [footprints])."""
    (tmp_path / "scene.toml").write_text(text + '[[assign]]\nruleset = "x.grammar"\n')
    with pytest.raises(SceneError) as info:
        load_scene(tmp_path / "scene.toml")
    assert str(info.value).startswith(f"{tmp_path / 'scene.toml'}:{line}: ")


def test_deeply_nested_layout_json_is_a_layout_error():
    """Regression (hypothesis example cmp_b0035.layout.json, seed 8920906): a mutation nesting arrays past
    Python's recursion limit made ``FacadeLayout.loads`` raise RecursionError instead of a LayoutError."""
    with pytest.raises(LayoutError, match="nested too deeply"):
        FacadeLayout.loads('{"size": [1, 1], "root": ' + "[" * 5000 + "]" * 5000 + "}", "deep.layout.json")
    text = mutate((REPO / "rulesets" / "cmp_b0035.layout.json").read_text(), "json", random.Random(8920906))
    with pytest.raises(LayoutError):
        FacadeLayout.loads(text, "cmp_b0035.layout.json")
