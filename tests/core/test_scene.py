import pytest

from citygen.errors import SceneError
from citygen.registry import default_registry
from citygen.scene import load_scene

BASE = '''[scene]
name = "t"
seed = 1

[footprints]
path = "city.geojson"
default_height = 9

[defaults]
floor_height = 3.0

[[assign]]
when = { building = ["church", "cathedral"] }
ruleset = "a.grammar"

[[assign]]
when = { levels = ">= 5" }
ruleset = ["a.grammar", "b.grammar"]

[[assign]]
ruleset = "b.grammar"
'''


def write(tmp_path, text):
    for name in ("a.grammar", "b.grammar"):
        (tmp_path / name).write_text("")
    (tmp_path / "s.toml").write_text(text)
    return tmp_path / "s.toml"


def test_scene_parses_and_matches(tmp_path):
    scene = load_scene(write(tmp_path, BASE))
    assert scene.seed == 1 and scene.defaults.floor_height == 3.0
    assert scene.footprint_options == {"default_height": 9}
    church, tall, other = scene.assignments
    assert church.matches({"building": "church"}) and not church.matches({"building": "yes"})
    assert tall.matches({"levels": 7}) and not tall.matches({"levels": 3}) and not tall.matches({"levels": None})
    assert len(tall.rulesets) == 2 and other.matches({})


@pytest.mark.parametrize("edit, message, line", [
    (("seed = 1", "seed = -4"), "seed must be", 3),
    (("floor_height = 3.0", "floor_height = 0"), "floor_height must be a finite number of at least 2", 10),
    # regressions: NaN passed every check (a NaN floor height was then blamed on [footprints], a NaN tile size
    # ended in a traceback), storeys of a micrometre were built, and a comparison without a number matched nothing
    (("floor_height = 3.0", "floor_height = nan"), "floor_height must be a finite number", 10),
    (("floor_height = 3.0", "floor_height = 1e-6"), "floor_height must be a finite number of at least 2", 10),
    (("floor_height = 3.0", "floor_height = 3.0\nground_floor_height = nan"), "ground_floor_height must be", 11),
    (("floor_height = 3.0", "floor_height = 3.0\ncorner_width = inf"), "corner_width must be a finite positive", 11),
    (('ruleset = "b.grammar"\n', 'ruleset = "b.grammar"\n[output]\ntile_size = nan\n'), "tile_size must be", 23),
    (('levels = ">= 5"', 'levels = "< abc"'), "a comparison needs a number", 17),
    # regressions: an unknown kind, or a ruleset no kind reads, skipped every building at generation
    (('ruleset = "b.grammar"\n', 'ruleset = "b.grammar"\nkind = "nonsense"\n'), "unknown ruleset kind 'nonsense'",
     20),
    (('ruleset = "b.grammar"\n', 'ruleset = "s.toml"\n'), r"no ruleset kind reads \.toml \(s\.toml\)", 20),
    (('ruleset = "b.grammar"\n', 'ruleset = "b.grammar"\nfallback = "s.toml"\n'), "no ruleset kind reads", 20),
    (("[defaults]", "[defaults]\nfloorheight = 3"), "unknown key 'floorheight'", 10),
    (('ruleset = "b.grammar"\n', 'ruleset = "missing.grammar"\n'), "missing.grammar does not exist", 20),
    (('ruleset = "b.grammar"\n', 'ruleset = "b.grammar"\nfallback = "gone.grammar"\n'), "gone.grammar does not exist",
     20),
    (('ruleset = "b.grammar"\n', 'ruleset = "b.grammar"\nfallback = ["a.grammar"]\n'), "fallback must be a ruleset",
     20),
    (("seed = 1", "seed = = 1"), "not valid TOML", 3),
    (('ruleset = "b.grammar"\n', 'ruleset = "b.grammar"\n[output]\nuvs = "yes"\n'), "uvs must be true or false", 23),
])
def test_scene_errors_name_file_and_line(tmp_path, edit, message, line):
    path = write(tmp_path, BASE.replace(*edit))
    with pytest.raises(SceneError, match=message) as info:
        load_scene(path, kinds=default_registry().ruleset_kinds)
    assert f"s.toml:{line}" in str(info.value)


def test_fallback_ruleset_is_read_relative_to_the_scene(tmp_path):
    scene = load_scene(write(tmp_path, BASE.replace('ruleset = "b.grammar"\n',
                                                    'ruleset = "b.grammar"\nfallback = "a.grammar"\n')))
    assert scene.assignments[2].fallback == (tmp_path / "a.grammar").resolve()
    assert scene.assignments[0].fallback is None


def test_missing_footprints_table(tmp_path):
    with pytest.raises(SceneError, match=r"\[footprints\]"):
        load_scene(write(tmp_path, '[scene]\nseed = 1\n[[assign]]\nruleset = "a.grammar"\n'))
