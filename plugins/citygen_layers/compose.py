"""The outer product (§5): each layer's horizontal x vertical segments become its shapes; shapes get labels,
depth and materials (§3.1, shape overrides per layer or pattern), masks and transparency hide shapes (§3.4),
and shapes fully covered by upper layers are removed (§3.2, "a window fully covered by a wall can be omitted").
With ``occlusion cut`` a shape partly covered is cut to its uncovered pieces (the layers composite, §3.2)."""
from __future__ import annotations

import bisect
import operator
from collections.abc import Sequence
from dataclasses import dataclass, replace

from citygen.layout import FLOOR_BOUND_LABELS, FacadeLayout, Region
from citygen.plausible import DEFAULT_RULES
from citygen_layers.model import Layer, Ruleset, ShapeSpec
from citygen_layers.sizing import Segment
from citygen_layers.solver import DirectionSolution
from citygen_layers.words import Letter

#: Depth offset (metres along the normal) of a shape by label when neither shape nor symbol sets one.
LABEL_DEPTH = {"window": -0.25, "door": -0.2, "glass": -0.25, "shop": -0.15, "blind": -0.05, "sill": 0.06,
               "cornice": 0.15, "balcony": 0.35, "ledge": 0.08, "pillar": 0.1, "molding": 0.04, "deco": 0.05,
               "frame": 0.03}


def wall_depth(label: str | None, depth: float) -> float:
    """The depth of a shape at ``depth`` made wall: its label's default offset taken back (an opening's recess)."""
    return depth - LABEL_DEPTH.get(label, 0.0)


@dataclass(frozen=True)
class Look:
    """Resolved attributes of one shape (symbol pair) in one layer."""

    visible: bool
    label: str | None
    depth: float
    material: str | None
    asset: str | None


def _specs(ruleset: Ruleset, layer: Layer, h: str, v: str) -> list[ShapeSpec]:
    """Shape specs for ``(h, v)`` that apply to ``layer``, least specific first (later ones override)."""
    if not ruleset.shapes:
        return []
    hits = [s for s in ruleset.shapes if s.h == h and s.v == v
            and s.layer in (None, layer.name) and s.pattern in (None, layer.x, layer.y)]
    return sorted(hits, key=lambda s: (s.layer is not None) + (s.pattern is not None))


def look(ruleset: Ruleset, layer: Layer, h: Letter, v: Letter) -> Look:
    picked = {}      # the most specific shape spec's value of each attribute it sets
    for spec in _specs(ruleset, layer, h.symbol, v.symbol):
        for attr in ("visible", "label", "depth", "material", "asset"):
            value = getattr(spec, attr)
            if value is not None:
                picked[attr] = value
    symbols = [s for s in (ruleset.symbols.get(h.symbol), ruleset.symbols.get(v.symbol)) if s is not None]
    visible = not (h.transparent or v.transparent)
    if visible and layer.mask is not None:
        visible = h.symbol in layer.mask or v.symbol in layer.mask
    override = picked.get("visible")
    if override is not None and not (h.transparent or v.transparent):
        visible = override
    label = picked.get("label")
    if label is None:
        labels = [s.label for s in symbols if s.label is not None]
        label = "wall" if not labels or "wall" in labels else labels[0]
    depth = picked.get("depth")
    if depth is None:
        depth = next((s.depth for s in symbols if s.depth is not None), LABEL_DEPTH.get(label, 0.0))
    material = picked.get("material") or next((s.material for s in symbols if s.material), None)
    asset = picked.get("asset") or next((s.asset for s in symbols if s.asset), None)
    return Look(visible, label, layer.depth + depth, material, asset)


def layer_segments(solution: DirectionSolution, layer_index: int, layer: Layer) -> tuple[Segment, ...]:
    axis = solution.axis
    pattern = layer.x if axis == "x" else layer.y
    group = layer.groups[0 if axis == "x" else 1]
    return solution.sizing.segments[(group, pattern)]


