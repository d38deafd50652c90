"""Subdivision of facade tiles (mueller2007 §3) and labelling of the elements.

The tiles of one group (similar tiles, ``photo.cluster_tiles``) are resampled to their median size and averaged:
the group's stack of the irreducible facade (§2.3). Its subdivision is found once and mapped proportionally onto
every member, so similar tiles are split at corresponding positions (the aim of §3.2's synchronisation). Each
step finds the first relevant edge moving inward from each side (§3.1: average directional gradient above
``TAU_EDGE`` times the wall response measured in a zone along the tile boundary), drops candidates whose line
crosses the edge-responding segment of a perpendicular candidate and keeps the longest (two opposite ones of at
least 80 % length give a dual split). A region that no longer touches the tile boundary and whose intensity
differs from the wall is an element: a window (a door when it stands on the ground floor's bottom edge); it is
not split by edges further, only separated at interior wall bands (two windows in one tile). Where §3.1 labels
(almost) no window above the ground floor -- a railing spanning the tile stops every first edge -- windows come
from the non-wall projection profiles of the mean tile (``profile_split``, our extension).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from PIL import Image

from citygen_photo.elements import cluster_type

#: §3.1 edge relevance factor (the paper uses 4 on its images; JPEG street photos need less).
TAU_EDGE = 2.5
#: Fraction of a line over which its edge strength is averaged.
SPAN = 0.3
#: §3 minimum region size in pixels (the paper's 5).
TAU_SIZE = 5
#: A runner-up parallel to the winner with this fraction of its length makes a dual split (§3.1).
DUAL = 0.8
#: Element when the mean intensity differs from the wall by this many wall standard deviations.
CONTRAST = 0.6
#: ... or when at most this fraction of its colour histogram (``LEVELS`` per channel) is shared with the wall's.
SHARED = 0.5
LEVELS = 4
#: Least area of an element as a fraction of its tile (smaller contrasting pieces are frames, bars, ornament).
MIN_AREA = 0.1
#: Split steps per tile (ground-based images need 2-5, §3).
MAX_STEPS = 6
#: Element extent from the group's mean tile: a column (row) belongs to an element when at least this fraction
#: of its pixels differs from the wall.
FILL = 0.5
#: ... and a pixel differs from the wall when its intensity is off by this many wall standard deviations or its
#: colour is this rare in the wall zone's histogram.
PIXEL_CONTRAST = 1.5
#: The profile windows replace §3.1's when those cover less than this fraction of their area.
COVER = 0.5
RARE = 0.01
#: A door is at least this many times as high as wide (CMP doors: 1.2-2.3, a few double doors 0.8-0.9) ...
DOOR_ASPECT = 1.2
#: ... and stands in a group of at most this many ground-floor tiles (a door repeated in every tile of a longer
#: row is a row of shop fronts or an arcade).
MAX_DOORS = 2
#: §3.2 global synchronisation: split distances of one orientation within this fraction (plus a pixel) of a
#: cluster's smallest are one size.
SYNC = 0.1
#: Edge boxes: least height and width as fractions of the tile; a member box whose size is off the group's
#: median by more than ``BOX_AGREE`` takes the median box.
BOX_MIN = (0.15, 0.1)
BOX_AGREE = 0.2

Rect = tuple[int, int, int, int]  # r0, r1, c0, c1 (image rows down, half-open)


@dataclass(frozen=True)
class Node:
    """A region of the group's shared subdivision: ``rects[m]`` is its rectangle in member tile ``m``."""

    rects: tuple[Rect, ...]
    label: str | None = None
    children: tuple[Node, ...] = ()
    cuts: tuple[tuple[str, int], ...] = ()  # §3.1 split of this region: (side, distance of its line from the side)
    element: str | None = None  # name of the matched library element (§4, ``photo_elements``)


@dataclass(frozen=True)
class Candidate:
    side: str  # L, R, T, B
    pos: int  # split index (first row/column of the inner part)
    seg: tuple[int, int]  # edge-responding segment along the line (absolute rows or columns)
    length: int


