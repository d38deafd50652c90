"""Matching 3D elements (mueller2007 §4): a library of citygen's element prototypes and the region type by MI.

Each library element ``e_i`` is one or more prototypes of :mod:`citygen.geometry.prototypes` (the meshes the
generator instances for windows, doors, shop fronts, balconies, blinds) placed on a wall plane. Its 2D
representation ``p(e_i)`` is a fronto-parallel orthographic rendering (:func:`render`: a z-buffered quad
rasteriser, material albedo of :mod:`citygen.usd.materials` shaded by depth) with ``MARGIN`` of wall on each
side. A region ``R`` is compared with the same margin of its surroundings (a uniform window is only recognisable
by its contrast with the wall around it), the view resampled to that size:

    T(R) = argmax_i MI(I(p(e_i)), I(R))              (Eq. 7)
    T(C) = argmax_i sum_{R in C} MI(I(p(e_i)), I(R))  (Eq. 8, a cluster C of similar regions)

The wall element renders as a constant image, so its MI is 0: a region is an element only when some element
explains it better than chance (MI is Eq. 1 less the Miller-Madow bias, ``photo_symmetry.mutual_information``).
"""
from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from PIL import Image

from citygen.geometry.prototypes import ProtoKey, build_prototype
from citygen.usd.materials import material as find_material
from citygen_photo.symmetry import BINS, mutual_information, quantize

#: Wall context rendered (and compared) on each side of an element, as a fraction of its width / height.
MARGIN = 0.25
#: Pixels along the longer side of a rendered view (element and margins).
RES = 96
#: Wall material behind the elements.
WALL = "plaster_cream"
#: Shading by depth: albedo times ``1 + DEPTH_SHADE * z`` (z in metres, recesses darker), clipped to 0.3..1.3.
DEPTH_SHADE = 1.5
#: MI (nats) the wall scores per region: an element must explain a region better than this (the largest of
#: some 30 elements' MI with an unrelated region is above 0 despite the bias correction).
WALL_MI = 0.05
#: An element is a candidate for a region whose aspect (height / width) is within this factor of its own.
ASPECT = 1.6

Rect = tuple[int, int, int, int]  # r0, r1, c0, c1 (image rows down, half-open)
Placed = tuple[ProtoKey, float, float]  # prototype and its bottom-left corner on the wall (metres)


@dataclass(frozen=True)
class Element:
    """A library element: its label in the layout, depth (m along the outward normal) and material of its main
    prototype, size (m) and 2D representation ``view`` (rows down, element plus ``MARGIN`` on each side)."""

    name: str
    label: str
    depth: float
    material: str | None
    size: tuple[float, float]
    view: np.ndarray

    @property
    def aspect(self) -> float:
        return self.size[1] / self.size[0]


def _luminance(material: str) -> float:
    r, g, b = find_material(material).colour  # display colour: an image as a photo shows it
    return 0.299 * r + 0.587 * g + 0.114 * b


def render(parts: Sequence[Placed], size: tuple[float, float], res: int = RES) -> np.ndarray:
    """Orthographic front view (camera on +z) of the prototypes ``parts`` in front of a wall, over the element box
    ``size`` plus ``MARGIN``: every visible quad is filled with its material's luminance shaded by its depth, the
    nearest quad per pixel winning (z-buffer). Openings cut the wall plane (their recess is seen through it)."""
    w, h = size
    x0, y0, x1, y1 = -MARGIN * w, -MARGIN * h, (1 + MARGIN) * w, (1 + MARGIN) * h
    scale = res / max(x1 - x0, y1 - y0)
    cols, rows = max(int(round((x1 - x0) * scale)), 1), max(int(round((y1 - y0) * scale)), 1)
    px = x0 + (np.arange(cols) + 0.5) / scale
    py = y1 - (np.arange(rows) + 0.5) / scale  # image rows run down
    X, Y = np.meshgrid(px, py)
    zbuf = np.zeros((rows, cols))
    image = np.full((rows, cols), _luminance(WALL))
    for key, ox, oy in parts:
        kw, kh, _ = key.size
        if key.label in ("window", "door", "shop", "glass"):
            hole = (X >= ox) & (X < ox + kw) & (Y >= oy) & (Y < oy + kh)
            zbuf[hole] = -np.inf
    for key, ox, oy in parts:
        for part in build_prototype(key):
            shade = _luminance(part.material)
            for quad in part.quads + (ox, oy, 0.0):
                _fill(quad, shade, X, Y, zbuf, image)
    return image


