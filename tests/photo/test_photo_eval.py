"""The photo benchmark's floor measures (``benchmarks/photo_eval.py``) on hand-made boxes."""
from __future__ import annotations

import sys
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
