"""The city's work cut into tiles: what the pipeline's main process holds per building, and what it sends a tile's
task.

The planning child plans every building's mass (:class:`~citygen.mass.MassPlan`: outline, heights, roof -- a few
objects each; tiling, the ground and the neighbour cover's neighbours need no more) as the importer hands the
footprints over, puts each building aside in a temporary file (:class:`Strips`, keeping ~0.1 kB of it) and, once
all are planned, packs each tile's work a strip of tile columns at a time, pickled as it is sent to a task anyway:
a :class:`TileWork` packs one tile's buildings and the plans of the buildings of other tiles that may stand
against them, ~0.8 kB a building where the objects took ~6 kB. The packed tiles go to a spill file
(:class:`Spill`) as they are made: the main process holds only where each tile's bytes are
(a :class:`Spilled`, read back when the tile is built), so its memory does not grow with the city. Its
:meth:`~TileWork.items` -- the masses with their faces and neighbour covers -- are made where the tile is built, one
tile at a time, and are the same as the whole city's would be. A building whose mass or cover cannot be made is
skipped there (:func:`failed`), the rest of its tile is built: both ways of building a city -- tile tasks and
building by building -- make their work items here, so they skip the same buildings with the same reasons.
"""
from __future__ import annotations

import math
import pickle
import tempfile
from array import array
from collections import defaultdict
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import shapely

from citygen.errors import CitygenError
from citygen.footprints import Footprint, Skipped
from citygen.mass import COVER_OFFSET, Mass, MassPlan, neighbour_cover, neighbours

#: A work item of the builder: footprint, mass, neighbour cover, prim name, tile.
Work = tuple[Footprint, Mass, np.ndarray, str, tuple[int, int]]


@dataclass(frozen=True)
class Spilled:
    """Where one tile's packed bytes lie in a :class:`Spill` file: ``size`` bytes from ``offset``."""

    path: str
    offset: int
    size: int

    def read(self) -> bytes:
        with open(self.path, "rb") as f:
            f.seek(self.offset)
            data = f.read(self.size)
        if len(data) != self.size:
            raise OSError(f"{self.path}: the spilled tile work ends {self.size - len(data)} bytes short")
        return data


@dataclass(frozen=True)
class Spill:
    """A file the packed tiles are appended to as they are made (by the planning child), and read back from where
    each tile is built (this machine's processes): the main process keeps only each tile's :class:`Spilled`."""

    path: Path

    def reset(self) -> None:
        """Empty the file (a planning that starts again)."""
        self.path.write_bytes(b"")

    def put(self, work: TileWork) -> TileWork:
        """``work`` with its bytes appended to the file and replaced by where they lie."""
        assert isinstance(work.packed, bytes)
        with open(self.path, "ab") as f:
            offset = f.tell()
            f.write(work.packed)
        return replace(work, packed=Spilled(str(self.path), offset, len(work.packed)))


@dataclass(frozen=True)
class TileWork:
    """One tile's work, packed: its buildings (footprint, mass plan, prim name; in prim name order) and the plans
    of the buildings of other tiles around them (:func:`~citygen.mass.neighbours`), pickled -- the bytes, or where
    they lie in a :class:`Spill` file; ``count``: how many buildings, ``pitched``: how many of them carry a roof that
    is not flat (what a mass-only city's build costs, :func:`citygen.lod1.build_cost`)."""

    tile: tuple[int, int]
    count: int
    packed: bytes | Spilled
    pitched: int = 0

    @classmethod
    def pack(cls, tile: tuple[int, int], buildings: Sequence[tuple[Footprint, MassPlan, str]],
             around: Sequence[MassPlan] = ()) -> TileWork:
        return cls.of_pickles(tile, [(_pickled((footprint, name)), _pickled(plan))
                                     for footprint, plan, name in buildings],
                              [_pickled(plan) for plan in around],
                              sum(plan.roof.height is not None for _, plan, _ in buildings))

    @classmethod
    def of_pickles(cls, tile: tuple[int, int], buildings: Sequence[tuple[bytes, bytes]], around: Sequence[bytes],
                   pitched: int) -> TileWork:
        """The work of ``tile`` from its buildings' pickled ``(footprint, prim name)`` and plan, and the pickled
        plans ``around`` them (what :class:`Strips` holds on disk: copied, never unpickled to be packed)."""
        return cls(tile, len(buildings), pickle.dumps((tuple(buildings), tuple(around)),
                                                      protocol=pickle.HIGHEST_PROTOCOL), pitched)

    def __len__(self) -> int:
        return self.count

    def loaded(self) -> TileWork:
        """This work with its bytes in it (read from the spill file): what goes to another machine."""
        return self if isinstance(self.packed, bytes) else replace(self, packed=self.packed.read())

    def unpacked(self) -> tuple[tuple[tuple[Footprint, MassPlan, str], ...], tuple[MassPlan, ...]]:
        """The buildings and the plans around them."""
        buildings, around = pickle.loads(self.loaded().packed)
        made = []
        for pair, plan in buildings:
            footprint, name = pickle.loads(pair)
            made.append((footprint, pickle.loads(plan), name))
        return tuple(made), tuple(map(pickle.loads, around))

    def items(self) -> tuple[list[Work], list[Skipped]]:
        """The builder's work items of this tile -- the masses with their faces and neighbour covers -- and the
        buildings skipped because their mass or cover could not be made."""
        buildings, around = self.unpacked()
        made, skipped = [], []
        for footprint, plan, name in buildings:
            try:
                made.append((footprint, plan.mass(), name))
            except Exception as exc:  # (one building's, not the tile's)
                skipped.append(failed(footprint, exc, "making its wall faces"))
        items = []
        for (footprint, mass, name), cover in zip(made, covers([mass for _, mass, _ in made], around)):
            if isinstance(cover, Exception):
                skipped.append(failed(footprint, cover, "measuring its neighbour cover"))
            else:
                items.append((footprint, mass, cover, name, self.tile))
        return items, skipped


