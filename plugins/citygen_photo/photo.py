"""A rectified facade photo -> FacadeLayout (mueller2007, "Image-based procedural modeling of facades").

Pipeline (documented in ``docs/photo.md``): the photo (optionally cropped to the facade) is reduced to a working
resolution of at most ``WORK`` pixels (``MI_WORK`` for the mutual information) and converted to grayscale
(colour is kept for labelling);

1. §2.2-2.3 (``photo_symmetry``): mutual information between vertically adjacent bands gives the floor period,
   checked against the irreducible facade's first stacking (a period spanning several floors is reduced to one);
   the same on the regular floors' band, transposed, gives the tile period;
2. §2.4 (``photo_structure``): floor lines are the minima of ``Ver(y)`` whose spacing fits the period (an
   irregular ground floor and attic are allowed), tile lines the minima of ``Hor(x)`` on the regular floors;
3. our extension (``photo_doors``): the entrance door, a box on the ground centred on the mirror axis of the
   floors above; the ground floor gets the door's sides as tile lines of its own, and only the tiles those lines
   cut or merge are grouped and subdivided anew (every other tile keeps its door-free group, subdivision and §3.2
   sizes: the door changes nothing but its own tiles);
   §3 (``photo_tiles``): similar tiles are grouped (``cluster_tiles``), each group's mean tile is subdivided
   and the subdivision mapped onto its members; a contrast test tells elements from wall;
4. §4 (``photo_elements``): each element's cluster of similar regions takes the best-matching element of a
   library of rendered citygen prototypes by summed mutual information (Eq. 8): label, depth and material.

The layout is in metres: ``width`` metres for the crop, else ``floor_height`` metres per detected floor period.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.ndimage import gaussian_filter

from citygen.errors import LayoutError
from citygen.layout import FacadeLayout, Region, check_partition
from citygen_photo.doors import (axis_door, door_tile, ground_columns, mirror_axis, repeats_floor_above,
                                         untouched_tiles)
from citygen_photo.elements import library
from citygen_photo.refit import carry
from citygen_photo.structure import GAP_TOLERANCE, edge_functions, interest, split_lines
from citygen_photo.symmetry import detect_symmetry, irreducible, quantize, validated_period
from citygen_photo.tiles import TAU_SIZE, EdgeImage, Node, subdivide_groups

#: Longest side (pixels) of the image the split lines and tiles are found in, and of the one for MI.
WORK = 400
MI_WORK = 300
#: Floor periods searched, as fractions of the facade height; tile periods as fractions of its width.
FLOOR_RANGE = (1 / 20, 1 / 2)
TILE_RANGE = (1 / 25, 1 / 2)
#: Least height of the top and bottom floor and least width of the first and last tile, in periods.
END_FLOOR = 0.35
END_TILE = 0.2
#: Eq. 4 smoothing as a fraction of the detected period (the paper's sigma = 1 m of a 3-5.5 m floor).
SIGMA = 0.25
#: Element pieces of one tile this close (working pixels) are one element.
MERGE_GAP = 6
#: A ground-floor tile left beside the door narrower than this fraction of the tile period joins the door's tile.
DOOR_GAP = 0.5
#: Window sides are refined at full resolution within this fraction of the box's width (height).
REFINE = 0.3
#: Depth of a tile in the layout tree (Facade -> floor -> tile): refined window sides move only inside it.
TILE_DEPTH = 2
#: Tile clustering: thumbnail size and least normalised correlation with a group's first tile.
THUMB = 16
SIMILAR = 0.5
#: The library elements by name (§4): a matched terminal takes its label, depth and material.
ELEMENTS = {e.name: e for e in library()}

Box = tuple[float, float, float, float]  # x0, y0, x1, y1 in crop pixels, y down
Rect = tuple[int, int, int, int]  # r0, r1, c0, c1 in working pixels, y down


@dataclass(frozen=True)
class PhotoAnalysis:
    """Detected structure in crop pixels (y down): floor and tile lines, element boxes and labels, layout."""

    layout: FacadeLayout
    floor_lines: tuple[float, ...]
    tile_lines: tuple[float, ...]
    elements: tuple[tuple[Box, str], ...]
    floor_period: float
    tile_period: float
    probabilities: np.ndarray | None = field(default=None, compare=False, repr=False)  # (learned parser)

    def boxes(self, label: str = "window") -> list[Box]:
        return [b for b, lab in self.elements if lab == label]


def load_photo(path: str | Path, crop: tuple[float, float, float, float] | None = None) -> np.ndarray:
    """The photo (cropped to ``x0 y0 x1 y1`` pixels, y down) as float RGB in 0..1, shape ``(H, W, 3)``."""
    from PIL import Image, UnidentifiedImageError
    try:
        with Image.open(path) as image:
            image.load()
            rgb = _as_rgb(image)
    except Image.DecompressionBombError as exc:
        raise LayoutError(f"the image is too large to open safely ({exc.args[0].split(',')[0]})", where=str(path),
                          hint="downscale the photo (the analysis works on at most ~1000 pixels a side)") from None
    except (UnidentifiedImageError, OSError, ValueError) as exc:
        if isinstance(exc, (FileNotFoundError, IsADirectoryError)):
            raise
        raise LayoutError("cannot read the image", where=str(path),
                          hint="give a photo Pillow can read (JPEG, PNG, TIFF ...)") from None
    if crop is not None:
        x0, y0, x1, y1 = (float(v) for v in crop)
        H, W = rgb.shape[:2]
        if not (0 <= x0 < x1 <= W and 0 <= y0 < y1 <= H):
            raise LayoutError(f"--crop {x0:g} {y0:g} {x1:g} {y1:g} is not inside the {W}x{H} image",
                              where=str(path), hint="give x0 y0 x1 y1 in pixels, y down, x0 < x1, y0 < y1")
        rgb = rgb[int(round(y0)):int(round(y1)), int(round(x0)):int(round(x1))]
    return rgb


def _as_rgb(image) -> np.ndarray:
    """Float RGB in 0..1; 16-bit and float grayscale keep their range (``convert("RGB")`` would clip them)."""
    if image.mode.startswith("I;16") or image.mode in ("I", "F"):
        gray = np.asarray(image, dtype=float)
        lo, hi = (0.0, 65535.0) if image.mode.startswith("I;16") else (float(gray.min()), float(gray.max()))
        gray = (gray - lo) / max(hi - lo, 1e-12)
        return np.repeat(gray[..., None], 3, axis=2)
    return np.asarray(image.convert("RGB"), dtype=float) / 255.0


def _work(image: np.ndarray, longest: int) -> tuple[np.ndarray, float]:
    """Resample to at most ``longest`` pixels (box filter) and blur slightly; returns the image and its pixel size
    in crop pixels."""
    from PIL import Image
    H, W = image.shape[:2]
    f = max(H, W) / longest
    if f > 1:
        size = (max(int(round(W / f)), 1), max(int(round(H / f)), 1))
        planes = image[..., None] if image.ndim == 2 else image
        image = np.stack([np.asarray(Image.fromarray(planes[..., k].astype(np.float32)).resize(
            size, Image.Resampling.BOX)) for k in range(planes.shape[2])], axis=-1).astype(float)
        image = image[..., 0] if planes.shape[2] == 1 else image
    sigma = (0.7, 0.7) if image.ndim == 2 else (0.7, 0.7, 0)
    return gaussian_filter(image, sigma), max(f, 1.0)


def luminance(rgb: np.ndarray) -> np.ndarray:
    return rgb if rgb.ndim == 2 else rgb @ np.array([0.299, 0.587, 0.114])


def analyse(image: np.ndarray, source: str = "<photo>", *, width: float | None = None,
            floor_height: float = 3.0, meta: dict | None = None) -> PhotoAnalysis:
    """Run the pipeline on an RGB ``(H, W, 3)`` or grayscale ``(H, W)`` crop of the facade (0..1)."""
    colour, f = _work(image, WORK)
    work = luminance(colour)
    small, g = _work(luminance(image), MI_WORK)
    H, W = work.shape
    h, w = small.shape
    if min(H, W) < 4 * TAU_SIZE:
        raise LayoutError(f"the facade is only {image.shape[1]}x{image.shape[0]} pixels", where=source,
                          hint="give a larger photo or a larger --crop")
    vsym = detect_symmetry(quantize(small), int(FLOOR_RANGE[0] * h), int(FLOOR_RANGE[1] * h))
    if not vsym.found:
        raise LayoutError(f"no repetition of floors detected (MI prominence {vsym.prominence:.3f})", where=source,
                          hint="crop the photo to the facade (--crop x0 y0 x1 y1); it must be rectified and show "
                               "at least two similar floors")
    P = int(round(validated_period(vsym, irreducible(vsym)) * g / f))
    hor, ver = edge_functions(work)
    Ver = interest(ver.sum(axis=1), hor.sum(axis=1), max(SIGMA * P, 1.0))
    floors = split_lines(Ver, P, 0, H, min_end=max(int(END_FLOOR * P), TAU_SIZE))
    gaps = np.diff(floors)
    regular = np.abs(gaps - P) <= GAP_TOLERANCE * P
    band = (floors[:-1][regular].min(), floors[1:][regular].max()) if regular.any() else (0, H)
    lo, hi = int(band[0] * f / g), max(int(np.ceil(band[1] * f / g)), int(band[0] * f / g) + 1)
    hsym = detect_symmetry(quantize(small[lo:hi]).T, int(TILE_RANGE[0] * w), int(TILE_RANGE[1] * w))
    Q = int(round(validated_period(hsym, irreducible(hsym)) * g / f)) if hsym.found else 0
    if Q:
        Hor = interest(hor[band[0]:band[1]].sum(axis=0), ver[band[0]:band[1]].sum(axis=0), max(SIGMA * Q, 1.0))
        tiles = split_lines(Hor, Q, 0, W, min_end=max(int(END_TILE * Q), TAU_SIZE))
    else:
        tiles = np.array([0, W])
    ground, top = floors.size - 2, int(floors[-2])
    axis = mirror_axis(work[:top] if top >= 2 * TAU_SIZE else work)
    door = axis_door(work, top, axis) if top >= 2 * TAU_SIZE and not repeats_floor_above(work, top) else None
    columns = [tiles] * (floors.size - 1)
    edges = EdgeImage.of(work, colour)
    groups = cluster_tiles(work, floors, columns, regular)  # as without a door: the door changes only its tiles
    trees: dict[tuple[int, int], tuple[str, Node, int]] = {}
    kept = {k: k for k in range(tiles.size - 1)}  # the ground floor's tiles the door leaves: shared -> own index
    rebuilt: list[list[tuple[int, int]]] = []  # groups of the ground-floor tiles rebuilt around the door
    if door is not None:
        columns[ground], j = ground_columns(tiles, door.rect, max(2 * TAU_SIZE, int(DOOR_GAP * Q)))
        rect = (top, H, int(columns[ground][j]), int(columns[ground][j + 1]))
        trees[(ground, j)] = ("DoorTile", door_tile(edges, rect, door.rect), 0)
        kept = untouched_tiles(tiles, columns[ground], j)
        cut = set(range(columns[ground].size - 1)) - {j} - set(kept.values())
        rebuilt = cluster_tiles(work, floors, columns, regular, {(ground, k) for k in cut}) if cut else []
    everything = groups + rebuilt
    grounds = [all(i == ground for i, _ in members) for members in everything]
    rects = _rects(floors, [tiles] * (floors.size - 1), groups) + _rects(floors, columns, rebuilt)
    nodes = subdivide_groups(edges, rects, grounds, door is None, [g >= len(groups) for g in range(len(rects))])
    for g, (members, node) in enumerate(zip(everything, nodes)):
        for m, (i, k) in enumerate(members):
            if i == ground and g < len(groups):  # a door-free ground-floor group: its tiles the door left
                if k not in kept:
                    continue
                k = kept[k]
            trees[(i, k)] = (f"Tile{g + 1}", node, m)
    scale = (width / W) if width else floor_height / P
    layout, elements, paths = _layout(floors, columns, regular, trees, H, scale)
    root, boxes, sides = _refined(layout.root, luminance(image), elements, paths, f, scale, H)
    meta = dict(meta or {}, importer="photo (mueller2007)", metres_per_pixel=scale / f,
                scale_from=f"width {width} m" if width else f"floor period x {floor_height} m",
                floor_period_px=round(P * f, 2), tile_period_px=round(Q * f, 2),
                floors=int(floors.size - 1), tiles_per_floor=int(tiles.size - 1),
                mi_prominence={"floors": round(vsym.prominence, 4), "tiles": round(hsym.prominence, 4)},
                refined_sides=sides, door_axis_px=round(axis * f, 2),
                door_edge=round(door.strength, 3) if door else None)
    layout = FacadeLayout(layout.width, layout.height, root, meta)
    problems = check_partition(layout)
    if problems:
        raise LayoutError("photo analysis did not give a partition: " + "; ".join(problems[:3]), where=source)
    return PhotoAnalysis(layout, tuple(float(v * f) for v in floors), tuple(float(v * f) for v in tiles), boxes,
                         float(P * f), float(Q * f))


def _refined(root: Region, full: np.ndarray, elements: list, paths: list, f: float, s: float,
             H: int) -> tuple[Region, tuple[tuple[Box, str], ...], dict[str, int]]:
    """The element boxes in crop pixels, windows refined at full resolution (:func:`refine_box`), and the layout
    root with the refined sides carried into the window terminals where the tile's structure allows
    (``photo_refit.carry``); counts of the window sides moved in the layout and of those that differed."""
    def metres(box: Box) -> Box:
        x0, y0, x1, y1 = box
        return x0 * s / f, (H - y1 / f) * s, x1 * s / f, (H - y0 / f) * s
    eps = 1e-9 * max(root.w, root.h)
    boxes, moved, wanted = [], 0, 0
    for (r0, r1, c0, c1), lab, members in merge_elements(elements):
        box = (c0 * f, r0 * f, c1 * f, r1 * f)
        if lab == "window":
            new = refine_box(full, box)
            root, m, w = carry(root, [paths[k] for k in members], metres(box), metres(new), TILE_DEPTH, s / f, eps)
            moved, wanted, box = moved + m, wanted + w, new
        boxes.append((box, lab))
    return root, tuple(boxes), {"moved": moved, "refined": wanted}


def refine_box(gray: np.ndarray, box: Box) -> Box:
    """A window box (crop pixels) with each side moved to the strongest edge of the box's polarity (darker or
    brighter inside than the 3 px ring around it) within ``REFINE`` of the box size, at the crop's full resolution:
    §3.1's edge test without the work image's quantisation (a side sums the edge over the middle of the box, the
    corners excluded). The box is kept when the sides would come closer than 4 px."""
    H, W = gray.shape
    x0, y0, x1, y1 = (int(round(v)) for v in box)
    x0, y0, x1, y1 = max(x0, 1), max(y0, 1), min(x1, W - 1), min(y1, H - 1)
    if x1 - x0 < 4 or y1 - y0 < 4:
        return box
    dx = gray[:, 1:] - gray[:, :-1]  # dx[:, c - 1]: across the line between columns c - 1 and c
    dy = gray[1:] - gray[:-1]
    inner = gray[y0:y1, x0:x1].mean()
    ring = np.concatenate([gray[max(y0 - 3, 0):y0, x0:x1].ravel(), gray[y1:y1 + 3, x0:x1].ravel(),
                           gray[y0:y1, max(x0 - 3, 0):x0].ravel(), gray[y0:y1, x1:x1 + 3].ravel()])
    s = 1.0 if ring.size == 0 or ring.mean() >= inner else -1.0  # +1: darker inside
    rx, ry = max(2, int(REFINE * (x1 - x0))), max(2, int(REFINE * (y1 - y0)))
    a, b = y0 + ry, y1 - ry  # edge rows used for the vertical sides: the middle of the box
    c, d = x0 + rx, x1 - rx

    def best(profile, lo, hi, sign):
        lo, hi = max(lo, 1), min(hi, profile.size)
        seg = sign * profile[lo - 1:hi - 1]
        return lo + int(np.argmax(seg)) if seg.size else None
    left = best(dx[a:b].sum(axis=0) if b > a else dx[y0:y1].sum(axis=0), x0 - rx, x0 + rx + 1, -s)
    right = best(dx[a:b].sum(axis=0) if b > a else dx[y0:y1].sum(axis=0), x1 - rx, x1 + rx + 1, s)
    top = best(dy[:, c:d].sum(axis=1) if d > c else dy[:, x0:x1].sum(axis=1), y0 - ry, y0 + ry + 1, -s)
    bot = best(dy[:, c:d].sum(axis=1) if d > c else dy[:, x0:x1].sum(axis=1), y1 - ry, y1 + ry + 1, s)
    nx0, nx1 = (left or x0), (right or x1)
    ny0, ny1 = (top or y0), (bot or y1)
    if nx1 - nx0 < 4 or ny1 - ny0 < 4:
        return box
    return (float(nx0), float(ny0), float(nx1), float(ny1))


def cluster_tiles(work: np.ndarray, floors: np.ndarray, columns: list[np.ndarray], regular: np.ndarray,
                  only: set[tuple[int, int]] | None = None) -> list[list[tuple[int, int]]]:
    """Groups of similar tiles (§2: "similar tile appearances are detected and registered in groups").

    Only tiles of the stacked (regular) floors, or of one irregular floor, are grouped together; the ground floor
    is never stacked with the floors above (§2.2: "the bottom and top floors often differ"). Tiles are compared as ``THUMB x THUMB`` thumbnails (zero mean, unit variance) by normalised correlation; a
    tile joins the first group whose first member it matches by at least ``SIMILAR`` and whose size it has
    within the gap tolerance, else it starts a group. ``columns[i]`` are floor ``i``'s tile lines (the ground
    floor's differ where a door was found); only the cells ``only`` are grouped when given (the ground-floor
    tiles rebuilt around the door)."""
    from PIL import Image
    cells = [(i, j) for i in range(floors.size - 1) for j in range(columns[i].size - 1)
             if only is None or (i, j) in only]
    ground = floors.size - 2
    thumbs, sizes = [], []
    for i, j in cells:
        block = work[floors[i]:floors[i + 1], columns[i][j]:columns[i][j + 1]]
        t = np.asarray(Image.fromarray(block.astype(np.float32)).resize((THUMB, THUMB), Image.Resampling.BOX))
        t = t - t.mean()
        thumbs.append(t.ravel() / max(float(np.linalg.norm(t)), 1e-9))
        sizes.append(block.shape)
    thumbs_a, sizes_a = np.array(thumbs), np.array(sizes, dtype=float)
    similar = thumbs_a @ thumbs_a.T
    heads: list[int] = []
    groups: list[list[tuple[int, int]]] = []
    for k, cell in enumerate(cells):
        for g, head in enumerate(heads):
            a, b = cell[0], cells[head][0]
            same_floors = a == b or (regular[a] and regular[b] and ground not in (a, b))
            if same_floors and similar[k, head] >= SIMILAR and np.all(np.abs(sizes_a[k] - sizes_a[head])
                                                      <= GAP_TOLERANCE * sizes_a[head]):
                groups[g].append(cell)
                break
        else:
            heads.append(k)
            groups.append([cell])
    return groups


def _rects(floors: np.ndarray, columns: list[np.ndarray], groups: list[list[tuple[int, int]]]) -> list[list[Rect]]:
    """The member tiles of every group as rectangles (``columns[i]``: floor ``i``'s tile lines)."""
    return [[(int(floors[i]), int(floors[i + 1]), int(columns[i][j]), int(columns[i][j + 1])) for i, j in members]
            for members in groups]


def merge_elements(elements: list[tuple[Rect, str, tuple[int, int]]]) -> list[tuple[Rect, str, tuple[int, ...]]]:
    """One box per element: terminals of one label and tile that share an edge, or face each other across at
    most ``MERGE_GAP`` pixels, are one window (a window split at its mullion, or into frame and glass, is still
    one window), as their bounding box, with the indices of its terminals in ``elements``."""
    parent = list(range(len(elements)))

    def find(k: int) -> int:
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k
    for a, (ra, la, ta) in enumerate(elements):
        for b in range(a + 1, len(elements)):
            rb, lb, tb = elements[b]
            if (la, ta) != (lb, tb):
                continue
            rows = min(ra[1], rb[1]) - max(ra[0], rb[0])
            cols = min(ra[3], rb[3]) - max(ra[2], rb[2])
            if (rows > 0 and -MERGE_GAP <= cols <= 0) or (cols > 0 and -MERGE_GAP <= rows <= 0):
                parent[find(a)] = find(b)
    merged: dict[int, tuple[Rect, str, tuple[int, ...]]] = {}
    for k, (rect, label, _) in enumerate(elements):
        root = find(k)
        members: tuple[int, ...] = (k,)
        if root in merged:
            (r0, r1, c0, c1), _, members = merged[root]
            rect = (min(r0, rect[0]), max(r1, rect[1]), min(c0, rect[2]), max(c1, rect[3]))
            members += (k,)
        merged[root] = (rect, label, members)
    return [merged[k] for k in sorted(merged)]


def _layout(floors: np.ndarray, columns: list[np.ndarray], regular: np.ndarray, trees: dict, H: int,
            s: float) -> tuple[FacadeLayout, list, list]:
    """Region tree in metres (y up), the element rectangles in working pixels and the paths of their terminals
    from the root (child indices; the tile is at depth ``TILE_DEPTH``)."""
    elements: list = []
    paths: list = []

    def region(rect, symbol, label=None, children=(), element=None):
        r0, r1, c0, c1 = rect
        x0, x1, y0, y1 = c0 * s, c1 * s, (H - r1) * s, (H - r0) * s
        e = ELEMENTS.get(element)
        return Region(x=x0, y=y0, w=x1 - x0, h=y1 - y0, symbol=symbol, label=label, depth=e.depth if e else 0.0,
                      material=e.material if e else None, children=tuple(children))

    def build(node: Node, m: int, symbol: str, i: int, j: int, path: tuple[int, ...]):
        if node.children:  # regions that the proportional mapping shrank to nothing are left out
            kept = [(k, c) for k, c in enumerate(node.children)
                    if c.rects[m][0] < c.rects[m][1] and c.rects[m][2] < c.rects[m][3]]
            kids = [build(c, m, f"{symbol}_{k}", i, j, path + (n,)) for n, (k, c) in enumerate(kept)]
            return region(node.rects[m], symbol, children=kids)
        if node.element is not None:
            elements.append((node.rects[m], node.label, (i, j)))
            paths.append(path)
        return region(node.rects[m], (node.label or "wall").capitalize(), node.label or "wall", element=node.element)

    floor_regions = []
    last = floors.size - 2
    for i in range(floors.size - 1):
        name = "Floor" if regular[i] else ("GroundFloor" if i == last else f"Floor{i}")
        row = []
        for j in range(columns[i].size - 1):
            symbol, node, m = trees[(i, j)]
            row.append(build(node, m, symbol, i, j, (floors.size - 2 - i, j)))
        floor_regions.append(region((floors[i], floors[i + 1], columns[i][0], columns[i][-1]), name, children=row))
    root = region((0, H, columns[0][0], columns[0][-1]), "Facade", children=reversed(floor_regions))
    return FacadeLayout(root.w, root.h, root), elements, paths


def layout_from_photo(path: str | Path, *, width: float | None = None, floor_height: float = 3.0,
                      crop: tuple[float, float, float, float] | None = None, parser: str = "learned"
                      ) -> PhotoAnalysis:
    """Read ``path`` and analyse it with ``parser`` (one of :data:`citygen_photo.PARSERS`)."""
    rgb = load_photo(path, crop)
    meta = {"source": Path(path).name, "image_crop": list(crop) if crop else None}
    if parser == "learned":
        from citygen_photo.learned import analyse_learned
        return analyse_learned(rgb, str(path), width=width, floor_height=floor_height, meta=meta)
    return analyse(rgb, str(path), width=width, floor_height=floor_height, meta=meta)