def compose(ruleset: Ruleset, sx: DirectionSolution, sy: DirectionSolution, meta: dict | None = None
            ) -> FacadeLayout:
    """The FacadeLayout: one subtree per layer (bottom first), terminals partitioning the canvas per layer."""
    width, height = sx.canvas, sy.canvas
    grids: list[tuple[list[tuple[float, float]], list[tuple[float, float]]]] = []
    # per layer and grid row: the cells as (region template, shown), shown = the shape is visible, and the
    # templates of the visible shapes when hidden (occluded) by column; rows of equal vertical letters share them
    rows: list[list[tuple[list[tuple[dict, bool]], dict[int, dict]]]] = []
    for index, layer in enumerate(ruleset.layers):
        hseg, vseg = layer_segments(sx, index, layer), layer_segments(sy, index, layer)
        grids.append(([(hs.s, hs.t - hs.s) for hs in hseg], [(vs.s, vs.t - vs.s) for vs in vseg]))
        hole = (Region.template("hole", layer=layer.name), False)
        kinds: dict[tuple | None, tuple[list[tuple[dict, bool]], dict[int, dict]]] = {None: ([hole] * len(hseg), {})}
        layer_rows = []
        for vs in vseg:
            # a shape's look depends on the symbols, transparency and mirroring of its two letters
            vkey = None if vs.letter is None else (vs.letter.symbol, vs.letter.transparent, vs.letter.mirrored)
            kind = kinds.get(vkey)
            if kind is None:
                kind = kinds[vkey] = _row_cells(ruleset, layer, hseg, vs.letter, hole)
            layer_rows.append(kind)
        rows.append(layer_rows)
    occluded, parts = _occluded(grids, [[list(hidden) for _, hidden in layer_rows] for layer_rows in rows],
                                ruleset.cut)
    stamped = Region.stamped
    children = []
    for index, layer in enumerate(ruleset.layers):
        xspans, yspans = grids[index]
        terminals: list[Region] = []
        for j, ((y, h), (cells, hidden)) in enumerate(zip(yspans, rows[index])):
            covered = occluded[index].get(j)
            if covered:
                cells = [(hidden[i], False) if i in covered else cell for i, cell in enumerate(cells)]
            cut = parts[index].get(j, {})
            terminals += [stamped(template, x, y, w, h) for i, ((template, shown), (x, w)) in
                          enumerate(zip(cells, xspans)) if (shown or w * h > 1e-12) and i not in cut]
            for i, pieces in cut.items():
                terminals += _pieces(cells[i][0], hidden[i], pieces)
        children.append(Region(0.0, 0.0, width, height, layer.name, layer=layer.name, children=tuple(terminals)))
    root = Region(0.0, 0.0, width, height, ruleset.name, children=tuple(children))
    return FacadeLayout(width, height, root, meta or {})


def _row_cells(ruleset: Ruleset, layer: Layer, hseg: Sequence[Segment], v: Letter,
               hole: tuple[dict, bool]) -> tuple[list[tuple[dict, bool]], dict[int, dict]]:
    """The cells of a grid row of vertical letter ``v`` as (region template, shown), and by the column of each
    visible shape its template when hidden."""
    looks: dict[tuple, tuple[tuple[dict, bool], dict]] = {}
    cells, hidden = [], {}
    for hs in hseg:
        h = hs.letter
        if h is None:
            cells.append(hole)
            continue
        hkey = (h.symbol, h.transparent, h.mirrored)
        known = looks.get(hkey)
        if known is None:
            symbol = f"{h.name}.{v.name}"
            lk = look(ruleset, layer, h, v)
            plain = Region.template(symbol, layer=layer.name)
            known = looks[hkey] = ((Region.template(symbol, label=lk.label, depth=lk.depth, material=lk.material,
                                                    asset=lk.asset, layer=layer.name), True) if lk.visible else
                                   (plain, False), plain)
        if known[0][1]:
            hidden[len(cells)] = known[1]
        cells.append(known[0])
    return cells, hidden


