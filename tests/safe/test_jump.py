"""§4 topological jumps: the worked example of Fig. 4/5, removal, coupled rows, floors."""
from __future__ import annotations

import pytest

from citygen.layout import check_partition
from citygen_safe.compose import to_layout
from citygen_safe.graph import neighbourhood_graph
from citygen_safe.grids import GridSpec, detect_grid
from citygen_safe.jump import insert_column, remove_column, source_columns
from citygen_safe.leaves import facade_from_layout
from citygen_safe.tree import decompose

from .conftest import layout_of, regular

WIN = GridSpec("window", ("window",))


def fig4():
    """Anchors A_l, A_r (windows) with wall 2 between them, wall 3 above the row and wall 6 below."""
    return facade_from_layout(layout_of(5, 3, [
        (0, 0, 5, 1, "wall"),                                   # 6: below the whole row
        (0, 1, 1, 1, "wall"), (1, 1, 1, 1, "window"), (2, 1, 1, 1, "wall"), (3, 1, 1, 1, "window"),
        (4, 1, 1, 1, "wall"),                                   # A_l = window at 1, 2 = wall at 2, A_r at 3
        (0, 2, 5, 1, "wall")]))                                 # 3: above the whole row


def _named(f):
    return {(f.origin, round(f.x, 6)): f for f in f.leaves}


def test_fig4_insert_source_between_anchors_without_fig5_conflict():
    f = fig4()
    grid = detect_grid(f, WIN)
    new = insert_column(f, grid, source=0, position=1)  # S = a copy of A_l between A_l and A_r
    assert new is not None and check_partition(to_layout(new)) == []
    row = sorted((x for x in new.leaves if x.y == 1), key=lambda x: x.x)
    # A_l | 2' | S | 2 | A_r: the wall between the anchors is duplicated once, S sits between its two copies
    assert [(x.origin, x.label) for x in row] == [(1, "wall"), (2, "window"), (3, "wall"), (2, "window"),
                                                  (3, "wall"), (4, "window"), (5, "wall")]
    # 6 and 3 are stretched, not duplicated: each is one node whose neighbours include S and 2'
    below = [x for x in new.leaves if x.origin == 0]
    above = [x for x in new.leaves if x.origin == 6]
    assert len(below) == 1 and len(above) == 1 and below[0].w == new.width == 7
    nodes = tuple(n for n in decompose(new).walk() if n.is_leaf)
    g = neighbourhood_graph(nodes)
    index = {n.leaves[0]: k for k, n in enumerate(nodes)}
    s = next(i for i, x in enumerate(new.leaves) if x.label == "window" and x.x == 3)
    dup = next(i for i, x in enumerate(new.leaves) if x.origin == 3 and x.x == 2)
    six = new.leaves.index(below[0])
    three = new.leaves.index(above[0])
    assert (index[six], index[s]) in g.vertical and (index[six], index[dup]) in g.vertical
    assert (index[s], index[three]) in g.vertical
    # Fig. 5's conflict would make some node both left and right of another: the horizontal graph is acyclic
    order = {k: n.x for k, n in enumerate(nodes)}
    assert all(order[a] < order[b] for a, b in g.horizontal)
    assert not ({(b, a) for a, b in g.horizontal} & g.horizontal)


def test_remove_column_is_the_inverse_size_and_count():
    f = facade_from_layout(regular(4, 2))
    grid = detect_grid(f, WIN)
    for c in range(4):
        new = remove_column(f, grid, c)
        assert check_partition(to_layout(new)) == []
        assert new.width == pytest.approx(9.0)
        assert len(detect_grid(new, WIN).columns) == 3


def test_coupled_insertion_in_all_rows_keeps_columns_aligned():
    f = facade_from_layout(regular(3, 3))
    new = insert_column(f, detect_grid(f, WIN), source=0, position=2)
    grid = detect_grid(new, WIN)
    assert len(grid.columns) == 4 and grid.phantoms == 0 and len(grid.rows) == 3
    for c in range(4):
        xs = {round(new.leaves[i].x, 9) for i in grid.column(c)}
        assert len(xs) == 1


