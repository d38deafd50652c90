"""The photo benchmark's floor measures (``benchmarks/photo_eval.py``) on hand-made boxes."""
from __future__ import annotations

import sys

import numpy as np
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

from photo_eval import rows_in_floors, windows_cut  # noqa: E402

#: Two rows of two windows (x0, y0, x1, y1; y down), 20 px tall, between y 10-30 and 50-70.
WINDOWS = [(0, 10, 10, 30), (20, 10, 30, 30), (0, 50, 10, 70), (20, 50, 30, 70)]


def test_a_floor_line_in_the_wall_band_cuts_no_window():
    assert windows_cut([0, 40, 80], WINDOWS) == 0
    assert rows_in_floors([0, 40, 80], WINDOWS) == 2


def test_a_floor_line_through_a_row_cuts_its_windows_but_not_at_their_edge():
    assert windows_cut([0, 25, 80], WINDOWS) == 2  # through the upper row's lower half
    assert rows_in_floors([0, 25, 80], WINDOWS) == 2  # (window centres still one floor a row: the row measure
    #                                                   does not see the cut)
    assert windows_cut([0, 11, 80], WINDOWS) == 0  # within a tenth of the windows' height of their top


def test_the_crop_luminance_is_the_facade_box_s_mean_and_selects_the_darker_photos(tmp_path, capsys):
    """Round 10's validation subset matched to the held-out photos: the photos whose facade crop is darker than a
    given mean luminance, a property of the photo, not of its labels."""
    from PIL import Image

    from photo_eval import crop_luminance, main

    for name, grey in (("cmp_b0001", 60), ("cmp_b0002", 200)):
        rgb = np.full((100, 80, 3), 255, np.uint8)
        rgb[20:90, 10:70] = grey  # the facade box; white around it
        Image.fromarray(rgb).save(tmp_path / f"{name}.jpg", quality=100)
        (tmp_path / f"{name}.xml").write_text(
            "<object><points><x>0.2</x><x>0.9</x><y>0.125</y><y>0.875</y></points><label>2</label>"
            "<labelname>facade</labelname><flag>1</flag></object>")
    assert abs(crop_luminance(tmp_path / "cmp_b0001.jpg") - 60 / 255) < 0.02
    assert abs(crop_luminance(tmp_path / "cmp_b0002.jpg") - 200 / 255) < 0.02
    assert main([str(tmp_path), "--first", "1", "--last", "2", "--darker-than", "0.1"]) == 2  # none left
    assert "no cmp_b*.jpg photos" in capsys.readouterr().err


def _box(label: int, name: str, x0: float, x1: float, y0: float, y1: float) -> str:
    """A CMP annotation object for the box ``x0..x1`` across, ``y0..y1`` down (0..1; CMP's ``<x>`` run down)."""
    return (f"<object><points><x>{y0}</x><x>{y1}</x><y>{x0}</y><y>{x1}</y></points><label>{label}</label>"
            f"<labelname>{name}</labelname><flag>1</flag></object>")


def test_boxes_outside_the_facade_crop_are_not_counted():
    """Regression (round 14): CMP annotates windows of the storey above the facade box and shops below it (e.g.
    cmp_b0097, b0109); counted, they were rows and ground floors no layout of the crop could have."""
    from photo_eval import in_crop

    crop = (10, 20, 110, 220)
    boxes = [(20, 30, 40, 60), (20, 0, 40, 25), (50, 210, 90, 260)]  # inside; centre above; centre below
    assert in_crop(boxes, crop) == [(10, 10, 30, 40)]


def test_the_annotated_labels_give_the_layout_a_parser_without_mistakes(tmp_path):
    """``--annotated-labels``: the learned path's structure on the photo's own label map finds its three rows of
    windows and its ground floor of shops -- the ceiling the parser's mistakes are measured against."""
    from PIL import Image

    from photo_eval import evaluate

    h, w = 400, 300
    labels = np.full((h, w), 2, np.uint8)  # facade
    rgb = np.full((h, w, 3), 190, np.uint8)
    xml = [_box(2, "facade", 0, 1, 0, 1)]
    for top in (40, 140, 240):
        for left in (30, 130, 230):
            labels[top:top + 50, left:left + 40] = 3
            rgb[top:top + 50, left:left + 40] = 40
            xml.append(_box(3, "window", left / w, (left + 40) / w, top / h, (top + 50) / h))
    labels[330:, 20:280] = 12  # shop
    rgb[330:, 20:280] = 90
    xml.append(_box(12, "shop", 20 / w, 280 / w, 330 / h, 1))
    Image.fromarray(rgb).save(tmp_path / "cmp_b0001.jpg", quality=100)
    Image.fromarray(labels).save(tmp_path / "cmp_b0001.png")
    (tmp_path / "cmp_b0001.xml").write_text("".join(xml))
    row = evaluate(tmp_path / "cmp_b0001.jpg", annotated=True)
    assert (row["rows"], row["storeys"]) == (3, 4)
    assert row["floors"] == 4 and row["rows_ok"] == 3 and row["cut"] == 0
    assert row["px_tp"] >= 0.9 * row["px_ref"] and row["px_tp"] >= 0.9 * row["px_pred"]
