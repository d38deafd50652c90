"""Mass-only (LOD1) buildings, many at a time: each building's walls (its mass's faces as plain quads) and roof,
with their face normals, ready for :mod:`citygen.lod1stage`.

The geometry is the mass level of detail a detailed building carries (its ``LOD1`` walls and its roof): the same
plain wall quads welded per building, the same roof builders, the same normals, the same materials and
``citygen:*`` attributes (``ruleset`` is ``none``). What differs is how it is computed: the walls of a batch of
buildings in a few numpy calls instead of the facade machinery per building, and no facade is generated, no
ruleset loaded, no worker process started.
"""
from __future__ import annotations

import itertools
import os
import time
from collections import deque
from collections.abc import Iterable, Iterator, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from typing import Any

import numpy as np

from citygen.attributes import building_attributes, building_materials, building_pivot
from citygen.coordinator import face_roles
from citygen.errors import CitygenError
from citygen.footprints import Footprint, Skipped
from citygen.geometry.building import MeshData
from citygen.lifeline import stop_workers, tie_to_parent
from citygen.mass import Mass
from citygen.registry import RoofBuilder, default_registry, load_registry
from citygen.roofmesh import build_roof
from citygen.scene import Scene
from citygen.tilework import TileWork, Work
from citygen.usd.normals import face_normals

#: Buildings whose walls are computed in one batch (bounds the arrays of a city of any size).
BATCH = 4096
#: Estimated CPU seconds of one mass-only building under a flat roof (a cap) and under any other roof (a straight
#: skeleton and its planes), measured on the Helsinki demo: 0.6 and 5.7 ms.
FLAT_COST, PITCHED_COST = 0.0007, 0.006
#: Estimated build CPU (seconds) from which worker processes build the buildings: below it, starting and feeding
#: them (a fork each, the plugins registered again, the work items and outcomes pickled: about 0.3 s of CPU per
#: worker) costs more than they save. The flat-roofed demo (0.34 s) is built in this process, the hipped one (2.8 s)
#: in workers.
WORKERS_FROM = 1.0


@dataclass(frozen=True)
class MassRecord:
    """A mass-only building ready for the stage: prim name, tile, its ``walls`` and ``roof`` (city coordinates;
    the roof None when none was built) with their :func:`~citygen.usd.normals.face_normals`, materials,
    ``citygen:`` attributes and pivot."""

    name: str
    tile: tuple[int, int]
    walls: MeshData
    walls_normals: tuple[np.ndarray, np.ndarray]
    roof: MeshData | None
    roof_normals: tuple[np.ndarray, np.ndarray] | None
    wall_material: str
    roof_material: str
    attributes: Mapping[str, Any]
    pivot: tuple[float, float, float]


@dataclass(frozen=True)
class MassOutcome:
    """A building's :class:`MassRecord`, or why it was skipped; and the warnings met on the way."""

    record: MassRecord | None
    skipped: Skipped | None
    warnings: tuple[str, ...]


@dataclass(frozen=True)
class _Planned:
    """A building between its per-building part (roof, attributes) and the batched walls."""

    footprint: Footprint
    mass: Mass
    name: str
    tile: tuple[int, int]
    roof: MeshData | None
    gables: MeshData | None
    materials: tuple[str, str]
    attributes: dict[str, Any]
    warnings: tuple[str, ...]


def build_cost(works: Sequence[TileWork]) -> float:
    """The estimated CPU seconds of building ``works``' buildings as masses (:data:`FLAT_COST`,
    :data:`PITCHED_COST` per building)."""
    return sum(FLAT_COST * (len(w) - w.pitched) + PITCHED_COST * w.pitched for w in works)


def in_workers(cost: float, jobs: int) -> bool:
    """Whether :func:`mass_batches` is to build buildings of estimated build CPU ``cost`` (:func:`build_cost`) in
    ``jobs`` worker processes: from :data:`WORKERS_FROM`."""
    return jobs > 1 and cost >= WORKERS_FROM


def mass_batches(work: Iterable[Work], scene: Scene, seed: int, roofs: Mapping[str, RoofBuilder], jobs: int = 1,
                 plugins: tuple[tuple[object, ...], bool] | None = None, chunk: int = 0
                 ) -> Iterator[tuple[list[MassOutcome], float]]:
    """The outcome of every work item (footprint, mass, neighbour cover, prim name, tile), in order, in lists of
    buildings built together, each with the CPU seconds it took: here, :data:`BATCH` at a time, or with ``chunk``
    in ``jobs`` worker processes, ``chunk`` at a time (``plugins``: how they load the registry, ``None`` for the
    default one). ``work`` is taken as it comes: a lazy one is never held whole."""
    if not chunk:
        for batch in _chunks(work, BATCH):
            yield _timed(batch, scene, seed, roofs)
        return
    chunks = _chunks(work, chunk)
    pool = ProcessPoolExecutor(max_workers=jobs, initializer=_init_worker, initargs=(plugins, os.getpid()))
    try:
        pending = deque(pool.submit(_timed, c, scene, seed) for c in itertools.islice(chunks, 4 * jobs))
        while pending:
            done = pending.popleft().result()
            following = next(chunks, None)
            if following is not None:
                pending.append(pool.submit(_timed, following, scene, seed))
            yield done
    except BaseException:  # an error, Ctrl-C, SIGTERM, or the consumer closing early: the workers end now
        stop_workers(pool)
        raise
    pool.shutdown()


def _chunks(work: Iterable[Work], size: int) -> Iterator[list[Work]]:
    """``work`` in lists of ``size`` items (the last one shorter)."""
    items = iter(work)
    while chunk := list(itertools.islice(items, size)):
        yield chunk


