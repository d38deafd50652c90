"""PNG of a layer-stack layout: layers composited bottom to top, coloured by label, with the alignment columns
of both directions drawn over them (``citygen facade RULESET --png``)."""
from __future__ import annotations

from pathlib import Path

from PIL import Image, ImageDraw

from citygen.layout import FacadeLayout
from citygen.outpaths import write_png

#: RGB per label; other labels are drawn grey.
COLOURS = {"wall": (214, 200, 178), "window": (92, 146, 196), "door": (120, 72, 40), "balcony": (150, 90, 60),
           "sill": (235, 235, 225), "cornice": (190, 180, 160), "pillar": (170, 165, 155), "shop": (80, 170, 120),
           "blind": (120, 130, 90), "deco": (200, 160, 120), "molding": (225, 215, 195), "ledge": (200, 190, 170),
           "frame": (250, 250, 250), "glass": (110, 160, 210), "roof": (150, 60, 50)}
COLUMN_COLOURS = ((220, 40, 40), (40, 90, 220))


def render(layout: FacadeLayout, path: str | Path, scale: float | None = None, columns: bool = True) -> Path:
    """Write ``layout`` as a PNG to ``path``; ``scale`` is pixels per metre (default: about 800 px wide)."""
    scale = scale or max(8.0, min(80.0, 800.0 / max(layout.width, 1e-6)))
    size = (max(1, round(layout.width * scale)), max(1, round(layout.height * scale)))
    image = Image.new("RGB", size, (255, 255, 255))
    draw = ImageDraw.Draw(image)

    def box(x: float, y: float, w: float, h: float) -> tuple[float, float, float, float]:
        return (x * scale, (layout.height - y - h) * scale, (x + w) * scale, (layout.height - y) * scale)

    for layer in (layout.root.children or (layout.root,)):
        for region in layer.terminals():
            if region.label is None or region.w * region.h <= 0:
                continue
            draw.rectangle(box(region.x, region.y, region.w, region.h),
                           fill=COLOURS.get(region.label, (160, 160, 160)), outline=(60, 60, 60))
    if columns:
        for axis, colour in zip(("x", "y"), COLUMN_COLOURS):
            for borders in layout.meta.get("columns", {}).get(axis, {}).values():
                for value in borders:
                    if axis == "x":
                        draw.line([(value * scale, 0), (value * scale, size[1])], fill=colour, width=1)
                    else:
                        yy = (layout.height - value) * scale
                        draw.line([(0, yy), (size[0], yy)], fill=colour, width=1)
    path = Path(path)
    write_png(image, path)
    return path