def _fill(quad: np.ndarray, shade: float, X: np.ndarray, Y: np.ndarray, zbuf: np.ndarray, image: np.ndarray) -> None:
    """Rasterise one planar convex quad ``(4, 3)``: pixels inside its projection where it is nearer than the
    z-buffer. Quads seen edge-on (no projected area) are skipped."""
    xy = quad[:, :2]
    edges = np.roll(xy, -1, axis=0) - xy
    area = 0.5 * float(np.sum(xy[:, 0] * np.roll(xy[:, 1], -1) - np.roll(xy[:, 0], -1) * xy[:, 1]))
    if abs(area) < 1e-9:
        return
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    box = (X >= lo[0]) & (X <= hi[0]) & (Y >= lo[1]) & (Y <= hi[1])
    if not box.any():
        return
    x, y = X[box], Y[box]
    cross = edges[:, 0, None] * (y - xy[:, 1, None]) - edges[:, 1, None] * (x - xy[:, 0, None])
    inside = np.all(cross * np.sign(area) >= -1e-12, axis=0)
    normal = np.cross(quad[1] - quad[0], quad[2] - quad[0])
    z = quad[0, 2] - (normal[0] * (x - quad[0, 0]) + normal[1] * (y - quad[0, 1])) / normal[2]
    near = inside & (z > zbuf[box])
    idx = np.flatnonzero(box)[near]
    zbuf.flat[idx] = z[near]
    image.flat[idx] = shade * np.clip(1 + DEPTH_SHADE * z[near], 0.3, 1.3)


def _element(name: str, label: str, parts: Sequence[Placed]) -> Element:
    main = parts[0][0]
    w = max(ox + k.size[0] for k, ox, _ in parts) - min(ox for _, ox, _ in parts)
    h = max(oy + k.size[1] for k, _, oy in parts) - min(oy for _, _, oy in parts)
    x0, y0 = min(ox for _, ox, _ in parts), min(oy for _, _, oy in parts)
    shifted = [(k, ox - x0, oy - y0) for k, ox, oy in parts]
    return Element(name, label, main.size[2], main.material, (w, h), render(shifted, (w, h)))


