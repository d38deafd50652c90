"""``citygen layout from-photo`` (mueller2007): structure, windows, partition, grammar round trip, CLI errors."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from citygen.cli import main
from citygen.errors import LayoutError
from citygen.layout import FacadeLayout, check_partition
from citygen_inverse.extract import extract_grammar
from citygen_photo.photo import analyse, layout_from_photo
from citygen_inverse.cmp import count_groups
from citygen_photo.score import cmp_boxes, facade_box, matches
from citygen_photo.structure import split_lines
from citygen_photo.symmetry import detect_symmetry, irreducible, quantize, validated_period
from tests.photo.synthetic import facade

CMP = Path(__file__).parents[2] / ".." / "shared" / "data" / "cmp_facade" / "base"

CASES = [
    dict(),
    dict(floors=4, cols=8, floor_h=75, tile_w=40, win=(40, 20), off=(20, 10), seed=2),
    dict(floors=6, cols=3, floor_h=50, tile_w=110, win=(25, 60), off=(10, 25), seed=3, noise=0.08),
]


def close(a, b, tol):
    return all(abs(u - v) <= tol for u, v in zip(a, b))


@pytest.mark.parametrize("case", CASES)
def test_synthetic_floors_tiles_and_windows(case):
    image, truth, _ = facade(**case)
    result = analyse(image)
    floors = case.get("floors", 5)
    cols = case.get("cols", 6)
    assert len(result.floor_lines) - 1 == floors
    assert len(result.tile_lines) - 1 == cols
    assert result.floor_period == pytest.approx(case.get("floor_h", 60), abs=2)
    assert result.tile_period == pytest.approx(case.get("tile_w", 50), abs=2)
    boxes = sorted(result.boxes("window"), key=lambda b: (b[1], b[0]))
    assert len(boxes) == len(truth)
    for got, want in zip(boxes, sorted(truth, key=lambda b: (b[1], b[0]))):
        assert close(got, want, 3), (got, want)
    assert matches(boxes, truth) == len(truth)


def test_a_tall_facade_of_sixteen_floors_keeps_one_floor_per_row():
    """Bug fixture (cmp_b0011, 12 window rows in 15 floors): floor periods below 1/14 of the facade height were
    not searched, so two rows made one floor. Now down to 1/20 (tests: 16 floors of 40 px)."""
    image, truth, _ = facade(floors=16, cols=4, floor_h=40, tile_w=60, win=(24, 30), off=(8, 15), seed=4)
    result = analyse(image)
    assert len(result.floor_lines) - 1 == 16
    assert result.floor_period == pytest.approx(40, abs=2)
    assert matches(result.boxes("window"), truth) == len(truth)


def test_layout_partitions_and_scales():
    image, truth, _ = facade()
    by_floor = analyse(image, floor_height=3.0).layout
    assert check_partition(by_floor) == []
    assert by_floor.height == pytest.approx(15.0, abs=0.6)  # 5 floors of 3 m (period 60 px)
    assert by_floor.count("window") == len(truth)
    by_width = analyse(image, width=18.0).layout
    assert by_width.width == pytest.approx(18.0)
    assert check_partition(by_width) == []
    labels = {t.label for t in by_width.terminals()}
    assert labels == {"wall", "window"}


def test_irregular_ground_floor_is_its_own_floor():
    image, truth, door = facade(ground_h=80)
    result = analyse(image)
    assert len(result.floor_lines) - 1 == 6
    assert result.floor_lines[-1] - result.floor_lines[-2] == pytest.approx(80, abs=15)
    assert matches(result.boxes("window"), truth) == len(truth)
    assert matches(result.boxes("door"), [door]) == 1
    assert check_partition(result.layout) == []


@pytest.mark.parametrize("shop", [(36, 30), (40, 35)])
def test_shop_fronts_are_not_doors(shop):
    """Regression: every contrasting ground-floor region reaching the ground was a door, so a ground floor with
    five low, wide shop fronts (40 x 35 px) beside one door gave 6 doors. Shop fronts are lower than
    ``DOOR_ASPECT`` times their width and repeat in a group of more than ``MAX_DOORS`` tiles: only the door is."""
    image, truth, door = facade(ground_h=80)
    wide, high = shop
    for j in (0, 2, 3, 4, 5):
        c0 = j * 50 + (50 - wide) // 2
        image[-high:, c0:c0 + wide] = 0.3 * np.array([1.0, 0.92, 0.85])
    result = analyse(image)
    assert len(result.boxes("door")) == 1 and matches(result.boxes("door"), [door]) == 1
    assert matches(result.boxes("window"), truth) == len(truth)
    assert check_partition(result.layout) == []


def test_layout_round_trips_through_greedy_extraction():
    image, _, _ = facade(floors=3, cols=4)
    layout = analyse(image, width=12.0).layout
    again = FacadeLayout.loads(layout.dumps())
    grammar = extract_grammar(again, "greedy")
    assert grammar.terminals == len(layout.terminals())
    assert "Window" in grammar.text or "window" in grammar.text


def test_symmetry_finds_the_period_and_refuses_noise():
    image, _, _ = facade()
    gray = image.mean(axis=2)
    sym = detect_symmetry(quantize(gray), 20, 150)
    assert sym.found and sym.period == 60
    noise = np.random.default_rng(1).random((300, 300))
    assert not detect_symmetry(quantize(noise), 20, 150).found


def test_irreducible_facade_stacks_the_floors():
    """§2.3: the collage keeps every original row exactly once; the first stacking shifts by one floor, every
    stacking by whole floors, and the six floors collapse into one stack of corresponding rows."""
    image, _, _ = facade(floors=6)
    sym = detect_symmetry(quantize(image.mean(axis=2)), 20, 180)
    stack = irreducible(sym)
    assert sorted(y for line in stack.lines for y in line) == list(range(360))
    assert stack.period == 60 and all(h % 60 == 0 for _, h, _ in stack.steps)
    assert len(stack.lines) == 60
    assert all(len(line) == 6 and len({y % 60 for y in line}) == 1 for line in stack.lines)
    assert validated_period(sym, stack) == 60


def test_floor_period_spanning_several_floors_is_recovered():
    """Regression (cmp_b0009): when every fourth floor has a cornice and a balcony slab the line-averaged MI
    prefers four floors (240 px) and the facade came out as 2 floors with 20-35 of 40 windows; the irreducible
    facade's first stacking is one floor apart, so the period is one floor."""
    image, truth, _ = facade(floors=8, cols=5, accent=4)
    gray = image.mean(axis=2)
    sym = detect_symmetry(quantize(gray), 34, 240)
    assert sym.period == 240
    assert validated_period(sym, irreducible(sym)) == 60
    result = analyse(image)
    assert result.floor_period == pytest.approx(60, abs=2)
    assert len(result.floor_lines) - 1 == 8
    assert matches(result.boxes("window"), truth) == len(truth)


