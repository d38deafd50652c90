"""Curved walls (``citygen.runs``): a run of narrow faces that turn a little at each corner is laid out as one
facade and cut back onto its faces."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from citygen.builder import Builder
from citygen.coordinator import plan_building
from citygen.geometry.building import BuildingGeometry
from citygen.geometry.prototypes import ProtoKey
from citygen.layout import check_partition
from citygen.mass import neighbour_cover
from citygen.pipeline import import_footprints
from citygen.registry import default_registry
from citygen.request import FacadeRequest
from citygen.roofplan import plan_mass
from citygen.runs import MIN_PART, RUN_FACET, face_runs, facet_layouts, grouped, per_face, run_request
from citygen.scene import load_scene

REPO = Path(__file__).resolve().parents[2]


def polygon_scene(tmp_path: Path, rings: list[list[tuple[float, float]]], levels: int = 1,
                  ruleset: str = "house.grammar") -> tuple:
    """A scene of one building per ring (EPSG:3067 metres), planned as the pipeline plans it."""
    x0, y0 = 385000.0, 6672000.0
    features = [{"type": "Feature", "properties": {"id": k, "osm_type": "way", "building:levels": str(levels)},
                 "geometry": {"type": "Polygon", "coordinates": [[[x0 + x, y0 + y] for x, y in [*ring, ring[0]]]]}}
                for k, ring in enumerate(rings)]
    (tmp_path / "b.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": features}))
    (tmp_path / "scene.toml").write_text(
        '[scene]\nseed = 3\n[footprints]\npath = "b.geojson"\ncrs = "EPSG:3067"\n[defaults]\nroof_shape = "flat"\n'
        f'[[assign]]\nruleset = "{(REPO / "rulesets" / ruleset).as_posix()}"\n[output]\npath = "c.usdc"\n')
    scene = load_scene(tmp_path / "scene.toml")
    footprints = import_footprints(scene).footprints
    masses = [plan_mass(fp, scene, default_registry().roof_builders)[0] for fp in footprints]
    return scene, footprints, masses, neighbour_cover(masses)


def circle(radius: float, n: int, cx: float = 0.0, cy: float = 0.0) -> list[tuple[float, float]]:
    return [(cx + radius * math.cos(2 * math.pi * k / n), cy + radius * math.sin(2 * math.pi * k / n))
            for k in range(n)]


def windows(geometry: BuildingGeometry) -> int:
    """Window placements of a building: window elements, directly or inside its modules."""
    def count(instances) -> int:
        rows = np.bincount(instances.proto_indices, minlength=len(instances.protos))
        return int(sum(n * (1 if isinstance(p, ProtoKey) and p.label == "window" else
                            count(geometry.modules[p].elements) if not isinstance(p, ProtoKey) else 0)
                       for p, n in zip(instances.protos, rows)))
    return count(geometry.instances)


def test_a_round_buildings_faces_are_one_run_but_the_entrance(tmp_path):
    scene, footprints, masses, cover = polygon_scene(tmp_path, [circle(5.0, 32)])
    plan = plan_building(footprints[0], masses[0], cover[0], scene.defaults, 3)
    assert plan.entrance_face is not None
    n = len(masses[0].faces)  # (16: the outline's cleaning merges nearly straight corners)
    (run,) = plan.runs
    assert len(run) == n - 1 and plan.entrance_face not in run
    assert run[0] == (plan.entrance_face + 1) % n and run[-1] == (plan.entrance_face - 1) % n  # (around)
    inner = {i for i in run[1:]}
    for request in plan.requests:
        if request.context.face_index in inner:  # (no corner strips where the bays run across)
            assert request.corner_widths[0] == 0.0


def test_square_corners_and_wide_faces_make_no_run(tmp_path):
    square = [(0.0, 0.0), (12.0, 0.0), (12.0, 9.0), (0.0, 9.0)]
    wide = circle(30.0, 24)  # (24 faces of 7.8 m turning 15 degrees)
    scene, footprints, masses, cover = polygon_scene(tmp_path, [square, [(x + 100, y) for x, y in wide]])
    for k in range(2):
        assert plan_building(footprints[k], masses[k], cover[k], scene.defaults, 3).runs == ()


def test_a_bay_front_with_an_arc_of_narrow_faces_is_one_run(tmp_path):
    """A rectangle whose front is a half circle of 12 faces (1.3 m, 15 degrees apart): the arc is a run; the
    8 m sides it turns into are too wide to join it, the back's square corners end nothing."""
    arc = [(5.0 - 5.0 * math.cos(math.pi * k / 12), -5.0 * math.sin(math.pi * k / 12)) for k in range(13)]
    scene, footprints, masses, cover = polygon_scene(tmp_path, [[*arc, (10.0, 8.0), (0.0, 8.0)]], levels=3)
    faces = masses[0].faces
    runs = face_runs(faces, np.ones(len(faces), bool))
    assert len(faces) == 15 and len(runs) == 1 and len(runs[0]) == 12
    assert all(faces[i].width < RUN_FACET for i in runs[0])


