"""Pictures of a photo analysis: the parser's label map (``--labels``) and the layout drawn over the photo
(``--png``)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from citygen.errors import LayoutError
from citygen.preview import colour
from citygen_photo.labels import COLOURS
from citygen_photo.photo import PhotoAnalysis, load_photo


def save_labels(result: PhotoAnalysis, path: Path) -> None:
    """The most probable CMP label of every pixel of the crop, in the CMP label colours."""
    from PIL import Image
    if result.probabilities is None:
        raise LayoutError("--labels needs the learned parser", where=str(path),
                          hint="leave out --parser contrast to get a label map")
    ids = result.probabilities.argmax(axis=-1)
    image = Image.fromarray(np.asarray(COLOURS, dtype=np.uint8)[ids])
    h = round(result.layout.height / result.layout.meta["metres_per_pixel"])
    w = round(result.layout.width / result.layout.meta["metres_per_pixel"])
    _save(image.resize((max(w, 1), max(h, 1)), Image.Resampling.NEAREST), path)


def save_overlay(result: PhotoAnalysis, photo: str | Path, crop: tuple[float, ...] | None, path: Path) -> None:
    """The (cropped) photo with the layout's terminals outlined in their label colours and floor lines in red."""
    from PIL import Image, ImageDraw
    rgb = load_photo(photo, crop)
    image = Image.fromarray(np.round(rgb * 255).astype(np.uint8))
    draw = ImageDraw.Draw(image)
    s = result.layout.meta["metres_per_pixel"]
    H = image.height
    for r in result.layout.leaves:
        if r.label in (None, "wall"):
            continue
        box = (r.x / s, H - (r.y + r.h) / s, (r.x + r.w) / s, H - r.y / s)
        draw.rectangle(box, outline=colour(r.label), width=max(1, H // 250))
    for y in result.floor_lines[1:-1]:
        draw.line([(0, y), (image.width, y)], fill=(220, 30, 30), width=max(1, H // 400))
    _save(image, path)


def _save(image, path: Path) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    image.save(path)