@pytest.mark.parametrize("stripe", [12, 15, 20])
def test_striped_floor_does_not_shorten_the_floor_period(stripe):
    """A floor-high band of horizontal stripes (a roller shutter) stacks best at a fraction of the floor (24-30 px
    of 60) but repeats only there: the period stays one floor and the windows of the other floors are found."""
    image, truth, _ = facade()
    rows = np.arange(120, 180)
    image[120:180] = np.where((rows // (stripe // 2)) % 2 == 0, 0.3, 0.8)[:, None, None]
    result = analyse(image)
    assert result.floor_period == pytest.approx(60, abs=2)
    outside = [b for b in truth if not 120 <= b[1] < 180]
    assert matches(result.boxes("window"), outside) == len(outside) == 24


def test_split_lines_follow_minima_within_the_period():
    values = np.ones(300)
    values[[40, 100, 160, 220, 280]] = 0.0
    values[130] = -0.5  # a deep minimum off the lattice is not taken with 100 and 160
    lines = split_lines(values, 60, 0, 300, min_end=5)
    assert list(lines) == [0, 40, 100, 160, 220, 280, 300]


def test_no_repetition_is_a_clear_error(tmp_path):
    noise = (np.random.default_rng(0).random((200, 200)) * 255).astype(np.uint8)
    path = tmp_path / "noise.png"
    Image.fromarray(noise).save(path)
    for parser in ("learned", "contrast"):
        with pytest.raises(LayoutError, match="no repetition of floors"):
            layout_from_photo(path, parser=parser)


def test_cli_from_photo(tmp_path, capsys):
    image, truth, _ = facade()
    path = tmp_path / "facade.png"
    Image.fromarray((image * 255).astype(np.uint8)).save(path)
    out = tmp_path / "layout.json"
    assert main(["layout", "from-photo", str(path), "--width", "18", "-o", str(out)]) == 0
    layout = FacadeLayout.loads(out.read_text())
    assert check_partition(layout) == [] and layout.count("window") == len(truth)
    assert "5 floors x 6 tiles" in capsys.readouterr().err
    assert main(["layout", "from-photo", str(path), "--crop", "0", "0", "300", "240", "-o", str(out)]) == 0
    assert json.loads(out.read_text())["meta"]["floors"] == 4


@pytest.mark.parametrize("mode", ["I;16", "RGBA", "L"])
def test_16bit_grayscale_photo(tmp_path, mode):
    """Regression: ``convert("RGB")`` clipped 16-bit PNGs to white ("no repetition of floors")."""
    image, truth, _ = facade()
    gray = image.mean(axis=2)
    if mode == "I;16":
        pil = Image.fromarray((gray * 65535).astype(np.uint16))
    else:
        pil = Image.fromarray((image * 255).astype(np.uint8)).convert(mode)
    path = tmp_path / "facade.png"
    pil.save(path)
    result = layout_from_photo(path, crop=(0, 0, 300, 300))
    assert matches(result.boxes("window"), truth) == len(truth)


@pytest.mark.parametrize("content", [b"not an image at all", b""])
def test_cli_refuses_a_non_image(tmp_path, capsys, content):
    path = tmp_path / "facade.jpg"
    path.write_bytes(content)
    assert main(["layout", "from-photo", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and str(path) in err and "cannot read the image" in err
    assert "Traceback" not in err


def test_regression_an_image_over_pillows_pixel_limit_is_refused(tmp_path, capsys, monkeypatch):
    """Pillow refuses images over its decompression-bomb limit (~179 megapixels) with an exception that is not an
    OSError: it ended in a traceback, for a photo and for a CMP label map."""
    path = tmp_path / "facade.png"
    Image.fromarray(np.zeros((60, 50, 3), np.uint8)).save(path)
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 1000)
    assert main(["layout", "from-photo", str(path)]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and "too large to open safely" in err and "downscale" in err
    xml = Path(__file__).resolve().parents[1] / "data" / "inverse" / "cmp_b0012.xml"
    assert main(["layout", "import-cmp", str(xml), "--png", str(path)]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and "cannot read the label map" in err and "Traceback" not in err


def test_cli_errors_name_the_file(tmp_path, capsys):
    assert main(["layout", "from-photo", str(tmp_path / "missing.png")]) == 2
    assert "missing.png: no such file" in capsys.readouterr().err
    image, _, _ = facade()
    path = tmp_path / "facade.png"
    Image.fromarray((image * 255).astype(np.uint8)).save(path)
    assert main(["layout", "from-photo", str(path), "--crop", "0", "0", "900", "10"]) == 2
    assert "not inside the 300x300 image" in capsys.readouterr().err
    assert main(["layout", "from-photo", str(path), "--width", "-2"]) == 2
    assert "--width must be a finite positive number of metres" in capsys.readouterr().err
    assert main(["layout", "from-photo", str(path), "--width", "inf"]) == 2  # (was "did not give a partition")
    assert "--width must be a finite positive number of metres, got inf" in capsys.readouterr().err
    noise = tmp_path / "noise.png"
    Image.fromarray((np.random.default_rng(0).random((200, 200)) * 255).astype(np.uint8)).save(noise)
    assert main(["layout", "from-photo", str(noise)]) == 2
    err = capsys.readouterr().err
    assert "noise.png" in err and "no repetition of floors" in err and "--crop" in err


@pytest.mark.skipif(not (CMP / "cmp_b0031.jpg").is_file(), reason="CMP photos (shared data) not available")
def test_real_cmp_photo():
    jpg = CMP / "cmp_b0031.jpg"
    with Image.open(jpg) as image:
        size = image.size
    boxes = cmp_boxes(jpg.with_suffix(".xml"), size)
    crop = tuple(round(v) for v in facade_box(boxes))
    result = layout_from_photo(jpg, crop=crop, floor_height=3.2)
    assert check_partition(result.layout) == []
    ref = [(x0 - crop[0], y0 - crop[1], x1 - crop[0], y1 - crop[1]) for x0, y0, x1, y1 in boxes["window"]]
    rows = count_groups([(b[1], b[3]) for b in ref])
    assert abs(len(result.floor_lines) - 1 - rows) <= 1
    found = matches(result.boxes("window"), ref)
    assert found >= 0.5 * len(ref), (found, len(ref))
    assert extract_grammar(result.layout, "greedy").terminals == len(result.layout.terminals())


def _leaves(node):
    return [node] if not node.children else [leaf for c in node.children for leaf in _leaves(c)]


def _railing_group(rows: tuple[int, int], shade: float):
    """Two 60 x 50 tiles, each with a dark 30 x 22 window and a railing of ``shade`` across the whole tile."""
    from citygen_photo.tiles import EdgeImage, subdivide_group
    gray = 0.7 + 0.02 * np.random.default_rng(4).standard_normal((120, 50))
    for top in (0, 60):
        gray[top + 14:top + 44, 14:36] = 0.25
        gray[top + rows[0]:top + rows[1], :] = shade
    tree = subdivide_group(EdgeImage.of(gray), [(0, 60, 0, 50), (60, 120, 0, 50)])
    return [n.rects for n in _leaves(tree) if n.label == "window"]


def test_window_behind_a_railing_spanning_the_tile():
    """Regression: a railing across the whole tile over a window's lower two thirds left §3.1's first-edge splits
    with only regions touching the tile boundary, so no window was found; the profile fallback finds it whole."""
    assert _railing_group((24, 44), 0.3) == [((14, 44, 14, 36), (74, 104, 14, 36))]


def test_window_half_hidden_by_a_railing_is_found_whole():
    """Regression: with a lighter railing §3.1 labels only the glass above it (14 of 30 rows); the profile window
    replaces §3.1's when those cover less than ``COVER`` of its area."""
    assert _railing_group((28, 44), 0.55) == [((14, 44, 14, 36), (74, 104, 14, 36))]


def _two_groups():
    """Two groups of two tiles whose windows differ by 1-2 px (tops 14 / 16 px below the tile top, left sides 14 /
    13 px from the tile side): the edge image and the groups' tiles."""
    from citygen_photo.tiles import EdgeImage
    gray = 0.7 + 0.02 * np.random.default_rng(5).standard_normal((120, 100))
    for top in (0, 60):
        gray[top + 14:top + 44, 14:36] = 0.25
        gray[top + 16:top + 44, 63:86] = 0.25
    return EdgeImage.of(gray), [[(0, 60, 0, 50), (60, 120, 0, 50)], [(0, 60, 50, 100), (60, 120, 50, 100)]]


def test_split_distances_are_synchronised_across_groups():
    """§3.2 global synchronisation: two groups whose windows differ by 1-2 px (imperfect symmetry: tops 14 / 16 px
    below the tile top, left sides 14 / 13 px from the tile side) are split separately, then every split distance
    takes its facade-wide cluster's median, so both groups' windows get the same offsets in their tiles."""
    from citygen_photo.tiles import stack_tree, subdivide_groups
    edges, groups = _two_groups()
    alone = [[n.rects[0] for n in _leaves(stack_tree(edges, g, False)) if n.label == "window"] for g in groups]
    assert alone == [[(14, 44, 14, 36)], [(16, 44, 13, 36)]]
    trees = subdivide_groups(edges, groups, [False, False])
    synced = [[n.rects for n in _leaves(t) if n.label == "window"] for t in trees]
    assert synced == [[((16, 44, 14, 36), (76, 104, 14, 36))], [((16, 44, 64, 86), (76, 104, 64, 86))]]


def test_rebuilt_groups_do_not_change_the_others_split_distances():
    """Regression (docs/photo.md doors step 6): the ground-floor tiles rebuilt around the door were synchronised
    together with every other group, so their split distances moved windows in tiles the door does not touch.
    A group flagged ``rebuilt`` is synchronised with all groups, the others only among themselves: the first group
    keeps the windows it has alone (not those synchronised with the second, above), the rebuilt one takes the
    medians of both."""
    from citygen_photo.tiles import subdivide_groups
    edges, groups = _two_groups()
    trees = subdivide_groups(edges, groups, [False, False], rebuilt=[False, True])
    windows = [[n.rects for n in _leaves(t) if n.label == "window"] for t in trees]
    assert windows == [[((15, 45, 14, 36), (75, 105, 14, 36))], [((16, 44, 64, 86), (76, 104, 64, 86))]]
    assert trees[0] == subdivide_groups(edges, groups[:1], [False])[0]
    assert trees[1] == subdivide_groups(edges, groups, [False, False])[1]


def test_synchronised_split_that_no_longer_fits_is_mapped():
    """Regression: a split moved by synchronisation can leave a child region too small for the child's own split
    (distance 30 in a region now 20 high); ``_resync`` crashed on it (seen with ``SYNC`` = 0.2 on the CMP photos).
    It maps that subtree proportionally, and the leaves still tile the region."""
    from citygen_photo.tiles import Node, _resync
    lower = Node(((20, 60, 0, 50),), None, (Node(((20, 30, 0, 50),), "wall"), Node(((30, 60, 0, 50),), "window")),
                 (("B", 30),))
    tree = Node(((0, 60, 0, 50),), None, (Node(((0, 20, 0, 50),), "wall"), lower), (("T", 20),))
    again = _resync(tree, (0, 60, 0, 50), {(True, 20): 40, (True, 30): 30})
    rects = [n.rects[0] for n in _leaves(again)]
    assert rects == [(0, 40, 0, 50), (40, 45, 0, 50), (45, 60, 0, 50)]


def test_profile_split_finds_two_windows_and_partitions_the_tile():
    """Two windows side by side in one mean tile: two element strips between wall strips, a partition."""
    from citygen_photo.tiles import EdgeImage, profile_split, wall_stats
    rng = np.random.default_rng(1)
    gray = 0.7 + 0.02 * rng.standard_normal((60, 80))
    gray[12:45, 10:30] = 0.2
    gray[12:45, 48:70] = 0.2
    edges = EdgeImage.of(gray)
    leaves = _leaves(profile_split(edges, wall_stats(edges, [(0, 60, 0, 80)])))
    windows = sorted(n.rects[0] for n in leaves if n.label == "window")
    assert windows == [(12, 45, 10, 30), (12, 45, 48, 70)]
    assert sum((r1 - r0) * (c1 - c0) for r0, r1, c0, c1 in (n.rects[0] for n in leaves)) == 60 * 80


def test_profile_split_none_on_plain_wall():
    from citygen_photo.tiles import EdgeImage, profile_split, wall_stats
    gray = 0.7 + 0.02 * np.random.default_rng(2).standard_normal((50, 50))
    edges = EdgeImage.of(gray)
    assert profile_split(edges, wall_stats(edges, [(0, 50, 0, 50)])) is None


def _misaligned_group():
    """Four 60 x 50 tiles whose 30 x 22 windows sit at different heights and sides (floor and tile lines off by up
    to 8 px, as on the CMP photos): the group's mean tile is a blur."""
    gray = 0.7 + 0.02 * np.random.default_rng(7).standard_normal((240, 50))
    tiles, boxes = [], []
    for k, (dr, dc) in enumerate(((0, 0), (8, -4), (-8, 4), (4, 6))):
        t0 = 60 * k
        r0, c0 = t0 + 15 + dr, 14 + dc
        gray[r0:r0 + 30, c0:c0 + 22] = 0.25
        tiles.append((t0, t0 + 60, 0, 50))
        boxes.append((r0, r0 + 30, c0, c0 + 22))
    return gray, tiles, boxes


def test_misaligned_group_windows_are_found_per_member():
    """Regression (CMP dev: 213 annotated windows lay in tiles with no detected window, e.g. cmp_b0016 with 1 of
    18): averaging members that are not aligned blurs the mean tile, §3.1 finds no window in it. The edge boxes
    found per member, with the group's size imposed, give every member's window exactly (they replace §3.1's
    windows in ``subdivide_groups`` where those cover less than ``COVER`` of them)."""
    from citygen_photo.tiles import EdgeImage, box_split, stack_tree
    gray, tiles, boxes = _misaligned_group()
    edges = EdgeImage.of(gray)
    mean_windows = [n.rects[0] for n in _leaves(stack_tree(edges, tiles, False)) if n.label == "window"]
    assert not any(close(w, boxes[0], 1) for w in mean_windows)  # the blur: 46 x 31 px for 30 x 22
    tree = box_split(edges, tiles)
    (found,) = [n.rects for n in _leaves(tree) if n.label == "window"]
    assert all(close(f, b, 1) for f, b in zip(found, boxes))
    assert check_partition_of(tree, tiles)


def check_partition_of(tree, tiles) -> bool:
    leaves = _leaves(tree)
    return all(sum((r1 - r0) * (c1 - c0) for r0, r1, c0, c1 in (n.rects[m] for n in leaves))
               == (t1 - t0) * (u1 - u0) for m, (t0, t1, u0, u1) in enumerate(tiles))


def test_edge_box_member_off_the_group_size_takes_the_median():
    """A member whose own edge box has another size (a window merged with a dark shutter) takes the group's median
    box relative to its tile (§3.2: the group's common split imposed)."""
    from citygen_photo.tiles import EdgeImage, box_split
    gray, tiles, boxes = _misaligned_group()
    gray[165:195, 40:47] = 0.25  # third member: a shutter beside the window widens its box
    (r0, r1, c0, c1) = box_split(EdgeImage.of(gray), tiles).children[1].children[1].rects[2]
    assert (r1 - r0, c1 - c0) == (30, 22)


def test_window_box_refined_at_full_resolution():
    """Regression: boxes scaled up from the ~400 px work image are off by up to a work pixel (2.5 crop px on a
    1000 px CMP crop) plus the work image's blur; each side is moved to the strongest edge of the box's polarity
    at full resolution."""
    from citygen_photo.photo import refine_box
    gray = 0.7 + 0.02 * np.random.default_rng(3).standard_normal((300, 300))
    gray[57:139, 103:161] = 0.2
    assert refine_box(gray, (100.5, 60.0, 163.0, 135.5)) == (103.0, 57.0, 161.0, 139.0)
    assert refine_box(gray, (106.0, 53.0, 158.0, 142.0)) == (103.0, 57.0, 161.0, 139.0)
