"""The visual audit's defects of the shipped extracted grammar (docs/performance.md, "Visual audit")."""
from __future__ import annotations

import pytest

from tests.looks import generated, storeys


@pytest.mark.parametrize(("width", "height", "storey", "ground"),
                         [(11.3, 13.3, 2.6, None), (17.7, 13.3, 3.3, 4.4), (7.9, 13.3, 2.6, None)])
def test_cmp_b0002_wide_floors_keep_a_row_of_windows(width, height, storey, ground):
    """Where the input's 8.59 m tile is implausible squeezed into a lower storey, each such floor took the narrow
    alternative: one 0.83 m window in an 11.3 m (17.7 m) blank wall. Now the window repeats at the typical
    storey's pitch (2.86 m), in the same columns on every floor."""
    layout, request = generated("cmp_b0002.grammar", width, height, storey, ground)
    middle = storeys(layout, request)[1:-1]
    assert middle and all(len(row) >= width // 2.86 for row in middle), [len(row) for row in middle]
    columns = {tuple(round(r.x + r.w / 2, 6) for r in sorted(row, key=lambda r: r.x)) for row in middle
               if all(r.w == row[0].w for r in row)}
    assert len(columns) == 1
