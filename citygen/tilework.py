"""The city's work cut into tiles: what the pipeline's main process holds per building, and what it sends a tile's
task.

The main process plans every building's mass (:class:`~citygen.mass.MassPlan`: outline, heights, roof -- a few
objects each; tiling, the ground and the neighbour cover's neighbours need no more) and then keeps each tile's work
pickled, as it is sent to a task anyway: a :class:`TileWork` packs one tile's buildings and the plans of the
buildings of other tiles that may stand against them, ~0.45 kB a building where the objects took ~6 kB. Its
:meth:`~TileWork.items` -- the masses with their faces and neighbour covers -- are made where the tile is built, one
tile at a time, and are the same as the whole city's would be.
"""
from __future__ import annotations

import math
import pickle
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from citygen.footprints import Footprint
from citygen.mass import Mass, MassPlan, neighbour_cover, neighbours

#: A work item of the builder: footprint, mass, neighbour cover, prim name, tile.
Work = tuple[Footprint, Mass, np.ndarray, str, tuple[int, int]]


@dataclass(frozen=True)
class TileWork:
    """One tile's work, packed: its buildings (footprint, mass plan, prim name; in prim name order) and the plans
    of the buildings of other tiles around them (:func:`~citygen.mass.neighbours`), pickled; ``count``: how many
    buildings."""

    tile: tuple[int, int]
    count: int
    packed: bytes

    @classmethod
    def pack(cls, tile: tuple[int, int], buildings: Sequence[tuple[Footprint, MassPlan, str]],
             around: Sequence[MassPlan] = ()) -> TileWork:
        return cls(tile, len(buildings), pickle.dumps((tuple(buildings), tuple(around)),
                                                      protocol=pickle.HIGHEST_PROTOCOL))

    def __len__(self) -> int:
        return self.count

    def unpacked(self) -> tuple[tuple[tuple[Footprint, MassPlan, str], ...], tuple[MassPlan, ...]]:
        """The buildings and the plans around them."""
        return pickle.loads(self.packed)

    def items(self) -> list[Work]:
        """The builder's work items of this tile: the masses with their faces and neighbour covers."""
        buildings, around = self.unpacked()
        masses = [plan.mass() for _, plan, _ in buildings]
        covers = neighbour_cover(masses, around=around)
        return [(footprint, mass, cover, name, self.tile)
                for (footprint, _, name), mass, cover in zip(buildings, masses, covers)]


def tile_of(plan: MassPlan, size: float) -> tuple[int, int]:
    """The tile (column, row) of ``size`` metres holding the centroid of the plan's outline."""
    centroid = plan.outline.centroid
    return math.floor(centroid.x / size), math.floor(centroid.y / size)


def tile_works(footprints: Sequence[Footprint], plans: Sequence[MassPlan], names: Sequence[str],
               size: float) -> list[TileWork]:
    """The buildings (``footprints[k]``, ``plans[k]``, ``names[k]``) in tiles of ``size`` metres, in tile order,
    each tile with the plans of its neighbours in other tiles."""
    tiles = [tile_of(plan, size) for plan in plans]
    order = sorted(range(len(plans)), key=lambda k: (tiles[k], names[k]))
    members: dict[tuple[int, int], list[int]] = {}
    for k in order:
        members.setdefault(tiles[k], []).append(k)
    others: defaultdict[tuple[int, int], set[int]] = defaultdict(set)
    for i, j in neighbours([plan.outline for plan in plans]).T.tolist():
        if tiles[i] != tiles[j]:
            others[tiles[i]].add(j)
    return [TileWork.pack(tile, [(footprints[k], plans[k], names[k]) for k in ks],
                          [plans[j] for j in sorted(others[tile])])
            for tile, ks in members.items()]


def work_items(works: Sequence[TileWork]) -> list[Work]:
    """Every tile's :meth:`~TileWork.items`, in tile order: the whole city's, for the paths that build it
    building by building."""
    return [item for work in works for item in work.items()]