def test_overlapping_anchors_give_no_insertion():
    f = facade_from_layout(layout_of(3, 2, [(0, 0, 2, 1, "window"), (2, 0, 1, 1, "wall"), (0, 1, 1, 1, "wall"),
                                            (1, 1, 2, 1, "window")]))
    grid = detect_grid(f, WIN)
    assert len(grid.columns) == 1 or insert_column(f, grid, 0, 1) is None


def test_source_columns_are_unique_kinds():
    f = facade_from_layout(regular(4, 2))
    assert source_columns(f, detect_grid(f, WIN)) == [0]


def test_band_of_k_copies_is_the_insertion_repeated():
    from citygen_safe.jump import insert_slab, insertion_gap, merge_leaves
    f = facade_from_layout(regular(3, 2))
    grid = detect_grid(f, WIN)
    once = insert_column(f, grid, 0, 1)
    twice = insert_column(once, detect_grid(once, WIN), 0, 1)
    bulk = insert_slab(f, insertion_gap(grid, 1), grid.columns[0], copies=2)
    fixed = frozenset({"window"})
    shape = lambda g: sorted((round(x.x, 9), round(x.y, 9), round(x.w, 9), x.label)  # noqa: E731
                             for x in merge_leaves(g, fixed)[0].leaves)
    assert bulk.width == twice.width == f.width + 2 * 3.0 and shape(bulk) == shape(twice)
    assert check_partition(to_layout(bulk)) == []


def test_removal_repeated_is_one_wider_slab():
    from citygen_safe.jump import removal_slab, remove_slab
    f = facade_from_layout(regular(5, 2))
    grid = detect_grid(f, WIN)
    once = remove_column(f, grid, 1)
    twice = remove_column(once, detect_grid(once, WIN), 1)
    bulk = remove_slab(f, removal_slab(grid, 1, 2))
    assert bulk.width == pytest.approx(twice.width) and len(detect_grid(bulk, WIN).columns) == 3
    assert removal_slab(grid, 3, 2) == (grid.columns[2][1], grid.columns[4][1])  # through the last column
    assert removal_slab(grid, 0, 5) is None and removal_slab(grid, 4, 2) is None  # one column must stay


def test_regression_one_column_grid_gains_columns_at_the_boundary():
    """A one-column grid could not gain columns (insertion needs two anchor columns). Now the column is copied
    next to itself with its gap to the facade boundary (``A_l | gap' | S' | gap | boundary``), on either side."""
    from citygen_safe.edit import Settings, column_candidates
    f = facade_from_layout(regular(1, 2))  # 3 m: wall 0.9 | window 1.2 | wall 0.9
    cands = column_candidates(f, Settings((WIN,)), grow=True)
    assert sorted(c.jump.position for c in cands) == [0, 1]
    assert all(c.delta == pytest.approx(2.1) for c in cands)
    for cand in cands:
        new = cand.apply(2)
        assert new.width == pytest.approx(3.0 + 2 * 2.1) and check_partition(to_layout(new)) == []
        grid = detect_grid(new, WIN)
        assert len(grid.columns) == 3 and len(grid.rows) == 2
        assert [round(b[0] - a[1], 6) for a, b in zip(grid.columns, grid.columns[1:])] == [0.9, 0.9]
        assert round(grid.columns[0][0], 6) == 0.9 and round(new.width - grid.columns[-1][1], 6) == 0.9


def test_one_column_facade_widens_to_the_request(tmp_path):
    from citygen.request import FacadeRequest, check_request
    from citygen_safe.generate import edit
    from citygen_safe.ruleset import parse_ruleset
    (tmp_path / "f.layout.json").write_text(regular(1, 2).dumps())
    ruleset = parse_ruleset('safe f\nlayout "f.layout.json"\ngrid window window\n', "f.safe", base=tmp_path)
    request = FacadeRequest.preview(9.0, 6.0, 3.0, entrance=False)
    result = edit(ruleset, request)
    windows = [r for r in result.layout.leaves if r.label == "window"]
    assert "fallback" not in result.layout.meta and len(windows) >= 6
    assert check_partition(result.layout) == [] and check_request(result.layout, request) == []
