"""A regular facade layout from the learned parser's label probabilities (mueller2007 §2-§3 on label maps).

The parser (:mod:`citygen_photo.parser`) says, per pixel, how likely each CMP label is; this module finds the
structure mueller2007 looks for -- floors, tiles, and one subdivision shared by similar tiles -- in those
probabilities instead of in raw intensities, and writes it as a FacadeLayout:

1. **Floors** (§2.2-2.4): the rows of windows are the runs of the window probability's row profile; floor lines
   lie in the gaps between them. A gap much longer than the others' pitch holds floors whose windows the parser
   missed (closed blinds, reflections): it is split at the pitch the others agree on, which the mutual-information
   floor period (§2.3's irreducible facade, :mod:`citygen_photo.symmetry`) confirms when the rows alone are too
   few; where that period is the rows' pitch (or two or three of them) it also checks the rows
   (:mod:`citygen_photo.lattice`: a strip between floors dropped, a row the intensity bands repeat put back). The
   floors at the edges -- an attic row of a few dormers, a basement row of cellar windows, a ground floor below
   the lowest row -- are decided by
   evidence integrated over their bands (:mod:`citygen_photo.edges`); the glass of a band of shops and doors on
   the ground is not a row of windows. A floor line between two rows sits in the wall band between them,
   the least open stretch of the window + blind + balcony + door profile (a railing below a row is not wall).
2. **Tiles** (§2.4, §3.2 voting): window columns are the runs of the window probability's column profile over all
   upper floors together, so every upper floor shares one set of tile lines; whether a tile holds a window is
   voted per tile (the mean probability in its window box), and so is its label: a window box that holds more
   blind or balcony probability than glass (closed shutters, a French window behind a railing) is a blind or a
   balcony.
3. **Synchronised sizes** (§3.2, wu2014 §3.3): windows share their row's height and their column's width; rows
   and columns within ``SAME_SIZE`` of the median take the median, so a regular facade gets one window size;
   each window then moves (its size kept) to where it holds the most glass probability. The windows behind
   railings (the balcony group) stop at one railing height, a balcony below them.
4. **Ground floor**: shops and doors from their own probabilities and their own columns (the upper floors' tile
   lines do not cut a shop window); the doors stand on the ground and cut the shops they stand in. Without a
   ground floor of its own the doors are looked for in the lowest floor and replace the windows they overlap.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d

from citygen.layout import FacadeLayout, Region
from citygen_photo.edges import ground_floor, with_attic, with_basement
from citygen_photo.labels import CMP_LABELS
from citygen_photo.lattice import Similarity, lattice_rows

WINDOW, DOOR, SHOP, BLIND, BALCONY = (CMP_LABELS.index(n) for n in ("window", "door", "shop", "blind", "balcony"))
#: A row or column belongs to a run of windows where its profile exceeds this share of the profile's high value.
RUN_SHARE = 0.4
#: Runs of the window profile closer than this share of their median length are one run (a row of windows split
#: by a transom bar is one row) ...
RUN_JOIN = 0.25
#: ... but columns of windows only closer than this: twin windows a mullion apart are two windows, as CMP
#: annotates them (until round 14 they were one box over both).
COLUMN_JOIN = 0.1
#: Rows (columns) of windows whose height (width) is within this share of the median take the median.
SAME_SIZE = 0.25
#: A tile holds a window when the mean window (or blind) probability in its box reaches this.
VOTE = 0.3
#: A window's sides lie where its row's (column's) window probability reaches this share of its peak.
TIGHT = 0.5
#: A gap between rows of windows this many pitches long holds more floors.
MISSING_ROW = 1.6
#: A band of shops and doors stands on the ground where its rows' mean shop + door probability reaches this; the
#: windows the parser sees in it are shop windows, not a row of windows (whether it is a floor: ``edges``).
SHOP_BAND = 0.3
#: A window belongs to the balcony group when the mean balcony probability in the lower half of its box reaches
#: this; the group's railing height is found once on the group's mean profile (mueller2007 §3.2).
BALCONY_VOTE = 0.15
#: Each window of a tile group keeps the group's size and moves, by at most ``FIT_REACH`` of its size, to where it
#: holds the most glass probability, when that is at least ``FIT_GAIN`` more than where it is (wu2014 §3.3: sizes
#: synchronised, positions per element).
FIT_REACH = 0.5
FIT_GAIN = 0.1
#: A voted window is a blind (balcony) when the mean blind (balcony) probability in its box exceeds this share of
#: the mean glass probability there: closed shutters and French windows behind a railing, which CMP labels so.
RELABEL = 0.7
#: Samples of a window's height in the balcony group's mean profile.
PROFILE = 32
#: A door found by its probability stands on the ground: its run of rows ends at most this share of the floor's
#: height above the bottom.
GROUNDED = 0.2
#: A door is at least this share of the windows' median width (narrower runs of door probability are frames, gaps
#: between windows, a dark strip in a shop front).
DOOR_WIDTH = 0.6

Span = tuple[float, float]
Box = tuple[float, float, float, float]  # x0, y0, x1, y1 in working pixels, y down


@dataclass(frozen=True)
class RegularFacade:
    """Structure in working pixels (y down): floor lines top to bottom, the upper floors' tile lines, element
    boxes with labels, the floor pitch and tile pitch (0 when unknown)."""

    floor_lines: tuple[float, ...]
    tile_lines: tuple[float, ...]
    elements: tuple[tuple[Box, str], ...]
    pitch: float
    tile_pitch: float
    ground: bool


def runs(profile: np.ndarray, share: float = RUN_SHARE, least: int = 2, floor: float = 0.08,
         join: float = RUN_JOIN) -> list[Span]:
    """Spans ``[a, b)`` where ``profile`` exceeds ``share`` of its 95th percentile (and at least ``floor``), at
    least ``least`` samples long; neighbours closer than ``join`` of their median length are joined."""
    high = float(np.percentile(profile, 95)) if profile.size else 0.0
    above = profile > max(share * high, floor)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], above.astype(np.int8), [0]])))
    spans = [(float(a), float(b)) for a, b in zip(edges[::2], edges[1::2]) if b - a >= least]
    if len(spans) < 2:
        return spans
    joined = [spans[0]]
    close = join * float(np.median([b - a for a, b in spans]))
    for a, b in spans[1:]:
        if a - joined[-1][1] < close:
            joined[-1] = (joined[-1][0], b)
        else:
            joined.append((a, b))
    return joined


def synchronised(spans: list[Span]) -> list[Span]:
    """Spans within ``SAME_SIZE`` of the median length resized to it about their centres."""
    if not spans:
        return spans
    median = float(np.median([b - a for a, b in spans]))
    out = []
    for a, b in spans:
        if abs((b - a) - median) <= SAME_SIZE * median:
            c = (a + b) / 2
            a, b = c - median / 2, c + median / 2
        out.append((a, b))
    return out


def _pitch(rows: list[Span], period: float | None) -> float:
    """The floor pitch: the median distance between row centres, else the mutual-information period."""
    if len(rows) >= 3 or (len(rows) == 2 and not period):
        return float(np.median(np.diff([(a + b) / 2 for a, b in rows])))
    return float(period or 0.0)


def _with_missing_rows(rows: list[Span], pitch: float) -> list[Span]:
    """Rows with the ones the parser missed put back: a gap of ``k`` pitches between two rows holds ``k - 1``."""
    if pitch <= 0 or len(rows) < 2:
        return rows
    out = [rows[0]]
    for a, b in rows[1:]:
        pa, pb = out[-1]
        k = round(((a + b) / 2 - (pa + pb) / 2) / pitch)
        if ((a + b) / 2 - (pa + pb) / 2) >= MISSING_ROW * pitch and k >= 2:
            step = ((a + b) / 2 - (pa + pb) / 2) / k
            out += [(pa + i * step, pb + i * step) for i in range(1, k)]
        out.append((a, b))
    return out


def regular_facade(prob: np.ndarray, period: float | None = None,
                   door: Callable[[float], Box | None] | None = None,
                   similar: Similarity | None = None) -> RegularFacade:
    """The structure of a facade from its label probabilities ``prob`` (h, w, 12); ``period``: the floor period
    (working pixels) by mutual information, used where the rows of windows alone cannot tell the pitch; ``door``:
    the entrance door of a ground floor starting at a given line (working pixels), found by other means, taken
    before the door probability's; ``similar``: the MI of two intensity bands of the photo, with which the rows are
    checked against the floor period's lattice (:func:`citygen_photo.lattice.lattice_rows`)."""
    h, w, _ = prob.shape
    window = prob[..., WINDOW] + prob[..., BLIND]  # (a window behind closed blinds is a window of the layout)
    rows = runs(gaussian_filter1d(window.mean(axis=1), 1.0), least=max(2, round(0.015 * h)))
    shops = shop_band(prob)
    if shops is not None:
        rows = [(a, b) for a, b in rows if b <= shops]  # (a run reaching into the shop band is its glass)
    pitch = _pitch(rows, period)
    rows = synchronised(_with_missing_rows(rows, pitch))
    rows = with_attic(window, lattice_rows(rows, pitch, period, similar, shops or h), pitch, similar)
    if shops is None:  # (below a band of shops, glass is the shops')
        rows = with_basement(window, rows, pitch)
    openings = gaussian_filter1d((window + prob[..., BALCONY] + prob[..., DOOR]).mean(axis=1), 1.0)
    lines = [0.0, *(_wall_line(openings, upper, lower) for upper, lower in zip(rows, rows[1:]))]
    ground_top = ground_floor(prob, rows, pitch, shops, similar)
    if ground_top is not None:
        lines.append(ground_top)
    lines.append(float(h))
    lines = _monotonic(lines, h)
    upper = window[: round(ground_top) if ground_top else h]
    inside = np.zeros(upper.shape[0], dtype=bool)
    for a, b in rows:
        inside[max(int(a), 0):min(int(np.ceil(b)), upper.shape[0])] = True
    columns = runs(gaussian_filter1d(upper[inside].mean(axis=0), 1.0), least=max(2, round(0.01 * w)),
                   join=COLUMN_JOIN) \
        if inside.any() else []
    glass = prob[..., WINDOW]  # (sides from the glass alone: open shutters beside a window are not the window)
    rows = [_tightened(glass, row, columns, 0) for row in rows]  # each row's height from its windows' pixels
    mids = _between(columns, w)  # (a column's side search stops halfway to its neighbours)
    columns = synchronised([_tightened(glass[:upper.shape[0]], column, rows, 1, (mids[i], mids[i + 1]))
                            for i, column in enumerate(columns)])
    rows = synchronised(rows)
    tiles = _between(columns, w)
    elements: list[tuple[Box, str]] = []
    for a, b in rows:
        for c, d in columns:
            box = _clip((c, a, d, b), w, h)
            if box and window[int(box[1]):int(np.ceil(box[3])), int(box[0]):int(np.ceil(box[2]))].mean() >= VOTE:
                elements.append((box, "window"))
    elements = _relabelled(prob, _fitted(glass, elements))
    windows = [e for e in elements if e[1] == "window"]
    elements = _with_balconies(prob, windows) + [e for e in elements if e[1] != "window"]
    widths = [box[2] - box[0] for box, label in elements if label == "window"]
    least = DOOR_WIDTH * float(np.median(widths)) if widths else 0.0
    if ground_top is not None:
        elements += _ground(prob, ground_top, door(ground_top) if door else None, least)
    elif len(lines) > 2 and widths:  # (no ground floor of its own: the entrance is in the lowest floor)
        for found in _doors(prob, lines[-2], door(lines[-2]) if door else None, least):
            elements = [(box, label) for box, label in elements if not _overlap(box, found)] + [(found, "door")]
    tile_pitch = float(np.median(np.diff([(c + d) / 2 for c, d in columns]))) if len(columns) > 1 else 0.0
    return RegularFacade(tuple(lines), tuple(tiles), tuple(elements), pitch, tile_pitch, ground_top is not None)


