"""PNG drawings of facade layouts: terminal regions filled by label, outlined, y up.

Authors want to look, not read: ``citygen facade RULESET --png out.png`` draws the layout at a fixed pixel
density; layers of a layer stack are drawn back to front so upper layers cover lower ones.
"""
from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from citygen.layout import FacadeLayout, Region
from citygen.outpaths import write_png

if TYPE_CHECKING:  # (Pillow is imported when a preview is drawn: a plugin importing this module pays nothing)
    from PIL import Image

COLOURS = {"wall": (222, 205, 170), "window": (70, 110, 160), "door": (120, 70, 40), "balcony": (90, 90, 100),
           "sill": (240, 240, 235), "cornice": (250, 250, 245), "pillar": (190, 180, 160), "shop": (40, 70, 110),
           "blind": (60, 120, 70), "deco": (230, 220, 200), "molding": (245, 240, 225), "ledge": (200, 195, 185),
           "roof": (80, 80, 85)}


def colour(label: str | None) -> tuple[int, int, int]:
    if label in COLOURS:
        return COLOURS[label]
    h = sum(map(ord, label or "")) * 2654435761 % 2**24
    return (96 + (h & 0x7F), 96 + (h >> 8 & 0x7F), 96 + (h >> 16 & 0x7F))


def draw_layout(layout: FacadeLayout, px_per_m: float = 40.0, margin: int = 10,
                lines: Sequence[tuple[str, float]] = ()) -> Image.Image:
    """An image of ``layout``; ``lines`` adds guides (``("x", 3.2)`` vertical, ``("y", 4.0)`` horizontal)."""
    width = max(1, round(layout.width * px_per_m)) + 2 * margin
    height = max(1, round(layout.height * px_per_m)) + 2 * margin
    from PIL import Image, ImageDraw
    img = Image.new("RGB", (width, height), (255, 255, 255))
    draw = ImageDraw.Draw(img)

    def box(r: Region) -> tuple[float, float, float, float]:
        x0 = margin + r.x * px_per_m
        y0 = height - margin - (r.y + r.h) * px_per_m
        return x0, y0, x0 + r.w * px_per_m, y0 + r.h * px_per_m

    layers: dict[str | None, list[Region]] = {}
    for r in layout.leaves:
        layers.setdefault(r.layer, []).append(r)
    for regions in layers.values():
        for r in regions:
            if r.label is None or r.w <= 0 or r.h <= 0:
                continue
            draw.rectangle(box(r), fill=colour(r.label), outline=(40, 40, 40))
    for axis, value in lines:
        if axis == "x":
            x = margin + value * px_per_m
            draw.line([(x, margin), (x, height - margin)], fill=(220, 30, 30))
        else:
            y = height - margin - value * px_per_m
            draw.line([(margin, y), (width - margin, y)], fill=(220, 30, 30))
    return img


def save_png(layout: FacadeLayout, path: str | Path, **kw) -> Path:
    path = Path(path)
    write_png(draw_layout(layout, **kw), path)
    return path


def contact_sheet(images: Sequence[Image.Image], columns: int = 4, gap: int = 8) -> Image.Image:
    """Several images in a grid (variations side by side)."""
    columns = max(1, min(columns, len(images)))
    rows = -(-len(images) // columns)
    cw = max(i.width for i in images)
    ch = max(i.height for i in images)
    from PIL import Image
    sheet = Image.new("RGB", (columns * (cw + gap) + gap, rows * (ch + gap) + gap), (255, 255, 255))
    for k, img in enumerate(images):
        sheet.paste(img, (gap + (k % columns) * (cw + gap), gap + (k // columns) * (ch + gap)))
    return sheet


def add_output_arguments(parser: argparse.ArgumentParser) -> None:
    """``--json`` / ``--png FILE`` for a command that shows several layouts (see :func:`write_layouts`)."""
    out = parser.add_mutually_exclusive_group()
    out.add_argument("--json", action="store_true", help="print the layouts as FacadeLayout JSON")
    out.add_argument("--png", type=Path, metavar="FILE", help="draw a contact sheet")


def write_layouts(layouts: Sequence[FacadeLayout], as_json: bool, png: Path | None) -> bool:
    """Print ``layouts`` as a JSON list or draw them as one contact sheet at a common scale; False when neither
    was asked for (or there is nothing to draw), so the caller prints its own summary."""
    if as_json:
        print(json.dumps([lay.to_json() for lay in layouts], indent=1, sort_keys=True))
        return True
    if png is None or not layouts:
        return False
    px_per_m = 320 / max(max(lay.width, lay.height) for lay in layouts)
    write_png(contact_sheet([draw_layout(lay, px_per_m=px_per_m) for lay in layouts]), png)
    print(f"wrote {png} ({len(layouts)} variations)")
    return True
