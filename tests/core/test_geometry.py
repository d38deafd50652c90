import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from citygen.geometry.quads import box_quads, merge_rects, weld

REPO = Path(__file__).resolve().parents[2]


def area(rects):
    return float(np.sum((rects[:, 2] - rects[:, 0]) * (rects[:, 3] - rects[:, 1])))


def test_merge_rects_joins_a_row_and_a_column():
    row = np.array([[0, 0, 1, 1], [1, 0, 2, 1], [2, 0, 3, 1], [0, 1, 3, 2]], float)
    merged = merge_rects(row)
    assert merged.tolist() == [[0, 0, 3, 2]]


@settings(max_examples=50, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 9), st.integers(0, 9)), min_size=1, max_size=60, unique=True))
def test_merge_rects_preserves_the_covered_cells(cells):
    rects = np.array([(x, y, x + 1, y + 1) for x, y in cells], float)
    merged = merge_rects(rects)
    assert area(merged) == area(rects) and len(merged) <= len(rects)
    covered = {(x, y) for x0, y0, x1, y1 in merged for x in range(int(x0), int(x1)) for y in range(int(y0), int(y1))}
    assert covered == set(cells)


def test_box_normals_point_out_of_protrusions_and_into_recesses():
    def normals(q):
        return np.cross(q[:, 1] - q[:, 0], q[:, 3] - q[:, 0])
    out = box_quads(np.array([[0, 0, 1, 1]]), np.array([0.5]))
    centre = np.array([0.5, 0.5, 0.25])
    assert np.all(np.einsum("ij,ij->i", normals(out), out.mean(axis=1) - centre) > 0)
    rec = box_quads(np.array([[0, 0, 1, 1]]), np.array([-0.5]), front=False)
    centre = np.array([0.5, 0.5, -0.25])
    assert np.all(np.einsum("ij,ij->i", normals(rec), rec.mean(axis=1) - centre) < 0)


def test_weld_shares_corners_of_adjacent_quads():
    quads = box_quads(np.array([[0, 0, 1, 1], [1, 0, 2, 1]]), np.zeros(2))
    points, indices = weld(quads)
    assert len(points) == 6 and indices.shape == (8,)
    assert np.allclose(points[indices].reshape(2, 4, 3), quads)


def test_weld_of_quads_beyond_the_packed_key_range_orders_points_the_same():
    # was: ValueError "weld: extent 10000 m exceeds the 21-bit key range" (a 10 km tower skipped as internal error)
    quads = box_quads(np.array([[0, 0, 1, 1], [1, 0, 2, 1]]), np.zeros(2))
    tall = quads * np.array([1.0, 2500.0, 1.0])  # 2 x 2500 m: y beyond 2**21 mm
    small_points, small_indices = weld(quads)
    points, indices = weld(tall)
    assert np.array_equal(indices, small_indices)
    assert np.allclose(points[indices].reshape(2, 4, 3), tall)


def _bay(x, y, key=None):
    from citygen.layout import Region
    kids = (Region(x, y, 1, 3, "W", "wall"), Region(x + 1, y, 1.2, 1, "W", "wall"),
            Region(x + 1, y + 1, 1.2, 1.5, "Win", "window", depth=-0.2), Region(x + 1, y + 2.5, 1.2, 0.5, "W", "wall"),
            Region(x + 2.2, y, 0.8, 3, "W", "wall"))
    return Region(x, y, 3, 3, "Bay", children=kids, key=key)


def _facade(keyed):
    from citygen.layout import Region
    floors = tuple(Region(0, 3 * f, 30, 3, "Floor", children=tuple(_bay(3 * b, 3 * f, 7 if keyed else None)
                                                                    for b in range(10))) for f in range(3))
    return Region(0, 0, 30, 9, "Facade", children=floors)


def test_modules_found_with_and_without_generator_keys():
    from citygen.geometry.modules import Signatures
    plain, keyed = _facade(False), _facade(True)
    a, b = Signatures([plain]), Signatures([keyed])
    placed_a, loose_a = a.split(plain)
    placed_b, loose_b = b.split(keyed)
    mods_a, mods_b = [m for m, _, _ in placed_a], [m for m, _, _ in placed_b]
    assert [m.symbol for m in mods_a] == [m.symbol for m in mods_b] == ["Bay"] * 30
    assert [(m.x, m.y) for m in mods_a] == [(m.x, m.y) for m in mods_b]
    assert {a.signature(m) for m in mods_a} == {b.signature(m) for m in mods_b}
    assert len(loose_a) == len(loose_b)
    assert len(b.info) < len(a.info)  # keyed copies were not hashed again