@dataclass(frozen=True)
class EdgeImage:
    """Directional gradient magnitudes of the whole image and the intensities."""

    gray: np.ndarray
    eh: np.ndarray  # |dI/dy| where the gradient is mostly vertical (horizontal edges)
    ev: np.ndarray  # |dI/dx| where the gradient is mostly horizontal (vertical edges)
    mag: np.ndarray
    colour: np.ndarray  # (h, w, 3) RGB, or (h, w, 1) gray

    @classmethod
    def of(cls, gray: np.ndarray, colour: np.ndarray | None = None) -> EdgeImage:
        gy, gx = np.gradient(gray)
        ay, ax = np.abs(gy), np.abs(gx)
        colour = gray[..., None] if colour is None or colour.ndim == 2 else colour
        return cls(gray, np.where(ay > ax, ay, 0.0), np.where(ax > ay, ax, 0.0), np.hypot(gx, gy), colour)

    def histogram(self, rect: Rect, mask: np.ndarray | None = None) -> np.ndarray:
        """Normalised histogram of ``rect``'s colours quantised to ``LEVELS`` per channel."""
        r0, r1, c0, c1 = rect
        block = self.colour[r0:r1, c0:c1]
        pixels = block.reshape(-1, block.shape[2]) if mask is None else block[mask]
        q = np.clip((pixels * LEVELS).astype(int), 0, LEVELS - 1)
        codes = (q * LEVELS ** np.arange(q.shape[1])).sum(axis=1)
        hist = np.bincount(codes, minlength=LEVELS ** q.shape[1]).astype(float)
        return hist / max(hist.sum(), 1.0)


def wall_zone(rect: Rect) -> np.ndarray:
    """Mask of the zone along the tile boundary (where §2 puts wall)."""
    r0, r1, c0, c1 = rect
    band = max(2, int(0.08 * min(r1 - r0, c1 - c0)))
    mask = np.zeros((r1 - r0, c1 - c0), dtype=bool)
    mask[:band], mask[-band:], mask[:, :band], mask[:, -band:] = True, True, True, True
    return mask


def _first_edge(profile: np.ndarray, thr: float, lo: int, reverse: bool) -> int | None:
    """Split index at the first run of ``profile > thr`` met from one end (weighted centre of the run)."""
    hot = profile > thr
    if not hot.any():
        return None
    idx = np.flatnonzero(hot)
    start = idx[-1] if reverse else idx[0]
    run_lo = run_hi = start
    while run_lo - 1 >= 0 and hot[run_lo - 1]:
        run_lo -= 1
    while run_hi + 1 < hot.size and hot[run_hi + 1]:
        run_hi += 1
    w = profile[run_lo: run_hi + 1]
    centre = float(np.dot(np.arange(run_lo, run_hi + 1), w) / w.sum())
    return lo + int(np.floor(centre + 1.0))


def _strength(edge: np.ndarray, axis: int) -> np.ndarray:
    """Edge strength of every line: its mean over the strongest ``SPAN`` of the line (an element's edge crosses
    part of a tile, not all of it)."""
    k = max(int(SPAN * edge.shape[axis]), 1)
    return -np.mean(np.partition(-edge, k - 1, axis=axis).take(range(k), axis=axis), axis=axis)


def local_candidates(edges: EdgeImage, rect: Rect, thr: float) -> list[Candidate]:
    """§3.1: the first relevant edge from each side of ``rect`` and its edge-responding segment."""
    r0, r1, c0, c1 = rect
    out = []
    # horizontal split lines (sides T, B) from eh along the rows, vertical ones (L, R) from ev along the columns;
    # the vertical case is the horizontal one on the transposed block
    for sides, edge, (a0, a1), start in (("TB", edges.eh[r0:r1, c0:c1], (r0, r1), c0),
                                         ("LR", edges.ev[r0:r1, c0:c1].T, (c0, c1), r0)):
        if a1 - a0 < 2 * TAU_SIZE + 1:
            continue
        profile = _strength(edge, axis=1)
        inner = slice(TAU_SIZE - 1, a1 - a0 - TAU_SIZE)
        for side, rev in zip(sides, (False, True)):
            pos = _first_edge(profile[inner], thr, a0 + TAU_SIZE - 1, rev)
            if pos is not None and a0 + TAU_SIZE <= pos <= a1 - TAU_SIZE:
                line = np.maximum(edge[pos - a0 - 1], edge[min(pos - a0, a1 - a0 - 1)]) > thr
                out.append(_candidate(side, pos, line, start))
    # the first edge from both sides can be the same edge (a door reaching the tile bottom): one candidate
    seen: set[tuple[bool, int]] = set()
    unique = []
    for c in out:
        key = (c.side in "TB", c.pos)
        if c.length > 0 and key not in seen:
            seen.add(key)
            unique.append(c)
    return unique


