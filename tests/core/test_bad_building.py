"""One bad building never fails a tile (issue 24, hardening at scale): a building whose mass, wall faces,
neighbour cover, build or stage writing raises is skipped with its id, source and the reason, the other buildings
of its tile and the tile's layer are written -- the same buildings and reasons whether tile tasks build the city
(in worker processes or here) or it is built building by building."""
from __future__ import annotations

import json
from pathlib import Path

import pytest
from pxr import Usd

from citygen import builder, tilework
from citygen.mass import MassPlan
from citygen.pipeline import generate_city
from citygen.scene import load_scene
from citygen.usd import writer
from citygen.usd.validate import validate_stage
from tests.conftest import SMALL_CITY
from tests.usd_util import buildings

#: way/1's outline bounds: it shares its tile (40 m tiles) and a party wall with way/2.
BAD_BOUNDS = (0.0, 0.0, 20.0, 12.0)
#: How a city is built: tile layers or one file, and jobs. With 40 m tiles, two tiles: tile tasks (in two worker
#: processes, or here); one file: building by building.
PATHS = {"tile tasks in workers": ("true", 2), "tile tasks here": ("true", 1), "building by building": ("false", 1)}


def _run(small_scene: Path, registry, path: str):
    tile_layers, jobs = PATHS[path]
    small_scene.write_text(small_scene.read_text().split("[output]")[0]
                           + f'[output]\npath = "out/small.usdc"\ntile_size = 40\ntile_layers = {tile_layers}\n')
    report = generate_city(load_scene(small_scene), registry=registry, jobs=jobs)
    stage = Usd.Stage.Open(str(report.stats.path))
    assert [f for f in validate_stage(stage) if f.severity == "error"] == []
    return report, sorted(p.GetName() for p in buildings(stage))


def _raising_for_way_1(monkeypatch, step: str) -> None:
    """Make ``step`` raise ZeroDivisionError("boom") for way/1 only (forked workers inherit the patch)."""
    def boom():
        raise ZeroDivisionError("boom")

    if step == "making its wall faces":
        mass = MassPlan.mass
        monkeypatch.setattr(MassPlan, "mass", lambda self: boom() if self.outline.bounds == BAD_BOUNDS else mass(self))
    elif step == "measuring its neighbour cover":
        cover = tilework.neighbour_cover

        def patched(masses, *args, **kwargs):
            if any(m.outline.bounds == BAD_BOUNDS for m in masses):
                boom()
            return cover(masses, *args, **kwargs)
        monkeypatch.setattr(tilework, "neighbour_cover", patched)
    elif step == "building it":  # (the building's pivot: made after the builder's own guard)
        pivot = builder.building_pivot
        monkeypatch.setattr(builder, "building_pivot",
                            lambda footprint, mass: boom() if footprint.id == "way/1" else pivot(footprint, mass))
    else:
        write = writer._write_building
        monkeypatch.setattr(writer, "_write_building",
                            lambda w, parent, record, *a: boom() if record.name == "way_1" else write(w, parent,
                                                                                                    record, *a))


@pytest.mark.parametrize("step", ["making its wall faces", "measuring its neighbour cover", "building it",
                                  "writing it to the stage"])
def test_a_building_that_raises_skips_itself_not_its_tile(small_scene, test_registry, monkeypatch, step):
    """Regression: a building's step raising inside a tile task failed the whole tile (its mass and cover were made
    for the tile at once, its pivot and its stage writing had no guard), and one the stage writer failed on failed
    the whole one-file city. way/2, in way/1's tile, is written; every path skips way/1 with the same reason,
    naming its source."""
    _raising_for_way_1(monkeypatch, step)
    for path in PATHS:
        report, names = _run(small_scene, test_registry, path)
        assert names == ["way_2", "way_3"], path
        skipped = {s.id: (s.reason, s.where) for s in report.skipped}
        assert skipped.keys() == {"way/1", "way/bad"}, path
        assert skipped["way/1"] == (f"internal error ZeroDivisionError {step}: boom", "city.local.json[0]"), path


@pytest.mark.parametrize("far_x, shown", [(1e200, "1e+200"), (1e7, "1e+07")])
def test_a_footprint_longer_than_any_building_is_skipped_on_every_path(small_scene, test_registry, far_x, shown):
    """Regressions: a valid footprint 1e200 m long overflowed its centroid and stopped the whole city with an
    OverflowError while its tile was found; one 1e7 m long (millimetres read as metres) hung the facade derivation.
    Both are skipped, saying what is wrong and what to check."""
    far = {"id": "way/far", "coordinates": [[[0, 100], [far_x, 100], [far_x, 112], [0, 112], [0, 100]]],
           "height": 9.0}
    (small_scene.parent / "city.local.json").write_text(json.dumps([*SMALL_CITY, far]))
    for path in PATHS:
        report, names = _run(small_scene, test_registry, path)
        assert names == ["way_1", "way_2", "way_3"], path
        (reason,) = [s.reason for s in report.skipped if s.id == "way/far"]
        assert reason.startswith("cannot build its mass: its outline spans ")
        assert f"(bounds 0, 100, {shown}, 112)" in reason
        assert "longer than any building (10,000 m at most)" in reason
        assert reason.endswith("-- check the source's coordinates, their units and CRS")


@pytest.mark.parametrize("step", ["making its wall faces", "measuring its neighbour cover"])
def test_a_mass_only_city_skips_the_same_building_with_the_same_reason(small_scene, test_registry, monkeypatch, step):
    _raising_for_way_1(monkeypatch, step)
    small_scene.write_text(small_scene.read_text().split("[output]")[0]
                           + '[output]\npath = "out/small.usdc"\ntile_size = 40\nmasses = true\n')
    report = generate_city(load_scene(small_scene), registry=test_registry)
    assert report.written == 2
    skipped = {s.id: (s.reason, s.where) for s in report.skipped}
    assert skipped["way/1"] == (f"internal error ZeroDivisionError {step}: boom", "city.local.json[0]")


def test_a_one_file_stage_leaves_out_the_building_its_writer_fails_on(small_scene, test_registry, monkeypatch):
    """Regression (issue 24): on the one-file path the root layer is written in place, and a building record the
    stage writer raised on failed the whole run. Now what the writer authored of it is taken back and the run
    goes on: the stage holds the others, with the figures of the buildings written."""
    _raising_for_way_1(monkeypatch, "writing it to the stage")
    report, names = _run(small_scene, test_registry, "building by building")
    assert names == ["way_2", "way_3"] and report.written == report.stats.buildings == 2
    (reason,) = [s.reason for s in report.skipped if s.id == "way/1"]
    assert reason == "internal error ZeroDivisionError writing it to the stage: boom"