_ROOFS: Mapping[str, RoofBuilder] = {}  # (a worker process's roof builders)


def _init_worker(plugins: tuple[tuple[object, ...], bool] | None, parent: int) -> None:
    global _ROOFS
    tie_to_parent(parent)
    _ROOFS = (default_registry() if plugins is None else load_registry(*plugins)).roof_builders


def _timed(work: Sequence[tuple], scene: Scene, seed: int, roofs: Mapping[str, RoofBuilder] | None = None
           ) -> tuple[list[MassOutcome], float]:
    start = time.thread_time()
    outcomes = _batch(work, scene, seed, _ROOFS if roofs is None else roofs)
    return outcomes, time.thread_time() - start


def _plan(footprint: Footprint, mass: Mass, cover: np.ndarray, name: str, tile: tuple[int, int], scene: Scene,
          seed: int, roofs: Mapping[str, RoofBuilder], warnings: list[str]) -> _Planned:
    """A building's per-building part: its face roles (levels, entrance, party walls), its roof split into roof
    and gables (vertical faces: walls), materials and attributes; the warnings met go to ``warnings``."""
    roles = face_roles(footprint, mass, cover, scene.defaults)
    party = tuple(int(i) for i in np.flatnonzero(roles.party))
    roof, shape = build_roof(footprint, mass, party, roofs, warnings)
    if roof is None:
        gables = None
    elif shape == "flat":  # (no vertical face: split_vertical would keep every face, and only the points they use)
        roof, gables = roof.subset(np.ones(len(roof.counts), dtype=bool)), None
    else:
        roof, gables = roof.split_vertical()
    attributes = building_attributes(footprint, mass, levels=roles.levels, entrance=roles.entrance, ruleset="none",
                                     seed=seed, roof_shape=shape, keep_tags=scene.output.keep_tags)
    return _Planned(footprint, mass, name, tile, roof, gables, building_materials(seed, footprint), attributes,
                    tuple(warnings))


def _batch(work: Sequence[tuple], scene: Scene, seed: int, roofs: Mapping[str, RoofBuilder]) -> list[MassOutcome]:
    planned: list[_Planned | MassOutcome] = []
    for footprint, mass, cover, name, tile in work:
        warnings: list[str] = []
        try:
            planned.append(_plan(footprint, mass, cover, name, tile, scene, seed, roofs, warnings))
        except CitygenError as exc:
            planned.append(MassOutcome(None, Skipped(footprint.id, str(exc), footprint.source), tuple(warnings)))
        except Exception as exc:  # a bug skips one building, not the city, and says it is one
            planned.append(MassOutcome(None, Skipped(footprint.id, f"internal error {type(exc).__name__}: {exc}",
                                                     footprint.source), tuple(warnings)))
    built = [p for p in planned if isinstance(p, _Planned)]
    walls = _walls([p.mass for p in built])
    walls = [MeshData.concat([w, p.gables]) if p.gables is not None else w for w, p in zip(walls, built)]
    normals = _normals(walls, [p.roof for p in built])
    records = iter(MassRecord(p.name, p.tile, w, wn, p.roof, rn, *p.materials, p.attributes,
                              building_pivot(p.footprint, p.mass))
                   for p, w, (wn, rn) in zip(built, walls, normals))
    built_warnings = iter(p.warnings for p in built)
    return [p if isinstance(p, MassOutcome) else MassOutcome(next(records), None, next(built_warnings))
            for p in planned]


def _walls(masses: Sequence[Mass]) -> list[MeshData]:
    """Each mass's walls: every face a plain quad from its foot to its top (``origin + x u + y v``, the face
    frame's transform of the rectangle ``0, 0, width, height``), welded per mass as
    :meth:`MeshData.from_quads` welds them."""
    faces = [f for m in masses for f in m.faces]
    if not faces:
        return [MeshData(np.zeros((0, 3), np.float32), np.zeros(0, np.int32), np.zeros(0, np.int32)) for _ in masses]
    origin = np.array([f.origin for f in faces])
    u = np.array([f.u for f in faces])[:, :2]
    size = np.array([(f.width, f.height) for f in faces])
    quads = np.empty((len(faces), 4, 3))
    quads[:, :, :2] = origin[:, None, :2]
    quads[:, 1:3, :2] = origin[:, None, :2] + (size[:, 0, None] * u)[:, None, :]
    quads[:, :, 2] = origin[:, None, 2]
    quads[:, 2:, 2] = size[:, 1, None] + origin[:, None, 2]
    ends = np.cumsum([len(m.faces) for m in masses])[:-1]
    return MeshData.many_from_quads(np.split(quads, ends))


def _normals(walls: Sequence[MeshData], roofs: Sequence[MeshData | None]
             ) -> list[tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray] | None]]:
    """Per building, the face normals of its walls and roof, as :func:`face_normals` gives them in a batch of the
    building's meshes: buildings whose polygons are all triangles and quads share one batch (their normals do not
    depend on the batch), each other building is a batch of its own."""
    out: list = [None] * len(walls)
    simple = []
    for k, (w, r) in enumerate(zip(walls, roofs)):
        meshes = [w] if r is None else [w, r]
        counts = np.concatenate([m.counts for m in meshes])
        if counts.size and (counts.min() < 3 or counts.max() > 4):
            found = face_normals(meshes)
            out[k] = (found[0], found[1] if r is not None else None)
        else:
            simple.append(k)
    batch = iter(face_normals([m for k in simple for m in ([walls[k]] if roofs[k] is None else [walls[k], roofs[k]])]))
    for k in simple:
        out[k] = (next(batch), next(batch) if roofs[k] is not None else None)
    return out
