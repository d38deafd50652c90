"""Import a CMP facade annotation (Tylecek & Sara 2013) as an exact FacadeLayout partition.

The CMP ``*.xml`` files are a single line of ``<object>`` elements without a root element; every object is an
axis-aligned box normalised to 0..1 of the photo, y measured from the top, and the boxes overlap (drawn in the
z-order of ``label_names.txt``). The import (documented in ``docs/inverse.md``):

1. boxes are converted to pixels (photo size from the label map PNG) with y up, clipped to the facade box
   (label ``facade``; the union when there are several, the bounding box of all objects when there is none);
2. box edges are snapped: per axis, coordinates closer than ``snap`` of the facade size are clustered to their
   mean (facade edges stay fixed); boxes that collapse to zero size are dropped and counted;
3. regularisation (wu2014 §3.3): boxes of one label whose widths (heights) differ by less than ``regularize``
   of the facade size are made exactly equal by a QP that moves the snapped lines as little as possible;
   every tolerance is at most its share (``element_share``) of the median window size on that axis, so a
   facade of many small elements is regularised at the scale of its elements, not of the whole facade;
4. boxes are painted on the grid of snapped lines in z-order; uncovered cells are wall;
5. the painted grid is cut recursively at every line no object crosses (y first, then x); a block that no line
   separates (a pinwheel, wu2014 §6.3) is cut into maximal rectangles and is explained by the extractor's
   ``grid`` rule. Objects whose visible part is not a rectangle (partly covered) become several terminals.

The scale is ``--width`` metres for the facade, or ``--floor-height`` metres times the number of rows of windows,
doors and shops (default 3 m per such row).
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from citygen.errors import LayoutError, ParseError, SourceLocation, read_user_text
from citygen.layout import FacadeLayout, Region, check_partition
from citygen_inverse.regularize import integer_lines, regularize_axis

#: CMP label names -> citygen labels (``facade`` and ``background`` inside the facade are wall).
CMP_TO_LABEL = {"background": "wall", "facade": "wall", "window": "window", "door": "door", "cornice": "cornice",
                "sill": "sill", "balcony": "balcony", "blind": "blind", "deco": "deco", "molding": "molding",
                "pillar": "pillar", "shop": "shop"}
#: Depth offsets (m along the outward normal) given to imported terminals.
LABEL_DEPTH = {"window": -0.25, "door": -0.3, "shop": -0.2, "sill": 0.08, "cornice": 0.3, "balcony": 0.6,
               "molding": 0.1, "pillar": 0.15, "deco": 0.05, "blind": 0.02}
#: The CMP label table (id, name, z-order), used when no ``label_names.txt`` is found next to the XML.
DEFAULT_LABELS = {1: ("background", 1), 2: ("facade", 2), 3: ("window", 10), 4: ("door", 5), 5: ("cornice", 11),
                  6: ("sill", 3), 7: ("balcony", 4), 8: ("blind", 6), 9: ("deco", 8), 10: ("molding", 7),
                  11: ("pillar", 12), 12: ("shop", 9)}
_ROW_LABELS = ("window", "door", "shop")
#: Output grid of the imported lines (m).
UNIT = 1e-4
#: Upper bounds of the snap, align and equal-size tolerances as shares of the median window size on each axis
#: (median of all boxes with fewer than two windows). CMP's annotation noise is 1-3 px (same-row windows: median
#: height difference 1 px, 75th percentile 2 px), while 1 % of a facade of 38 window rows is half a window.
ELEMENT_SHARE = (0.2, 0.4, 0.5)


@dataclass(frozen=True)
class CmpBox:
    """One annotated object in pixels, y up: ``x0 < x1``, ``y0 < y1``; ``order`` is its position in the file."""

    x0: float
    y0: float
    x1: float
    y1: float
    name: str
    z: int
    order: int


def read_label_table(path: Path) -> dict[int, tuple[str, int]]:
    """``label_names.txt``: lines ``id name z_order`` -> {id: (name, z)}."""
    table = {}
    for lineno, line in enumerate(read_user_text(path, ParseError, "label table").splitlines(), 1):
        if not line.strip():
            continue
        parts = line.split()
        if len(parts) != 3 or not parts[0].isdigit() or not parts[2].lstrip("-").isdigit():
            raise ParseError("expected 'id name z_order'", where=SourceLocation(str(path), lineno, 1))
        table[int(parts[0])] = (parts[1], int(parts[2]))
    return table


def _find_labels(xml_path: Path) -> dict[int, tuple[str, int]]:
    for folder in (xml_path.parent, xml_path.parent.parent):
        candidate = folder / "label_names.txt"
        if candidate.is_file():
            return read_label_table(candidate)
    return DEFAULT_LABELS


def parse_cmp_xml(text: str, source: str, labels: dict[int, tuple[str, int]]) -> list[tuple[float, ...]]:
    """Objects as ``(x0, x1, y0, y1, label_id, order)`` in normalised coordinates (y from the top)."""
    try:
        root = ET.fromstring("<annotation>" + text + "</annotation>")
    except ET.ParseError as exc:
        line, col = exc.position
        raise ParseError(f"malformed CMP annotation ({exc.msg if hasattr(exc, 'msg') else exc})",
                         where=SourceLocation(source, line, max(col - len("<annotation>") * (line == 1), 1)),
                         hint="expected <object><points><x>..</x><x>..</x><y>..</y><y>..</y></points>"
                              "<label>ID</label>...</object> elements") from None
    objects = []
    for order, obj in enumerate(root.iter("object")):
        try:
            xs = [float(e.text) for e in obj.find("points").findall("x")]
            ys = [float(e.text) for e in obj.find("points").findall("y")]
            label = int(obj.findtext("label"))
        except (AttributeError, TypeError, ValueError):
            raise ParseError(f"object {order} needs numeric <points> x, x, y, y and a <label>",
                             where=SourceLocation(source)) from None
        if len(xs) != 2 or len(ys) != 2:
            raise ParseError(f"object {order} has {len(xs)} x and {len(ys)} y values, expected 2 and 2",
                             where=SourceLocation(source))
        if label not in labels:
            raise LayoutError(f"object {order} has label {label}, unknown to the label table", where=source,
                              hint=f"known label ids: {sorted(labels)}")
        if not all(-0.01 <= v <= 1.01 for v in (*xs, *ys)):  # (NaN fails too)
            raise ParseError(f"object {order} has points {xs + ys}: CMP points are fractions 0..1 of the photo size",
                             where=SourceLocation(source), hint="give the points as fractions of the photo size")
        xs, ys = [min(max(v, 0.0), 1.0) for v in xs], [min(max(v, 0.0), 1.0) for v in ys]  # (rounding beyond)
        objects.append((min(xs), max(xs), min(ys), max(ys), label, order))
    if not objects:
        raise LayoutError("the annotation has no objects", where=source)
    return objects


def _decompose(grid: np.ndarray, r0: int, r1: int, c0: int, c1: int, out: list, pinwheels: list) -> None:
    """Guillotine decomposition of ``grid[r0:r1, c0:c1]`` (instance id per cell, -1 = wall) into rectangles."""
    block = grid[r0:r1, c0:c1]
    if np.all(block == block[0, 0]):
        out.append((r0, r1, c0, c1, int(block[0, 0])))
        return
    for axis in (0, 1):
        a, b = (block[1:], block[:-1]) if axis == 0 else (block[:, 1:], block[:, :-1])
        # a line is a cut when no object crosses it and the content changes there (wall-only lines of other
        # parts of the facade do not slice walls into slivers)
        crossed = np.any((a == b) & (a >= 0), axis=1 - axis) | np.all(a == b, axis=1 - axis)
        cuts = np.flatnonzero(~crossed) + 1
        if cuts.size:
            bounds = [0, *cuts.tolist(), block.shape[axis]]
            for s, e in zip(bounds, bounds[1:]):
                if axis == 0:
                    _decompose(grid, r0 + s, r0 + e, c0, c1, out, pinwheels)
                else:
                    _decompose(grid, r0, r1, c0 + s, c0 + e, out, pinwheels)
            return
    pinwheels.append((r0, r1, c0, c1))
    done = np.zeros(block.shape, dtype=bool)
    for r in range(block.shape[0]):
        for c in range(block.shape[1]):
            if done[r, c]:
                continue
            ident = block[r, c]
            c_end = c
            while c_end < block.shape[1] and block[r, c_end] == ident and not done[r, c_end]:
                c_end += 1
            r_end = r + 1
            while r_end < block.shape[0] and np.all(block[r_end, c:c_end] == ident) and not done[r_end, c:c_end].any():
                r_end += 1
            done[r:r_end, c:c_end] = True
            out.append((r0 + r, r0 + r_end, c0 + c, c0 + c_end, int(ident)))


def read_label_map(png: Path, labels: dict[int, tuple[str, int]]) -> np.ndarray:
    """The label map of a CMP photo: one label id per pixel (rows from the top), ids from the label table."""
    from PIL import Image
    try:
        with Image.open(png) as image:
            mode, ids = image.mode, np.asarray(image)
    except (OSError, Image.DecompressionBombError) as exc:  # (Pillow's "cannot identify image file" included)
        raise LayoutError(f"cannot read the label map: {exc}", where=str(png),
                          hint="give the CMP label map (a PNG of label ids) with --png, or remove the file") from None
    if mode not in ("P", "L", "I", "I;16") or ids.ndim != 2:
        raise LayoutError(f"not a label map: a {mode} image, expected one label id per pixel (a palette or grey "
                          "PNG, as CMP's)", where=str(png), hint="give the CMP label map with --png")
    present = np.flatnonzero(np.bincount(ids.ravel())) if ids.dtype.kind == "u" else np.unique(ids)
    unknown = sorted(set(present.tolist()) - set(labels))
    if unknown:
        raise LayoutError(f"label ids {unknown[:8]} of the label map are not in the label table", where=str(png),
                          hint="give the label map of this annotation, or the label table it uses")
    return ids


def _png_agreement(ids: np.ndarray, layout: FacadeLayout, box_px: tuple[float, float, float, float],
                   labels: dict[int, tuple[str, int]]) -> float:
    """Fraction of label-map pixels inside the facade box whose label equals the layout's label there."""
    fx0, fy0, fx1, fy1 = box_px
    H = ids.shape[0]
    rows = slice(int(round(H - fy1)), int(round(H - fy0)))
    cols = slice(int(round(fx0)), int(round(fx1)))
    crop = ids[rows, cols]
    code: dict[str, int] = {}  # labels as small integers: comparing strings per pixel is slow
    lut = np.array([code.setdefault(CMP_TO_LABEL.get(labels.get(i, ("?", 0))[0], "?"), len(code))
                    for i in range(int(ids.max()) + 1)])
    expected = lut[crop]
    got = np.full(crop.shape, code.get("wall", -1))
    sx, sy = crop.shape[1] / layout.width, crop.shape[0] / layout.height
    for t in layout.terminals():
        c0, c1 = int(round(t.x * sx)), int(round((t.x + t.w) * sx))
        r1, r0 = crop.shape[0] - int(round(t.y * sy)), crop.shape[0] - int(round((t.y + t.h) * sy))
        got[r0:r1, c0:c1] = code.get(t.label, -1)
    return float(np.mean(got == expected)) if got.size else 0.0