def test_a_floor_of_identical_bays_instances_the_bay():
    from citygen.geometry.modules import Signatures
    facade = _facade(False)
    mods, loose = Signatures([facade]).split(facade)
    assert len(mods) == 30 and {m.symbol for m, _, _ in mods} == {"Bay"} and loose.size == 0
    assert [(at, n) for _, at, n in mods] == [(5 * k, 5) for k in range(30)]  # each bay's terminals, in tree order


def test_render_walls_take_the_buildings_colour_and_a_data_colour_paints_every_wall():
    """Bug fixture: the shipped grammars' walls say `material: render`, a fixed colour, so the per-building palette
    never showed and the demo city was one colour; `render` is the building's own plaster."""
    from shapely.geometry import Polygon

    from citygen.footprints import Footprint
    from citygen.geometry.building import build_geometry
    from citygen.layout import FacadeLayout, Region
    from citygen.mass import build_mass

    mass = build_mass(Footprint("b", Polygon([(0, 0), (6, 0), (6, 4), (0, 4)]), 3.0, "height"))
    face = mass.faces[0]
    kids = (Region(0, 0, 2, 3, "W", "wall", material="render"), Region(2, 0, 2, 0.5, "P", "wall", material="stone"),
            Region(2, 0.5, 2, 2.5, "C", "cornice", material="stone"), Region(4, 0, 2, 3, "X", "wall"))
    layout = FacadeLayout(6, 3, Region(0, 0, 6, 3, "Facade", children=kids))

    def styles(wall):
        meshes = build_geometry(mass, [(face, layout)], wall, None, modules=False).meshes
        return {key for key in meshes if key[0] in ("wall", "cornice")}
    assert styles("plaster_ochre") == {("wall", "plaster_ochre"), ("wall", "stone"), ("cornice", "stone")}
    assert styles("colour_ff0000") == {("wall", "colour_ff0000"), ("cornice", "stone")}


def test_plain_walls_are_built_only_for_the_mass_level_of_detail():
    """The ``mass`` variant's plain walls were meshed for every building even without ``[output] lod``."""
    from citygen.footprints import Footprint
    from citygen.geometry.building import build_geometry
    from citygen.mass import build_mass
    from shapely.geometry import Polygon

    mass = build_mass(Footprint("b", Polygon([(0, 0), (6, 0), (6, 4), (0, 4)]), 3.0, "height"))
    faces = [(f, None) for f in mass.faces]
    assert build_geometry(mass, faces, "plaster_ochre", None).walls is None
    walls = build_geometry(mass, faces, "plaster_ochre", None, walls=True).walls
    assert len(walls.counts) == 4 and np.isclose(walls.points[:, 2].max(), 3.0)


def test_gables_leave_the_roof_as_wall_in_the_wall_material():
    """Bug fixture (issue 22): a gabled roof's vertical triangles were in the roof mesh, with the roof material and
    label ``roof``; they are wall: in the ``("wall", wall material)`` mesh of both levels of detail."""
    from shapely.geometry import Polygon

    from citygen.footprints import Footprint
    from citygen.geometry.building import build_geometry
    from citygen.mass import build_mass
    from citygen.registry import default_registry
    from citygen.roof import RoofSpec
    from citygen.usd.normals import polygon_normals

    outline = Polygon([(0, 0), (10, 0), (10, 6), (0, 6)])
    mass = build_mass(Footprint("b", outline, 3.0, "height"))
    roof = default_registry().roof_builders["gabled"].build(mass.outline, 3.0, RoofSpec("gabled", 30.0))
    geo = build_geometry(mass, [(f, None) for f in mass.faces], "plaster_ochre", roof, walls=True)
    normals = polygon_normals(geo.roof.points, geo.roof.counts, geo.roof.indices)
    assert len(geo.roof.counts) == 4 and np.all(np.abs(normals[:, 2]) > 0.5)
    wall = geo.meshes[("wall", "plaster_ochre")]
    gables = wall.subset(wall.counts == 3)
    assert len(gables.counts) == 2 and np.isclose(gables.points[:, 2].max(), 3.0 + 3.0 * np.tan(np.radians(30.0)))
    assert np.all(np.abs(polygon_normals(gables.points, gables.counts, gables.indices)[:, 2]) < 1e-6)
    assert int(np.sum(geo.walls.counts == 3)) == 2  # the mass level of detail keeps them too
    assert set(geo.meshes) == {("wall", "plaster_ochre")}  # no mesh of the roof material beside the roof


