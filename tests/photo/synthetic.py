"""Synthetic facade images: a grid of dark windows on a lighter noisy wall, with the true boxes."""
from __future__ import annotations

import numpy as np


def facade(floors: int = 5, cols: int = 6, floor_h: int = 60, tile_w: int = 50, win: tuple[int, int] = (30, 22),
           off: tuple[int, int] = (14, 14), noise: float = 0.04, seed: int = 0, ground_h: int = 0, accent: int = 0,
           door_x: int | None = None):
    """RGB image in 0..1, window boxes ``(x0, y0, x1, y1)`` (pixels, y down) and the door box (None without a
    ground floor). ``ground_h`` adds an irregular ground floor of that height with a 26 px wide door in its second
    tile, or with its left side at column ``door_x``;
    ``accent`` = k gives every k-th floor (from the top) a dark cornice band and a balcony slab across the facade."""
    rng = np.random.default_rng(seed)
    H, W = floors * floor_h + ground_h, cols * tile_w
    wall = 0.7 + 0.05 * rng.standard_normal((H, W))
    boxes = []
    for i in range(floors):
        for j in range(cols):
            r0, c0 = i * floor_h + off[0], j * tile_w + off[1]
            wall[r0:r0 + win[0], c0:c0 + win[1]] = 0.25 + 0.03 * rng.standard_normal(win)
            boxes.append((c0, r0, c0 + win[1], r0 + win[0]))
    door = None
    if ground_h:
        c0 = tile_w + (tile_w - 26) // 2 if door_x is None else door_x
        wall[H - ground_h + 20:, c0:c0 + 26] = 0.3 + 0.03 * rng.standard_normal((ground_h - 20, 26))
        door = (c0, H - ground_h + 20, c0 + 26, H)
    for i in range(0, floors, accent) if accent else ():
        wall[i * floor_h + 2:i * floor_h + 10] *= 0.5
        wall[i * floor_h + off[0] + win[0] + 2:i * floor_h + off[0] + win[0] + 8] *= 0.6
    gray = np.clip(wall + noise * rng.standard_normal((H, W)), 0, 1)
    tint = np.array([1.0, 0.92, 0.85])
    return np.clip(gray[..., None] * tint, 0, 1), boxes, door


def labelled_photos(count: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """``count`` synthetic facades at the parser's working size with their label maps (wall and windows), as
    the training scripts take them."""
    from citygen_photo.features import working_image

    photos = []
    for seed in range(count):
        rgb, boxes, _ = facade(floors=3, cols=4, seed=seed)
        lab = np.full(rgb.shape[:2], 2, dtype=np.uint8)  # facade
        for x0, y0, x1, y1 in boxes:
            lab[y0:y1, x0:x1] = 3  # window
        work = working_image(rgb)
        rows = (np.arange(work.shape[0]) * rgb.shape[0] / work.shape[0]).astype(int)
        cols = (np.arange(work.shape[1]) * rgb.shape[1] / work.shape[1]).astype(int)
        photos.append((work, lab[np.ix_(rows, cols)]))
    return photos
