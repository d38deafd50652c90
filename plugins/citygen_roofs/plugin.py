"""Roof builders: ``flat`` (a cap over the outline, courtyards left open)."""
from __future__ import annotations

import numpy as np
import trimesh
from shapely.geometry import MultiPolygon, Polygon

from citygen.geometry.building import MeshData
from citygen.hookspecs import hookimpl
from citygen.registry import RoofBuilder


class FlatRoof(RoofBuilder):
    id = "flat"
    description = "flat roof cap at the wall top (holes stay open)"

    def build(self, outline: Polygon | MultiPolygon, top: float) -> MeshData:
        parts = outline.geoms if isinstance(outline, MultiPolygon) else [outline]
        points, faces, offset = [], [], 0
        for part in parts:
            verts, tris = trimesh.creation.triangulate_polygon(part, engine="earcut")
            points.append(np.column_stack([verts, np.full(len(verts), top)]))
            faces.append(tris + offset)
            offset += len(verts)
        tris = np.concatenate(faces).astype(np.int32)
        return MeshData(np.concatenate(points).astype(np.float32), np.full(len(tris), 3, np.int32), tris.ravel())


@hookimpl
def citygen_roof_builders():
    return [FlatRoof()]