def test_split_vertical_keeps_every_face_once_and_handles_polygons_far_from_the_origin():
    from citygen.geometry.building import MeshData

    far = np.array([3.0e5, 6.7e6, 0.0])  # EPSG:3067-like coordinates
    points = (np.array([[0, 0, 0], [4, 0, 0], [4, 0, 2], [0, 0, 2], [4, 3, 2], [0, 3, 2.5]]) + far).astype(np.float32)
    mesh = MeshData(points, np.array([4, 3, 3], np.int32), np.array([0, 1, 2, 3, 3, 2, 4, 3, 4, 5], np.int32))
    roof, walls = mesh.split_vertical()
    assert walls.counts.tolist() == [4] and len(walls.points) == 4
    assert roof.counts.tolist() == [3, 3] and len(roof.points) == 4
    assert mesh.subset(np.zeros(3, bool)).counts.tolist() == []


@settings(max_examples=50, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 9), st.integers(0, 9), st.integers(0, 2)), min_size=1, max_size=60,
                unique_by=lambda c: c[:2]))
def test_grouped_merge_and_boxes_match_each_group_alone(cells):
    from citygen.geometry.quads import box_quads_grouped, merge_rects_grouped
    rects = np.array([(x, y, x + 1, y + 1) for x, y, _ in cells], float)
    groups = np.array([g for _, _, g in cells])
    merged, merged_groups = merge_rects_grouped(rects, groups)
    assert np.all(np.diff(merged_groups) >= 0)
    depth = np.array([0.0, -0.2, 0.3])
    quads, quad_groups = box_quads_grouped(merged, depth[merged_groups], merged_groups)
    for g in np.unique(groups):
        alone = merge_rects(rects[groups == g])
        assert np.array_equal(merged[merged_groups == g], alone)
        assert np.array_equal(quads[quad_groups == g], box_quads(alone, np.full(len(alone), depth[g])))


@settings(max_examples=40, deadline=None)
@given(st.lists(st.lists(st.tuples(st.integers(0, 9), st.integers(0, 9), st.sampled_from([0.0, 0.1, -0.2])),
                         min_size=1, max_size=12), min_size=1, max_size=5), st.floats(-500.0, 500.0))
def test_weld_many_welds_each_array_as_weld_does(meshes, shift):
    """Batched welding (a building's facade and module meshes at once) must give each mesh weld's exact points
    and indices: its own origin, its own vertex order."""
    from citygen.geometry.quads import weld_many
    arrays = [box_quads(np.array([(x, y, x + 1, y + 1) for x, y, _ in cells], float) + shift * k,
                        np.array([d for _, _, d in cells])) for k, cells in enumerate(meshes)]
    arrays.append(box_quads(np.array([[0.0, 0.0, 1.0, 1.0]]), np.zeros(1)) * np.array([1.0, 2500.0, 1.0]))
    points, indices, pb, ib = weld_many(arrays)
    for k, (alone_points, alone_indices) in enumerate(map(weld, arrays)):
        batched_points, batched_indices = points[pb[k]:pb[k + 1]], indices[ib[k]:ib[k + 1]]
        assert batched_points.dtype == alone_points.dtype and batched_indices.dtype == alone_indices.dtype
        assert np.array_equal(batched_points, alone_points) and np.array_equal(batched_indices, alone_indices)
    points, indices, pb, ib = weld_many([arrays[0], np.zeros((0, 4, 3)), arrays[1]])
    assert pb[1] == pb[2] and ib[1] == ib[2]
    assert indices[ib[2]:ib[3]].tobytes() == weld(arrays[1])[1].tobytes()