def _candidate(side: str, pos: int, line: np.ndarray, offset: int) -> Candidate:
    """The edge-responding segment: the longest run of responding pixels along the line (gaps of up to
    ``TAU_SIZE`` pixels closed)."""
    hot = np.flatnonzero(line)
    if hot.size == 0:
        return Candidate(side, pos, (0, 0), 0)
    breaks = np.flatnonzero(np.diff(hot) > TAU_SIZE)
    starts, ends = np.r_[0, breaks + 1], np.r_[breaks, hot.size - 1]
    k = int(np.argmax(hot[ends] - hot[starts]))
    lo, hi = int(hot[starts[k]]), int(hot[ends[k]]) + 1
    return Candidate(side, pos, (offset + lo, offset + hi), int(ends[k] - starts[k] + 1))


def choose_split(cands: list[Candidate]) -> tuple[str, dict[str, int]]:
    """§3.1: drop crossed candidates, take the longest (dual with a parallel runner-up of >= 80 %)."""
    def crossed(c: Candidate) -> bool:
        for o in cands:
            if (c.side in "TB") == (o.side in "TB"):
                continue
            if o.seg[0] + 2 < c.pos < o.seg[1] - 2:
                return True
        return False
    alive = sorted((c for c in cands if not crossed(c)), key=lambda c: -c.length)
    if not alive:
        return "none", {}
    win = alive[0]
    opposite = {"L": "R", "R": "L", "T": "B", "B": "T"}[win.side]
    runner = next((c for c in alive[1:] if c.side in (win.side, opposite)), None)
    if runner is not None and runner.side == opposite and runner.length >= DUAL * win.length:
        kind = "LR" if win.side in "LR" else "TB"
        return kind, {win.side: win.pos, runner.side: runner.pos}
    return win.side, {win.side: win.pos}


def _offsets(kind: str, pos: dict[str, int], rect: Rect) -> dict[str, int]:
    r0, r1, c0, c1 = rect
    ref = {"T": r0, "B": r1, "L": c0, "R": c1}
    return {s: abs(p - ref[s]) for s, p in pos.items()}


def _apply(kind: str, off: dict[str, int], rect: Rect) -> list[Rect] | None:
    r0, r1, c0, c1 = rect
    if kind in ("T", "B", "TB"):
        cuts = ([r0 + off["T"]] if "T" in off else []) + ([r1 - off["B"]] if "B" in off else [])
        edges = [r0, *cuts, r1]
        if any(b - a < 1 for a, b in zip(edges, edges[1:])):
            return None
        return [(a, b, c0, c1) for a, b in zip(edges, edges[1:])]
    cuts = ([c0 + off["L"]] if "L" in off else []) + ([c1 - off["R"]] if "R" in off else [])
    edges = [c0, *cuts, c1]
    if any(b - a < 1 for a, b in zip(edges, edges[1:])):
        return None
    return [(r0, r1, a, b) for a, b in zip(edges, edges[1:])]


@dataclass(frozen=True)
class Wall:
    """Per-member wall statistics from the boundary zone: edge threshold, mean and std intensity, colours."""

    thr: np.ndarray
    mean: float
    std: float
    hist: np.ndarray


def wall_stats(edges: EdgeImage, tiles: list[Rect]) -> Wall:
    thr, values = [], []
    for t in tiles:
        r0, r1, c0, c1 = t
        mask = wall_zone(t)
        thr.append(TAU_EDGE * float(edges.mag[r0:r1, c0:c1][mask].mean()))
        values.append(edges.gray[r0:r1, c0:c1][mask])
    allv = np.concatenate(values)
    hist = np.mean([edges.histogram(t, wall_zone(t)) for t in tiles], axis=0)
    return Wall(np.array(thr), float(np.median(allv)), float(allv.std()) + 1e-6, hist)


