"""§3 structures: decomposition tree, neighbourhood graph, facade grids with phantoms and subgrids."""
from __future__ import annotations

from citygen.layout import check_partition
from citygen_safe.compose import to_layout
from citygen_safe.graph import neighbourhood_graph, to_tree
from citygen_safe.grids import GridSpec, auto_specs, build_grid, detect_grid, subgrid_of
from citygen_safe.leaves import EPS, facade_from_layout, transpose
from citygen_safe.tree import GROUP, X, decompose

from .conftest import layout_of, regular


def assert_tiles(node):
    """Every split node's children tile it exactly along the split axis and span it across."""
    for n in node.walk():
        if n.split in (None, GROUP):
            continue
        pos = n.x if n.split == X else n.y
        for c in n.children:
            assert abs((c.x if n.split == X else c.y) - pos) < 1e-9
            assert abs((c.h if n.split == X else c.w) - (n.h if n.split == X else n.w)) < 1e-9
            pos += c.w if n.split == X else c.h
        assert abs(pos - ((n.x + n.w) if n.split == X else (n.y + n.h))) < 1e-9


def test_decomposition_tree_of_cmp_layout_recovers_cuts(cmp_facade):
    tree = decompose(cmp_facade)
    assert_tiles(tree)
    assert sorted(tree.leaves) == list(range(len(cmp_facade.leaves)))
    assert tree.split == "y" and len(tree.children) > 5  # floors and bands first
    assert not [n for n in tree.walk() if n.split == GROUP]


def test_pinwheel_block_is_one_group_leaf():
    lay = layout_of(3, 3, [(0, 0, 2, 1, "a"), (2, 0, 1, 2, "b"), (1, 2, 2, 1, "c"), (0, 1, 1, 2, "d"),
                           (1, 1, 1, 1, "window")])
    tree = decompose(facade_from_layout(lay))
    assert tree.split == GROUP and len(tree.leaves) == 5


def test_neighbourhood_graph_edges():
    lay = layout_of(3, 2, [(0, 0, 1, 2, "wall"), (1, 0, 1, 1, "wall"), (1, 1, 1, 1, "window"), (2, 0, 1, 2, "wall")])
    tree = decompose(facade_from_layout(lay))
    nodes = tuple(n for n in tree.walk() if n.is_leaf)
    g = neighbourhood_graph(nodes)
    name = {k: n.leaves[0] for k, n in enumerate(nodes)}
    assert {(name[a], name[b]) for a, b in g.vertical} == {(1, 2)}
    assert {(name[a], name[b]) for a, b in g.horizontal} == {(0, 1), (0, 2), (1, 3), (2, 3)}


def test_chain_collapsing_rebuilds_a_valid_tree(cmp_facade):
    tree = decompose(cmp_facade)
    rebuilt = to_tree(neighbourhood_graph(tuple(n for n in tree.walk() if n.is_leaf)))
    assert_tiles(rebuilt)
    assert sorted(rebuilt.leaves) == sorted(tree.leaves)
    assert (rebuilt.w, rebuilt.h) == (tree.w, tree.h)


def test_cmp_window_grid_rows_columns(cmp_facade):
    grid = detect_grid(cmp_facade, GridSpec("window", ("window",)))
    # upper windows; the transom over the door (its own row); the ground windows with a phantom over the door
    assert (len(grid.rows), len(grid.columns), grid.phantoms) == (3, 5, 5)
    assert {s.name for s in auto_specs(cmp_facade)} >= {"window", "door", "window+door"}
    for c in range(5):  # columns are non-overlapping, left to right
        column = [cmp_facade.leaves[i] for i in grid.column(c) if i is not None]
        lo, hi = grid.columns[c]
        assert all(lo - EPS <= f.x and f.right <= hi + EPS for f in column)


def test_phantom_fills_a_missing_cell():
    lay = layout_of(5, 4, [(0, 0, 1, 4, "wall"), (1, 0, 1, 3, "door"), (1, 3, 1, 1, "wall"), (2, 0, 1, 4, "wall"),
                           (3, 0, 1, 1, "wall"), (3, 1, 1, 1, "window"), (3, 2, 1, 0.5, "wall"),
                           (3, 2.5, 1, 1, "window"), (3, 3.5, 1, 0.5, "wall"), (4, 0, 1, 4, "wall")])
    f = facade_from_layout(lay)
    grid = detect_grid(f, GridSpec("g", ("window", "door")))
    assert len(grid.rows) == 2 and len(grid.columns) == 2
    assert grid.phantoms == 1 and grid.cells[0][0] is None  # the door is assigned to the lower row only
    assert f.leaves[grid.cells[1][0]].label == "door"


def test_subgrid_hierarchy():
    lay = layout_of(4, 2, [(0, 0, 2, 2, "window"), (2, 0, 2, 2, "wall")])
    f = facade_from_layout(lay)
    outer = build_grid(f, "outer", [0])
    inner = build_grid(f, "inner", [1])
    assert not subgrid_of(f, inner, outer)
    # an element standing for a block (a pinwheel group) contains the grid of smaller elements
    assert not subgrid_of(f, outer, outer)


def test_transpose_is_an_involution(cmp_facade):
    assert transpose(transpose(cmp_facade)) == cmp_facade
    assert check_partition(to_layout(transpose(cmp_facade))) == []


def test_regular_fixture_partitions():
    assert check_partition(regular(4, 3)) == []