@pytest.mark.parametrize("modules", [True, False])
def test_a_buildings_faces_built_together_match_each_face_built_alone(modules):
    """Every face's terminals and module prototypes go through one batch per building; a face's quads, element
    prototypes and module prototypes must come out as if it were the building's only face (per-face style order,
    per-face transform), so batching never changes a stage."""
    from shapely.geometry import Polygon

    from citygen.footprints import Footprint
    from citygen.geometry.building import build_geometry, clear_module_cache
    from citygen.layout import FacadeLayout
    from citygen.mass import build_mass

    mass = build_mass(Footprint("b", Polygon([(0, 0), (30, 0), (30, 9), (0, 9)]), 9.0, "height"))
    layout = FacadeLayout(30, 9, _facade(False))
    faces = [(f, layout if f.index % 2 == 0 else None) for f in mass.faces]
    clear_module_cache()
    together = build_geometry(mass, faces, "plaster_ochre", None, modules=modules)
    alone = []
    for face in faces:
        clear_module_cache()
        alone.append(build_geometry(mass, [face], "plaster_ochre", None, modules=modules))
    for key, mesh in together.meshes.items():
        quads = np.concatenate([g.meshes[key].points[g.meshes[key].indices].reshape(-1, 4, 3)
                                for g in alone if key in g.meshes])
        assert np.array_equal(mesh.points[mesh.indices].reshape(-1, 4, 3), quads)
    assert bool(together.modules) == modules and list(together.modules) == list(alone[0].modules)
    for key, proto in together.modules.items():
        assert {k: m.points.tobytes() for k, m in proto.meshes.items()} == {
            k: m.points.tobytes() for k, m in alone[0].modules[key].meshes.items()}
    rows = [g.instances for g in alone if len(g.instances.positions)]
    assert np.array_equal(together.instances.positions, np.concatenate([r.positions for r in rows]))
    assert [together.instances.protos[k] for k in together.instances.proto_indices] == [
        r.protos[k] for r in rows for k in r.proto_indices]


def test_signatures_do_not_depend_on_the_remembered_terminals():
    """Terminal signatures are remembered across buildings (``_LEAVES``): a cold and a warm memo, and a memo
    filled by other terminals, give the same signatures and counts."""
    from citygen.geometry import modules
    from citygen.layout import Region
    facade = _facade(False)
    modules._LEAVES.clear()
    cold = modules.Signatures([facade])
    warm = modules.Signatures([facade])
    modules._LEAVES.clear()
    modules.Signatures([Region(0, 0, 2.2, 3, "Other", children=(Region(0, 0, 1, 3, "W", "wall", depth=-0.0),
                                                                Region(1, 0, 1.2, 1.5, "Win", "window")))])
    other = modules.Signatures([facade])
    assert cold.info == warm.info == other.info
    assert cold.log == warm.log == other.log and cold.counts == warm.counts == other.counts


@pytest.mark.parametrize("extent, meshes", [(30.0, 3), (30.0, 300), (600.0, 2), (600.0, 20)])
def test_weld_many_packs_the_mesh_into_the_key_only_when_it_fits(extent, meshes):
    """One int64 key per vertex holds the mesh above the three axes when they leave it room (a building's tens of
    metres), else the mesh is a second sort key (600 m at 1 mm takes 20 bits per axis: 60 bits, room for 8
    meshes): either way each mesh comes out as ``weld`` makes it alone."""
    from citygen.geometry.quads import weld_many
    rng = np.random.default_rng(7)
    arrays = []
    for _ in range(meshes):
        corner = rng.uniform(0, extent * 0.9, (6, 2))
        rects = np.column_stack([corner, corner + rng.uniform(0.5, extent * 0.1, (6, 2))])
        arrays.append(box_quads(np.vstack([rects, rects[:2]]), rng.choice([0.0, 0.15, -0.2], 8)))
    arrays[0] = np.concatenate([arrays[0], box_quads(np.array([[0.0, 0.0, extent, extent]]), np.zeros(1))])
    points, indices, pb, ib = weld_many(arrays)
    for k, (alone_points, alone_indices) in enumerate(map(weld, arrays)):
        assert points[pb[k]:pb[k + 1]].tobytes() == alone_points.tobytes()
        assert indices[ib[k]:ib[k + 1]].tobytes() == alone_indices.tobytes()