def _pickled(value: object) -> bytes:
    return pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)


def covers(masses: Sequence[Mass], around: Sequence[MassPlan]) -> list[np.ndarray | Exception]:
    """The :func:`~citygen.mass.neighbour_cover` of ``masses``, in one batch; if the batch raises, each mass's own
    with the others around it (the same figures: a sample's depends only on the buildings it falls in), and the
    error of each mass whose own raises."""
    try:
        return neighbour_cover(masses, around=around)
    except Exception:
        found: list[np.ndarray | Exception] = []
        for k, mass in enumerate(masses):
            try:
                found.append(neighbour_cover([mass], around=[*masses[:k], *masses[k + 1:], *around])[0])
            except Exception as exc:
                found.append(exc)
        return found


def failed(footprint: Footprint, exc: Exception, doing: str) -> Skipped:
    """``footprint`` skipped because ``doing`` it (``"making its wall faces"``) raised ``exc``: a
    :class:`~citygen.errors.CitygenError` says what is wrong with the input; anything else is a bug, and the reason
    says it is one."""
    if isinstance(exc, CitygenError):
        return Skipped(footprint.id, f"{exc} ({doing})", footprint.source)
    return Skipped(footprint.id, f"internal error {type(exc).__name__} {doing}: {exc}", footprint.source)


def tile_of(plan: MassPlan, size: float) -> tuple[int, int]:
    """The tile (column, row) of ``size`` metres holding the centroid of the plan's outline (finite: a plan spans at
    most :data:`~citygen.roofplan.MAX_SPAN`)."""
    centroid = plan.outline.centroid
    return math.floor(centroid.x / size), math.floor(centroid.y / size)


def tile_works(footprints: Sequence[Footprint], plans: Sequence[MassPlan], names: Sequence[str],
               tiles: Sequence[tuple[int, int]], spill: Spill | None = None) -> list[TileWork]:
    """The buildings (``footprints[k]``, ``plans[k]``, ``names[k]``) in their ``tiles[k]`` (:func:`tile_of`), in
    tile order, each tile with the plans of its neighbours in other tiles; each tile's bytes put in ``spill`` as it
    is packed (given one). The whole city at once, in memory: what :class:`Strips` gives a strip at a time."""
    order = sorted(range(len(plans)), key=lambda k: (tiles[k], names[k]))
    members: dict[tuple[int, int], list[int]] = {}
    for k in order:
        members.setdefault(tiles[k], []).append(k)
    others: defaultdict[tuple[int, int], set[int]] = defaultdict(set)
    for i, j in neighbours([plan.outline for plan in plans]).T.tolist():
        if tiles[i] != tiles[j]:
            others[tiles[i]].add(j)
    works = []
    for tile, ks in members.items():
        work = TileWork.pack(tile, [(footprints[k], plans[k], names[k]) for k in ks],
                             [plans[j] for j in sorted(others[tile])])
        works.append(work if spill is None else spill.put(work))
    return works


