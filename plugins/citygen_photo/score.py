"""Score a photo analysis against a CMP annotation: rows, columns and window boxes (``benchmarks/photo_eval.py``)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from citygen_inverse.cmp import _find_labels, parse_cmp_xml

Box = tuple[float, float, float, float]  # x0, y0, x1, y1 pixels, y down


def cmp_boxes(xml: str | Path, size: tuple[int, int]) -> dict[str, list[Box]]:
    """Annotated boxes per CMP label name, in pixels of a ``size = (W, H)`` photo, y down.

    As in ``cmp.import_cmp``: the ``<x>`` values run down the photo and the ``<y>`` values across it."""
    xml = Path(xml)
    labels = _find_labels(xml)
    W, H = size
    out: dict[str, list[Box]] = {}
    for u0, u1, v0, v1, lab, _ in parse_cmp_xml(xml.read_text(), str(xml), labels):
        out.setdefault(labels[lab][0], []).append((v0 * W, u0 * H, v1 * W, u1 * H))
    return out


def facade_box(boxes: dict[str, list[Box]]) -> Box:
    """The facade object's box (the union of several); the bounding box of everything when there is none."""
    frame = boxes.get("facade") or [b for bs in boxes.values() for b in bs]
    a = np.array(frame)
    return float(a[:, 0].min()), float(a[:, 1].min()), float(a[:, 2].max()), float(a[:, 3].max())


def layout_boxes(layout, label: str = "window") -> list[Box]:
    """The ``label`` terminals of a photo's FacadeLayout as crop-pixel boxes (y down), through the layout's
    ``metres_per_pixel``: what ``citygen layout from-photo`` writes, scored like the element boxes."""
    m = layout.meta["metres_per_pixel"]
    return [(r.x / m, (layout.height - r.y - r.h) / m, (r.x + r.w) / m, (layout.height - r.y) / m)
            for r in layout.leaves if r.label == label]


def iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pairwise intersection over union of boxes ``(n, 4)`` and ``(m, 4)``."""
    ix = np.clip(np.minimum(a[:, None, 2], b[None, :, 2]) - np.maximum(a[:, None, 0], b[None, :, 0]), 0, None)
    iy = np.clip(np.minimum(a[:, None, 3], b[None, :, 3]) - np.maximum(a[:, None, 1], b[None, :, 1]), 0, None)
    inter = ix * iy
    area = lambda c: (c[:, 2] - c[:, 0]) * (c[:, 3] - c[:, 1])  # noqa: E731
    return inter / np.maximum(area(a)[:, None] + area(b)[None, :] - inter, 1e-12)


def matches(pred: list[Box], ref: list[Box], threshold: float = 0.5) -> int:
    """One-to-one greedy matches (highest IoU first) with IoU >= ``threshold``."""
    if not pred or not ref:
        return 0
    m = iou(np.array(pred, dtype=float), np.array(ref, dtype=float))
    count = 0
    while True:
        i, j = np.unravel_index(np.argmax(m), m.shape)
        if m[i, j] < threshold:
            return count
        count += 1
        m[i, :], m[:, j] = -1.0, -1.0
