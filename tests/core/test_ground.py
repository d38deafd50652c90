"""The ground under the city (citygen.ground): a quad for a flat city, a terrain meeting every building's foot."""
from pathlib import Path

import numpy as np
import pytest
import shapely
from hypothesis import given, settings, strategies as st
from shapely.geometry import box

from citygen.ground import ground_mesh
from citygen.pipeline import import_footprints
from citygen.scene import load_scene

REPO = Path(__file__).resolve().parents[2]


def _feet(*outlines):
    return [(shapely.to_wkb(outline), z) for outline, z in outlines]


def _height_at(mesh, xy):
    """The mesh's height at points ``xy`` (barycentric in the triangle holding each; NaN where none does)."""
    tri = mesh.indices.reshape(-1, 3)
    p = mesh.points.astype(float)
    a, b, c = p[tri[:, 0]], p[tri[:, 1]], p[tri[:, 2]]
    out = np.full(len(xy), np.nan)
    for i, q in enumerate(xy):
        v0, v1, v2 = b[:, :2] - a[:, :2], c[:, :2] - a[:, :2], q - a[:, :2]
        den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
        u = (v2[:, 0] * v1[:, 1] - v1[:, 0] * v2[:, 1]) / den
        v = (v0[:, 0] * v2[:, 1] - v2[:, 0] * v0[:, 1]) / den
        hit = np.flatnonzero((u >= -1e-4) & (v >= -1e-4) & (u + v <= 1 + 1e-4))  # (float32 points)
        if len(hit):
            k = hit[0]
            out[i] = a[k, 2] + u[k] * (b[k, 2] - a[k, 2]) + v[k] * (c[k, 2] - a[k, 2])
    return out


def _ring_samples(outline, step=0.5, out=0.0):
    ring = outline.exterior if out == 0 else outline.buffer(out, join_style="mitre").exterior
    return shapely.get_coordinates(shapely.segmentize(ring, step))


def test_a_flat_city_gets_the_one_quad():
    mesh = ground_mesh((-5, -5, 25, 15), _feet((box(0, 0, 10, 8), 1.5), (box(12, 0, 20, 8), 1.5)), 0.0)
    assert mesh.counts.tolist() == [4]
    assert np.allclose(mesh.points, [[-5, -5, 1.5], [25, -5, 1.5], [25, 15, 1.5], [-5, 15, 1.5]])
    assert ground_mesh((0, 0, 1, 1), [], -2.0).points[:, 2].tolist() == [-2.0] * 4  # only lifted parts


def test_delft_buildings_stand_on_the_ground_not_above_it():
    """Bug fixture (Dec 2026, Blender render at street level): Delft's CityJSON buildings stand at their own ground
    heights (-0.34 to 0.6 m); the flat ground quad at the lowest left the others floating, a dark slot under every
    facade. Along every building's outline the ground now meets its foot: never below it, and above it only
    where a neighbour's higher foot meets it (a terrace's party wall)."""
    scene = load_scene(REPO / "scenes" / "delft.toml")
    footprints = [fp for fp in import_footprints(scene).footprints if not fp.lift]
    outlines = [fp.polygon for fp in footprints]
    feet = _feet(*((o, fp.base) for o, fp in zip(outlines, footprints)))
    bounds = np.array([o.bounds for o in outlines])
    x0, y0 = bounds[:, :2].min(0) - 20
    x1, y1 = bounds[:, 2:].max(0) + 20
    mesh = ground_mesh((x0, y0, x1, y1), feet, 0.0)
    bases = np.array([fp.base for fp in footprints])
    assert np.ptp(bases) > 0.5 and len(mesh.counts) > 1000
    tri = mesh.points[mesh.indices.reshape(-1, 3)].astype(float)
    up = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])[:, 2]
    assert (up > 0).all()  # every triangle faces the sky
    below, worst = 0, 0.0
    for outline, fp in list(zip(outlines, footprints))[::3]:
        xy = _ring_samples(outline)
        z = _height_at(mesh, xy)
        assert not np.isnan(z).any()
        near = [(o, b.base) for o, b in zip(outlines, footprints) if o is not outline and o.distance(outline) < 0.1]
        neighbour = max([z for _, z in near], default=fp.base)
        open_air = ~np.any([shapely.dwithin(o, shapely.points(xy), 0.1) for o, _ in near], axis=0)
        below += int((z[open_air] < fp.base - 0.005).sum())  # (a party wall's foot is hidden)
        assert (z <= max(fp.base, neighbour) + 0.005).all(), fp.id
        out = _ring_samples(outline, out=0.05)
        others = shapely.union_all([o for o in outlines if o is not outline and o.distance(outline) < 2.0])
        alone = ~shapely.dwithin(others, shapely.points(out), 2.0)  # (between close buildings the ground slopes)
        worst = max(worst, float(np.max(fp.base - _height_at(mesh, out[alone]), initial=0.0)))
    assert below == 0
    assert worst < 0.02  # 5 cm out from a wall, the ground has not fallen away from the foot


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(st.floats(-2, 2), st.floats(3, 12), st.floats(3, 12)), min_size=2, max_size=6),
       st.integers(0, 2**31 - 1))
def test_terrain_covers_the_city_and_meets_each_foot(sizes, seed):
    rng = np.random.default_rng(seed)
    outlines, x = [], 0.0
    for z, w, d in sizes:
        outlines.append((box(x, 0, x + w, d), z))
        x += w + float(rng.uniform(1.5, 6.0))
    mesh = ground_mesh((-10, -10, x + 10, 22), _feet(*outlines), 0.0)
    if np.ptp([z for _, z in outlines]) <= 1e-3:
        assert mesh.counts.tolist() == [4]
        return
    tri = mesh.points[mesh.indices.reshape(-1, 3)].astype(float)
    area = 0.5 * np.cross(tri[:, 1, :2] - tri[:, 0, :2], tri[:, 2, :2] - tri[:, 0, :2]).sum()
    built = sum(o.area for o, _ in outlines)
    assert area == pytest.approx((x + 20) * 32 - built, rel=1e-4)  # the rectangle, less the hidden footprints
    for outline, z in outlines:
        got = _height_at(mesh, _ring_samples(outline, step=1.0))
        assert np.allclose(got, z, atol=2e-4)  # (float32 points)


def test_a_huge_outline_is_sampled_sparsely():
    """A 10,000 km footprint (the readers' fuzzing meets such) would have taken 20 million samples at 1 m."""
    feet = _feet((box(0, 0, 1e7, 10), 1.0), (box(0, 20, 10, 30), 0.0))
    mesh = ground_mesh((-20, -20, 1e7 + 20, 50), feet, 0.0)
    assert 3 < len(mesh.points) < 20_000 and np.isfinite(mesh.points).all()