@functools.lru_cache(maxsize=1)
def library() -> tuple[Element, ...]:
    """The element library: several proportions and styles per label (sizes in ``QUANTUM`` = 0.1 m, depth in
    cm), plus the wall (no prototype)."""
    out = []
    for w, h in ((6, 9), (8, 12), (10, 15), (12, 15), (10, 10), (16, 12), (14, 20), (10, 22), (20, 14), (24, 10), (6, 15)):
        window = (ProtoKey("window", "frame_white", w, h, -22), 0.0, 0.0)
        out.append(_element(f"window_{w}x{h}", "window", [window]))
        if h < 20:
            sill = (ProtoKey("sill", "stone", w + 2, 1, 9), -0.1, -0.1)
            out.append(_element(f"window_sill_{w}x{h}", "window", [window, sill]))
    for w, h in ((10, 15), (12, 18)):
        shutters = [(ProtoKey("window", "frame_white", w, h, -22), 0.0, 0.0),
                    (ProtoKey("blind", "shutter_green", w // 2, h, 4), -w / 20, 0.0),
                    (ProtoKey("blind", "shutter_green", w // 2, h, 4), w / 10, 0.0)]
        out.append(_element(f"window_shutters_{w}x{h}", "window", shutters))
    for w, h in ((10, 22), (12, 24)):
        out.append(_element(f"door_{w}x{h}", "door", [(ProtoKey("door", "door_wood", w, h, -28), 0.0, 0.0)]))
        out.append(_element(f"door_double_{2 * w - 4}x{h}", "door", [
            (ProtoKey("door", "door_wood", w - 2, h, -28), 0.0, 0.0),
            (ProtoKey("door", "door_wood", w - 2, h, -28), (w - 2) / 10, 0.0)]))
        out.append(_element(f"door_fanlight_{w}x{h + 5}", "door", [
            (ProtoKey("door", "door_wood", w, h, -28), 0.0, 0.0),
            (ProtoKey("window", "frame_white", w, 5, -28), 0.0, h / 10)]))
    for w, h in ((25, 22), (40, 26), (30, 30)):
        out.append(_element(f"shop_{w}x{h}", "shop", [(ProtoKey("shop", "frame_dark", w, h, -18), 0.0, 0.0)]))
    out.append(Element("wall", "wall", 0.0, None, (1.0, 1.0), np.full((RES, RES), _luminance(WALL))))
    return tuple(out)


def context(rect: Rect, shape: tuple[int, int]) -> tuple[Rect, Rect]:
    """The region ``rect`` grown by ``MARGIN`` on each side (unclipped) and that box clipped to an image of
    ``shape``."""
    r0, r1, c0, c1 = rect
    dr, dc = int(round(MARGIN * (r1 - r0))), int(round(MARGIN * (c1 - c0)))
    grown = (r0 - dr, r1 + dr, c0 - dc, c1 + dc)
    return grown, (max(grown[0], 0), min(grown[1], shape[0]), max(grown[2], 0), min(grown[3], shape[1]))


@functools.lru_cache(maxsize=8192)
def _levels(index: int, rows: int, cols: int) -> np.ndarray:
    """Element ``index``'s view resampled to ``rows x cols`` and quantised (cached: similar regions share sizes)."""
    view = library()[index].view
    resized = np.asarray(Image.fromarray(view.astype(np.float32)).resize((cols, rows), Image.Resampling.BILINEAR))
    return quantize(resized)


def region_mi(gray: np.ndarray, rect: Rect, index: int) -> float:
    """``MI(I(p(e_i)), I(R))`` for library element ``index`` and region ``rect`` of ``gray``, both with margins."""
    (g0, g1, h0, h1), (k0, k1, l0, l1) = context(rect, gray.shape)
    levels = _levels(index, g1 - g0, h1 - h0)[k0 - g0:k1 - g0, l0 - h0:l1 - h0]
    if levels.size == 0 or levels.min() == levels.max():
        return 0.0
    codes = quantize(gray[k0:k1, l0:l1]) * BINS + levels
    joint = np.bincount(codes.ravel(), minlength=BINS * BINS).astype(float)
    return float(mutual_information(joint))


def candidates(labels: Sequence[str], aspect: float) -> list[int]:
    """Library indices for a region of ``aspect`` (height / width) and the allowed ``labels``: the elements within
    ``ASPECT`` of the region's aspect, else the one nearest to it (resampling to the region hides an element's
    proportions, so they select the elements compared). The wall is not among them."""
    lib = library()
    own = [i for i, e in enumerate(lib[:-1]) if e.label in labels]
    fit = [i for i in own if 1 / ASPECT <= lib[i].aspect / aspect <= ASPECT]
    return fit or sorted(own, key=lambda i: abs(np.log(lib[i].aspect / aspect)))[:1]


def cluster_type(gray: np.ndarray, rects: Sequence[Rect], labels: Sequence[str]) -> tuple[Element, float]:
    """Eq. 8 over the :func:`candidates` for ``labels``: the element with the largest summed MI over the regions
    ``rects`` of a cluster (Eq. 7 for one region), and that sum. With ``"wall"`` in ``labels`` the wall scores
    ``WALL_MI`` per region; ties keep the library order."""
    lib = library()
    r0, r1, c0, c1 = rects[0]
    best, score = lib[-1], WALL_MI * len(rects) if "wall" in labels else -np.inf
    for i in candidates(labels, (r1 - r0) / max(c1 - c0, 1)):
        s = sum(region_mi(gray, rect, i) for rect in rects)
        if s > score:
            best, score = lib[i], s
    return best, score
