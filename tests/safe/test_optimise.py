"""§5 spatial optimisation: Eq. 1 with hierarchy, alignment and symmetry constraints; variable reduction."""
from __future__ import annotations

import numpy as np
import pytest

from citygen.layout import check_partition
from citygen_safe.compose import to_layout
from citygen_safe.grids import auto_specs, detect_grid
from citygen_safe.leaves import facade_from_layout, transpose
from citygen_safe.optimise import MIN_SIZE, _anchor_eps, optimise_widths
from citygen_safe.tree import decompose

from .conftest import regular


def _grids(f):
    return [g for g in (detect_grid(f, s) for s in auto_specs(f)) if g]


@pytest.mark.parametrize("target", [9.0, 15.6125, 21.0, 40.0])
def test_cmp_widths_meet_target_alignment_and_symmetry(cmp_facade, target):
    grids = _grids(cmp_facade)
    res = optimise_widths(cmp_facade, decompose(cmp_facade), grids, target)
    assert res.success and res.dropped == ()
    out = res.facade
    assert out.width == target and check_partition(to_layout(out)) == []
    assert min(f.w for f in out.leaves) >= MIN_SIZE - 1e-9
    for grid in grids:  # C_a: distances between anchor points of consecutive column elements are kept
        for c in range(len(grid.columns)):
            col = [i for i in grid.column(c) if i is not None]
            eps = _anchor_eps(cmp_facade, col)
            for a, b in zip(col, col[1:]):
                before = (cmp_facade.leaves[a].x + eps * cmp_facade.leaves[a].w) - (
                    cmp_facade.leaves[b].x + eps * cmp_facade.leaves[b].w)
                after = (out.leaves[a].x + eps * out.leaves[a].w) - (out.leaves[b].x + eps * out.leaves[b].w)
                assert after == pytest.approx(before, abs=1e-6)


def test_same_size_windows_stay_same_size():
    f = facade_from_layout(regular(4, 2))
    res = optimise_widths(f, decompose(f), _grids(f), 17.0)
    widths = {round(x.w, 9) for x in res.facade.leaves if x.label == "window"}
    assert res.success and len(widths) == 1


def test_original_size_is_a_fixed_point():
    f = facade_from_layout(regular(3, 2))
    res = optimise_widths(f, decompose(f), _grids(f), f.width)
    assert res.objective == pytest.approx(0.0, abs=1e-9)
    assert np.allclose([x.x for x in res.facade.leaves], [x.x for x in f.leaves])


def test_variable_reduction_collapses_unconstrained_and_transverse_subtrees():
    f = facade_from_layout(regular(4, 3))
    res = optimise_widths(f, decompose(f), _grids(f), 14.0)
    # per floor and bay: two side walls and the window column (one variable after collapsing its y split)
    assert res.variables == 3 * 4 * 3 < len(f.leaves)
    free = optimise_widths(f, decompose(f), [], 14.0)
    assert free.variables == 1  # nothing constrained: the root alone


def test_heights_are_the_transposed_problem():
    f = facade_from_layout(regular(3, 3))
    t = transpose(f)
    res = optimise_widths(t, decompose(t), _grids(t), 12.0)
    up = transpose(res.facade)
    assert up.height == 12.0 and check_partition(to_layout(up)) == []
    assert len({round(x.h, 9) for x in up.leaves if x.label == "window"}) == 1


def test_impossible_target_reports_failure():
    f = facade_from_layout(regular(3, 1))
    res = optimise_widths(f, decompose(f), _grids(f), 1e-4)
    assert not res.success and res.message
