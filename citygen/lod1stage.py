"""The stage of a mass-only (LOD1) city: :class:`~citygen.usd.writer.StageWriter`'s stage (tiles, tile layers,
materials, look sets, ground), each building holding its mass only.

A mass-only building is the component a detailed one is (at its pivot, ``assetInfo``, ``extentsHint``, its
``citygen:*`` attributes and ``primvars:citygen:variation``, its own ``Looks``) with two meshes: ``Walls`` (label
``wall``) and ``Roof`` (label ``roof``). It has no ``LOD`` variant set: its mass is its only level of detail (a
detailed building's ``LOD1`` variant holds the same ``Walls``).
"""
from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from pxr import Sdf

from citygen.footprints import Skipped
from citygen.lod1 import MassOutcome, MassRecord
from citygen.usd.bounds import union
from citygen.usd.writer import StageStats, StageWriter, _model_bound, component


class MassWriter(StageWriter):
    """A :class:`StageWriter` whose :meth:`add` takes :class:`~citygen.lod1.MassRecord` s (in tile order)."""

    def add(self, record: MassRecord) -> None:  # type: ignore[override]
        target = self._tile(record.tile)
        if isinstance(target, StageWriter):
            target.add(record)
            return
        with Sdf.ChangeBlock():
            bound = _write_mass(self, target, record)
        if bound is not None:
            self.tile_bound = union([self.tile_bound, bound + np.asarray(record.pivot)])

    def add_layer(self, name: str, stats: StageStats) -> None:
        """Payload the tile layer ``name`` another process wrote into :meth:`staging_folder`, after the tile open
        here (tiles come in tile order)."""
        self._flush_tile()
        self.add_tile_layer(name, stats, ())


def _write_mass(writer: StageWriter, parent: Sdf.PrimSpec, record: MassRecord) -> np.ndarray | None:
    """One mass-only building prim at its pivot, its meshes in local coordinates; returns its local bound."""
    author, counts = writer.author, writer.counts
    pivot = np.asarray(record.pivot, dtype=float)
    prim = component(author, parent, record.name, pivot, record.attributes)
    roof = record.roof
    used = sorted({record.wall_material} | ({record.roof_material} if roof is not None else set()))
    writer.define(used)
    looks = author.looks(prim, used)
    bounds = [author.mesh(prim, "Walls", record.walls, looks, record.wall_material, "wall", record.walls_normals,
                          pivot)]
    counts["meshes"] += bounds[0] is not None
    counts["polygons"] += len(record.walls.counts)
    if roof is not None:
        bounds.append(author.mesh(prim, "Roof", roof, looks, record.roof_material, "roof", record.roof_normals, pivot))
        counts["meshes"] += 1
        counts["polygons"] += len(roof.counts)
    counts["buildings"] += 1
    building = union(bounds)
    _model_bound(prim, building)
    return building


@dataclass(frozen=True)
class Part:
    """Part of a mass-only city done: its skipped buildings, warnings and buildings written, and the CPU seconds
    of its builds and of writing it (``here``: in this process, else in a helper, :mod:`citygen.lod1tiles`)."""

    skipped: tuple[Skipped, ...]
    warnings: tuple[str, ...]
    written: int
    builds: float
    usd: float
    here: bool = True


def write_outcomes(writer: StageWriter, outcomes: Sequence[MassOutcome], builds: float) -> Part:
    """``outcomes``' records added to ``writer`` (``builds``: the CPU seconds they took to build)."""
    start = time.process_time()
    written = 0
    for outcome in outcomes:
        if outcome.record is not None:
            writer.add(outcome.record)
            written += 1
    return Part(tuple(o.skipped for o in outcomes if o.record is None), tuple(w for o in outcomes for w in o.warnings),
                written, builds, time.process_time() - start)