def group_stack(edges: EdgeImage, tiles: list[Rect]) -> EdgeImage:
    """The members resampled to their median size and averaged; edges are those of the average."""
    h = int(np.median([r1 - r0 for r0, r1, _, _ in tiles]))
    w = int(np.median([c1 - c0 for _, _, c0, c1 in tiles]))

    def mean(image: np.ndarray) -> np.ndarray:
        acc = np.zeros((h, w))
        for r0, r1, c0, c1 in tiles:
            block = Image.fromarray(image[r0:r1, c0:c1].astype(np.float32))
            acc += np.asarray(block.resize((w, h), Image.Resampling.BILINEAR))
        return acc / len(tiles)
    colour = np.stack([mean(edges.colour[..., k]) for k in range(edges.colour.shape[2])], axis=-1)
    return EdgeImage.of(mean(edges.gray), colour)


def subdivide_groups(edges: EdgeImage, groups: list[list[Rect]], grounds: list[bool], doors: bool = True,
                     rebuilt: list[bool] | None = None) -> list[Node]:
    """The shared subdivision of every group of similar tiles, as trees with one rectangle per member: §3.1's
    edge splits on each group's mean tile (:func:`stack_tree`), their split distances synchronised across the
    whole facade (§3.2, :func:`synchronised`), mapped proportionally onto the members, and §4's element type per
    cluster of corresponding regions (:func:`match_elements`).

    ``doors`` False: the facade's door was found on its mirror axis (``photo_doors``), no other region is a door.
    ``rebuilt`` flags the groups of the ground-floor tiles rebuilt around that door: they are synchronised with
    every group, the others only among themselves (as without the door), so that the door step changes no tile
    but those its tile lines touch."""
    stacks = [stack_tree(edges, tiles, ground) for tiles, ground in zip(groups, grounds)]
    rebuilt = rebuilt or [False] * len(groups)
    base = synchronised([tree for tree, late in zip(stacks, rebuilt) if not late])
    sizes = synchronised(stacks) if any(rebuilt) else base
    out = []
    for tree, tiles, ground, late in zip(stacks, groups, grounds, rebuilt):
        node = _members(_resync(tree, tree.rects[0], sizes if late else base), tree.rects[0], tiles)
        boxed = None if ground else box_split(edges, tiles)
        if boxed is not None and _area(node, "window") < COVER * _area(boxed, "window"):
            node = boxed
        out.append(match_elements(edges, node, doors))
    return out


def subdivide_group(edges: EdgeImage, tiles: list[Rect], ground: bool = False) -> Node:
    """:func:`subdivide_groups` for one group."""
    return subdivide_groups(edges, [tiles], [ground])[0]


def stack_tree(edges: EdgeImage, tiles: list[Rect], ground: bool) -> Node:
    """The subdivision of a group's mean tile ``(0, h, 0, w)``: §3.1's edge splits; when they find no window above
    the ground floor, :func:`profile_split`."""
    stack = group_stack(edges, tiles)
    h, w = stack.gray.shape
    whole = (0, h, 0, w)
    wall = wall_stats(stack, [whole])
    tree = _split(stack, Node((whole,)), (whole,), wall, ground, MAX_STEPS)
    profile = None if ground else profile_split(stack, wall)
    if profile is not None and _area(tree, "window") < COVER * _area(profile, "window"):
        tree = profile
    return tree


def match_elements(edges: EdgeImage, tree: Node, doors: bool = True) -> Node:
    """§4: every element leaf -- a region the contrast test (:func:`_element_label`) or the profile windows took
    for an element -- is a cluster of similar regions, one per member tile; its label and element are Eq. 8's
    best library element among those :func:`_element_labels` allows. The contrast test stays the prior that
    decides element or wall (Eq. 8 with the wall element decided worse on the CMP development photos)."""
    tiles = tree.rects

    def visit(node: Node) -> Node:
        if node.children:
            return Node(node.rects, node.label, tuple(visit(c) for c in node.children), node.cuts)
        if node.label in (None, "wall"):
            return node
        element, _ = cluster_type(edges.gray, node.rects, _element_labels(node, tiles, doors))
        return Node(node.rects, element.label, element=element.name)
    return visit(tree)


