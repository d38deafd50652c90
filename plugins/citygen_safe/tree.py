"""The decomposition tree (dang2014 §3): recursive x/y splits recovered from a facade's leaf shapes.

Our layouts arrive as partitions (a CMP import is one flat list of terminals), so the guillotine cuts are
recovered top-down: a node is split along y at every line no leaf crosses (floors first), else along x; a block
that no single cut separates (a pinwheel of four or more shapes) becomes one ``group`` node whose members are
treated as one leaf by the optimisation (they are scaled together, see docs/safe.md).
"""
from __future__ import annotations

from dataclasses import dataclass

from citygen_safe.leaves import EPS, Facade
from citygen_safe.memory import Memory

X, Y, GROUP = "x", "y", "group"


@dataclass(frozen=True)
class Node:
    """A facade shape of the tree: a rectangle, its split (``x``, ``y``, ``group`` or None for a leaf) and
    children in split order (left to right, bottom to top). ``leaves`` are the leaf indices below it."""

    x: float
    y: float
    w: float
    h: float
    split: str | None
    children: tuple[Node, ...]
    leaves: tuple[int, ...]

    @property
    def is_leaf(self) -> bool:
        return self.split is None or self.split == GROUP

    def walk(self):
        stack = [self]
        while stack:
            node = stack.pop()
            yield node
            stack.extend(reversed(node.children))


def decompose(facade: Facade) -> Node:
    """The decomposition tree of ``facade`` (y cuts tried before x cuts at every node), remembered by the leaves'
    rectangles: the tree depends on nothing else, and the same facades recur (the input layout of every edit of a
    ruleset's text, the states its jumps reach)."""
    boxes = tuple((f.x, f.y, f.right, f.top) for f in facade.leaves)
    return TREES.get(boxes, lambda: _Splitter(boxes).node(list(range(len(boxes)))), lambda _: len(boxes))


TREES: Memory[Node] = Memory(50_000)  #: decomposition trees by their leaves' rectangles (capacity in leaves)


class _Splitter:
    """The top-down recovery of guillotine cuts over fixed rectangles (columns of their edges, looked up by leaf
    index; plain Python: the nodes are small, numpy's per-call cost dominated)."""

    def __init__(self, boxes: tuple[tuple[float, float, float, float], ...]) -> None:
        self.lo = ([b[0] for b in boxes], [b[1] for b in boxes])
        self.hi = ([b[2] for b in boxes], [b[3] for b in boxes])

    def cuts(self, idx: list[int], axis: int) -> list[list[int]]:
        """Groups of ``idx`` separated by lines across ``axis`` that no box crosses, in increasing order."""
        lo, hi = self.lo[axis], self.hi[axis]
        groups: list[list[int]] = []
        reach = float("-inf")
        for i in sorted(idx, key=lo.__getitem__):
            if not groups or lo[i] >= reach - EPS:
                groups.append([])
            groups[-1].append(i)
            if hi[i] > reach:
                reach = hi[i]
        return groups

    def node(self, idx: list[int]) -> Node:
        (xl, yl), (xh, yh) = self.lo, self.hi
        if len(idx) == 1:
            i = idx[0]
            return Node(xl[i], yl[i], xh[i] - xl[i], yh[i] - yl[i], None, (), (i,))
        x0, y0 = min(map(xl.__getitem__, idx)), min(map(yl.__getitem__, idx))
        x1, y1 = max(map(xh.__getitem__, idx)), max(map(yh.__getitem__, idx))
        for split, axis in ((Y, 1), (X, 0)):
            groups = self.cuts(idx, axis)
            if len(groups) > 1:
                children = tuple(self.node(sorted(g)) for g in groups)
                return Node(x0, y0, x1 - x0, y1 - y0, split, children, tuple(i for c in children for i in c.leaves))
        return Node(x0, y0, x1 - x0, y1 - y0, GROUP, (), tuple(idx))


def common_parent(root: Node, members: set[int]) -> Node:
    """The deepest node whose subtree holds every leaf in ``members``."""
    node = root
    while True:
        inner = [c for c in node.children if members <= set(c.leaves)]
        if not inner:
            return node
        node = inner[0]
