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
