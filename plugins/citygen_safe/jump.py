"""Topological jumps (dang2014 §4): insert or remove a column of a facade grid (rows: on the transposed facade).

A column insertion puts a copy of the *source* column between the *anchor* columns ``A_l`` and ``A_r`` of every
row at once (the coupled insertion of §4, with the face as the common parent). The source is embedded in the
anchors' neighbourhood: the content between the anchors is duplicated with it, so a row reads
``A_l | gap' | S' | gap | A_r``. We realise the neighbourhood-graph insertion geometrically, as a band of width
``|gap| + |S|`` opened at the right edge of ``A_l`` (see docs/safe.md):

* a leaf that the band's copies continue on the same rows is *stretched* across the band (the node that the
  paper's relinking connects to both ``S`` and ``2'`` in Fig. 4: one node, two neighbours, no conflict);
* a leaf crossing the insertion line whose rows the band fills with other content is *duplicated once*: its two
  halves keep both sides' neighbourhoods (the conflict of Fig. 5, where ``S`` would be both left and right of a
  node, cannot arise);
* leaves inside the copied slabs are duplicated.

Removal is the inverse: the slab from a column's left edge to the next column's left edge (the last column:
from the previous column's right edge) is cut out; leaves crossing it shrink, leaves inside it vanish.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from citygen_safe.grids import FacadeGrid
from citygen_safe.leaves import EPS, Facade, Leaf
from citygen_safe.memory import Memory
from citygen_safe.tree import GROUP, X, Node, decompose

#: facades after a slab insertion or removal, by facade and slab; merged facades and their trees, by facade and
#: fixed labels (capacities in leaves)
JUMPS: Memory[Facade] = Memory(50_000)
MERGED: Memory[tuple[Facade, Node]] = Memory(50_000)


def _leaves(facade: Facade) -> int:
    return len(facade.leaves)


@dataclass(frozen=True)
class Jump:
    """One topological jump of a grid: ``insert`` copies column ``source`` between columns ``position - 1`` and
    ``position``; ``remove`` deletes column ``source``. ``axis`` is ``x`` (columns) or ``y`` (rows)."""

    op: str
    grid: str
    axis: str
    source: int
    position: int = -1

    def __str__(self) -> str:
        what = "column" if self.axis == "x" else "row"
        if self.op == "insert":
            return f"insert {what} {self.source} of {self.grid} at {self.position}"
        return f"remove {what} {self.source} of {self.grid}"


def source_columns(facade: Facade, grid: FacadeGrid, exclude: frozenset[str] = frozenset()) -> list[int]:
    """The unique columns (first of each kind: labels and sizes of their cells) that hold no excluded label."""
    seen: set[tuple] = set()
    out = []
    for c in range(len(grid.columns)):
        cells = grid.column(c)
        if any(i is not None and facade.leaves[i].label in exclude for i in cells):
            continue
        key = tuple(None if i is None else (facade.leaves[i].label, round(facade.leaves[i].w, 2),
                                            round(facade.leaves[i].h, 2)) for i in cells)
        if key not in seen:
            seen.add(key)
            out.append(c)
    return out


def insert_column(facade: Facade, grid: FacadeGrid, source: int, position: int) -> Facade | None:
    """Insert a copy of column ``source`` between anchor columns ``position - 1`` and ``position``; None when
    the anchors overlap (no gap to open the band in)."""
    gap = insertion_gap(grid, position)
    return None if gap is None else insert_slab(facade, gap, grid.columns[source])


def insert_slab(facade: Facade, gap: tuple[float, float], slab: tuple[float, float], copies: int = 1) -> Facade:
    """Open a band at ``gap[0]`` holding a copy of ``gap`` followed by a copy of ``slab``, ``copies`` times (the
    same insertion repeated: each repeat opens its band between ``A_l`` and the previous copy). Remembered
    (:mod:`citygen_safe.memory`)."""
    return JUMPS.get(("insert", facade, gap, slab, copies), lambda: _inserted(facade, gap, slab, copies), _leaves)


def _inserted(facade: Facade, gap: tuple[float, float], slab: tuple[float, float], copies: int) -> Facade:
    c0, c1 = gap
    s0, s1 = slab
    width_gap, pitch = c1 - c0, (c1 - c0) + (s1 - s0)
    delta = copies * pitch
    pieces: list[tuple[float, float, int]] = []  # (x0, x1, leaf index)
    for k, f in enumerate(facade.leaves):
        if f.right <= c0 + EPS:
            pieces.append((f.x, f.right, k))
        elif f.x >= c0 - EPS:
            pieces.append((f.x + delta, f.right + delta, k))
        else:
            pieces += [(f.x, c0, k), (c0 + delta, f.right + delta, k)]
        for lo, hi, at in ((c0, c1, c0), (s0, s1, c0 + width_gap)):
            a, b = max(f.x, lo), min(f.right, hi)
            if b - a > EPS:
                pieces += [(at + a - lo + c * pitch, at + b - lo + c * pitch, k) for c in range(copies)]
    return replace(facade, width=facade.width + delta, leaves=_merge(facade, pieces))


def insertion_gap(grid: FacadeGrid, position: int) -> tuple[float, float] | None:
    """The gap between anchor columns ``position - 1`` and ``position``; None when they overlap."""
    if not 0 < position < len(grid.columns):
        return None
    c0, c1 = grid.columns[position - 1][1], grid.columns[position][0]
    return None if c1 < c0 - EPS else (c0, max(c0, c1))


def boundary_gaps(extent: tuple[float, float], width: float) -> tuple[tuple[int, tuple[float, float]], ...]:
    """Insertions next to the only column (or floor band) ``extent`` of a face ``width`` wide, anchored at the
    facade boundary: (position, gap) with the gap between the left boundary and the column (position 0, the copy
    goes left of it) and between the column and the right boundary (position 1). A copy of the column with the
    gap, ``A_l | gap' | S' | gap | boundary``, spaces the copies by the gap as two anchors would be."""
    lo, hi = extent
    return (0, (0.0, max(0.0, lo))), (1, (hi, max(hi, width)))


def removal_slab(grid: FacadeGrid, column: int, count: int = 1) -> tuple[float, float] | None:
    """The slab removing column ``column``: to the next column's left edge (the last column: from the previous
    column's right edge); None when there is nothing to cut. ``count`` > 1: the removal repeated (the columns
    ``column .. column + count - 1``), at least one column stays."""
    n = len(grid.columns)
    if n < 2 or not 0 <= column < n or count >= n or column + count > n:
        return None
    if column + count < n:
        a, b = grid.columns[column][0], grid.columns[column + count][0]
    elif column > 0:
        a, b = grid.columns[column - 1][1], grid.columns[n - 1][1]
    else:
        return None
    return (a, b) if b - a > EPS else None


def remove_column(facade: Facade, grid: FacadeGrid, column: int) -> Facade | None:
    """Remove column ``column`` with the gap to its right neighbour (the last column: to its left neighbour)."""
    slab = removal_slab(grid, column)
    return None if slab is None else remove_slab(facade, slab)


def remove_slab(facade: Facade, slab: tuple[float, float]) -> Facade:
    """``facade`` without ``slab`` (remembered)."""
    return JUMPS.get(("remove", facade, slab), lambda: _removed(facade, slab), _leaves)


def _removed(facade: Facade, slab: tuple[float, float]) -> Facade:
    a, b = slab
    cut = b - a

    def shift(v: float) -> float:
        return v if v <= a else (a if v < b else v - cut)

    leaves = []
    for f in facade.leaves:
        x0, x1 = shift(f.x), shift(f.right)
        if x1 - x0 > EPS:
            leaves.append(Leaf.fast(x0, f.y, x1 - x0, f.h, f.region, f.origin))
    return replace(facade, width=facade.width - cut, leaves=tuple(leaves))


def merge_leaves(facade: Facade, fixed: frozenset[str]) -> tuple[Facade, Node]:
    """``facade`` with adjacent sibling leaves of its decomposition tree that show the same region (label, symbol,
    material, ...) merged into one leaf, except labels in ``fixed`` (grid elements, floor-bound openings), and the
    tree of the result. Jumps cut leaves at the copied slabs' edges; merging the pieces back keeps the leaf count
    growing only with the copied content. Siblings only, so the partition stays guillotine (merging arbitrary
    neighbours could close a pinwheel); leaves come in tree order. Remembered (:mod:`citygen_safe.memory`)."""
    return MERGED.get((facade, fixed), lambda: _merged(facade, fixed), lambda merged: _leaves(merged[0]))


def _merged(facade: Facade, fixed: frozenset[str]) -> tuple[Facade, Node]:
    out: list[Leaf] = []

    keys: dict[int, object] = {}

    def key(leaf: Leaf) -> object:
        """The leaf's region without its geometry (cached: copies share their region object)."""
        if id(leaf.region) not in keys:
            keys[id(leaf.region)] = replace(leaf.region, x=0.0, y=0.0, w=0.0, h=0.0)
        return keys[id(leaf.region)]

    def same(a: Leaf, b: Leaf) -> bool:
        return a.label not in fixed and (a.region is b.region or key(a) == key(b))

    def runs(node: Node) -> list[Leaf | Node]:
        """The node's children as merged leaves (not yet numbered) or finished subtrees."""
        items: list[Leaf | Node] = []
        for child in node.children:
            item = visit(child)
            if isinstance(item, Leaf) and items and isinstance(items[-1], Leaf) and same(items[-1], item):
                a = items[-1]
                items[-1] = (Leaf.fast(a.x, a.y, item.right - a.x, a.h, a.region, a.origin) if node.split == X
                             else Leaf.fast(a.x, a.y, a.w, item.top - a.y, a.region, a.origin))
            else:
                items.append(item)
        return items

    def visit(node: Node) -> Leaf | Node:
        if node.split is None:
            return facade.leaves[node.leaves[0]]
        if node.split == GROUP:
            first = len(out)
            out.extend(facade.leaves[i] for i in node.leaves)
            return Node(node.x, node.y, node.w, node.h, GROUP, (), tuple(range(first, len(out))))
        items = runs(node)
        if len(items) == 1 and isinstance(items[0], Leaf):
            return items[0]
        children = tuple(_numbered(item, out) for item in items)
        return Node(node.x, node.y, node.w, node.h, node.split, children,  # (not replace(): it was a tenth
                    tuple(i for c in children for i in c.leaves))        # of the merge's time)

    root = _numbered(visit(decompose(facade)), out)
    return replace(facade, leaves=tuple(out)), root


def _numbered(item: Leaf | Node, out: list[Leaf]) -> Node:
    """A leaf node for a merged leaf (appended to ``out``), or the finished subtree."""
    if isinstance(item, Node):
        return item
    out.append(item)
    return Node(item.x, item.y, item.w, item.h, None, (), (len(out) - 1,))


def _merge(facade: Facade, pieces: list[tuple[float, float, int]]) -> tuple[Leaf, ...]:
    """Leaves from pieces: touching pieces of one leaf are one (stretched) leaf, others are its duplicates."""
    pieces.sort(key=lambda p: (p[2], p[0]))
    out: list[Leaf] = []
    run: list[float] | None = None
    for x0, x1, k in pieces:
        if run is not None and run[2] == k and x0 <= run[1] + EPS:
            run[1] = max(run[1], x1)
            continue
        if run is not None:
            out.append(_leaf(facade, run))
        run = [x0, x1, k]
    if run is not None:
        out.append(_leaf(facade, run))
    out.sort(key=lambda f: (f.y, f.x))
    return tuple(out)


def _leaf(facade: Facade, run: list) -> Leaf:
    f = facade.leaves[run[2]]
    return Leaf.fast(run[0], f.y, run[1] - run[0], f.h, f.region, f.origin)