class Strips:
    """The city's planned buildings put aside as they are planned, then packed in tiles a strip at a time: what the
    planning child holds of the whole city is ~0.1 kB a building (tile, bounds, prim name, where its pickles lie),
    never the footprints and plans themselves.

    :meth:`add` appends a building's pickled footprint and prim name, and its pickled plan, to a temporary file;
    :meth:`works` packs the tiles a strip of ``columns`` tile columns at a time, in tile order: the strip's buildings
    and the plans of those that may stand against them (:func:`~citygen.mass.neighbours`, found from the bounds
    alone: wherever they lie, in the strip or not), copied from the file (:meth:`TileWork.of_pickles`), spilled and
    dropped. The tiles are :func:`tile_works`' for the whole city, byte for byte (tests/core/test_tilework.py)."""

    def __init__(self) -> None:
        self.scratch = tempfile.TemporaryFile()  # noqa: SIM115 (no name: gone when closed or the process ends)
        self.end = 0
        self.tiles = array("q")  # (column, row) a building
        self.bounds = array("d")  # (x0, y0, x1, y1) of its outline
        self.places = array("q")  # (offset, footprint's size, plan's size) of its pickles in the scratch file
        self.pitched = bytearray()  # (its roof is not flat)
        self.names: list[str] = []

    def __len__(self) -> int:
        return len(self.names)

    def close(self) -> None:
        self.scratch.close()

    def add(self, footprint: Footprint, plan: MassPlan, name: str, tile: tuple[int, int]) -> None:
        pair, planned = _pickled((footprint, name)), _pickled(plan)
        self.scratch.write(pair + planned)
        self.places.extend((self.end, len(pair), len(planned)))
        self.end += len(pair) + len(planned)
        self.tiles.extend(tile)
        self.bounds.extend(plan.outline.bounds)
        self.pitched.append(plan.roof.height is not None)
        self.names.append(name)

    def _pickles(self, k: int) -> tuple[bytes, bytes]:
        """Building ``k``'s pickled footprint and prim name, and its pickled plan."""
        offset, pair, plan = self.places[3 * k:3 * k + 3]
        self.scratch.seek(offset)
        data = self.scratch.read(pair + plan)
        return data[:pair], data[pair:]

    def works(self, spill: Spill | None = None, columns: int = 1) -> Iterator[TileWork]:
        """The tiles' packed work, in tile order, a strip of ``columns`` tile columns at a time (each tile's bytes
        put in ``spill``, given one)."""
        if not self.names:
            return
        tiles = np.frombuffer(self.tiles, dtype=np.int64).reshape(-1, 2)
        bounds = np.frombuffer(self.bounds, dtype=np.float64).reshape(-1, 4)
        reach = 2 * COVER_OFFSET  # (as :func:`~citygen.mass.neighbours` widens them)
        widened = bounds + np.array([-reach, -reach, reach, reach])
        strip_of = np.searchsorted(np.unique(tiles[:, 0]), tiles[:, 0]) // columns
        for strip in range(int(strip_of.max()) + 1):
            ks = np.flatnonzero(strip_of == strip)
            near = np.flatnonzero((bounds[:, 2] >= widened[ks, 0].min()) & (bounds[:, 0] <= widened[ks, 2].max()))
            at, hit = shapely.STRtree(shapely.box(*bounds[near].T)).query(shapely.box(*widened[ks].T))
            i, j = ks[at], near[hit]
            keep = (i != j) & np.any(tiles[i] != tiles[j], axis=1)
            others: defaultdict[tuple[int, int], set[int]] = defaultdict(set)
            for a, b in zip(i[keep].tolist(), j[keep].tolist()):
                others[tuple(tiles[a].tolist())].add(b)
            members: defaultdict[tuple[int, int], list[int]] = defaultdict(list)
            for k in ks.tolist():
                members[tuple(tiles[k].tolist())].append(k)
            for tile in sorted(members):
                ordered = sorted(members[tile], key=self.names.__getitem__)
                work = TileWork.of_pickles(tile, [self._pickles(k) for k in ordered],
                                           [self._pickles(k)[1] for k in sorted(others[tile])],
                                           sum(self.pitched[k] for k in ordered))
                yield work if spill is None else spill.put(work)


def work_items(works: Sequence[TileWork]) -> tuple[list[Work], list[Skipped]]:
    """Every tile's :meth:`~TileWork.items` and skipped buildings, in tile order: the whole city's, for the paths
    that build it building by building."""
    items: list[Work] = []
    skipped: list[Skipped] = []
    for work in works:
        made, lost = work.items()
        items += made
        skipped += lost
    return items, skipped