def _wall_line(openings: np.ndarray, upper: Span, lower: Span) -> float:
    """The floor line between two rows of windows: the least open row (window, blind, balcony and door
    probability) of the wall band between them, the middle of that band's least open stretch; the middle of
    the gap when the rows touch."""
    a, b = int(np.ceil(upper[1])), int(lower[0])
    if b - a < 2:
        return (upper[1] + lower[0]) / 2
    band = openings[a:b]
    low = np.flatnonzero(band <= band.min() + 0.1 * (band.max() - band.min()))
    return float(a + (low[0] + low[-1] + 1) / 2)


def _fitted(glass: np.ndarray, elements: list[tuple[Box, str]]) -> list[tuple[Box, str]]:
    """Every window box moved (same size) to the integer shift within ``FIT_REACH`` of its size where the glass
    probability inside it is largest (ties: the smallest move), if that holds ``FIT_GAIN`` more than no move."""
    h, w = glass.shape
    table = np.zeros((h + 1, w + 1))
    table[1:, 1:] = glass.cumsum(0).cumsum(1)
    out = []
    for (x0, y0, x1, y1), label in elements:
        rx, ry = int(FIT_REACH * (x1 - x0)), int(FIT_REACH * (y1 - y0))
        dx, dy = np.meshgrid(np.arange(-rx, rx + 1), np.arange(-ry, ry + 1))
        dx, dy = dx.ravel(), dy.ravel()
        a0 = np.clip(np.round(x0 + dx).astype(int), 0, w)
        a1 = np.clip(np.round(x1 + dx).astype(int), 0, w)
        b0 = np.clip(np.round(y0 + dy).astype(int), 0, h)
        b1 = np.clip(np.round(y1 + dy).astype(int), 0, h)
        mass = table[b1, a1] - table[b0, a1] - table[b1, a0] + table[b0, a0]
        best = np.flatnonzero(mass >= mass.max() - 1e-9)
        k = best[np.argmin(np.abs(dx[best]) + np.abs(dy[best]))]
        here = int(np.flatnonzero((dx == 0) & (dy == 0))[0])
        if mass[k] < (1 + FIT_GAIN) * mass[here]:
            k = here
        box = _clip((x0 + dx[k], y0 + dy[k], x1 + dx[k], y1 + dy[k]), w, h)
        out.append((box or (x0, y0, x1, y1), label))
    return out