def test_weld_many_of_parts_welds_each_run_of_arrays_joined():
    from citygen.geometry.quads import weld_many
    rng = np.random.default_rng(3)
    arrays = [box_quads(rng.uniform(0, 5, (n, 4)).cumsum(axis=1), rng.choice([0.0, 0.1], n)) for n in (3, 1, 4, 2, 5)]
    joined = weld_many([np.concatenate(arrays[:2]), arrays[2], np.concatenate(arrays[3:])])
    in_parts = weld_many(arrays, parts=[2, 1, 2])
    assert all(a.tobytes() == b.tobytes() for a, b in zip(joined, in_parts))


def test_subset_keeps_the_used_points_in_order_and_the_faces_corners():
    from citygen.geometry.building import MeshData
    rng = np.random.default_rng(5)
    points = rng.uniform(-50, 50, (40, 3)).astype(np.float32)
    counts = rng.integers(3, 6, 25).astype(np.int32)
    mesh = MeshData(points, counts, rng.integers(0, 30, int(counts.sum())).astype(np.int32))
    faces = rng.random(25) < 0.4
    part = mesh.subset(faces)
    corners = mesh.indices[np.repeat(faces, counts)]
    assert part.points.tobytes() == points[np.unique(corners)].tobytes()
    assert part.indices.dtype == np.int32 and np.array_equal(part.points[part.indices], points[corners])
    assert np.array_equal(part.counts, counts[faces])


@pytest.mark.parametrize("angle", [0.0, 0.7, 1.9, math.pi, -2.4, -math.pi / 2])
@pytest.mark.parametrize("tilt", [0.0, 0.5, -1.2, math.pi])
def test_face_quaternion_rotates_as_the_faces_matrix(angle, tilt):
    """Every branch (positive trace, and each largest diagonal entry): the quaternion turns the face's axes where its
    matrix does (row vectors: ``v @ m``)."""
    from citygen.geometry.building import face_quaternion
    c, s, ct, st = math.cos(angle), math.sin(angle), math.cos(tilt), math.sin(tilt)
    yaw = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])
    pitch = np.array([[1, 0, 0], [0, ct, st], [0, -st, ct]])
    matrix = np.eye(4)
    matrix[:3, :3] = pitch @ yaw
    x, y, z, w = face_quaternion(matrix)
    rotation = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                         [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                         [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    assert np.allclose(np.eye(3) @ matrix[:3, :3], (rotation @ np.eye(3)).T, atol=1e-12)


def _eager(region):
    """``region``'s tree with every lazily moved copy made (keys kept)."""
    from dataclasses import replace
    return replace(region, children=tuple(_eager(c) for c in region.children))


@pytest.mark.parametrize("modules", [True, False])
def test_geometry_reads_the_derivations_arrays_as_it_read_the_regions(modules):
    """Geometry takes a face's loose terminals and module terminals as positions in the layout's terminal arrays
    (the derivation's, with lazily moved copies left unmade): the same meshes and instances, bit for bit, as from
    the same tree made region by region."""
    from shapely.geometry import Polygon

    from citygen.footprints import Footprint
    from citygen.geometry.building import build_geometry, clear_module_cache
    from citygen.layout import FacadeLayout
    from citygen.mass import build_mass
    from citygen.request import FacadeRequest
    from citygen_split import derive, load

    mass = build_mass(Footprint("b", Polygon([(0, 0), (23.3, 0), (23.3, 9), (0, 9)]), 12.5, "height"))
    grammar = load(REPO / "rulesets" / "apartment.grammar")
    faces = []
    for face in mass.faces:
        request = FacadeRequest(face.width, 12.5, (0.0, 3.5, 6.5, 9.5, 12.5), entrance=face.index == 0,
                                corner_widths=(0.4, 0.7), seed=(3, face.index))
        faces.append((face, derive(grammar, request)))
    eager = [(face, FacadeLayout(layout.width, layout.height, _eager(layout.root))) for face, layout in faces]

    def arrays(pairs):
        clear_module_cache()
        g = build_geometry(mass, pairs, "plaster_ochre", None, modules=modules)
        out = [g.instances.proto_indices, g.instances.positions, g.instances.scales, g.instances.orientations]
        for meshes in [g.meshes, *(p.meshes for p in g.modules.values())]:
            out += [a for key in sorted(meshes) for a in (meshes[key].points, meshes[key].indices)]
        return [a.tobytes() for a in out], list(g.modules), g.instances.protos

    lazy = arrays(faces)
    assert lazy == arrays(eager)
    assert not modules or lazy[1]  # (the grammar's bays are modules)