def _tolerances(boxes: np.ndarray, names: list[str], extent: tuple[float, float],
                shares: tuple[float, float, float], element_share: tuple[float, float, float] | None
                ) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """(snap, align, size) in pixels for x and for y: ``shares`` of the facade extent, each at most its
    ``element_share`` of the median window extent on that axis (of all boxes with fewer than two windows)."""
    sizes = boxes[:, 2:] - boxes[:, :2]
    solid = np.all(sizes > 0, axis=1)
    windows = solid & np.array([n == "window" for n in names], dtype=bool)
    ref = sizes[windows] if windows.sum() >= 2 else sizes[solid]
    out = []
    for axis in (0, 1):
        tol = [share * extent[axis] for share in shares]
        if element_share is not None and len(ref):
            scale = float(np.median(ref[:, axis]))
            tol = [min(t, e * scale) for t, e in zip(tol, element_share)]
        out.append(tuple(tol))
    return out[0], out[1]


def _annotation_agreement(layout: FacadeLayout, annotated: list, fw: float, fh: float) -> dict[str, float]:
    """How much of the annotation the layout keeps, on the facade's pixel grid: the share of all pixels, and of
    the pixels that are an element in the annotation or the layout, whose label is the same (the annotation's
    boxes painted in z-order, uncovered pixels wall)."""
    w, h = max(int(round(fw)), 1), max(int(round(fh)), 1)
    codes = {"wall": 0}
    want = np.zeros((h, w), dtype=np.int16)
    for part, (x0, y0, x1, y1) in annotated:
        if x1 > x0 and y1 > y0:  # boxes outside the facade box are clipped to nothing
            code = codes.setdefault(CMP_TO_LABEL[part.name], len(codes))
            want[int(round(y0)):int(round(y1)), int(round(x0)):int(round(x1))] = code
    got = np.zeros((h, w), dtype=np.int16)
    sx, sy = w / layout.width, h / layout.height
    for t in layout.terminals():
        code = codes.setdefault(t.label, len(codes))
        got[int(round(t.y * sy)):int(round((t.y + t.h) * sy)), int(round(t.x * sx)):int(round((t.x + t.w) * sx))] = code
    same = want == got
    element = (want > 0) | (got > 0)
    return {"pixels": round(float(same.mean()), 4),
            "element_pixels": round(float(same[element].mean()) if element.any() else 1.0, 4)}