def _element_labels(node: Node, tiles: tuple[Rect, ...], doors: bool = True) -> tuple[str, ...]:
    """Labels an element leaf may take: a region the contrast test took for a door (on the ground floor's bottom
    edge, or a piece of one) is a door -- if plausible: ``doors`` (no door found on the facade's mirror axis), at
    least ``DOOR_ASPECT`` times as high as wide, in a group of at most ``MAX_DOORS`` tiles (a door repeated in
    every tile of a longer row is a row of shop fronts or an arcade) -- or a shop front; any other a window."""
    if node.label != "door":
        return ("window",)
    r0, r1, c0, c1 = node.rects[0]
    plausible = doors and len(tiles) <= MAX_DOORS and r1 - r0 >= DOOR_ASPECT * (c1 - c0)
    return ("door", "shop") if plausible else ("shop",)


def synchronised(trees: list[Node]) -> dict[tuple[bool, int], int]:
    """§3.2: "there are only a limited set of element sizes on each facade" -- the distances of all split lines
    from the side they were found from, over all groups, clustered per orientation (sorted; a value more than
    ``SYNC`` plus a pixel above its cluster's smallest starts a new cluster). Maps (horizontal line, distance) to
    its cluster's median."""
    values: dict[bool, list[int]] = {True: [], False: []}

    def collect(node: Node) -> None:
        for side, d in node.cuts:
            values[side in "TB"].append(d)
        for c in node.children:
            collect(c)
    for tree in trees:
        collect(tree)
    sizes = {}
    for horizontal, found in values.items():
        clusters: list[list[int]] = []
        for d in sorted(found):
            if clusters and d <= clusters[-1][0] * (1 + SYNC) + 1:
                clusters[-1].append(d)
            else:
                clusters.append([d])
        sizes.update({(horizontal, d): int(round(float(np.median(c)))) for c in clusters for d in c})
    return sizes


def _resync(node: Node, rect: Rect, sizes: dict[tuple[bool, int], int]) -> Node:
    """The subdivision rebuilt in ``rect`` with the synchronised split distances (a split that no longer fits
    keeps its own); regions split otherwise (wall bands between elements, profile windows), and splits whose own
    distances no longer fit the region either, are mapped proportionally."""
    if not node.children:
        return Node((rect,), node.label)
    kind = "TB" if node.cuts and node.cuts[0][0] in "TB" else "LR"
    parts = None
    for off in ({s: sizes[(s in "TB", d)] for s, d in node.cuts}, dict(node.cuts)) if node.cuts else ():
        parts = _apply(kind, off, rect)
        if parts is not None and len(parts) == len(node.children):
            break
        parts = None
    if parts is None:
        return _members(node, node.rects[0], [rect])
    return Node((rect,), node.label, tuple(_resync(c, p, sizes) for c, p in zip(node.children, parts)), node.cuts)


def _area(node: Node, label: str) -> int:
    """Area of the ``label`` leaves of a single-member tree."""
    if node.children:
        return sum(_area(c, label) for c in node.children)
    r0, r1, c0, c1 = node.rects[0]
    return (r1 - r0) * (c1 - c0) if node.label == label else 0


def non_wall(edges: EdgeImage, wall: Wall) -> np.ndarray:
    """Pixels that differ from the wall: intensity off by ``PIXEL_CONTRAST`` wall standard deviations, or a
    colour that is rare (``RARE``) in the wall zone."""
    q = np.clip((edges.colour * LEVELS).astype(int), 0, LEVELS - 1)
    codes = (q * LEVELS ** np.arange(q.shape[2])).sum(axis=2)
    return (np.abs(edges.gray - wall.mean) >= PIXEL_CONTRAST * wall.std) | (wall.hist[codes] < RARE)


def _runs(flags: np.ndarray, close: int, least: int) -> list[tuple[int, int]]:
    """Half-open runs of ``flags`` (gaps of up to ``close`` closed) at least ``least`` long."""
    idx = np.flatnonzero(flags)
    if idx.size == 0:
        return []
    breaks = np.flatnonzero(np.diff(idx) > close + 1)
    starts, ends = idx[np.r_[0, breaks + 1]], idx[np.r_[breaks, idx.size - 1]] + 1
    return [(int(a), int(b)) for a, b in zip(starts, ends) if b - a >= least]


