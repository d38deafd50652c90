"""Size resolution, placement and repeat counts: worked numbers from docs/grammar.md."""
from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from citygen_split.ast import Size
from citygen_split.sizes import aba_count, place, repeat_count, resolve

A, R, F = (lambda v: Size("abs", v)), (lambda v: Size("rel", v)), (lambda v: Size("float", v))


def approx(values):
    return pytest.approx(values, abs=1e-12)


def test_relative_items_share_what_fixed_items_leave():
    # 10 m: absolute 2 and floating 1 stay, relatives 1:3 share 7 m
    assert resolve([A(2), R(1), F(1), R(3)], 10) == approx([2, 1.75, 1, 5.25])


def test_floating_items_scale_by_one_factor_without_relatives():
    assert resolve([A(1), F(2), F(1)], 7) == approx([1, 4, 2])
    assert resolve([A(1), F(2), F(1)], 2.5) == approx([1, 1, 0.5])


def test_absolute_only_scaled_to_fill():
    assert resolve([A(1), A(2), A(1)], 4) == [1, 2, 1]
    assert resolve([A(1), A(2), A(1)], 8) == approx([2, 4, 2])


def test_fallback_drops_relative_items_and_scales_fixed():
    # docs: split(x) { 0.5: Pier | '1: Shop | 0.5: Pier } on 2 m and 0.8 m
    assert resolve([A(0.5), R(1), A(0.5)], 2) == approx([0.5, 1, 0.5])
    assert resolve([A(0.5), R(1), A(0.5)], 0.8) == approx([0.4, 0, 0.4])
    # floating with relatives present counts as fixed
    assert resolve([F(3), R(1)], 1.5) == approx([1.5, 0])


def test_fallback_drops_floating_items_when_absolute_exceed():
    assert resolve([A(1), F(3), A(1)], 1.5) == approx([0.75, 0, 0.75])


@given(st.lists(st.tuples(st.sampled_from(["abs", "rel", "float"]), st.floats(0.01, 50)), min_size=1, max_size=8),
       st.floats(1e-3, 200))
def test_resolution_fills_exactly_and_never_negative(sizes, length):
    extents = resolve([Size(k, v) for k, v in sizes], length)
    assert all(e >= 0 for e in extents)
    assert sum(extents) == pytest.approx(length, rel=1e-9)
    placed = place(extents, 3.0, length)
    assert placed[0][0] == 3.0
    assert placed[-1][0] + placed[-1][1] == pytest.approx(3.0 + length, rel=1e-12)
    for (p0, e0), (p1, _) in zip(placed, placed[1:]):
        assert p0 + e0 == pytest.approx(p1, rel=1e-12)


def test_last_item_ends_exactly_at_the_edge():
    placed = place([0.1] * 10, 0.0, 1.0)
    assert placed[-1][0] + placed[-1][1] == pytest.approx(1.0, abs=0)  # exact, not within rounding
    assert all(e >= 0 for _, e in placed)


@pytest.mark.parametrize(("tile", "length", "n"), [(3, 9.2, 3), (3, 10.6, 4), (3, 1, 1), (3.2, 0.4, 1), (2, 5, 2)])
def test_repeat_count(tile, length, n):
    assert repeat_count(tile, length) == n


@pytest.mark.parametrize(("a", "b", "length", "n"), [(1, 2, 10, 3), (0.5, 3.6, 20, 5), (0.6, 2.8, 2, 0), (1, 1, 1, 0)])
def test_aba_count(a, b, length, n):
    assert aba_count(a, b, length) == n
