"""The entrance door of a facade photo: a door on the facade's mirror axis (our extension of mueller2007).

The paper's tiles hold "a window or door" (§2) but it says nothing on telling them apart; its ground floors "are
often problematic" (§5). A CMP ground floor is cut by the tile lines of the floors above and its shop fronts look
like doors to §3.1's contrast test, so the door is found in the ground floor as a whole instead:

1. :func:`mirror_axis`: the vertical mirror axis of the floors above the ground floor, where the image correlates
   best with its own reflection (an entrance sits on the axis of a symmetric facade; shop fronts come in mirrored
   pairs beside it);
2. :func:`axis_door`: the box standing on the ground, (almost) centred on that axis, whose three edges -- left,
   right, top -- are strongest, the *weakest* of the three counting (a lamp post or a car gives one or two edges,
   a door all three). Its top may lie up to ``ABOVE`` of the ground floor's height above the floor line (doors
   often cut it); the box reported is clipped to the ground floor. A door whose weakest side is below
   ``DOOR_EDGE`` mean gradients of the ground floor is not a door: the facade then has no door found.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from citygen_photo.elements import cluster_type
from citygen_photo.tiles import TAU_SIZE, EdgeImage, Node

#: Half-widths searched around the mirror axis: each side may move this many working pixels off the symmetric
#: position.
SLACK = 2
#: The door's top edge is searched up to this fraction of the ground floor's height above its top line.
ABOVE = 0.3
#: Least door width and height as fractions of the ground floor's height; least height / width.
MIN_WIDTH = 0.25
MIN_HEIGHT = 0.5
MIN_ASPECT = 0.7
#: A door's weakest side has at least this mean gradient, in mean gradient magnitudes of the ground floor.
DOOR_EDGE = 0.6
#: A ground floor correlating at least this much with the floor above is a regular floor (``photo.SIMILAR``).
SIMILAR = 0.5

Rect = tuple[int, int, int, int]  # r0, r1, c0, c1 (image rows down, half-open)


@dataclass(frozen=True)
class Door:
    """A door found on the mirror axis: ``rect`` in working pixels (clipped to the ground floor) and the mean
    gradient of its weakest side in mean gradients of the ground floor."""

    rect: Rect
    strength: float


def mirror_axis(gray: np.ndarray) -> float:
    """Column (a multiple of 0.5) about which ``gray`` is most like its own reflection: the correlation of the
    standardised image's column ``c`` with column ``2a - c``, summed over the overlap (so of a periodic facade,
    symmetric about every tile centre, the axis the most of it agrees with: the middle one), for axes whose overlap
    is at least half the width. One FFT convolution of every row with itself gives all axes."""
    h, w = gray.shape
    z = (gray - gray.mean()) / (gray.std() + 1e-9)
    spectrum = np.fft.rfft(z, 2 * w, axis=1)
    conv = np.fft.irfft(spectrum * spectrum, 2 * w, axis=1).sum(axis=0)[:2 * w - 1]  # conv[k]: sum z[c] z[k - c]
    k = np.arange(2 * w - 1)
    overlap = np.minimum(k, 2 * (w - 1) - k) + 1
    score = np.where(overlap >= w / 2, conv, -np.inf)
    return float(np.argmax(score)) / 2


def repeats_floor_above(gray: np.ndarray, top: int) -> bool:
    """The ground floor ``gray[top:]`` repeats the floor above it (normalised correlation of the two bands, aligned
    at their tops, at least ``SIMILAR``, the tile grouping's bound): it is one more regular floor, its elements are
    windows, no entrance is searched in it. (CMP development ground floors: -0.12 to 0.39, b0009's misplaced floor
    line 0.73.)"""
    n = min(gray.shape[0] - top, top)
    if n < 2:
        return False
    a, b = gray[top:top + n], gray[top - n:top]
    a, b = a - a.mean(), b - b.mean()
    return float((a * b).sum()) >= SIMILAR * float(np.linalg.norm(a) * np.linalg.norm(b))


def axis_door(gray: np.ndarray, top: int, axis: float) -> Door | None:
    """The door of the ground floor ``gray[top:]`` on the column ``axis`` (see the module docstring), or None.

    Box sides are scored by mean directional gradient: the left side by the fall of intensity into the box over
    its rows, the right side by the rise out of it, the top by the fall across its columns (a dark opening in a
    lighter wall; the bottom is the ground, hidden by cars and people, and not scored). For given rows the
    columns are searched exhaustively around the axis."""
    H, W = gray.shape
    floor_h = H - top
    start = max(top - int(ABOVE * floor_h), 0)
    g = gray[start:]
    h = g.shape[0]
    dx = np.zeros_like(g)
    dx[:, 1:-1] = (g[:, 2:] - g[:, :-2]) / 2
    dy = np.zeros_like(g)
    dy[1:-1] = (g[2:] - g[:-2]) / 2
    norm = float(np.mean(np.hypot(dx[top - start:], dy[top - start:]))) + 1e-9
    cx = np.vstack([np.zeros((1, W)), np.cumsum(dx, axis=0)])  # column sums of dx above a row
    cy = np.hstack([np.zeros((h, 1)), np.cumsum(dy, axis=1)])  # row sums of dy left of a column
    min_w, min_h = max(int(MIN_WIDTH * floor_h), 2), max(int(MIN_HEIGHT * floor_h), 2)
    half = np.arange(max(min_w // 2, 1), int(min(axis, W - 1 - axis)) + 1)
    shift = np.arange(-SLACK, SLACK + 1)
    c0, c1 = np.broadcast_arrays((np.floor(axis - half)[:, None, None] + shift[None, :, None]).astype(int),
                                 (np.ceil(axis + half)[:, None, None] + shift[None, None, :]).astype(int))
    inside = (c0 >= 1) & (c1 <= W - 2) & (c1 - c0 >= min_w)
    if not inside.any():
        return None
    c0, c1, width = c0[inside], c1[inside], (c1 - c0)[inside]
    best = None
    for r0 in range(1, h - min_h + 1):
        tall = (h - r0) >= MIN_ASPECT * width
        if not tall.any():
            continue
        sides = (cx[h] - cx[r0]) / (h - r0)  # mean dx of every column over the box's rows
        weakest = np.minimum(np.minimum(-sides[c0], sides[c1]), -(cy[r0, c1] - cy[r0, c0]) / width)
        weakest = np.where(tall, weakest, -np.inf)
        k = int(np.argmax(weakest))
        if best is None or weakest[k] > best[0]:
            best = (float(weakest[k]), r0, int(c0[k]), int(c1[k]))
    if best is None or best[0] < DOOR_EDGE * norm:
        return None
    s, r0, a, b = best
    return Door((max(start + r0, top), H, a, b), s / norm)


def ground_columns(tiles: np.ndarray, door: Rect, gap: int = 2 * TAU_SIZE) -> tuple[np.ndarray, int]:
    """The ground floor's tile lines with the door's columns as a tile of their own: the shared lines at least
    ``gap`` outside the door's sides, and its sides (the tiles beside the door reach to it; where the facade's
    edge is closer than ``gap``, the door's tile reaches to the edge, the strip beside the door is its wall).
    Returns the lines and the door tile's index."""
    _, _, c0, c1 = door
    left = [int(t) for t in tiles if t <= c0 - gap]
    right = [int(t) for t in tiles if t >= c1 + gap]
    lines = left + [c0 if left else int(tiles[0]), c1 if right else int(tiles[-1])] + right
    return np.array(lines), len(left)


def untouched_tiles(tiles: np.ndarray, lines: np.ndarray, door: int) -> dict[int, int]:
    """The tiles of the shared tile lines ``tiles`` that the door's lines leave as they are: those that are also
    tiles of the ground floor's ``lines`` (:func:`ground_columns`) other than the door's tile ``door``, by their
    index in ``tiles`` -> in ``lines``. The rest of the ground floor's tiles are cut or merged by the door's sides."""
    index = {(int(a), int(b)): k for k, (a, b) in enumerate(zip(lines[:-1], lines[1:])) if k != door}
    return {k: index[(int(a), int(b))] for k, (a, b) in enumerate(zip(tiles[:-1], tiles[1:]))
            if (int(a), int(b)) in index}


def door_tile(edges: EdgeImage, tile: Rect, door: Rect) -> Node:
    """The door's ground-floor tile: wall | (wall above the door / door) | wall, the door leaf typed by §4's Eq. 7
    among the library's doors (``photo_elements.cluster_type``)."""
    t0, t1, u0, u1 = tile
    r0, r1, c0, c1 = door
    element, _ = cluster_type(edges.gray, [door], ("door",))
    leaf = Node((door,), element.label, element=element.name)
    strip = Node(((t0, t1, c0, c1),), None, ((Node(((t0, r0, c0, c1),), "wall"),) if r0 > t0 else ()) + (leaf,))
    parts = ((Node(((t0, t1, u0, c0),), "wall"),) if c0 > u0 else ()) + (strip,) + (
        (Node(((t0, t1, c1, u1),), "wall"),) if u1 > c1 else ())
    if len(parts) > 1:
        return Node((tile,), None, parts)
    return Node((tile,), None, strip.children) if len(strip.children) > 1 else Node((tile,), leaf.label,
                                                                                   element=leaf.element)