def profile_split(edges: EdgeImage, wall: Wall) -> Node | None:
    """Windows of a mean tile by projection profiles of its non-wall pixels (our fallback where §3.1's first-edge
    splits end in regions touching the tile boundary, e.g. at a railing spanning the tile): the element columns are the runs of columns
    at least ``FILL`` non-wall, its rows the longest such run of rows within them. Each element is cut out by a
    vertical split (wall | element strip | wall) and a horizontal one in its strip. None when there is none."""
    mask = non_wall(edges, wall)
    h, w = mask.shape
    cols = _runs(mask.mean(axis=0) >= FILL, TAU_SIZE, max(TAU_SIZE, int(MIN_AREA * w)))
    boxes = []
    for c0, c1 in cols:
        rows = _runs(mask[:, c0:c1].mean(axis=1) >= FILL, TAU_SIZE, TAU_SIZE)
        if rows:
            r0, r1 = max(rows, key=lambda r: r[1] - r[0])
            if (r1 - r0) * (c1 - c0) >= MIN_AREA * h * w and (r0, r1) != (0, h):
                boxes.append((r0, r1, c0, c1))
    if not boxes:
        return None
    strips, x = [], 0
    for r0, r1, c0, c1 in boxes:
        if c0 > x:
            strips.append(Node(((0, h, x, c0),), "wall"))
        cuts = [0, *(v for v in (r0, r1) if 0 < v < h), h]
        parts = [Node(((a, b, c0, c1),), "window" if (a, b) == (r0, r1) else "wall") for a, b in zip(cuts, cuts[1:])]
        strips.append(Node(((0, h, c0, c1),), None, tuple(parts)))
        x = c1
    if x < w:
        strips.append(Node(((0, h, x, w),), "wall"))
    return Node(((0, h, 0, w),), None, tuple(strips))


def _members(node: Node, source: Rect, tiles: list[Rect]) -> Node:
    """Map a subdivision of the rectangle ``source`` proportionally onto every rectangle of ``tiles``."""
    s0, s1, z0, z1 = source
    h, w = s1 - s0, z1 - z0
    r0, r1, c0, c1 = node.rects[0]
    rects = tuple((t0 + round((r0 - s0) * (t1 - t0) / h), t0 + round((r1 - s0) * (t1 - t0) / h),
                   u0 + round((c0 - z0) * (u1 - u0) / w), u0 + round((c1 - z0) * (u1 - u0) / w))
                  for t0, t1, u0, u1 in tiles)
    return Node(rects, node.label, tuple(_members(c, source, tiles) for c in node.children), node.cuts)


def _touches(rects: tuple[Rect, ...], tiles: tuple[Rect, ...]) -> tuple[bool, bool]:
    """(touches any side but the bottom, touches the bottom) for the first member."""
    (r0, r1, c0, c1), (t0, t1, u0, u1) = rects[0], tiles[0]
    return r0 == t0 or c0 == u0 or c1 == u1, r1 == t1


