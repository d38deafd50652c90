"""A window standing on a balcony is the balcony's door: it reaches down behind the railing to the slab, and the
wall behind the railing is cut around it (citygen.geometry.backs)."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from shapely.geometry import Polygon, box
from shapely.ops import unary_union

from citygen.footprints import Footprint
from citygen.geometry.backs import balcony_backs, balcony_doors
from citygen.geometry.building import build_geometry
from citygen.geometry.prototypes import balcony_heights
from citygen.layout import FacadeLayout, Region
from citygen.mass import build_mass

SLAB = float(balcony_heights(1.0)[0])


def _column(x, w=2.2, window_w=None):
    """The apartment grammar's balcony column: railing 1 m, the French window above it, wall over it."""
    window_w = w if window_w is None else window_w
    side = (w - window_w) / 2
    kids = [Region(x, 0, w, 1.0, "Balcony", "balcony"), Region(x + side, 1.0, window_w, 1.45, "French", "window"),
            Region(x, 2.45, w, 0.55, "W", "wall")]
    if side > 0:
        kids += [Region(x, 1.0, side, 1.45, "W", "wall"), Region(x + side + window_w, 1.0, side, 1.45, "W", "wall")]
    return Region(x, 0, w, 3, "Column", children=tuple(kids))


def _geometry(columns, modules):
    mass = build_mass(Footprint("b", Polygon([(0, 0), (12, 0), (12, 4), (0, 4)]), 3.0, "height"))
    kids, x = [], 0.0
    for col in columns:
        kids += [Region(x, 0, 0.5, 3, "W", "wall"), col(x + 0.5)]
        x += 0.5 + kids[-1].w
    kids.append(Region(x, 0, 12 - x, 3, "W", "wall"))
    layout = FacadeLayout(12, 3, Region(0, 0, 12, 3, "Facade", children=tuple(kids)))
    return build_geometry(mass, [(mass.faces[0], layout)], "plaster_ochre", None, modules=modules)


def _flat_wall(geometry):
    """The wall mesh's quads as (x0, z0, x1, z1) in the face (the face is y = 0)."""
    mesh = geometry.meshes[("wall", "plaster_ochre")]
    quads = mesh.points[mesh.indices.reshape(-1, 4)]
    flat = quads[np.all(np.abs(quads[:, :, 1]) < 1e-6, axis=1)]
    return np.column_stack([flat[:, :, 0].min(1), flat[:, :, 2].min(1), flat[:, :, 0].max(1), flat[:, :, 2].max(1)])


@pytest.mark.parametrize("modules", [False, True])
def test_apartment_balcony_has_a_door_behind_its_railing(modules):
    """Bug fixture (Dec 2026, seen in Blender): apartment balconies had 1 m of blank wall behind the railing and
    the French window started above it -- no way onto the balcony."""
    g = _geometry([_column, _column, _column], modules)
    windows = [k for k, p in enumerate(g.instances.protos) if p.label == "window"]
    assert windows
    rows = np.isin(g.instances.proto_indices, windows)
    assert np.allclose(g.instances.positions[rows, 2], SLAB)  # from the slab's top ...
    tall = np.array([g.instances.protos[i].size[1] for i in g.instances.proto_indices[rows]])
    assert np.allclose(tall * g.instances.scales[rows, 1], 2.45 - SLAB)  # ... to the window's head
    behind_railing = unary_union([box(x, SLAB + 0.01, x + 2.2, 0.99) for x in (0.5, 3.2, 5.9)])
    walls = unary_union([box(*r) for r in _flat_wall(g)])
    assert walls.intersection(behind_railing).area < 1e-5  # (float32 points)


def test_a_narrower_window_leaves_wall_beside_its_door_and_a_wider_one_stays_a_window():
    narrow = _geometry([lambda x: _column(x, 2.2, 1.2)], False)
    walls = unary_union([box(*r) for r in _flat_wall(narrow)])
    beside = box(0.5, SLAB, 1.0, 1.0).union(box(2.2, SLAB, 2.7, 1.0))
    assert walls.intersection(beside).area == pytest.approx(beside.area)
    assert walls.intersection(box(1.0, SLAB, 2.2, 1.0)).area < 1e-5

    rects = np.array([[0, 0, 2, 1], [-0.2, 1, 2.2, 2.4], [3, 0, 5, 1], [3, 1.1, 5, 2.4]], float)
    doors, under = balcony_doors(rects, np.zeros(4, np.intp), np.array([1, 0, 1, 0], bool),
                                 np.array([0, 1, 0, 1], bool))
    assert len(doors) == 0  # wider than its balcony; not standing on it


def test_doors_are_matched_within_their_unit_only():
    rects = np.array([[0, 0, 2, 1], [0, 1, 2, 2.4]], float)
    doors, _ = balcony_doors(rects, np.array([0, 1]), np.array([1, 0], bool), np.array([0, 1], bool))
    assert len(doors) == 0


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(0.6, 4.0), st.floats(0.3, 1.5), st.integers(0, 3)), min_size=1, max_size=6),
       st.floats(0.0, 60.0))
def test_a_balconys_back_and_its_doors_tile_it(balconies, y0):
    """Wall pieces behind a balcony plus its doors' parts behind the railing cover the balcony exactly once."""
    rects, balcony, opening, units = [], [], [], []
    x = 0.0
    for unit, (w, h, n) in enumerate(balconies):
        top = y0 + h
        rects.append((x, y0, x + w, top))
        balcony.append(True), opening.append(False), units.append(unit % 2)
        edges = np.linspace(x, x + w, 2 * n + 2)
        for k in range(n):  # n doors, with wall between them
            rects.append((edges[2 * k + 1], top, edges[2 * k + 2], top + 2.0))
            balcony.append(False), opening.append(True), units.append(unit % 2)
        x += w + 1.0
    rects, units = np.array(rects), np.array(units)
    balcony, opening = np.array(balcony), np.array(opening)
    doors, under = balcony_doors(rects, units, balcony, opening)
    assert len(doors) == opening.sum()
    new, backs, back_units = balcony_backs(rects, units, balcony, doors, under)
    for b in np.flatnonzero(balcony):
        outline = box(*rects[b])
        mine = [box(*r) for r, u in zip(backs, back_units) if u == units[b] and box(*r).intersection(outline).area > 0]
        mine += [box(*new[d]).intersection(outline) for d, u in zip(doors, under) if u == b]
        assert sum(p.area for p in mine) == pytest.approx(outline.area)
        assert unary_union(mine).area == pytest.approx(outline.area)
    moved = new[doors, 1]
    assert np.allclose(moved, rects[under, 1] + balcony_heights(rects[under, 3] - rects[under, 1])[0])