def _pieces(shown: dict, hidden: dict, pieces: list[tuple[float, float, float, float, bool]]) -> list[Region]:
    """A partly covered shape as its pieces: covered ones hidden; an uncovered one keeps the shape's look unless
    nothing usable is left of it (a sliver, or an opening under its least size: wall there)."""
    out = []
    for x, y, w, h, free in pieces:
        template = hidden
        if free and min(w, h) >= DEFAULT_RULES.sliver - 1e-9:
            least = DEFAULT_RULES.min_size.get(shown.get("label") or "", (0.0, 0.0))
            template = shown
            if w < least[0] - 1e-9 or h < least[1] - 1e-9:
                template = {**shown, "label": "wall", "depth": wall_depth(shown["label"], shown["depth"])}
        out.append(Region.stamped(template, x, y, w, h))
    return out


def _occluded(grids: Sequence[tuple[Sequence[tuple[float, float]], Sequence[tuple[float, float]]]],
              visible: Sequence[Sequence[Sequence[int]]], cut: bool = False
              ) -> tuple[list[dict[int, set[int]]], list[dict[int, dict[int, list]]]]:
    """Per layer, by grid row: the columns of the visible shapes fully covered by visible shapes of the layers
    above, and (``cut``) by column the pieces ``(x, y, w, h, uncovered)`` of the partly covered ones.

    ``grids`` holds each layer's horizontal and vertical spans ``(start, size)``, ``visible`` per layer and grid
    row the columns of its visible shapes. The canvas is cut at every cell border; ``covered[j]`` holds the
    covered grid cells of grid row ``j`` as bits.
    """
    used = [(xspans, yspans) for xspans, yspans in grids if xspans and yspans]
    # rounded as the look-ups below round (numpy's round differs from Python's at some halves: a cell then
    # reached one cut too far and counted as covered)
    xs = sorted({round(v, 9) for xspans, _ in used for x, w in xspans for v in (x, x + w)})
    ys = sorted({round(v, 9) for _, yspans in used for y, h in yspans for v in (y, y + h)})
    nx, ny = max(len(xs) - 1, 0), max(len(ys) - 1, 0)
    xbits: dict[tuple[float, float], int] = {}     # memos: layers share spans
    yrows: dict[tuple[float, float], range] = {}

    def bits(x: float, w: float) -> int:
        i0, i1 = (min(bisect.bisect_left(xs, round(v, 9)), nx) for v in (x, x + w))
        return (1 << i1) - (1 << i0) if i1 > i0 else 0

    def rows(y: float, h: float) -> range:
        return range(*(min(bisect.bisect_left(ys, round(v, 9)), ny) for v in (y, y + h)))

    covered = [0] * ny
    out: list[dict[int, set[int]]] = [{} for _ in grids]
    parts: list[dict[int, dict[int, list]]] = [{} for _ in grids]
    for index in range(len(grids) - 1, -1, -1):
        xspans, yspans = grids[index]
        boxes = []
        for j, (span_y, columns) in enumerate(zip(yspans, visible[index])):
            for i in columns:
                span = xspans[i]
                if span[1] * span_y[1] <= 1e-12:
                    continue
                mask = xbits.get(span)
                if mask is None:
                    mask = xbits[span] = bits(*span)
                cells = yrows.get(span_y)
                if cells is None:
                    cells = yrows[span_y] = rows(*span_y)
                if all(covered[r] & mask == mask for r in cells):
                    out[index].setdefault(j, set()).add(i)
                    continue
                if cut and any(covered[r] & mask for r in cells):
                    parts[index].setdefault(j, {})[i] = _cut(xs, ys, span, span_y, mask, cells, covered)
                boxes.append((cells, mask))
        for cells, mask in boxes:
            for r in cells:
                covered[r] |= mask
    return out, parts