def import_cmp(xml_path: str | Path, *, png: str | Path | None = None, width: float | None = None,
               floor_height: float = 3.0, snap: float = 0.01, align: float = 0.025, regularize: float = 0.03,
               element_share: tuple[float, float, float] | None = ELEMENT_SHARE,
               labels_path: str | Path | None = None) -> FacadeLayout:
    """Read a CMP annotation as a FacadeLayout in metres whose terminals partition the facade exactly.

    ``snap``, ``align`` and ``regularize`` are shares of the facade's width (height), each capped by its share
    in ``element_share`` of the median window width (height); ``None`` lifts the caps."""
    xml_path = Path(xml_path)
    for name, value in (("width", width), ("floor_height", floor_height)):
        if value is not None and not 0 < value < float("inf"):
            raise LayoutError(f"{name} must be a positive number of metres, got {value!r}", where=str(xml_path),
                              hint="pass the facade width (or the height of one row of windows) in metres")
    labels = read_label_table(Path(labels_path)) if labels_path else _find_labels(xml_path)
    objects = parse_cmp_xml(read_user_text(xml_path, LayoutError, "CMP annotation"), str(xml_path), labels)
    png_path = Path(png) if png else xml_path.with_suffix(".png")
    if png and not png_path.is_file():
        raise LayoutError("label map not found", where=str(png))
    label_map = read_label_map(png_path, labels) if png_path.is_file() else None
    size = label_map.shape[::-1] if label_map is not None else None
    W, H = size if size else (1000, 1000)
    # the <x> values run down the photo and the <y> values across it (checked against every label map)
    boxes = [CmpBox(v0 * W, (1 - u1) * H, v1 * W, (1 - u0) * H, labels[lab][0], labels[lab][1], order)
             for u0, u1, v0, v1, lab, order in objects]
    facades = [b for b in boxes if b.name == "facade"]
    frame = facades or boxes
    fx0, fy0 = min(b.x0 for b in frame), min(b.y0 for b in frame)
    fx1, fy1 = max(b.x1 for b in frame), max(b.y1 for b in frame)
    if fx1 - fx0 <= 0 or fy1 - fy0 <= 0:
        raise LayoutError("the facade box has zero size", where=str(xml_path))
    fw, fh = fx1 - fx0, fy1 - fy0
    parts = [b for b in boxes if b.name not in ("facade", "background")]
    clipped = np.array([(max(b.x0, fx0) - fx0, max(b.y0, fy0) - fy0, min(b.x1, fx1) - fx0, min(b.y1, fy1) - fy0)
                        for b in parts]).reshape(-1, 4)
    annotated = sorted(zip(parts, clipped.tolist()), key=lambda pc: (pc[0].z, pc[0].order))
    tx, ty = _tolerances(clipped, [p.name for p in parts], (fw, fh), (snap, align, regularize), element_share)
    keep = (clipped[:, 2] - clipped[:, 0] > tx[0]) & (clipped[:, 3] - clipped[:, 1] > ty[0])
    dropped = int((~keep).sum())
    parts = [p for p, k in zip(parts, keep) if k]
    clipped = clipped[keep]
    names = [p.name for p in parts]
    xr = regularize_axis(clipped[:, 0], clipped[:, 2], clipped[:, [1, 3]], names, fw, snap=tx[0], align=tx[1],
                         size=tx[2])
    yr = regularize_axis(clipped[:, 1], clipped[:, 3], clipped[:, [0, 2]], names, fh, snap=ty[0], align=ty[1],
                         size=ty[2])
    xp, yp = np.stack([xr.lo, xr.hi], axis=1), np.stack([yr.lo, yr.hi], axis=1)
    alive = (xp[:, 0] < xp[:, 1]) & (yp[:, 0] < yp[:, 1])
    dropped += int((~alive).sum())
    parts = [p for p, a in zip(parts, alive) if a]
    xp, yp = xp[alive], yp[alive]
    xl, yl, x_status, y_status = xr.lines, yr.lines, xr.status, yr.status
    grid = np.full((yl.size - 1, xl.size - 1), -1, dtype=np.int64)
    for k in sorted(range(len(parts)), key=lambda k: (parts[k].z, parts[k].order)):
        grid[yp[k, 0]:yp[k, 1], xp[k, 0]:xp[k, 1]] = k
    rects: list[tuple[int, int, int, int, int]] = []
    pinwheels: list[tuple[int, int, int, int]] = []
    _decompose(grid, 0, grid.shape[0], 0, grid.shape[1], rects, pinwheels)
    rows = count_groups([(b.y0, b.y1) for b in parts if b.name in _ROW_LABELS])
    scale = width / fw if width else floor_height * max(rows, 1) / fh
    # 0.1 mm grid, rounded jointly so that sizes and pitches the QP made equal stay exactly equal
    X = np.round(integer_lines(xl * scale, xr.equal, UNIT) * UNIT, 4)
    Y = np.round(integer_lines(yl * scale, yr.equal, UNIT) * UNIT, 4)
    terminals = []
    for r0, r1, c0, c1, ident in rects:
        label = CMP_TO_LABEL[parts[ident].name] if ident >= 0 else "wall"
        terminals.append(Region(x=float(X[c0]), y=float(Y[r0]), w=float(X[c1] - X[c0]), h=float(Y[r1] - Y[r0]),
                                symbol=label.capitalize(), label=label, depth=LABEL_DEPTH.get(label, 0.0)))
    meta = {"source": xml_path.name, "importer": "cmp", "metres_per_pixel": scale,
            "scale_from": f"width {width} m" if width else f"{max(rows, 1)} rows x {floor_height} m",
            "image_size": [W, H] if size else None, "objects": len(objects), "dropped_boxes": dropped,
            "tolerances_px": {"x": [round(t, 2) for t in tx], "y": [round(t, 2) for t in ty]},
            "regularization": {"x": x_status, "y": y_status}, "pinwheel_blocks": len(pinwheels),
            "citation": "R. Tylecek, R. Sara. Spatial Pattern Templates for Recognition of Objects with Regular "
                        "Structure. Proc. GCPR 2013."}
    root = Region(x=0.0, y=0.0, w=float(X[-1]), h=float(Y[-1]), symbol="Facade", children=tuple(terminals))
    layout = FacadeLayout(width=float(X[-1]), height=float(Y[-1]), root=root, meta=meta)
    problems = check_partition(layout)
    if problems:
        raise LayoutError("import did not give a partition: " + "; ".join(problems[:3]), where=str(xml_path))
    meta["annotation_agreement"] = _annotation_agreement(layout, annotated, fw, fh)
    if size:
        meta["label_map_agreement"] = round(_png_agreement(label_map, layout, (fx0, fy0, fx1, fy1), labels), 4)
    return layout


def count_groups(intervals: list[tuple[float, float]]) -> int:
    """Number of groups of overlapping intervals (rows or columns of openings)."""
    groups, end = 0, -np.inf
    for lo, hi in sorted(intervals):
        if lo >= end:
            groups += 1
            end = hi
        else:
            end = max(end, hi)
    return groups

