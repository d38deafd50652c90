"""The city's work in tiles (issue 24, memory at scale): the main process holds mass plans, a tile's task makes its
masses and neighbour covers, the same as the whole city's."""
from __future__ import annotations

import pickle

import numpy as np
import pytest
from shapely.geometry import MultiPolygon, Polygon

from citygen.footprints import Footprint
from citygen.mass import MassPlan, build_mass, neighbour_cover, neighbours
from citygen.roofplan import mass_plan, plan_mass
from citygen.scene import load_scene
from citygen.tilework import Spill, Spilled, Strips, tile_of, tile_works, work_items


def _row(n: int = 9) -> list[Footprint]:
    """Row houses 8 m wide sharing party walls, of growing heights; the fourth one set back 0.2 m (its
    neighbours' walls against it partly free), the last reaching over the next tile's border."""
    prints = []
    for k in range(n):
        x, y = 8.0 * k, 0.2 if k == 3 else 0.0
        width = 20.0 if k == n - 1 else 8.0
        prints.append(Footprint(id=f"b{k}", polygon=Polygon([(x, y), (x + width, y), (x + width, 10), (x, 10)]),
                                height=6.0 + k, height_source="height", height_is_total=True))
    return prints


def _plans(small_scene, prints):
    scene = load_scene(small_scene)
    roofs = {}
    return [mass_plan(p, scene, roofs)[0] for p in prints]


def test_a_mass_plan_makes_the_mass_plan_mass_makes(small_scene):
    scene = load_scene(small_scene)
    for footprint in _row(3):
        assert mass_plan(footprint, scene, {})[0].mass() == plan_mass(footprint, scene, {})[0]


def test_tiles_get_the_neighbour_cover_of_the_whole_city_across_their_borders(small_scene):
    """Regression (memory at scale): covers measured per tile, with the buildings of other tiles around, are the
    same numbers as the whole city's -- a wall on a tile border stays a party wall."""
    prints = _row()
    plans = _plans(small_scene, prints)
    names = [p.id for p in prints]
    whole = dict(zip(names, neighbour_cover([plan.mass() for plan in plans])))
    works = tile_works(prints, plans, names, [tile_of(plan, 20.0) for plan in plans])
    assert [w.tile for w in works] == [(0, 0), (1, 0), (2, 0), (3, 0)]
    assert [len(w) for w in works] == [2, 3, 2, 2]
    items, skipped = work_items(works)
    assert skipped == []
    assert [name for _, _, _, name, _ in items] == names
    assert whole["b1"][1].min() == 7.0 and whole["b2"][3].min() == 7.0  # (their party wall: two tiles' border)
    for footprint, mass, cover, name, tile in items:
        assert np.array_equal(cover, whole[name]), name
        assert mass == plans[names.index(name)].mass()


def test_a_tile_carries_only_the_neighbours_that_may_stand_against_it(small_scene):
    prints = _row()
    plans = _plans(small_scene, prints)
    works = tile_works(prints, plans, [p.id for p in prints], [tile_of(plan, 20.0) for plan in plans])
    assert [[plans.index(p) for p in w.unpacked()[1]] for w in works] == [[2], [1, 5], [4, 7], [6]]


def test_neighbours_are_the_outlines_within_reach_of_each_other():
    boxes = [Polygon([(x, 0), (x + 5, 0), (x + 5, 5), (x, 5)]) for x in (0.0, 5.0, 10.5, 30.0)]
    pairs = neighbours(boxes, offset=0.3)
    assert sorted(map(tuple, pairs.T.tolist())) == [(0, 1), (1, 0), (1, 2), (2, 1)]
    assert neighbours([]).shape == (2, 0)


def test_a_mass_plan_is_what_build_mass_extrudes():
    footprint = Footprint(id="c", polygon=Polygon([(0, 0), (30, 0), (30, 30), (0, 30)],
                                                  [[(10, 10), (20, 10), (20, 20), (10, 20)]]),
                          height=9.0, height_source="height", base=2.0)
    mass = build_mass(footprint)
    assert MassPlan(mass.outline, 2.0, 9.0).mass() == mass


