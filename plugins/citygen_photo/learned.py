"""A facade photo -> FacadeLayout through the learned parser: label probabilities (:mod:`citygen_photo.parser`),
the mutual-information floor period (mueller2007 §2.2-2.3, :mod:`citygen_photo.symmetry`) and the regular
structure found in the probabilities (:mod:`citygen_photo.regular`)."""
from __future__ import annotations

import numpy as np

from citygen.errors import LayoutError
from citygen.layout import check_partition
from citygen_photo.parser import Ensemble, FacadeParser, load_parser
from citygen_photo.fcn import FacadeFCN
from citygen_photo.doors import axis_door, mirror_axis, repeats_floor_above
from citygen_photo.photo import FLOOR_RANGE, MI_WORK, WORK, PhotoAnalysis, _work, luminance
from citygen_photo.regular import Box
from citygen_photo.regular import facade_layout, regular_facade
from citygen_photo.symmetry import band_similarity, detect_symmetry, irreducible, quantize, validated_period

#: Least facade size (pixels) the parser works on.
LEAST = 48


def analyse_learned(image: np.ndarray, source: str = "<photo>", *, width: float | None = None,
                    floor_height: float = 3.0, meta: dict | None = None,
                    model: FacadeParser | FacadeFCN | Ensemble | None = None) -> PhotoAnalysis:
    """The layout of an RGB ``(H, W, 3)`` crop of the facade (0..1); ``width`` metres for the crop, else
    ``floor_height`` metres per floor pitch; ``model``: the parser (the shipped one by default)."""
    if image.ndim == 2:
        image = np.repeat(image[..., None], 3, axis=2)
    H, W = image.shape[:2]
    if min(H, W) < LEAST:
        raise LayoutError(f"the facade is only {W}x{H} pixels", where=source,
                          hint="give a larger photo or a larger --crop")
    prob = (model or load_parser()).probabilities(image)
    h, w = prob.shape[:2]
    f = H / h  # crop pixels per working pixel
    small, g = _work(luminance(image), MI_WORK)
    q = quantize(small)
    vsym = detect_symmetry(q, int(FLOOR_RANGE[0] * small.shape[0]), int(FLOOR_RANGE[1] * small.shape[0]))
    period = validated_period(vsym, irreducible(vsym)) * g / f if vsym.found else None
    k = f / g  # MI-image pixels per working pixel

    def similar(y0: float, y1: float, shift: float) -> float:
        return band_similarity(q, round(y0 * k), round(y1 * k), round(shift * k))
    facade = regular_facade(prob, period, _axis_door(image, h), similar)
    pitch = facade.pitch or period
    if not width and not pitch:
        raise LayoutError("no floors found: no rows of windows and no repetition of floors", where=source,
                          hint="crop the photo to the facade (--crop x0 y0 x1 y1), or give --width")
    scale = width / w if width else floor_height / pitch
    windows = sum(1 for _, label in facade.elements if label == "window")
    meta = dict(meta or {}, importer="photo (mueller2007, learned parser)", metres_per_pixel=scale / f,
                scale_from=f"width {width} m" if width else f"floor period x {floor_height} m",
                floor_period_px=round(pitch * f, 2), tile_period_px=round(facade.tile_pitch * f, 2),
                floors=len(facade.floor_lines) - 1, tiles_per_floor=len(facade.tile_lines) - 1,
                mi_prominence={"floors": round(vsym.prominence, 4)}, windows=windows)
    layout = facade_layout(facade, h, w, scale, meta)
    problems = check_partition(layout)
    if problems:
        raise LayoutError("photo analysis did not give a partition: " + "; ".join(problems[:3]), where=source)
    boxes = tuple(((x0 * f, y0 * f, x1 * f, y1 * f), label) for (x0, y0, x1, y1), label in facade.elements)
    return PhotoAnalysis(layout, tuple(v * f for v in facade.floor_lines), tuple(v * f for v in facade.tile_lines),
                         boxes, float(pitch * f), float(facade.tile_pitch * f), prob)


def _axis_door(image: np.ndarray, h: int):
    """The contrast path's entrance door (a dark opening on the facade's mirror axis, :mod:`citygen_photo.doors`)
    of a ground floor starting at a given line of the ``h``-row working image, as a box in those pixels; it finds
    doors the learned parser's door probability is too weak for (18 of 42 held-out CMP doors against 9)."""
    gray, _ = _work(luminance(image), WORK)
    k = gray.shape[0] / h  # door-image pixels per working pixel

    def door(top: float) -> Box | None:
        line = int(round(top * k))
        if line < 8 or repeats_floor_above(gray, line):
            return None
        found = axis_door(gray, line, mirror_axis(gray[:line]))
        if found is None:
            return None
        r0, r1, c0, c1 = found.rect
        return (c0 / k, r0 / k, c1 / k, r1 / k)
    return door