def test_bug_round_buildings_narrow_faces_got_no_window(tmp_path):
    """Bug fixture (Helsinki's round pavilions, relation/8525161: 32 faces of 0.9-1.7 m): face by face, none is wide
    enough for a bay, and the building had no window at all, only a plinth broken at every face. As one run, its
    bays run around it."""
    scene, footprints, masses, cover = polygon_scene(tmp_path, [circle(5.0, 32)])
    outcome = Builder(scene, scene.seed).build(footprints[0], masses[0], cover[0], "b", (0, 0))
    assert outcome.record is not None
    assert windows(outcome.record.geometry) >= 8


def test_run_layouts_partition_their_faces_and_keep_their_floors(tmp_path):
    scene, footprints, masses, cover = polygon_scene(tmp_path, [circle(7.0, 40)], levels=3)
    plan = plan_building(footprints[0], masses[0], cover[0], scene.defaults, 3)
    kind = default_registry().kind_for_path(REPO / "rulesets" / "apartment.grammar")
    ruleset = kind.load(REPO / "rulesets" / "apartment.grammar")
    asked, parts = grouped(list(plan.requests), plan.runs)
    assert len(asked) == 2 and max(map(len, parts)) == len(masses[0].faces) - 1
    layouts = [kind.generate(ruleset, request) for request in asked]
    for request, layout in per_face(parts, layouts):
        assert layout.width == request.width or abs(layout.width - request.width) < 1e-9
        assert check_partition(layout) == []


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(0.3, 2.9), min_size=2, max_size=12), st.integers(0, 2**31 - 1))
def test_facet_layouts_partition_every_face(widths, seed):
    """Any run's layout cut at any corners: every face's part is a partition of that face, the parts' terminals
    cover the run exactly, and only whole elements or wall are narrower than MIN_PART where cut."""
    kind = default_registry().kind_for_path(REPO / "rulesets" / "historic.grammar")
    ruleset = kind.load(REPO / "rulesets" / "historic.grammar")
    members = [FacadeRequest.preview(w, 10.0, entrance=False, seed=seed) for w in widths]
    layout = kind.generate(ruleset, run_request(members))
    parts = facet_layouts(layout, widths)
    assert np.allclose([p.width for p in parts], widths, rtol=0, atol=1e-9)
    area = 0.0
    whole = {(t.label, round(t.w, 9), round(t.h, 9)) for t in layout.terminals()}
    for part in parts:
        assert check_partition(part) == []
        area += sum(t.w * t.h for t in part.terminals())
        for t in part.terminals():
            assert t.w >= MIN_PART or t.label in (None, "wall") or (t.label, round(t.w, 9), round(t.h, 9)) in whole
    assert math.isclose(area, layout.width * layout.height, rel_tol=1e-9)