def test_the_packed_tiles_are_spilled_and_read_back_where_a_tile_is_built(small_scene, tmp_path):
    """Regression (main-process memory at scale): the main process held every tile's packed work (~0.45 kB a
    building) until the last tile was built; the planning child now appends each tile's bytes to a spill file as it
    packs them and the main process keeps where they lie -- the same bytes, read back by the tile's task."""
    prints = _row()
    plans = _plans(small_scene, prints)
    args = (prints, plans, [p.id for p in prints], [tile_of(plan, 20.0) for plan in plans])
    spill = Spill(tmp_path / "tiles.spill")
    spill.reset()
    held, spilled = tile_works(*args), tile_works(*args, spill)
    assert all(isinstance(w.packed, Spilled) for w in spilled)
    assert [w.loaded() for w in spilled] == held
    assert spill.path.stat().st_size == sum(len(w.packed) for w in held) > len(pickle.dumps(spilled))
    assert work_items(spilled)[0][3][3] == work_items(held)[0][3][3] == "b3"


def _city(seed: int = 3) -> list[Footprint]:
    """Rows of houses of random widths sharing party walls (across any tile border), some set back, a few long
    slabs reaching over several tiles, and an L-shaped MultiPolygon."""
    rng = np.random.default_rng(seed)
    prints = []
    for row in range(6):
        x = -37.0
        while x < 120.0:
            width = rng.uniform(4, 14) if rng.random() > 0.1 else rng.uniform(40, 70)
            y = 13.0 * row - 30.0 + (0.25 if rng.random() < 0.2 else 0.0)
            prints.append(Footprint(id=f"r{row}x{x:.2f}", polygon=Polygon([(x, y), (x + width, y),
                                                                            (x + width, y + 11), (x, y + 11)]),
                                    height=float(rng.uniform(5, 20)), height_source="height", height_is_total=True))
            x += width + (0.0 if rng.random() < 0.8 else 0.5)
    prints.append(Footprint(id="ell", polygon=MultiPolygon([Polygon([(130, 0), (150, 0), (150, 8), (130, 8)]),
                                                           Polygon([(130, 9), (138, 9), (138, 30), (130, 30)])]),
                            height=9.0, height_source="height", height_is_total=True))
    return prints


@pytest.mark.parametrize("size", [7.0, 20.0, 55.0, 500.0])
@pytest.mark.parametrize("columns", [1, 2, 3, 1000])
def test_planning_in_strips_gives_the_tiles_of_the_whole_city(small_scene, tmp_path, size, columns):
    """Issue 24 (planning in bounded memory): the buildings put aside as planned and packed a strip of tile columns
    at a time give the whole city's tiles byte for byte -- the same members in the same order, and the same
    neighbours from other tiles (across the strip's borders too: party walls, slabs over several tiles)."""
    prints = _city()
    plans = _plans(small_scene, prints)
    names = [p.id for p in prints]
    tiles = [tile_of(plan, size) for plan in plans]
    whole = tile_works(prints, plans, names, tiles)
    strips = Strips()
    for footprint, plan, name, tile in zip(prints, plans, names, tiles):
        strips.add(footprint, plan, name, tile)
    spill = Spill(tmp_path / "tiles.spill")
    spill.reset()
    assert list(strips.works(columns=columns)) == whole
    assert [w.loaded() for w in strips.works(spill, columns)] == whole
    strips.close()
    crossing = sum(len(w.unpacked()[1]) for w in whole)
    assert crossing > (0 if size == 500.0 else 10)  # (neighbours across tile borders: what the strips must find)


def test_a_city_planned_in_strips_builds_the_items_of_the_whole_city(small_scene):
    prints = _city(5)
    plans = _plans(small_scene, prints)
    names = [p.id for p in prints]
    tiles = [tile_of(plan, 20.0) for plan in plans]
    strips = Strips()
    for footprint, plan, name, tile in zip(prints, plans, names, tiles):
        strips.add(footprint, plan, name, tile)
    streamed, whole = work_items(list(strips.works()))[0], work_items(tile_works(prints, plans, names, tiles))[0]
    strips.close()
    assert [item[3] for item in streamed] == [item[3] for item in whole]
    assert all(np.array_equal(a[2], b[2]) and a[1] == b[1] for a, b in zip(streamed, whole))
    assert len(streamed) == len(prints)
