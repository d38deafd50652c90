"""PNG contact sheet of relayout variations: terminal rectangles filled by label."""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from PIL import Image, ImageDraw

from citygen.layout import FacadeLayout

COLOURS = {"wall": (222, 210, 190), "window": (70, 120, 190), "door": (150, 60, 40), "balcony": (120, 120, 120),
           "sill": (250, 250, 240), "cornice": (190, 160, 110), "pillar": (200, 180, 150), "shop": (60, 170, 170),
           "blind": (110, 150, 80), "deco": (220, 140, 60), "molding": (170, 140, 100), "ledge": (160, 130, 100),
           "roof": (110, 60, 50), "frame": (240, 240, 240), "glass": (90, 150, 210)}


def contact_sheet(layouts: Sequence[FacadeLayout], path: Path | str, cell: int = 320, columns: int = 4) -> Path:
    """Draw ``layouts`` side by side (same scale) into ``path``; returns the path."""
    scale = cell / max(max(lay.width, lay.height) for lay in layouts)
    cols = min(columns, len(layouts))
    rows = (len(layouts) + cols - 1) // cols
    pad = 8
    img = Image.new("RGB", (cols * (cell + pad) + pad, rows * (cell + pad) + pad), (255, 255, 255))
    draw = ImageDraw.Draw(img)
    for k, lay in enumerate(layouts):
        ox = pad + (k % cols) * (cell + pad)
        oy = pad + (k // cols) * (cell + pad) + cell  # bottom of the cell: y grows up in layouts
        for r in lay.terminals():
            x0, x1 = ox + r.x * scale, ox + (r.x + r.w) * scale
            y0, y1 = oy - (r.y + r.h) * scale, oy - r.y * scale
            draw.rectangle([x0, y0, max(x0, x1 - 1), max(y0, y1 - 1)], fill=COLOURS.get(r.label or "", (230, 230, 230)),
                           outline=(90, 90, 90))
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    img.save(tmp, format="PNG")
    tmp.replace(path)
    return path