def _element_label(edges: EdgeImage, node: Node, tiles: tuple[Rect, ...], wall: Wall, ground: bool) -> str | None:
    sides, bottom = _touches(node.rects, tiles)
    if sides or (bottom and not ground):
        return None
    (r0, r1, c0, c1), (t0, t1, u0, u1) = node.rects[0], tiles[0]
    if (r1 - r0) * (c1 - c0) < MIN_AREA * (t1 - t0) * (u1 - u0):
        return None
    mean = float(np.mean([edges.gray[r0:r1, c0:c1].mean() for r0, r1, c0, c1 in node.rects]))
    if _wall_like(edges, node.rects[0], mean, wall):
        return None
    if bottom:  # a door reaches the ground; wall below an opening is split off first
        r0, r1, c0, c1 = node.rects[0]
        band = (r1 - max(TAU_SIZE, (r1 - r0) // 10), r1, c0, c1)
        if _wall_like(edges, band, float(edges.gray[band[0]:r1, c0:c1].mean()), wall):
            return None
        return "door"
    return "window"


def _wall_like(edges: EdgeImage, rect: Rect, mean: float, wall: Wall) -> bool:
    shared = float(np.minimum(edges.histogram(rect), wall.hist).sum())
    return abs(mean - wall.mean) < CONTRAST * wall.std and shared > SHARED


def _wall_gap(edges: EdgeImage, node: Node, wall: Wall) -> tuple[str, int, int] | None:
    """A band of wall-coloured columns (else rows) strictly inside an element region: two elements side by side
    (windows paired in one tile) separated by wall. Returns (axis, start, end) as offsets into the region."""
    for axis in ("LR", "TB"):
        length = min((c1 - c0) if axis == "LR" else (r1 - r0) for r0, r1, c0, c1 in node.rects)
        profile = np.zeros(length)
        for r0, r1, c0, c1 in node.rects:
            block = edges.gray[r0:r1, c0:c1]
            profile += (block.mean(axis=0) if axis == "LR" else block.mean(axis=1))[:length]
        profile /= len(node.rects)
        like = np.abs(profile - wall.mean) < CONTRAST * wall.std
        like[:TAU_SIZE], like[length - TAU_SIZE:] = False, False
        if not like.any():
            continue
        idx = np.flatnonzero(like)
        breaks = np.flatnonzero(np.diff(idx) > 1)
        starts, ends = np.r_[0, breaks + 1], np.r_[breaks, idx.size - 1]
        k = int(np.argmax(ends - starts))
        if ends[k] - starts[k] + 1 >= max(2, TAU_SIZE // 2):
            return axis, int(idx[starts[k]]), int(idx[ends[k]]) + 1
    return None


def _separate(edges: EdgeImage, node: Node, wall: Wall, label: str, depth: int = 3) -> Node:
    """An element, or elements split apart at interior wall bands (:func:`_wall_gap`)."""
    gap = _wall_gap(edges, node, wall) if depth > 0 else None
    if gap is None:
        return Node(node.rects, label)
    axis, a, b = gap
    parts = [_apply(axis, {"L" if axis == "LR" else "T": a, "R" if axis == "LR" else "B":
                           ((r[3] - r[2]) if axis == "LR" else (r[1] - r[0])) - b}, r) for r in node.rects]
    if any(p is None for p in parts):
        return Node(node.rects, label)
    first = Node(tuple(p[0] for p in parts))
    last = Node(tuple(p[2] for p in parts))
    return Node(node.rects, None, (_separate(edges, first, wall, label, depth - 1), Node(tuple(p[1] for p in parts),
                                   "wall"), _separate(edges, last, wall, label, depth - 1)))


def _split(edges: EdgeImage, node: Node, tiles: tuple[Rect, ...], wall: Wall, ground: bool, steps: int) -> Node:
    label = _element_label(edges, node, tiles, wall, ground) if node.rects != tiles else None
    if label is not None:
        return _separate(edges, node, wall, label)
    kind, pos = choose_split(local_candidates(edges, node.rects[0], wall.thr[0])) if steps > 0 else ("none", {})
    if kind == "none":
        return Node(node.rects, "wall")
    off = _offsets(kind, pos, node.rects[0])
    parts = _apply(kind, off, node.rects[0])
    if parts is None:
        return Node(node.rects, "wall")
    children = []
    for rect in parts:
        r0, r1, c0, c1 = rect
        if min(r1 - r0, c1 - c0) < TAU_SIZE:
            children.append(Node((rect,), "wall"))
        else:
            children.append(_split(edges, Node((rect,)), tiles, wall, ground, steps - 1))
    return Node(node.rects, None, tuple(children), tuple(sorted(off.items())))


def edge_box(g: np.ndarray) -> tuple[Rect, float] | None:
    """The rectangle of a tile (at least ``TAU_SIZE`` from its sides, ``BOX_MIN`` of its size) whose four sides lie
    on the strongest edges of one polarity: the largest contrast summed across its boundary (outside minus inside
    for a dark element, the reverse for a bright one), with the score. The sum splits into a term of the left and
    one of the right column for given rows, so every row pair costs O(width)."""
    h, w = g.shape
    m = TAU_SIZE
    min_h, min_w = max(TAU_SIZE, int(BOX_MIN[0] * h)), max(TAU_SIZE, int(BOX_MIN[1] * w))
    dx = np.zeros_like(g)
    dx[:, 1:] = g[:, 1:] - g[:, :-1]
    dy = np.zeros_like(g)
    dy[1:] = g[1:] - g[:-1]
    cx = np.vstack([np.zeros((1, w)), np.cumsum(dx, axis=0)])  # (h+1, w): column sums of dx above a row
    cy = np.hstack([np.zeros((h, 1)), np.cumsum(dy, axis=1)])  # (h, w+1): row sums of dy left of a column
    cols = np.arange(m, w - m + 1)
    best = None
    for r0 in range(m, h - m - min_h + 1):
        r1 = np.arange(r0 + min_h, h - m + 1)
        if r1.size == 0:
            break
        D = cx[r1][:, cols] - cx[r0, cols][None, :]
        E = cy[r1][:, cols] - cy[r0, cols][None, :]
        for s in (1.0, -1.0):
            a = s * (-D - E)
            b = s * (D + E)
            pre = np.maximum.accumulate(a, axis=1)
            tot = b[:, min_w:] + pre[:, :-min_w]
            k = int(np.argmax(tot))
            i, j = divmod(k, tot.shape[1])
            if best is None or tot[i, j] > best[1]:
                c1 = j + min_w
                c0 = int(np.argmax(a[i, :c1 - min_w + 1]))
                best = ((r0, int(r1[i]), int(cols[c0]), int(cols[c1])), float(tot[i, j]))
    return best


def box_split(edges: EdgeImage, tiles: list[Rect]) -> Node | None:
    """Windows from edges per member tile (our extension where §3.1 on the group's mean tile finds no window: the
    mean of members that are not exactly aligned is too blurred for its first-edge splits). Each member's
    :func:`edge_box` is its window -- §3.2's synchronisation in the paper's own form: found per tile, the group's
    common size imposed -- unless its size is off the group's median by more than ``BOX_AGREE``, then the median
    box (relative to the tile) is. The tree is wall | strip (wall / window / wall) | wall per member."""
    found = []
    for t0, t1, u0, u1 in tiles:
        if min(t1 - t0, u1 - u0) < 4 * TAU_SIZE:
            return None
        b = edge_box(edges.gray[t0:t1, u0:u1])
        if b is None:
            return None
        (r0, r1, c0, c1), _ = b
        found.append((r0 / (t1 - t0), r1 / (t1 - t0), c0 / (u1 - u0), c1 / (u1 - u0)))
    f = np.array(found)
    med = np.median(f, axis=0)
    hh, ww = med[1] - med[0], med[3] - med[2]
    rects = []
    for (t0, t1, u0, u1), (a, b, c, d) in zip(tiles, f):
        if not (abs((b - a) - hh) <= BOX_AGREE * hh and abs((d - c) - ww) <= BOX_AGREE * ww):
            a, b, c, d = med
        rects.append((t0 + round(a * (t1 - t0)), t0 + round(b * (t1 - t0)), u0 + round(c * (u1 - u0)),
                      u0 + round(d * (u1 - u0))))
    left = Node(tuple((t0, t1, u0, c0) for (t0, t1, u0, u1), (r0, r1, c0, c1) in zip(tiles, rects)), "wall")
    right = Node(tuple((t0, t1, c1, u1) for (t0, t1, u0, u1), (r0, r1, c0, c1) in zip(tiles, rects)), "wall")
    top = Node(tuple((t0, r0, c0, c1) for (t0, t1, u0, u1), (r0, r1, c0, c1) in zip(tiles, rects)), "wall")
    bot = Node(tuple((r1, t1, c0, c1) for (t0, t1, u0, u1), (r0, r1, c0, c1) in zip(tiles, rects)), "wall")
    win = Node(tuple(rects), "window")
    strip = Node(tuple((t0, t1, c0, c1) for (t0, t1, u0, u1), (r0, r1, c0, c1) in zip(tiles, rects)), None,
                 (top, win, bot))
    return Node(tuple(tiles), None, (left, strip, right))