def _cut(xs: Sequence[float], ys: Sequence[float], span: tuple[float, float], span_y: tuple[float, float],
         mask: int, cells: range, covered: Sequence[int]) -> list[tuple[float, float, float, float, bool]]:
    """The rectangles ``(x, y, w, h, uncovered)`` tiling a cell whose fine cells are ``mask`` x ``cells``: per run
    of fine rows with the same covered bits, one rectangle per run of equal bits (the cell's own edges kept)."""
    lo, hi = (mask & -mask).bit_length() - 1, mask.bit_length()
    x_edges = [span[0], *xs[lo + 1:hi], span[0] + span[1]]
    y_edges = [span_y[0], *(ys[r] for r in cells[1:]), span_y[0] + span_y[1]]
    pieces = []
    start = 0
    for k in range(len(cells) + 1):
        if k < len(cells) and k > start and covered[cells[k]] & mask == covered[cells[start]] & mask:
            continue
        if k > start:
            row = covered[cells[start]] & mask
            run = 0
            for b in range(hi - lo + 1):
                if b == hi - lo or (row >> (lo + b) & 1) != (row >> (lo + run) & 1):
                    pieces.append((x_edges[run], y_edges[start], x_edges[b] - x_edges[run],
                                   y_edges[k] - y_edges[start], not row >> (lo + run) & 1))
                    run = b
        start = k
    return pieces


def conform(layout: FacadeLayout, floor_lines: Sequence[float], corner_widths: tuple[float, float]
            ) -> tuple[FacadeLayout, list[str]]:
    """Last-resort safety net of a best-effort solve: openings that straddle a floor line become wall, openings
    that enter a corner strip are cut at the strip line (the part in the strip becomes wall; all of it when the
    rest is under half the opening). Every repair is reported in the notes, and openings made wall are counted in
    ``meta["relabelled"]`` (a plausibility finding, :mod:`citygen.plausible`: never silent)."""
    lines = [float(v) for v in floor_lines[1:-1]]
    eps = 1e-6 * max(layout.width, layout.height, 1.0)
    left, right = corner_widths
    inner = (left, layout.width - right)
    notes: list[str] = []

    def wall(region: Region, **kw) -> Region:
        return replace(region, label="wall", depth=wall_depth(region.label, region.depth), **kw)

    def fix(region: Region) -> Region:
        if region.children:    # only openings can need a repair; an unchanged subtree is kept as it is
            kids = region.children
            children = list(kids)
            for i in [i for i, c in enumerate(kids) if c.children or c.label in FLOOR_BOUND_LABELS]:
                children[i] = fix(kids[i])
            same = all(map(operator.is_, children, kids))
            return region if same else replace(region, children=tuple(children))
        if region.label not in FLOOR_BOUND_LABELS:
            return region
        cut = any(region.y + eps < v < region.y + region.h - eps for v in lines)
        x0, x1 = max(region.x, inner[0]), min(region.x + region.w, inner[1])
        if not cut and x0 <= region.x + eps and x1 >= region.x + region.w - eps:
            return region
        where = f"{region.layer}/{region.symbol}: {region.label} at x={region.x:.2f} y={region.y:.2f}"
        if cut or x1 - x0 < 0.5 * region.w:
            notes.append(f"{where} {'straddles a floor line' if cut else 'lies in a corner strip'}; made wall")
            return wall(region)
        notes.append(f"{where} enters a corner strip; cut at the strip line")
        pieces = [wall(region, w=x0 - region.x) if x0 > region.x + eps else None,
                  replace(region, x=x0, w=x1 - x0),
                  wall(region, x=x1, w=region.x + region.w - x1) if x1 < region.x + region.w - eps else None]
        return replace(region, label=None, children=tuple(p for p in pieces if p is not None))

    root = fix(layout.root)
    del fix    # the recursive closure refers to itself: break the cycle so it is freed at once
    if root is layout.root:
        return layout, notes
    relabelled = sum(note.endswith("made wall") for note in notes)
    meta = {**layout.meta, "relabelled": relabelled} if relabelled else layout.meta
    return FacadeLayout(layout.width, layout.height, root, meta), notes
