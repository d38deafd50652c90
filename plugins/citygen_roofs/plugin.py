"""Roof builders: ``flat`` (a cap over the outline, courtyards left open) and the pitched roofs of
:mod:`citygen_roofs.pitched` (``hipped``, ``gabled``, ``pyramidal``, ``skillion``,
``half-hipped``, ``mansard``, ``gambrel``, ``dome``, ``round``, ``cone``), ``onion`` (:mod:`citygen_roofs.onion`) and
the roofs of planar pieces of :mod:`citygen_roofs.osm_shapes` (``saltbox``, ``side_hipped``, ``crosspitched``,
``butterfly``, ``sawtooth``)."""
from __future__ import annotations

import mapbox_earcut
import numpy as np
from shapely.geometry import MultiPolygon, Polygon

from citygen.geometry.building import MeshData
from citygen.hookspecs import hookimpl
from citygen.registry import RoofBuilder
from citygen.roof import RoofSpec
from citygen_roofs.onion import OnionRoof
from citygen_roofs.osm_shapes import ButterflyRoof, CrosspitchedRoof, SaltboxRoof, SawtoothRoof, SideHippedRoof
from citygen_roofs.pitched import (ConeRoof, DomeRoof, GabledRoof, GambrelRoof, HalfHippedRoof, HippedRoof, MansardRoof,
                                   PyramidalRoof, RoundRoof, SkillionRoof)


def _cap(part: Polygon, top: float) -> tuple[np.ndarray, np.ndarray]:
    """Ear-clipped triangles of one polygon with holes, wound to face up (+z)."""
    rings = [np.asarray(r.coords)[:-1, :2] for r in (part.exterior, *part.interiors)]
    verts = np.concatenate(rings)
    ends = np.cumsum([len(r) for r in rings]).astype(np.uint32)
    tris = mapbox_earcut.triangulate_float64(verts, ends).reshape(-1, 3).astype(np.int32)
    a, b, c = verts[tris[:, 0]], verts[tris[:, 1]], verts[tris[:, 2]]
    down = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) < 0
    tris[down] = tris[down][:, ::-1]
    return np.column_stack([verts, np.full(len(verts), top)]), tris


class FlatRoof(RoofBuilder):
    id = "flat"
    description = "flat roof cap at the wall top (holes stay open)"

    def build(self, outline: Polygon | MultiPolygon, top: float, spec: RoofSpec | None = None) -> MeshData:
        parts = outline.geoms if isinstance(outline, MultiPolygon) else [outline]
        points, faces, offset = [], [], 0
        for part in parts:
            verts, tris = _cap(part, top)
            points.append(verts)
            faces.append(tris + offset)
            offset += len(verts)
        tris = np.concatenate(faces)
        return MeshData(np.concatenate(points).astype(np.float32), np.full(len(tris), 3, np.int32), tris.ravel())

    def rise(self, outline: Polygon | MultiPolygon, spec: RoofSpec) -> float:
        return 0.0


@hookimpl
def citygen_roof_builders():
    return [FlatRoof(), HippedRoof(), GabledRoof(), HalfHippedRoof(), PyramidalRoof(), SkillionRoof(), MansardRoof(),
            GambrelRoof(), DomeRoof(), RoundRoof(), OnionRoof(), ConeRoof(), SaltboxRoof(), SideHippedRoof(),
            CrosspitchedRoof(), ButterflyRoof(), SawtoothRoof()]