def _relabelled(prob: np.ndarray, elements: list[tuple[Box, str]]) -> list[tuple[Box, str]]:
    """The voted windows with their label voted too (mueller2007 §3.2): a box whose mean blind or balcony
    probability exceeds ``RELABEL`` times its mean glass probability takes that label (blind where both do and it
    is the larger)."""
    out = []
    for box, label in elements:
        x0, y0, x1, y1 = box
        mean = prob[int(y0):max(int(np.ceil(y1)), int(y0) + 1),
                    int(x0):max(int(np.ceil(x1)), int(x0) + 1)].reshape(-1, prob.shape[-1]).mean(axis=0)
        blind, balcony, glass = mean[BLIND], mean[BALCONY], RELABEL * mean[WINDOW]
        if blind > glass and blind >= balcony:
            label = "blind"
        elif balcony > glass:
            label = "balcony"
        out.append((box, label))
    return out


def _with_balconies(prob: np.ndarray, windows: list[tuple[Box, str]]) -> list[tuple[Box, str]]:
    """Windows behind a balcony's railing split into the glass above and the balcony below, at one railing height
    for the whole balcony group: the windows whose lower half the balcony probability votes for (``BALCONY_VOTE``)
    are resampled to ``PROFILE`` rows and averaged (the group's mean tile, mueller2007 §3.2; synchronised sizes,
    wu2014 §3.3), and the railing starts at the first row below the window's middle where the mean balcony
    probability exceeds the mean glass probability."""
    glass, railing = prob[..., WINDOW], prob[..., BALCONY]

    def profile(plane: np.ndarray, box: Box) -> np.ndarray:
        x0, y0, x1, y1 = box
        rows = plane[int(y0):max(int(np.ceil(y1)), int(y0) + 1), int(x0):max(int(np.ceil(x1)), int(x0) + 1)]
        line = rows.mean(axis=1)
        return np.interp(np.linspace(0, line.size - 1, PROFILE), np.arange(line.size), line)

    group = [i for i, (box, _) in enumerate(windows)
             if profile(railing, box)[PROFILE // 2:].mean() >= BALCONY_VOTE]
    if not group:
        return windows
    mean_glass = np.mean([profile(glass, windows[i][0]) for i in group], axis=0)
    mean_railing = np.mean([profile(railing, windows[i][0]) for i in group], axis=0)
    below = np.flatnonzero(mean_railing[PROFILE // 2:] > mean_glass[PROFILE // 2:])
    if below.size == 0:
        return windows
    share = (PROFILE // 2 + below[0]) / PROFILE
    out = list(windows)
    for i in group:
        (x0, y0, x1, y1), _ = windows[i]
        cut = y0 + share * (y1 - y0)
        out[i] = ((x0, y0, x1, cut), "window")
        out.append(((x0, cut, x1, y1), "balcony"))
    return out


def shop_band(prob: np.ndarray) -> float | None:
    """The top (working pixels) of a band of shops and doors standing on the ground: the lowest run of the shop +
    door probability's row profile, when it reaches the bottom tenth of the facade and its mean is at least
    ``SHOP_BAND``; None without one."""
    h = prob.shape[0]
    profile = gaussian_filter1d((prob[..., SHOP] + prob[..., DOOR]).mean(axis=1), 1.0)
    bands = runs(profile, share=0.5, least=max(2, round(0.03 * h)))
    if not bands or bands[-1][1] < 0.9 * h:
        return None
    a, b = bands[-1]
    return a if profile[int(a):int(np.ceil(b))].mean() >= SHOP_BAND else None


def _tightened(window: np.ndarray, span: Span, across: list[Span], axis: int,
               bounds: Span = (0.0, np.inf)) -> Span:
    """A row (``axis`` 0) or column (1) of windows narrowed to where the window probability, averaged over the
    ``across`` columns (rows) of windows, reaches ``TIGHT`` of its peak: every tile of the row votes on the
    windows' common height (mueller2007 §3.2), so a sill or a blind reaching into one tile does not stretch it.
    The search reaches a quarter of the span beyond it, not past ``bounds`` (halfway to the neighbouring columns:
    a twin window's glass is not this window's)."""
    if not across:
        return span
    n = window.shape[axis]
    mask = np.zeros(window.shape[1 - axis], dtype=bool)
    for a, b in across:
        mask[max(int(a), 0):min(int(np.ceil(b)), mask.size)] = True
    pad = 0.25 * (span[1] - span[0])
    lo, hi = max(int(max(span[0] - pad, bounds[0])), 0), min(int(np.ceil(min(span[1] + pad, bounds[1]))), n)
    block = window[lo:hi][:, mask] if axis == 0 else window[:, lo:hi][mask]
    profile = block.mean(axis=1 - axis) if block.size else np.zeros(0)
    if profile.size == 0 or profile.max() < 0.1:
        return span
    above = np.flatnonzero(profile >= TIGHT * profile.max())
    return (float(lo + above[0]), float(lo + above[-1] + 1))


def _monotonic(lines: list[float], h: int, least: float = 2.0) -> list[float]:
    """Floor lines from 0 to ``h`` at least ``least`` pixels apart (rows that synchronisation made overlap, or a
    ground floor line above the last row, drop the line that comes too close)."""
    out = [0.0]
    for y in sorted(lines[1:-1]):
        if y - out[-1] >= least and h - y >= least:
            out.append(y)
    return [*out, float(h)]


def _clip(box: Box, w: int, h: int) -> Box | None:
    x0, y0, x1, y1 = max(box[0], 0.0), max(box[1], 0.0), min(box[2], float(w)), min(box[3], float(h))
    return (x0, y0, x1, y1) if x1 - x0 >= 1 and y1 - y0 >= 1 else None


def _doors(prob: np.ndarray, top: float, door: Box | None = None, least: float = 0.0) -> list[Box]:
    """The doors of the floor ``top``..h standing on the ground, left to right, each at least ``least`` wide and
    no wider than tall (a wider opening on the ground is a shop front, a gate, an arcade): every run of columns
    the door probability holds (mean >= 0.15 there) whose rows reach the ground (within ``GROUNDED`` of the
    floor's height: a dark window above a wall band is not a door), and ``door`` (found by other means: the
    entrance on the mirror axis) in place of those it overlaps."""
    h, w, _ = prob.shape
    band = prob[round(top):, :, DOOR]

    def shaped(box: Box) -> bool:
        return least <= box[2] - box[0] <= box[3] - box[1]
    found = []
    for c, d in runs(band.mean(axis=0), share=0.5, least=max(2, round(0.02 * w))):
        part = band[:, int(c):int(np.ceil(d))]
        rows = runs(part.mean(axis=1), share=0.5)
        if rows and part.mean() >= 0.15 and rows[-1][1] >= band.shape[0] - max(2.0, GROUNDED * band.shape[0]):
            box = _clip((c, top + rows[0][0], d, float(h)), w, h)
            if box and shaped(box):
                found.append(box)
    if door is not None and shaped(door):
        found = [box for box in found if not _overlap(box, door)] + [door]
    return sorted(found)


def _between(spans: list[Span], end: float) -> list[float]:
    """0, the midpoints of the gaps between consecutive ``spans``, ``end``: the tile lines of a row of columns."""
    return [0.0, *((b + a) / 2 for (_, b), (a, _) in zip(spans, spans[1:])), float(end)]


def _overlap(a: Box, b: Box) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def _ground(prob: np.ndarray, top: float, door: Box | None = None, least: float = 0.0) -> list[tuple[Box, str]]:
    """Shops and doors of the ground floor (``top``..h), each on its own columns, standing on the ground; the doors
    (:func:`_doors`, at least ``least`` wide) cut the shops they fall in."""
    h, w, _ = prob.shape
    band = prob[round(top):]
    out: list[tuple[Box, str]] = []
    doors = _doors(prob, top, door, least)
    for c, d in runs(band[..., SHOP].mean(axis=0), share=0.5, least=max(2, round(0.03 * w))):
        rows = runs(band[:, int(c):int(np.ceil(d)), SHOP].mean(axis=1), share=0.5)
        if not rows:
            continue
        pieces = [(c, d)]
        for x0, _, x1, _ in doors:
            pieces = [part for a, b in pieces for part in ([(a, b)] if x1 <= a or x0 >= b else [(a, x0), (x1, b)])]
        for a, b in pieces:
            box = _clip((a, top + rows[0][0], b, float(h)), w, h)
            if box and box[2] - box[0] >= 0.02 * w:
                out.append((box, "shop"))
    return out + [(box, "door") for box in doors]


def facade_layout(facade: RegularFacade, h: int, w: int, scale: float, meta: dict) -> FacadeLayout:
    """The partition of the ``w x h`` working-pixel facade (``scale`` metres per working pixel): floors bottom to
    top, each split into columns at its elements' sides, each column into wall / element / wall."""
    def metres_y(y: float) -> float:
        return (h - y) * scale
    lines = facade.floor_lines
    per_floor: list[list[tuple[Box, str]]] = [[] for _ in lines[1:]]
    for (x0, y0, x1, y1), label in facade.elements:  # each element in the floor of its centre, clipped to it
        k = min(max(int(np.searchsorted(lines, (y0 + y1) / 2)) - 1, 0), len(per_floor) - 1)
        y0, y1 = max(y0, lines[k]), min(y1, lines[k + 1])
        if y1 - y0 >= 1:
            per_floor[k].append(((x0, y0, x1, y1), label))
    floors = []
    for k, boxes in enumerate(per_floor):
        ground = facade.ground and k == len(per_floor) - 1
        name = "Ground" if ground else "Top" if k == 0 else "Floor"
        floors.append(_floor(name, sorted(boxes), metres_y(lines[k + 1]), metres_y(lines[k]), w, h, scale))
    root = Region(0.0, 0.0, w * scale, h * scale, "Facade", children=tuple(reversed(floors)))
    return FacadeLayout(w * scale, h * scale, root, meta)


def _floor(name: str, boxes: list[tuple[Box, str]], y0: float, y1: float, w: int, h: int, scale: float) -> Region:
    """One floor ``y0..y1`` (metres, y up) split at its elements' sides; each element column split into wall
    below, the element, wall above (elements in working pixels of a ``w x h`` facade, y down)."""
    cuts: list[tuple[float, float, list[tuple[float, float, str]]]] = []
    x, stacked = 0.0, None
    for (bx0, by0, bx1, by1), label in boxes:
        element = ((h - by1) * scale, (h - by0) * scale, label)
        if cuts and cuts[-1][2] and (bx0, bx1) == stacked:  # (a balcony below its window: one column)
            cuts[-1][2].append(element)
            continue
        stacked = (bx0, bx1)
        bx0 = max(bx0, x)  # (overlapping boxes of one floor: the later one starts where the earlier ends)
        if bx1 - bx0 < 1:
            continue
        if bx0 > x:
            cuts.append((x, bx0, []))
        cuts.append((bx0, bx1, [element]))
        x = bx1
    if x < w:
        cuts.append((x, float(w), []))
    columns = []
    for a, b, elements in cuts:
        xa, wd = a * scale, (b - a) * scale
        if not elements:
            columns.append(Region(xa, y0, wd, y1 - y0, "Wall", "wall"))
            continue
        parts, top = [], y0
        for ey0, ey1, label in sorted(elements):
            ey0, ey1 = max(ey0, top), min(ey1, y1)
            if ey1 - ey0 <= 1e-9:
                continue
            parts += [(top, ey0, "Wall", "wall"), (ey0, ey1, label.capitalize(), label)]
            top = ey1
        parts.append((top, y1, "Wall", "wall"))
        main = max(elements, key=lambda e: e[1] - e[0])[2]
        columns.append(Region(xa, y0, wd, y1 - y0, f"{main.capitalize()}Tile", children=tuple(
            Region(xa, a0, wd, a1 - a0, sym, lab) for a0, a1, sym, lab in parts if a1 - a0 > 1e-9)))
    return Region(0.0, y0, w * scale, y1 - y0, name, children=tuple(columns))
